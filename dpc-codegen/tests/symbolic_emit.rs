//! Emission of a residual with all its Jacobian entries, on the rolling-wheel plant sketched in
//! DESIGN.md section 3: the shape of the generated code (snapshot), CSE across all roots, and
//! the measured expression swell.

use dpc_codegen::symbolic::{ExprId, Func, Graph, Var};
use proc_macro2::TokenStream;
use quote::quote;

const STATES: usize = 5;
const INPUTS: usize = 2;
const PARAMS: [&str; 5] = ["m", "r", "i_r", "i_n", "g"];

/// Variable table: states, their derivatives, inputs, parameters.
fn tokens(v: Var) -> TokenStream {
    let i = v.0 as usize;
    if i < STATES {
        quote!(x[#i])
    } else if i < 2 * STATES {
        let i = i - STATES;
        quote!(dx[#i])
    } else if i < 2 * STATES + INPUTS {
        let i = i - 2 * STATES;
        quote!(u[#i])
    } else {
        let p = quote::format_ident!("{}", PARAMS[i - 2 * STATES - INPUTS]);
        quote!(p.#p)
    }
}

fn name(v: Var) -> String {
    let i = v.0 as usize;
    let states = ["theta", "psi", "dphi", "dtheta", "dpsi"];
    if i < STATES {
        states[i].to_string()
    } else if i < 2 * STATES {
        format!("der({})", states[i - STATES])
    } else if i < 2 * STATES + INPUTS {
        format!("u{}", i - 2 * STATES + 1)
    } else {
        PARAMS[i - 2 * STATES - INPUTS].to_string()
    }
}

/// The wheel residual `F(x', x, u)`.
fn wheel(g: &mut Graph) -> Vec<ExprId> {
    let v = |g: &mut Graph, i: usize| g.var(Var(i as u32));
    let x: Vec<ExprId> = (0..STATES).map(|i| v(g, i)).collect();
    let dx: Vec<ExprId> = (0..STATES).map(|i| v(g, STATES + i)).collect();
    let u: Vec<ExprId> = (0..INPUTS).map(|i| v(g, 2 * STATES + i)).collect();
    let p: Vec<ExprId> = (0..PARAMS.len())
        .map(|i| v(g, 2 * STATES + INPUTS + i))
        .collect();
    let (m, r, i_r, i_n, grav) = (p[0], p[1], p[2], p[3], p[4]);
    let (theta, dphi, dtheta, dpsi) = (x[0], x[2], x[3], x[4]);
    // a1 = i_n + m r r
    let mr = g.mul(m, r);
    let mrr = g.mul(mr, r);
    let a1 = g.add(i_n, mrr);
    let s = g.func(Func::Sin, theta);
    let c = g.func(Func::Cos, theta);
    let s2 = g.powi(s, 2);
    let c2 = g.powi(c, 2);
    let f0 = g.sub(dx[0], dtheta);
    let f1 = g.sub(dx[1], dpsi);
    // (i_r sin^2 + a1 cos^2) dphi' + a1 cos dpsi' - 2 (i_r - a1) sin cos dtheta dphi - u1 sin
    let k1 = g.mul(i_r, s2);
    let k2 = g.mul(a1, c2);
    let k = g.add(k1, k2);
    let t1 = g.mul(k, dx[2]);
    let a1c = g.mul(a1, c);
    let t2 = g.mul(a1c, dx[4]);
    let d = g.sub(i_r, a1);
    let sc = g.mul(s, c);
    let two = g.constant(2.0);
    let w = g.mul(dtheta, dphi);
    let t3 = g.mul(two, d);
    let t3 = g.mul(t3, sc);
    let t3 = g.mul(t3, w);
    let t4 = g.mul(u[0], s);
    let f2 = g.add(t1, t2);
    let f2 = g.sub(f2, t3);
    let f2 = g.sub(f2, t4);
    // a1 dtheta' + (a1 - i_r) sin cos dphi^2 - m g r cos(theta)
    let t5 = g.mul(a1, dx[3]);
    let dphi2 = g.powi(dphi, 2);
    let nd = g.neg(d);
    let t6 = g.mul(nd, sc);
    let t6 = g.mul(t6, dphi2);
    let mgr = g.mul(mr, grav);
    let t7 = g.mul(mgr, c);
    let f3 = g.add(t5, t6);
    let f3 = g.sub(f3, t7);
    // a1 cos dphi' + a1 dpsi' - u2 + hypot/atan2 terms to cover the emitter
    let t8 = g.mul(a1c, dx[2]);
    let t9 = g.mul(a1, dx[4]);
    let h = g.hypot(dphi, dpsi);
    let at = g.atan2(dpsi, dphi);
    let t10 = g.mul(h, at);
    let f4 = g.add(t8, t9);
    let f4 = g.sub(f4, u[1]);
    let f4 = g.add(f4, t10);
    vec![f0, f1, f2, f3, f4]
}

/// Residual roots followed by the nonzero entries of dF/dx' and dF/dx, row-major.
fn roots(g: &mut Graph) -> (Vec<ExprId>, Vec<String>) {
    let f = wheel(g);
    let mut roots = f.clone();
    let mut labels: Vec<String> = (0..f.len()).map(|i| format!("F{i}")).collect();
    for (base, tag) in [(STATES, "dF/dx'"), (0, "dF/dx")] {
        for (i, &fi) in f.iter().enumerate() {
            for j in 0..STATES {
                let d = g.diff(fi, Var((base + j) as u32));
                if !g.is_zero(d) {
                    roots.push(d);
                    labels.push(format!("{tag}[{i}][{j}]"));
                }
            }
        }
    }
    (roots, labels)
}

fn generated(g: &Graph, roots: &[ExprId]) -> String {
    let code = g.emit_rust(roots, &tokens);
    let stmts = &code.statements;
    let outs = code
        .roots
        .iter()
        .enumerate()
        .map(|(k, r)| quote!(out[#k] = #r;));
    let n = roots.len();
    let file: syn::File = syn::parse2(quote! {
        pub struct P { pub m: f64, pub r: f64, pub i_r: f64, pub i_n: f64, pub g: f64 }
        pub fn eval(x: &[f64; 5], dx: &[f64; 5], u: &[f64; 2], p: &P, out: &mut [f64; #n]) {
            #(#stmts)*
            #(#outs)*
        }
    })
    .expect("emitted code parses");
    prettyplease::unparse(&file)
}

#[test]
fn wheel_residual_and_jacobians() {
    let mut g = Graph::new();
    let (roots, labels) = roots(&mut g);
    let f_size = g.size(&roots[..STATES]);
    let all_size = g.size(&roots);
    let sched = g.schedule(&roots);
    let comps = sched.computations(&g);
    let mut uniq = comps.clone();
    uniq.sort();
    uniq.dedup();
    assert_eq!(comps.len(), uniq.len(), "an operation is computed twice");
    // Swell: residual plus 2 Jacobians stays within a small multiple of the residual.
    assert!(
        all_size < 3 * f_size,
        "{all_size} nodes vs residual {f_size}"
    );

    let text = generated(&g, &roots);
    let listing: Vec<String> = labels
        .iter()
        .zip(&roots)
        .map(|(l, &r)| format!("{l} = {}", g.display(r, &name)))
        .collect();
    if let Ok(path) = std::env::var("DPC_SYMBOLIC_DUMP") {
        std::fs::write(path, &text).expect("dump");
    }
    insta::assert_snapshot!("wheel_listing", listing.join("\n"));
    insta::assert_snapshot!("wheel_code", text);
}

/// A chain of `n` coupled pendulums, `x_i' = k (sin(x_{i-1} - x_i) + sin(x_{i+1} - x_i)) + u cos(x_i)`:
/// the full Jacobian (3n nonzeros) stays a small multiple of the residual, and the whole
/// pipeline is fast enough for a proc macro.
#[test]
fn chain_jacobian_swell_is_bounded() {
    let n = 300;
    let mut g = Graph::new();
    let x: Vec<ExprId> = (0..n).map(|i| g.var(Var(i))).collect();
    let dx: Vec<ExprId> = (0..n).map(|i| g.var(Var(n + i))).collect();
    let u = g.var(Var(2 * n));
    let k = g.var(Var(2 * n + 1));
    let started = std::time::Instant::now();
    let mut f = Vec::new();
    for i in 0..n as usize {
        let mut s = g.constant(0.0);
        for j in [i.wrapping_sub(1), i + 1] {
            if j < n as usize {
                let d = g.sub(x[j], x[i]);
                let sd = g.func(Func::Sin, d);
                s = g.add(s, sd);
            }
        }
        let ks = g.mul(k, s);
        let c = g.func(Func::Cos, x[i]);
        let uc = g.mul(u, c);
        let rhs = g.add(ks, uc);
        f.push(g.sub(dx[i], rhs));
    }
    let t_build = started.elapsed();
    let mut roots = f.clone();
    for &fi in &f {
        // sparsity first, as a caller would: only differentiate by variables that occur
        for v in g.vars(fi) {
            if v.0 < n {
                let d = g.diff(fi, v);
                if !g.is_zero(d) {
                    roots.push(d);
                }
            }
        }
    }
    let t_diff = started.elapsed();
    // A dense sweep over all (equation, variable) pairs must be cheap too.
    let mut nonzero = 0;
    for &fi in &f {
        for j in 0..n {
            let d = g.diff(fi, Var(j));
            nonzero += usize::from(!g.is_zero(d));
        }
    }
    assert_eq!(nonzero, 3 * n as usize - 2);
    let t_dense = started.elapsed();
    assert_eq!(roots.len(), n as usize + 3 * n as usize - 2);
    let (f_size, all_size) = (g.size(&f), g.size(&roots));
    assert!(
        all_size < 3 * f_size,
        "{all_size} nodes vs residual {f_size}"
    );
    let t_size = started.elapsed();
    let code = g.emit_rust(&roots, &|v| {
        let i = v.0 as usize;
        quote!(v[#i])
    });
    let comps = g.schedule(&roots).computations(&g).len();
    assert!(comps < 3 * f_size, "{comps} operations");
    assert_eq!(code.roots.len(), roots.len());
    let took = started.elapsed();
    eprintln!("chain n={n}: residual {f_size} nodes, with Jacobian {all_size}, {comps} ops, {took:?} (build {t_build:?}, diff {t_diff:?}, dense {t_dense:?}, size {t_size:?})");
    assert!(took.as_secs_f64() < 5.0, "{took:?}");
}
