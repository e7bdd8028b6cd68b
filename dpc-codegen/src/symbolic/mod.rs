//! The symbolic engine: expressions as a hash-consed DAG, derivatives, substitution,
//! evaluation, readable printing and CSE-scheduled emission to Rust.
//!
//! Techniques (all standard):
//! - *Hash-consing* ([`graph`]): each distinct node is stored once, so structural equality is
//!   [`ExprId`] equality and sharing is maximal from construction on. Constructors fold
//!   constants and apply algebraic identities, keeping canonical forms (sorted commutative
//!   operands, constants gathered) so that equal expressions tend to meet in the same node.
//! - *Forward symbolic differentiation* ([`diff`]): chain rule over the DAG in topological
//!   (id) order, memoised per `(node, variable)`, linear in the DAG size.
//! - *CSE by reference counting in topological order* ([`schedule`]): over all roots together,
//!   a node used more than once gets a temporary; emission ([`rust`]) turns the schedule into
//!   straight-line `f64` code.
//!
//! Conventions and limits worth knowing:
//! - Identities ignore IEEE special values (`0 * a = 0`, `a / a = 1`, `a - a = 0`), and
//!   `0 * a` gives `+0` where IEEE could give `-0` (visible only through `atan2`/`signum`).
//!   Fully constant subexpressions fold only to finite values: `ln(0)` or `1 / 0` stay in the
//!   expression and produce inf/NaN at run time.
//! - `d|a|/da = signum(a)` (`±1` at `±0`), `d signum(a)/da = 0`; `atan2` and `hypot`
//!   derivatives are singular at the origin, as the functions are.
//! - `max` and `min` are `f64::max` and `f64::min` in every layer (a NaN operand is ignored);
//!   `d max(a, b)` is exactly `a'` where `a > b`, `b'` where `a < b` and `(a' + b') / 2` at a
//!   tie (NaN if an operand is NaN), and so for `min` with the roles swapped.
//! - Sums and products are binary with sorted operands, not flattened n-ary terms, so
//!   `(a + b) + c` and `a + (b + c)` are different nodes (both are correct, only sharing is
//!   lost); like terms `k a + l a` and powers of one base are combined, one level deep.
//! - Emitted code keeps the DAG's evaluation order and matches [`Graph::eval`] bit for bit
//!   (up to how LLVM expands constant `powi` under optimisation).
//!
//! The caller owns the meaning of variables ([`Var`] is an index into its table). DESIGN.md
//! section 5 ("Symbolic") states the requirements this module answers.

pub mod diff;
pub mod display;
pub mod eval;
pub mod func;
pub mod graph;
pub mod rust;
pub mod schedule;
pub mod subst;

pub use func::Func;
pub use graph::{ExprId, Graph, Node, Var};
pub use rust::RustCode;
pub use schedule::Schedule;
