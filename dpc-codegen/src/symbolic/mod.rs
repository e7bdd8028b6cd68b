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
