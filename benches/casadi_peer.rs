//! The generated wheel code against CasADi's generated C (compiled with `-O2` by the build
//! script), side by side in one binary, on the same random points, interleaved.
//!
//! Kernels (what one Newton iteration of an implicit integrator needs):
//!
//! * the wheel's residual and its 5x5 iteration matrix `dF/dx + c dF/dx'`;
//! * the tracking DAE's residual and its 7x7 iteration matrix (`W = s + 5` on both outputs);
//! * the wheel's residual alone.
//!
//! dpc writes the matrix into a fixed-size nalgebra matrix (what its LU factorises); CasADi
//! writes its structural non-zeros into a compressed array (its natural output, the cheaper
//! one). Two dpc variants: the fused `residual_and_iteration_matrix` into a matrix zeroed once
//! (what the controller's Newton loop does), and the separate `residual` + `iteration_matrix`
//! with the matrix zeroed per call.
//!
//! The table printed first is the comparison: per round, every variant runs over all points
//! in a rotating order, and the medians over the rounds are reported with the median of the
//! per-round ratios. Criterion's own runs follow.
//!
//! ```text
//! bash bench/casadi/run.sh     # pip install casadi into a venv, generate the C, run this
//! ```

use criterion::{criterion_group, Criterion};
use dpc::core::model::DaeModel;
use dpc::nalgebra::SMatrix;
use dpc_models::{Wheel, WheelTracking};
use std::hint::black_box;
use std::os::raw::c_int;
use std::time::Instant;

type CasadiInt = i64;

extern "C" {
    fn wheel_res(
        arg: *const *const f64,
        res: *const *mut f64,
        iw: *mut CasadiInt,
        w: *mut f64,
        mem: c_int,
    ) -> c_int;
    fn wheel_res_iter(
        arg: *const *const f64,
        res: *const *mut f64,
        iw: *mut CasadiInt,
        w: *mut f64,
        mem: c_int,
    ) -> c_int;
    fn tracking_res_iter(
        arg: *const *const f64,
        res: *const *mut f64,
        iw: *mut CasadiInt,
        w: *mut f64,
        mem: c_int,
    ) -> c_int;
    fn wheel_res_iter_sparsity_out(i: CasadiInt) -> *const CasadiInt;
    fn tracking_res_iter_sparsity_out(i: CasadiInt) -> *const CasadiInt;
}

/// One evaluation point: states, their derivatives, the wheel's inputs (the tracking DAE's
/// algebraic unknowns), the tracking inputs `w` and the iteration coefficient `c`.
#[derive(Clone, Copy)]
struct Point {
    x: [f64; 5],
    xdot: [f64; 5],
    u: [f64; 2],
    w: [f64; 2],
    c: f64,
}

/// Deterministic points about the wheel's motion (xorshift, so no dependency).
fn points(n: usize) -> Vec<Point> {
    let mut state = 0x9e37_79b9_7f4a_7c15_u64;
    let mut next = move |lo: f64, hi: f64| {
        state ^= state << 13;
        state ^= state >> 7;
        state ^= state << 17;
        lo + (hi - lo) * ((state >> 11) as f64 / (1u64 << 53) as f64)
    };
    (0..n)
        .map(|_| Point {
            x: [
                next(1.2, 1.9),
                next(-10.0, 0.0),
                next(-1.0, 1.0),
                next(-1.0, 1.0),
                next(-7.0, -5.0),
            ],
            xdot: [
                next(-1.0, 1.0),
                next(-7.0, -5.0),
                next(-1.0, 1.0),
                next(-1.0, 1.0),
                next(-1.0, 1.0),
            ],
            u: [next(-2.0, 2.0), next(-2.0, 2.0)],
            w: [next(5.0, 10.0), next(-60.0, 0.0)],
            c: next(10.0, 1e4),
        })
        .collect()
}

/// CasADi's output buffers: the residual and the compressed matrix.
struct CasadiOut<const NE: usize, const NNZ: usize> {
    residual: [f64; NE],
    matrix: [f64; NNZ],
}

fn casadi_wheel(p: &Point, out: &mut CasadiOut<5, 16>) {
    let c = [p.c];
    let arg = [p.x.as_ptr(), p.xdot.as_ptr(), p.u.as_ptr(), c.as_ptr()];
    let res = [out.residual.as_mut_ptr(), out.matrix.as_mut_ptr()];
    // SAFETY: the argument and result arrays have the sizes the generated function reads and
    // writes (5, 5, 2, 1 in; 5 and the 16 structural non-zeros out); it needs no work arrays.
    unsafe {
        wheel_res_iter(
            arg.as_ptr(),
            res.as_ptr(),
            std::ptr::null_mut(),
            std::ptr::null_mut(),
            0,
        );
    }
}

fn casadi_tracking(p: &Point, out: &mut CasadiOut<7, 22>) {
    let c = [p.c];
    let arg = [
        p.x.as_ptr(),
        p.xdot.as_ptr(),
        p.u.as_ptr(),
        p.w.as_ptr(),
        c.as_ptr(),
    ];
    let res = [out.residual.as_mut_ptr(), out.matrix.as_mut_ptr()];
    // SAFETY: as in `casadi_wheel`, with 5, 5, 2, 2, 1 in and 7 and 22 out.
    unsafe {
        tracking_res_iter(
            arg.as_ptr(),
            res.as_ptr(),
            std::ptr::null_mut(),
            std::ptr::null_mut(),
            0,
        );
    }
}

fn casadi_residual(p: &Point, out: &mut [f64; 5]) {
    let arg = [p.x.as_ptr(), p.xdot.as_ptr(), p.u.as_ptr()];
    let res = [out.as_mut_ptr()];
    // SAFETY: 5, 5, 2 in, 5 out, no work arrays.
    unsafe {
        wheel_res(
            arg.as_ptr(),
            res.as_ptr(),
            std::ptr::null_mut(),
            std::ptr::null_mut(),
            0,
        );
    }
}

/// dpc's two kernels for one model: separate routines (matrix zeroed per call) and fused.
struct Dense<const N: usize> {
    residual: [f64; N],
    matrix: SMatrix<f64, N, N>,
}

impl<const N: usize> Dense<N> {
    fn new() -> Self {
        Self {
            residual: [0.0; N],
            matrix: SMatrix::zeros(),
        }
    }
}

fn dpc_wheel_separate(m: &Wheel, p: &Point, out: &mut Dense<5>) {
    out.matrix.fill(0.0);
    m.residual(0.0, &p.x, &p.xdot, &[], &p.u, &mut out.residual);
    m.iteration_matrix(0.0, &p.x, &p.xdot, &[], &p.u, p.c, &mut out.matrix);
}

fn dpc_wheel_fused(m: &Wheel, p: &Point, out: &mut Dense<5>) {
    m.residual_and_iteration_matrix(
        0.0,
        &p.x,
        &p.xdot,
        &[],
        &p.u,
        p.c,
        &mut out.residual,
        &mut out.matrix,
    );
}

fn dpc_tracking_separate(m: &WheelTracking, p: &Point, out: &mut Dense<7>) {
    out.matrix.fill(0.0);
    m.residual(0.0, &p.x, &p.xdot, &p.u, &p.w, &mut out.residual);
    m.iteration_matrix(0.0, &p.x, &p.xdot, &p.u, &p.w, p.c, &mut out.matrix);
}

fn dpc_tracking_fused(m: &WheelTracking, p: &Point, out: &mut Dense<7>) {
    m.residual_and_iteration_matrix(
        0.0,
        &p.x,
        &p.xdot,
        &p.u,
        &p.w,
        p.c,
        &mut out.residual,
        &mut out.matrix,
    );
}

/// Largest difference between CasADi's compressed matrix and dpc's dense one (entries
/// outside CasADi's pattern must be zero in dpc's), relative to the largest entry.
fn compare<const N: usize>(
    sparsity: *const CasadiInt,
    casadi: &[f64],
    dense: &SMatrix<f64, N, N>,
) -> f64 {
    // SAFETY: CasADi's sparsity is [nrow, ncol, colind[ncol + 1], row[nnz]] in static storage.
    let (colind, row) = unsafe {
        let ncol = *sparsity.add(1) as usize;
        let colind = std::slice::from_raw_parts(sparsity.add(2), ncol + 1);
        let nnz = colind[ncol] as usize;
        (
            colind,
            std::slice::from_raw_parts(sparsity.add(3 + ncol), nnz),
        )
    };
    assert_eq!(casadi.len(), row.len(), "CasADi's pattern size");
    let mut seen = SMatrix::<f64, N, N>::zeros();
    let mut worst = 0.0_f64;
    for j in 0..N {
        for k in colind[j] as usize..colind[j + 1] as usize {
            let i = row[k] as usize;
            seen[(i, j)] = 1.0;
            worst = worst.max((casadi[k] - dense[(i, j)]).abs());
        }
    }
    for j in 0..N {
        for i in 0..N {
            if seen[(i, j)] == 0.0 {
                worst = worst.max(dense[(i, j)].abs());
            }
        }
    }
    worst / dense.amax().max(1.0)
}

fn check_agreement(points: &[Point]) {
    let (wheel, tracking) = (Wheel::default(), WheelTracking::default());
    let mut worst = 0.0_f64;
    for p in points {
        let (mut cw, mut ct) = (
            CasadiOut::<5, 16> {
                residual: [0.0; 5],
                matrix: [0.0; 16],
            },
            CasadiOut::<7, 22> {
                residual: [0.0; 7],
                matrix: [0.0; 22],
            },
        );
        let (mut dw, mut dt, mut dws, mut dts) = (
            Dense::<5>::new(),
            Dense::<7>::new(),
            Dense::<5>::new(),
            Dense::<7>::new(),
        );
        casadi_wheel(p, &mut cw);
        casadi_tracking(p, &mut ct);
        dpc_wheel_fused(&wheel, p, &mut dw);
        dpc_tracking_fused(&tracking, p, &mut dt);
        dpc_wheel_separate(&wheel, p, &mut dws);
        dpc_tracking_separate(&tracking, p, &mut dts);
        // SAFETY: static sparsity arrays of the generated functions.
        let (sw, st) = unsafe {
            (
                wheel_res_iter_sparsity_out(1),
                tracking_res_iter_sparsity_out(1),
            )
        };
        worst = worst.max(compare(sw, &cw.matrix, &dw.matrix));
        worst = worst.max(compare(st, &ct.matrix, &dt.matrix));
        assert_eq!(dw.matrix, dws.matrix, "fused and separate wheel matrices");
        assert_eq!(
            dt.matrix, dts.matrix,
            "fused and separate tracking matrices"
        );
        let scale = |r: &[f64]| r.iter().fold(1.0_f64, |m, v| m.max(v.abs()));
        for (a, b) in cw.residual.iter().zip(&dw.residual) {
            worst = worst.max((a - b).abs() / scale(&dw.residual));
        }
        for (a, b) in ct.residual.iter().zip(&dt.residual) {
            worst = worst.max((a - b).abs() / scale(&dt.residual));
        }
        assert_eq!(dw.residual, dws.residual);
    }
    println!("dpc and CasADi agree to {worst:.1e} (relative to the largest entry)");
    assert!(worst < 1e-12, "dpc and CasADi disagree: {worst:e}");
}

/// Interleaved timing: `rounds` rounds, each running every kernel over all points (in an
/// order that rotates per round); per kernel the median time per call, and the median over
/// the rounds of the ratio to the kernel named `peer` of its group.
fn interleaved(points: &[Point], rounds: usize) {
    let (wheel, tracking) = (Wheel::default(), WheelTracking::default());
    let mut cw = CasadiOut::<5, 16> {
        residual: [0.0; 5],
        matrix: [0.0; 16],
    };
    let mut ct = CasadiOut::<7, 22> {
        residual: [0.0; 7],
        matrix: [0.0; 22],
    };
    let (mut dw, mut dt) = (Dense::<5>::new(), Dense::<7>::new());
    let (mut dws, mut dts) = (Dense::<5>::new(), Dense::<7>::new());
    let mut r5 = [0.0; 5];
    let mut rc = [0.0; 5];
    type Kernel<'a> = Box<dyn FnMut(&Point) + 'a>;
    // (group, name, kernel); the first of each group is CasADi.
    let mut kernels: Vec<(&str, &str, Kernel)> = vec![
        (
            "wheel: residual + 5x5 iteration matrix",
            "CasADi -O2",
            Box::new(|p| casadi_wheel(p, &mut cw)),
        ),
        (
            "wheel: residual + 5x5 iteration matrix",
            "dpc fused",
            Box::new(|p| dpc_wheel_fused(&wheel, p, &mut dw)),
        ),
        (
            "wheel: residual + 5x5 iteration matrix",
            "dpc residual + iteration_matrix",
            Box::new(|p| dpc_wheel_separate(&wheel, p, &mut dws)),
        ),
        (
            "tracking DAE: residual + 7x7 iteration matrix",
            "CasADi -O2",
            Box::new(|p| casadi_tracking(p, &mut ct)),
        ),
        (
            "tracking DAE: residual + 7x7 iteration matrix",
            "dpc fused",
            Box::new(|p| dpc_tracking_fused(&tracking, p, &mut dt)),
        ),
        (
            "tracking DAE: residual + 7x7 iteration matrix",
            "dpc residual + iteration_matrix",
            Box::new(|p| dpc_tracking_separate(&tracking, p, &mut dts)),
        ),
        (
            "wheel residual",
            "CasADi -O2",
            Box::new(|p| {
                casadi_residual(p, &mut rc);
                black_box(&rc);
            }),
        ),
        (
            "wheel residual",
            "dpc",
            Box::new(|p| {
                wheel.residual(0.0, &p.x, &p.xdot, &[], &p.u, &mut r5);
                black_box(&r5);
            }),
        ),
    ];
    let k = kernels.len();
    let mut times = vec![Vec::with_capacity(rounds); k];
    for round in 0..rounds {
        for s in 0..k {
            let i = (s + round) % k;
            let kernel = &mut kernels[i].2;
            let start = Instant::now();
            for p in points {
                kernel(black_box(p));
            }
            times[i].push(start.elapsed().as_secs_f64() * 1e9 / points.len() as f64);
        }
    }
    let median = |v: &mut Vec<f64>| {
        v.sort_by(f64::total_cmp);
        v[v.len() / 2]
    };
    println!(
        "\n| kernel | implementation | median ns/call | / CasADi (median of per-round ratios) |"
    );
    println!("|---|---|---|---|");
    let mut peer = 0;
    for i in 0..k {
        if kernels[i].1.starts_with("CasADi") {
            peer = i;
        }
        let mut ratios: Vec<f64> = times[i]
            .iter()
            .zip(&times[peer])
            .map(|(a, b)| a / b)
            .collect();
        let ratio = median(&mut ratios);
        let t = median(&mut times[i].clone());
        println!(
            "| {} | {} | {t:.1} | {ratio:.2} |",
            kernels[i].0, kernels[i].1
        );
    }
    println!();
}

/// One criterion group: CasADi's kernel beside dpc's fused one on the same points.
fn group<const N: usize, const NNZ: usize>(
    c: &mut Criterion,
    name: &str,
    points: &[Point],
    casadi: impl Fn(&Point, &mut CasadiOut<N, NNZ>),
    dpc: impl Fn(&Point, &mut Dense<N>),
) {
    let mut g = c.benchmark_group(name);
    g.bench_function("CasADi -O2", |b| {
        let mut out = CasadiOut::<N, NNZ> {
            residual: [0.0; N],
            matrix: [0.0; NNZ],
        };
        b.iter(|| points.iter().for_each(|p| casadi(black_box(p), &mut out)))
    });
    g.bench_function("dpc fused", |b| {
        let mut out = Dense::<N>::new();
        b.iter(|| points.iter().for_each(|p| dpc(black_box(p), &mut out)))
    });
    g.finish();
}

fn bench(c: &mut Criterion) {
    let points = points(256);
    let (wheel, tracking) = (Wheel::default(), WheelTracking::default());
    group(
        c,
        "wheel residual + iteration matrix (256 points)",
        &points,
        casadi_wheel,
        |p, out| dpc_wheel_fused(&wheel, p, out),
    );
    group(
        c,
        "tracking DAE residual + iteration matrix (256 points)",
        &points,
        casadi_tracking,
        |p, out| dpc_tracking_fused(&tracking, p, out),
    );
}

criterion_group!(benches, bench);

fn main() {
    let points = points(256);
    check_agreement(&points);
    let rounds = std::env::var("DPC_PEER_ROUNDS")
        .ok()
        .and_then(|r| r.parse().ok())
        .unwrap_or(2000);
    interleaved(&points, rounds);
    benches();
    Criterion::default().configure_from_args().final_summary();
}
