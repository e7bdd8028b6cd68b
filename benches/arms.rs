//! The planar n-link flexible-joint arm under DPC for n = 2, 4, 6, 8, 12, 16 with two stabilised
//! Hirschorn steps per joint: per n, the size of the tracking DAE, one evaluation of its
//! residual and iteration matrix, one DPC update (fixed-size LU), and the tracking error of
//! a closed loop with the preliminary feedback about the hanging rest (as
//! `scenarios/arm2.toml`). Prints the table of `docs/arms.md`.
//!
//! The arms' declaration (that of `models/src/arm.rs`, with the number of links a macro
//! argument, so that the larger ones are compiled only for this benchmark) and the
//! measurement are those of the compile-time examples, `examples/arm_compile/common.rs`.
//! Run with `cargo bench --bench arms`.

include!("../examples/arm_compile/common.rs");

flexible_joint_arm!("An arm of this benchmark.", Arm2, Arm2Tracking, 2);
flexible_joint_arm!("An arm of this benchmark.", Arm4, Arm4Tracking, 4);
flexible_joint_arm!("An arm of this benchmark.", Arm6, Arm6Tracking, 6);
flexible_joint_arm!("An arm of this benchmark.", Arm8, Arm8Tracking, 8);
flexible_joint_arm!("An arm of this benchmark.", Arm12, Arm12Tracking, 12);
flexible_joint_arm!("An arm of this benchmark.", Arm16, Arm16Tracking, 16);

fn main() {
    print_header();
    measure!(Arm2, Arm2Tracking, Arm2Reference, 2);
    measure!(Arm4, Arm4Tracking, Arm4Reference, 4);
    measure!(Arm6, Arm6Tracking, Arm6Reference, 6);
    measure!(Arm8, Arm8Tracking, Arm8Reference, 8);
    measure!(Arm12, Arm12Tracking, Arm12Reference, 12);
    measure!(Arm16, Arm16Tracking, Arm16Reference, 16);
}
