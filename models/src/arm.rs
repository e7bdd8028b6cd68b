//! The planar n-link robot arm with flexible joints (Spong's model): per joint, a link angle
//! `q[i]` (relative to the previous link, measured from the downward vertical for the first)
//! driven through a torsional spring of stiffness `ks[i]` by a motor at angle `th[i]`,
//!
//! ```text
//! M(q) q'' + C(q, q') q' + g(q) + K (q - th) = 0,      J th'' + K (th - q) = u,
//! ```
//!
//! with the link angles as outputs, each of relative degree 4. The equations of the links are
//! written once for every `N` with the DSL's indexed families, in the form of d'Alembert's
//! principle: per joint `i`, the sum over the links `c >= i` of `m_c (dp_c/dq_i) . p_c''`
//! (`p_c` the centre of mass of link `c`) plus `I_c phi_c''` (`phi_c` the absolute angle) plus
//! the gravity and spring torques, which is `M(q) q'' + C(q, q') q' + g(q)` without the mass
//! matrix or the Coriolis terms being written out. The mass matrix stays implicit: the
//! macro never inverts it.
//!
//! The motors and springs are those of [`crate::FlexibleJoint`] (`j_motor = 0.5`, `ks = 40`);
//! [`Arm1`] is that model with the link inertia split into its centre-of-mass part and
//! `m r^2`; [`Arm2`] and [`Arm6`] are the plants of `scenarios/arm2.toml` and
//! `scenarios/arm6.toml`. All three apply two stabilised Hirschorn steps per joint,
//! `W(s) = (s + 4)^2`; `docs/arms.md` measures the same declaration for other `N` and steps.

include!("arm_declaration.rs");

flexible_joint_arm!(
    "The one-link arm: [`crate::FlexibleJoint`] in the arm's parameters.",
    Arm1,
    Arm1Tracking,
    1
);
flexible_joint_arm!(
    "The two-link arm of `scenarios/arm2.toml`.",
    Arm2,
    Arm2Tracking,
    2
);
flexible_joint_arm!(
    "The six-link arm of `scenarios/arm6.toml`.",
    Arm6,
    Arm6Tracking,
    6
);
