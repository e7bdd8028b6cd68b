//! The model crate of the planar 16-link flexible-joint arm with two stabilised Hirschorn steps
//! per joint: the declaration alone (the plant and its tracking DAE, public), compiled as a
//! library, so that every routine the macro generates for it is compiled here and none of
//! DPC's generic code (which the crate that designs, controls or simulates with the arm
//! instantiates: `arm16.rs` measures that). Built only with the feature `arm-compile-time`,
//! never by `cargo test`; `bench/arm_compile_time.sh` times it (see `docs/arms.md`).

include!("../../models/src/arm_declaration.rs");

flexible_joint_arm!(
    "The 16-link arm of the compile-time measurement.",
    Arm16,
    Arm16Tracking,
    16
);
