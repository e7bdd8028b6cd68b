//! The compiled tape: a set of roots of the symbolic graph as a flat list of instructions.
//!
//! Compilation walks the nodes reachable from the roots in id order (a topological order of
//! the hash-consed graph, so every shared subexpression is one node and is computed once,
//! across all roots together, as in the emitted code) and gives each a register: constants
//! are preset in a template, variables are loaded from the routine's arguments, every other
//! node is one instruction reading registers computed before it. Evaluation copies the
//! template, loads the variables, runs the instructions in order and reads the roots'
//! registers. Each instruction performs the `f64` operation the emitted code performs for
//! that node.

use std::cell::RefCell;

use dpc_codegen::derive::{Layout, Source};
use dpc_codegen::ir::{Model, Symbol};
use dpc_codegen::symbolic::{ExprId, Func, Node};

/// One instruction; the destination register is implied by its position (see [`Tape`]).
#[derive(Clone, Copy, Debug)]
enum Op {
    Add(u32, u32),
    Mul(u32, u32),
    Div(u32, u32),
    Powi(u32, i32),
    Powf(u32, u32),
    Func(Func, u32),
    Atan2(u32, u32),
    Hypot(u32, u32),
    Max(u32, u32),
    Min(u32, u32),
}

/// A symbol the layout of a routine has no place for (the model checks exclude it, so this
/// is an inconsistency between the passes, reported rather than evaluated).
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct Unplaced {
    /// The symbol as written in listings.
    pub symbol: String,
}

/// The arguments of one evaluation.
#[derive(Clone, Copy, Debug)]
pub(crate) struct Args<'a> {
    pub t: f64,
    pub x: &'a [f64],
    pub xdot: &'a [f64],
    pub z: &'a [f64],
    pub u: &'a [f64],
    pub params: &'a [f64],
    pub w: &'a [f64],
    pub c: f64,
}

impl<'a> Args<'a> {
    /// A model's arguments with its parameters and `W` coefficients, at `t = 0` with no
    /// unknowns, inputs or `c`: the base the evaluations at a point complete with struct
    /// update syntax (`Args { t, x, z, u, ..Args::model(params, w) }`).
    pub fn model(params: &'a [f64], w: &'a [f64]) -> Self {
        Args {
            w,
            ..Args::time(0.0, params)
        }
    }

    /// Arguments of time and parameters only.
    pub fn time(t: f64, params: &'a [f64]) -> Self {
        Args {
            t,
            x: &[],
            xdot: &[],
            z: &[],
            u: &[],
            params,
            w: &[],
            c: 0.0,
        }
    }

    fn value(&self, source: Source) -> f64 {
        match source {
            Source::Time => self.t,
            Source::State(k) => self.x[k],
            Source::StateDot(k) => self.xdot[k],
            Source::Algebraic(k) => self.z[k],
            Source::Input(k) => self.u[k],
            Source::Param(k) => self.params[k],
            Source::WCoefficient(k) => self.w[k],
            Source::IterationCoefficient => self.c,
        }
    }
}

/// The roots of one routine, compiled (see the module doc).
#[derive(Clone, Debug)]
pub(crate) struct Tape {
    /// Register values before evaluation: the constants, zero elsewhere.
    template: Vec<f64>,
    /// `(register, where its value comes from)` per variable.
    loads: Vec<(u32, Source)>,
    /// Register of the first instruction; instruction `k` writes register `first + k`.
    first: usize,
    ops: Vec<Op>,
    /// Register of each root, in the order given.
    roots: Vec<u32>,
}

thread_local! {
    /// Registers of the evaluations on this thread, reused so that evaluation does not
    /// allocate once the largest tape has run.
    static REGISTERS: RefCell<Vec<f64>> = const { RefCell::new(Vec::new()) };
}

impl Tape {
    /// Compile `roots` of `model`'s graph, reading variables as `layout` places them.
    pub fn compile(
        model: &Model,
        layout: &Layout,
        w_degrees: &[usize],
        roots: &[ExprId],
    ) -> Result<Tape, Unplaced> {
        let order = model.graph.reachable(roots);
        // Leaves (constants, variables) first, then the instructions, each in id order.
        let mut register = vec![u32::MAX; order.last().map_or(0, |e| e.index() + 1)];
        let mut template = Vec::new();
        let mut loads = Vec::new();
        for &e in &order {
            match *model.graph.node(e) {
                Node::Const(v) => {
                    register[e.index()] = template.len() as u32;
                    template.push(v);
                }
                Node::Var(v) => {
                    let symbol: Symbol = model.symbols.symbol(v);
                    let source = layout.source(symbol, w_degrees).ok_or_else(|| Unplaced {
                        symbol: model.symbol_name(symbol),
                    })?;
                    register[e.index()] = template.len() as u32;
                    loads.push((template.len() as u32, source));
                    template.push(0.0);
                }
                _ => {}
            }
        }
        let first = template.len();
        let mut ops = Vec::new();
        for &e in &order {
            let r = |c: ExprId| register[c.index()];
            let op = match *model.graph.node(e) {
                Node::Const(_) | Node::Var(_) => continue,
                Node::Add(a, b) => Op::Add(r(a), r(b)),
                Node::Mul(a, b) => Op::Mul(r(a), r(b)),
                Node::Div(a, b) => Op::Div(r(a), r(b)),
                Node::Powi(a, n) => Op::Powi(r(a), n),
                Node::Powf(a, b) => Op::Powf(r(a), r(b)),
                Node::Func(f, a) => Op::Func(f, r(a)),
                Node::Atan2(y, x) => Op::Atan2(r(y), r(x)),
                Node::Hypot(a, b) => Op::Hypot(r(a), r(b)),
                Node::Max(a, b) => Op::Max(r(a), r(b)),
                Node::Min(a, b) => Op::Min(r(a), r(b)),
            };
            register[e.index()] = (first + ops.len()) as u32;
            ops.push(op);
        }
        template.resize(first + ops.len(), 0.0);
        Ok(Tape {
            template,
            loads,
            first,
            ops,
            roots: roots.iter().map(|e| register[e.index()]).collect(),
        })
    }

    /// The tape of no roots.
    pub fn compile_empty() -> Tape {
        Tape {
            template: Vec::new(),
            loads: Vec::new(),
            first: 0,
            ops: Vec::new(),
            roots: Vec::new(),
        }
    }

    /// Number of instructions (the arithmetic operations of one evaluation).
    pub fn len(&self) -> usize {
        self.ops.len()
    }

    /// Evaluate, then hand the root values (in the order compiled) to `read`.
    pub fn eval<R>(&self, args: &Args<'_>, read: impl FnOnce(Values<'_>) -> R) -> R {
        REGISTERS.with(|cell| match cell.try_borrow_mut() {
            Ok(mut regs) => self.eval_in(&mut regs, args, read),
            // Only reached if `read` evaluated another tape on this thread.
            Err(_) => self.eval_in(&mut Vec::new(), args, read),
        })
    }

    fn eval_in<R>(
        &self,
        regs: &mut Vec<f64>,
        args: &Args<'_>,
        read: impl FnOnce(Values<'_>) -> R,
    ) -> R {
        // Registers from `first` on are written by the instructions before they are read.
        if regs.len() < self.template.len() {
            regs.resize(self.template.len(), 0.0);
        }
        regs[..self.first].copy_from_slice(&self.template[..self.first]);
        for &(r, source) in &self.loads {
            regs[r as usize] = args.value(source);
        }
        for (k, op) in self.ops.iter().enumerate() {
            let g = |i: u32| regs[i as usize];
            let v = match *op {
                Op::Add(a, b) => g(a) + g(b),
                Op::Mul(a, b) => g(a) * g(b),
                Op::Div(a, b) => g(a) / g(b),
                Op::Powi(a, n) => g(a).powi(n),
                Op::Powf(a, b) => g(a).powf(g(b)),
                Op::Func(f, a) => f.apply(g(a)),
                Op::Atan2(y, x) => g(y).atan2(g(x)),
                Op::Hypot(a, b) => g(a).hypot(g(b)),
                Op::Max(a, b) => g(a).max(g(b)),
                Op::Min(a, b) => g(a).min(g(b)),
            };
            regs[self.first + k] = v;
        }
        read(Values {
            regs,
            roots: &self.roots,
        })
    }
}

/// The values of a tape's roots after an evaluation.
#[derive(Clone, Copy)]
pub(crate) struct Values<'a> {
    regs: &'a [f64],
    roots: &'a [u32],
}

impl Values<'_> {
    /// The value of root `k` (in the order compiled).
    pub fn get(&self, k: usize) -> f64 {
        self.regs[self.roots[k] as usize]
    }

    /// Number of roots.
    pub fn len(&self) -> usize {
        self.roots.len()
    }

    /// Roots `0..n` into `out[..n]`; panics if `out` is shorter (a wrong buffer length is a
    /// programming error, as for generated code).
    pub fn copy_into(&self, out: &mut [f64], n: usize) {
        for (k, o) in out[..n].iter_mut().enumerate() {
            *o = self.get(k);
        }
    }
}
