//! The Radau IIA integrator on the index-3 Test Set problems (Andrews' squeezing mechanism and
//! the car axis), as declared and in the GGL-stabilised index-2 form
//! ([`dpc_core::stabilised::Stabilised`]), as the Test Set scores them: per tolerance, the
//! medians over the tolerance jitter `tol * {0.9, 1, 1.1}` of the significant correct digits
//! (scd, relative error) and of the mixed-error digits (mescd, error over `1 + |r|` at
//! `rtol = atol`, deTestSet's measure), the steps and the work.
//!
//! ```sh
//! cargo run --release -p dpc-core --example radau_index3
//! ```
//! With `-- --components` it also prints the digits of every component at `tol`. The car axis
//! row also gives the digits of the four positions at `tol` (the velocities and multipliers,
//! index 2 and 3, are the least accurate components).

#[path = "../tests/common/testset_index3.rs"]
mod testset;

use dpc_core::linear_solver::FaerDenseLu;
use dpc_core::radau::{Options, Radau, Stats};
use dpc_core::ImplicitDae;
use testset::*;

/// How the index-3 problem is integrated.
#[derive(Clone, Copy, PartialEq)]
enum Form {
    /// As declared, with the index-dependent error weights.
    Index3,
    /// In the GGL-stabilised index-2 form ([`Stabilised`]).
    Stabilised,
}

/// Integrate `dae` from `(y0, yp0)` to `t_end`; the first `y0.len()` components at `t_end`.
fn run<D: ImplicitDae>(
    dae: D,
    index: Vec<u8>,
    (y0, yp0): (&[f64], &[f64]),
    t_end: f64,
    tol: f64,
    what: &str,
) -> Option<(Vec<f64>, Stats)> {
    let opts = Options {
        index,
        ..Options::with_tolerances(tol, tol)
    };
    let n = dae.dimension();
    let result = (|| {
        let mut r = Radau::new(dae, FaerDenseLu::new(n), opts, 0.0, y0, yp0)?;
        r.set_stop_time(t_end)?;
        let mut y = vec![0.0; n];
        r.solve_to(t_end, &mut y, None)?;
        Ok::<_, dpc_core::radau::RadauError>((y, r.stats()))
    })();
    match result {
        Ok(r) => Some(r),
        Err(e) => {
            eprintln!("{what} at tol {tol:e}: {e}");
            None
        }
    }
}

/// The index of every unknown of a stabilised form: 1 for the first `differential`
/// unknowns, 2 for the rest.
fn stabilised_index(differential: usize, n: usize) -> Vec<u8> {
    (0..n)
        .map(|i| if i < differential { 1 } else { 2 })
        .collect()
}

fn andrews(tol: f64, form: Form) -> Option<(Vec<f64>, Stats)> {
    let (y0, yp0) = Andrews::initial();
    match form {
        Form::Index3 => run(
            Andrews,
            andrews_index(),
            (&y0, &yp0),
            ANDREWS_T_END,
            tol,
            "Andrews",
        ),
        Form::Stabilised => {
            let s = Andrews::stabilised();
            let (y, yp) = s.extend(&y0, &yp0);
            let index = stabilised_index(Andrews::STABILISED_DIFFERENTIAL, 33);
            run(s, index, (&y, &yp), ANDREWS_T_END, tol, "Andrews (GGL)")
        }
    }
}

fn car_axis(tol: f64, form: Form) -> Option<(Vec<f64>, Stats)> {
    let p = CarAxis::default();
    let (y0, yp0) = p.initial();
    match form {
        Form::Index3 => run(
            p,
            CAR_AXIS_INDEX.to_vec(),
            (&y0, &yp0),
            CAR_AXIS_T_END,
            tol,
            "car axis",
        ),
        Form::Stabilised => {
            let s = p.stabilised();
            let (y, yp) = s.extend(&y0, &yp0);
            let index = stabilised_index(CarAxis::STABILISED_DIFFERENTIAL, 12);
            run(s, index, (&y, &yp), CAR_AXIS_T_END, tol, "car axis (GGL)")
        }
    }
}

/// Median of the scd over the jitter; a failed run counts as no digits (NaN sorts last).
fn median(mut v: Vec<f64>) -> f64 {
    v.sort_by(f64::total_cmp);
    v[v.len() / 2]
}

/// One problem of the table: its name, how it is solved, its reference, the scored components
/// and the extra column (in brackets) of other components.
struct Problem<'a> {
    name: &'a str,
    solve: &'a dyn Fn(f64, Form) -> Option<(Vec<f64>, Stats)>,
    reference: &'a [f64],
    scored: &'a [usize],
    also: Option<(&'a str, &'a [usize])>,
}

/// The rows of `p` in `form` for tolerances 1e-4 .. 1e-10.
fn rows(p: &Problem, form: Form, label: &str, components: bool) {
    for k in [4, 5, 6, 7, 8, 9, 10] {
        let tol = 10f64.powi(-k);
        let runs: Vec<Option<Vec<f64>>> = [0.9, 1.0, 1.1]
            .iter()
            .map(|f| (p.solve)(tol * f, form).map(|(y, _)| y))
            .collect();
        let over_jitter = |measure: &dyn Fn(&[f64]) -> f64| {
            median(
                runs.iter()
                    .map(|y| y.as_deref().map_or(f64::NAN, measure))
                    .collect(),
            )
        };
        let d = over_jitter(&|y| scd(y, p.reference, p.scored));
        let m = over_jitter(&|y| mescd(y, p.reference, p.scored, tol, tol));
        let Some((y, s)) = (p.solve)(tol, form) else {
            println!("| {} {label} | 1e-{k} | failed | | | | | |", p.name);
            continue;
        };
        let also = p.also.map_or(String::new(), |(what, idx)| {
            format!(" ({what} {:.2})", scd(&y, p.reference, idx))
        });
        println!(
            "| {} {label}{also} | 1e-{k} | {d:.2} | {m:.2} | {} | {} | {} | {} |",
            p.name, s.steps, s.error_test_failures, s.newton_failures, s.jacobian_evaluations
        );
        if components {
            let e: Vec<String> = (0..p.reference.len())
                .map(|i| format!("{:.1}", scd(&y, p.reference, &[i])))
                .collect();
            println!("|   digits per component: {} |", e.join(" "));
        }
    }
}

fn main() {
    let components = std::env::args().any(|a| a == "--components");
    println!("| problem | tol | scd | mescd | steps | rejected | Newton failures | Jacobians |");
    println!("|---|---|---|---|---|---|---|---|");
    let all: Vec<usize> = (0..10).collect();
    let problems = [
        Problem {
            name: "Andrews (y1..y7)",
            solve: &andrews,
            reference: &ANDREWS_REF,
            scored: &ANDREWS_SCORED,
            also: None,
        },
        Problem {
            name: "car axis (all)",
            solve: &car_axis,
            reference: &CAR_AXIS_REF,
            scored: &all,
            also: Some(("positions", &[0, 1, 2, 3])),
        },
    ];
    for (form, label) in [(Form::Index3, "index 3"), (Form::Stabilised, "GGL")] {
        for p in &problems {
            rows(p, form, label, components);
        }
    }
}
