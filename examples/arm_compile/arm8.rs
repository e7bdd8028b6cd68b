//! Compile-time measurement of the planar 8-link flexible-joint arm with two stabilised
//! Hirschorn steps per joint: the declaration and the use of `benches/arms.rs` (the plant, its
//! tracking DAE, the design of the preliminary feedback, one DPC update with the fixed-size LU
//! and a closed loop), alone in one crate, so that the time to compile this example is what a
//! user's crate with this arm costs. Built only with the feature `arm-compile-time`, never by
//! `cargo test`; `bench/arm_compile_time.sh` times it (see `docs/arms.md`). Running it prints
//! the row of the benchmark's table (`benches/arms.rs`, which shares `common.rs` with it).

include!("common.rs");

flexible_joint_arm!("An arm of this benchmark.", Arm8, Arm8Tracking, 8);

fn main() {
    print_header();
    measure!(Arm8, Arm8Tracking, Arm8Reference, 8);
}
