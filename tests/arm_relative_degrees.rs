//! The check of the relative degrees at the nominal (`dpc::core::design::check_relative_degrees`)
//! on the planar n-link flexible-joint arm of `models/src/arm.rs` at the hanging rest, for
//! numbers of links up to 16. The arm's relative degrees are 4 per joint for every `n` (its
//! decoupling matrix is `M^-1 K J^-1`, regular), so the check must find them; the arms are
//! read at run time from the repository's `Arm2` declaration with `N` replaced (the
//! run-time evaluator agrees with the compiled code, `tests/runtime_agreement.rs`), so that
//! no large arm is compiled.

mod common;

use common::model_text::template_models;
use dpc::core::design::{check_relative_degrees, linear_relative_degrees};
use dpc::core::linearize::{linearize, OperatingPoint};
use dpc::core::DaeModel;
use dpc::runtime::RuntimePlant;
use std::path::Path;

/// The arm of `models/src/arm.rs` with `n` links: its declaration with `n` for the number of
/// links.
fn arm(n: usize) -> RuntimePlant {
    let path = Path::new(env!("CARGO_MANIFEST_DIR")).join("models/src/arm_declaration.rs");
    let template = std::fs::read_to_string(path).expect("models/src/arm_declaration.rs");
    let call = format!("flexible_joint_arm!(\"The arm.\", Arm{n}, Arm{n}Tracking, {n});");
    let [text] = &template_models(&call, &template)[..] else {
        panic!("one arm in {call}");
    };
    dpc::runtime::parse("arm.rs", text)
        .expect("the arm reads as a plant file")
        .plant()
}

#[test]
fn the_arm_has_relative_degree_four_per_joint_at_the_hanging_rest() {
    for n in [1, 2, 4, 8, 12, 16] {
        let plant = arm(n);
        let s = plant.structure();
        let (nx, nu) = (s.n_states(), s.n_inputs());
        let rest = vec![0.0; nx];
        let system = linearize(
            &plant,
            OperatingPoint {
                t: 0.0,
                x: &rest,
                xdot: &rest,
                z: &[],
                u: &vec![0.0; nu],
            },
        )
        .expect("the arm is of index 1");
        assert_eq!(
            linear_relative_degrees(&system),
            vec![Some(4); n],
            "n = {n}"
        );
        check_relative_degrees(&system, &s.outputs, &vec![Some(4); n])
            .unwrap_or_else(|e| panic!("n = {n}: {e}"));
    }
}
