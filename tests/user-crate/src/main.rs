//! A user's plant, not in the repository: four tanks in the quadruple-tank arrangement
//! (Johansson, 2000), two pumps whose flows are split between a lower and an upper tank, the
//! outflows through the orifices as algebraic unknowns, and the two lower levels as outputs.

use std::process::ExitCode;

use dpc::cli::registry::{Entry, Registry};

dpc::model! {
    /// The quadruple tank: levels `h1..h4` (cm), pump voltages `v1, v2` (V), orifice
    /// outflows `q1..q4` (cm^3/s) as algebraic unknowns.
    pub Tanks {
        params {
            a_1 = 28.0, a_2 = 32.0, a_3 = 28.0, a_4 = 32.0,
            o_1 = 0.071, o_2 = 0.057, o_3 = 0.071, o_4 = 0.057,
            k_1 = 3.33, k_2 = 3.35, gamma_1 = 0.7, gamma_2 = 0.6, g = 981.0,
        }
        states { h1, h2, h3, h4 }
        algebraic { q1, q2, q3, q4 }
        inputs { v1, v2 }
        equations {
            a_1 * der(h1) == -q1 + q3 + gamma_1 * k_1 * v1;
            a_2 * der(h2) == -q2 + q4 + gamma_2 * k_2 * v2;
            a_3 * der(h3) == -q3 + (1.0 - gamma_2) * k_2 * v2;
            a_4 * der(h4) == -q4 + (1.0 - gamma_1) * k_1 * v1;
            0.0 == q1 - o_1 * sqrt(2.0 * g * h1);
            0.0 == q2 - o_2 * sqrt(2.0 * g * h2);
            0.0 == q3 - o_3 * sqrt(2.0 * g * h3);
            0.0 == q4 - o_4 * sqrt(2.0 * g * h4);
        }
        outputs { h1, h2 }
        references {
            h1 = 12.4 + 0.5 * sin(0.1 * t),
            h2 = 12.7 - 0.5 * sin(0.1 * t),
        }
        tracking TanksTracking { h1: [0.5], h2: [0.5] }
    }
}

fn main() -> ExitCode {
    dpc::cli::main(
        Registry::new().model(
            Entry::new(
                "tanks",
                "four coupled tanks, two pumps",
                Tanks::default(),
                TanksTracking::default(),
            )
            .reference(TanksReference::default())
            .listing(TanksTracking::LISTING),
        ),
    )
}
