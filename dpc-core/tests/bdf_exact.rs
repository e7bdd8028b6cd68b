//! Linear constant-coefficient DAEs of index 1, 2 and 3 with known solutions, and the observed
//! convergence order of the fixed-step mode.

use dpc_core::bdf::{Bdf, FixedBdf, HigherIndexControl, Options};
use dpc_core::linear_solver::{FaerDenseLu, FaerSparseLu, NalgebraLu};
use dpc_core::{ImplicitDae, MatrixSink};

#[derive(Clone, Copy)]
/// Index 1: `y0' = -y0 + y1`, `0 = y1 - sin t`; `y0 = 1.5 e^-t + (sin t - cos t)/2`.
struct Index1;
impl Index1 {
    fn exact(t: f64) -> [f64; 2] {
        [1.5 * (-t).exp() + 0.5 * (t.sin() - t.cos()), t.sin()]
    }
    fn exact_p(t: f64) -> [f64; 2] {
        [-1.5 * (-t).exp() + 0.5 * (t.cos() + t.sin()), t.cos()]
    }
}
impl ImplicitDae for Index1 {
    fn dimension(&self) -> usize {
        2
    }
    fn residual(&self, t: f64, y: &[f64], yp: &[f64], out: &mut [f64]) {
        out[0] = yp[0] + y[0] - y[1];
        out[1] = y[1] - t.sin();
    }
    fn iteration_matrix<S: MatrixSink + ?Sized>(
        &self,
        _: f64,
        _: &[f64],
        _: &[f64],
        c: f64,
        m: &mut S,
    ) {
        m.set(0, 0, 1.0 + c);
        m.set(0, 1, -1.0);
        m.set(1, 1, 1.0);
    }
    fn is_differential(&self, i: usize) -> bool {
        i == 0
    }
    fn iteration_pattern(&self) -> Option<Vec<(usize, usize)>> {
        Some(vec![(0, 0), (0, 1), (1, 1)])
    }
}

/// Index 2: `x' = -x + z`, `0 = x - sin t`; `x = sin t`, `z = cos t + sin t`.
struct Index2;
impl Index2 {
    fn exact(t: f64) -> [f64; 2] {
        [t.sin(), t.cos() + t.sin()]
    }
}
impl ImplicitDae for Index2 {
    fn dimension(&self) -> usize {
        2
    }
    fn residual(&self, t: f64, y: &[f64], yp: &[f64], out: &mut [f64]) {
        out[0] = yp[0] + y[0] - y[1];
        out[1] = y[0] - t.sin();
    }
    fn iteration_matrix<S: MatrixSink + ?Sized>(
        &self,
        _: f64,
        _: &[f64],
        _: &[f64],
        c: f64,
        m: &mut S,
    ) {
        m.set(0, 0, 1.0 + c);
        m.set(0, 1, -1.0);
        m.set(1, 0, 1.0);
    }
    fn is_differential(&self, i: usize) -> bool {
        i == 0
    }
}

/// Index 3: `x1' = x2`, `x2' = z`, `0 = x1 - sin t`; `x1 = sin t`, `x2 = cos t`, `z = -sin t`.
#[derive(Clone, Copy)]
struct Index3;
impl Index3 {
    fn exact(t: f64) -> [f64; 3] {
        [t.sin(), t.cos(), -t.sin()]
    }
}
impl ImplicitDae for Index3 {
    fn dimension(&self) -> usize {
        3
    }
    fn residual(&self, t: f64, y: &[f64], yp: &[f64], out: &mut [f64]) {
        out[0] = yp[0] - y[1];
        out[1] = yp[1] - y[2];
        out[2] = y[0] - t.sin();
    }
    fn iteration_matrix<S: MatrixSink + ?Sized>(
        &self,
        _: f64,
        _: &[f64],
        _: &[f64],
        c: f64,
        m: &mut S,
    ) {
        m.set(0, 0, c);
        m.set(0, 1, -1.0);
        m.set(1, 1, c);
        m.set(1, 2, -1.0);
        m.set(2, 0, 1.0);
    }
    fn is_differential(&self, i: usize) -> bool {
        i < 2
    }
}

fn max_err(a: &[f64], b: &[f64]) -> f64 {
    a.iter()
        .zip(b)
        .map(|(x, y)| (x - y).abs())
        .fold(0.0, f64::max)
}

#[test]
fn index1_variable_step_all_back_ends() {
    let opts = Options::with_tolerances(1e-8, 1e-10);
    let (y0, yp0) = (Index1::exact(0.0), Index1::exact_p(0.0));
    let mut out = [0.0; 2];
    let mut a = Bdf::new(Index1, NalgebraLu::<2>::new(), opts.clone(), 0.0, &y0, &yp0).unwrap();
    let mut b = Bdf::new(Index1, FaerDenseLu::new(2), opts.clone(), 0.0, &y0, &yp0).unwrap();
    let sparse = FaerSparseLu::new(2, &Index1.iteration_pattern().unwrap()).unwrap();
    let mut c = Bdf::new(Index1, sparse, opts, 0.0, &y0, &yp0).unwrap();
    for k in 1..=10 {
        let t = f64::from(k);
        let mut outp = [0.0; 2];
        a.solve_to(t, &mut out, Some(&mut outp)).unwrap();
        let ea = max_err(&out, &Index1::exact(t));
        assert!(ea < 1e-6, "t = {t}: error {ea}");
        let ep = max_err(&outp, &Index1::exact_p(t));
        assert!(ep < 1e-4, "t = {t}: derivative error {ep}");
        let ya = out;
        b.solve_to(t, &mut out, None).unwrap();
        assert!(max_err(&out, &ya) < 1e-12);
        c.solve_to(t, &mut out, None).unwrap();
        assert!(max_err(&out, &ya) < 1e-12);
    }
    let s = a.stats();
    assert!(s.steps > 10 && s.steps < 400, "{s:?}");
    assert!(
        s.factorisations < s.steps,
        "factorisations are reused: {s:?}"
    );
    assert_eq!(s, b.stats());
}

#[test]
fn index2_variable_step() {
    let mut opts = Options::with_tolerances(1e-8, 1e-10);
    opts.index = vec![1, 2];
    let y0 = Index2::exact(0.0);
    let yp0 = [1.0, -1.0 + 1.0];
    let mut bdf = Bdf::new(Index2, NalgebraLu::<2>::new(), opts, 0.0, &y0, &yp0).unwrap();
    let mut out = [0.0; 2];
    for k in 1..=10 {
        let t = f64::from(k);
        bdf.solve_to(t, &mut out, None).unwrap();
        let e = Index2::exact(t);
        assert!((out[0] - e[0]).abs() < 1e-7, "x at {t}: {out:?} vs {e:?}");
        assert!((out[1] - e[1]).abs() < 1e-4, "z at {t}: {out:?} vs {e:?}");
    }
}

#[test]
fn index3_variable_step_both_error_controls() {
    for control in [HigherIndexControl::Exclude, HigherIndexControl::Scale] {
        let mut opts = Options::with_tolerances(1e-8, 1e-10);
        opts.index = vec![1, 2, 3];
        opts.higher_index = control;
        let y0 = Index3::exact(0.0);
        let yp0 = [1.0, 0.0, -1.0];
        let mut bdf = Bdf::new(Index3, NalgebraLu::<3>::new(), opts, 0.0, &y0, &yp0).unwrap();
        let mut out = [0.0; 3];
        for k in 1..=10 {
            let t = f64::from(k);
            bdf.solve_to(t, &mut out, None).unwrap();
            let e = Index3::exact(t);
            assert!(
                (out[0] - e[0]).abs() < 1e-7,
                "{control:?} x1 at {t}: {out:?} vs {e:?}"
            );
            assert!(
                (out[1] - e[1]).abs() < 1e-4,
                "{control:?} x2 at {t}: {out:?} vs {e:?}"
            );
            assert!(
                (out[2] - e[2]).abs() < 1e-2,
                "{control:?} z at {t}: {out:?} vs {e:?}"
            );
        }
    }
}

/// Global error at `t = 1` of fixed-step BDF of order `q` with exact starting values.
fn fixed_error<D: ImplicitDae + Copy, const N: usize>(
    dae: D,
    exact: fn(f64) -> [f64; N],
    q: usize,
    steps: usize,
    component: usize,
) -> f64 {
    let h = 1.0 / steps as f64;
    let hist: Vec<[f64; N]> = (0..q).map(|j| exact(-(j as f64) * h)).collect();
    let refs: Vec<&[f64]> = hist.iter().map(|v| &v[..]).collect();
    let opts = Options::with_tolerances(1e-13, 1e-13);
    let mut bdf = FixedBdf::with_history(dae, FaerDenseLu::new(N), opts, q, h, 0.0, &refs).unwrap();
    for _ in 0..steps {
        bdf.step().unwrap();
    }
    (bdf.y()[component] - exact(bdf.t())[component]).abs()
}

/// Least-squares slope of `log e` against `log h`.
fn slope(hs: &[f64], es: &[f64]) -> f64 {
    let n = hs.len() as f64;
    let (x, y): (Vec<f64>, Vec<f64>) = hs.iter().zip(es).map(|(h, e)| (h.ln(), e.ln())).unzip();
    let (mx, my) = (x.iter().sum::<f64>() / n, y.iter().sum::<f64>() / n);
    let sxy: f64 = x.iter().zip(&y).map(|(a, b)| (a - mx) * (b - my)).sum();
    let sxx: f64 = x.iter().map(|a| (a - mx) * (a - mx)).sum();
    sxy / sxx
}

#[test]
fn fixed_step_convergence_order_matches_bdf_order() {
    for q in 1..=5 {
        let ns = [10usize, 20, 40, 80];
        let hs: Vec<f64> = ns.iter().map(|&n| 1.0 / n as f64).collect();
        let es: Vec<f64> = ns
            .iter()
            .map(|&n| fixed_error(Index1, Index1::exact, q, n, 0))
            .collect();
        let p = slope(&hs, &es);
        println!("index 1, order {q}: errors {es:?}, observed order {p:.2}");
        assert!(
            (p - q as f64).abs() < 0.35,
            "order {q}: observed {p}, errors {es:?}"
        );
    }
}

#[test]
fn fixed_step_consistent_start_keeps_the_order() {
    for q in 2..=5 {
        let ns = [10usize, 20, 40];
        let es: Vec<f64> = ns
            .iter()
            .map(|&n| {
                let h = 1.0 / n as f64;
                let opts = Options::with_tolerances(1e-12, 1e-12);
                let (y0, yp0) = (Index1::exact(0.0), Index1::exact_p(0.0));
                let mut f = FixedBdf::with_consistent_start(
                    Index1,
                    NalgebraLu::<2>::new(),
                    opts,
                    q,
                    h,
                    0.0,
                    &y0,
                    &yp0,
                )
                .unwrap();
                assert!((f.t() - (q - 1) as f64 * h).abs() < 1e-12);
                while f.t() < 1.0 - 0.5 * h {
                    f.step().unwrap();
                }
                (f.y()[0] - Index1::exact(f.t())[0]).abs()
            })
            .collect();
        let hs: Vec<f64> = ns.iter().map(|&n| 1.0 / n as f64).collect();
        let p = slope(&hs, &es);
        println!("consistent start, order {q}: errors {es:?}, observed order {p:.2}");
        assert!(
            (p - q as f64).abs() < 0.35,
            "order {q}: observed {p}, errors {es:?}"
        );
    }
}

#[test]
fn fixed_step_order_on_index3_velocity() {
    for q in 1..=4 {
        let ns = [20usize, 40, 80];
        let hs: Vec<f64> = ns.iter().map(|&n| 1.0 / n as f64).collect();
        let es: Vec<f64> = ns
            .iter()
            .map(|&n| fixed_error(Index3, Index3::exact, q, n, 1))
            .collect();
        let p = slope(&hs, &es);
        println!(
            "index 3 (x2, an index-2 component), order {q}: errors {es:?}, observed order {p:.2}"
        );
        assert!(
            (p - q as f64).abs() < 0.35,
            "order {q}: observed {p}, errors {es:?}"
        );
    }
}

#[test]
fn fixed_step_from_inconsistent_values() {
    // z(0) and x2(0) are wrong; the first implicit Euler step projects onto the constraint.
    let y0 = [0.0, 5.0, 7.0];
    let mut bdf = FixedBdf::new(
        Index3,
        NalgebraLu::<3>::new(),
        Options::default(),
        2,
        1e-3,
        0.0,
        &y0,
    )
    .unwrap();
    for _ in 0..1000 {
        bdf.step().unwrap();
    }
    let e = Index3::exact(bdf.t());
    assert!((bdf.y()[0] - e[0]).abs() < 1e-9);
    assert!((bdf.y()[1] - e[1]).abs() < 1e-3, "{:?} vs {e:?}", bdf.y());
}

#[test]
fn reinit_and_reset_restart_cleanly() {
    let opts = Options::with_tolerances(1e-8, 1e-10);
    let (y0, yp0) = (Index1::exact(0.0), Index1::exact_p(0.0));
    let mut bdf = Bdf::new(Index1, NalgebraLu::<2>::new(), opts, 0.0, &y0, &yp0).unwrap();
    let mut out = [0.0; 2];
    bdf.solve_to(2.0, &mut out, None).unwrap();
    // Restart at t = 5 from the exact solution there.
    bdf.reinit(5.0, &Index1::exact(5.0), &Index1::exact_p(5.0))
        .unwrap();
    bdf.solve_to(7.0, &mut out, None).unwrap();
    assert!(max_err(&out, &Index1::exact(7.0)) < 1e-6);

    let mut f = FixedBdf::new(
        Index3,
        NalgebraLu::<3>::new(),
        Options::default(),
        2,
        1e-3,
        0.0,
        &[0.0, 5.0, 7.0],
    )
    .unwrap();
    for _ in 0..10 {
        f.step().unwrap();
    }
    f.reset(1.0, &Index3::exact(1.0)).unwrap();
    for _ in 0..1000 {
        f.step().unwrap();
    }
    assert!((f.t() - 2.0).abs() < 1e-9);
    assert!(
        (f.y()[1] - Index3::exact(2.0)[1]).abs() < 1e-4,
        "{:?}",
        f.y()
    );
}

#[test]
fn reinit_on_a_smooth_solution_keeps_the_step_its_curvature_allows() {
    // Restarted on the solution itself (`y'` continuous), the first step comes from the
    // curvature of the steps before: fewer steps to `t = 3` than a new integrator from the same
    // point, whose default first step `h |y'| <= 1/2` takes steps to grow out of at tight
    // tolerances (measured: 70 against 101 at rtol 1e-10; at 1e-8 50 against 55).
    let opts = Options::with_tolerances(1e-10, 1e-12);
    let (y0, yp0) = (Index1::exact(0.0), Index1::exact_p(0.0));
    let mut bdf = Bdf::new(Index1, NalgebraLu::<2>::new(), opts.clone(), 0.0, &y0, &yp0).unwrap();
    let mut out = [0.0; 2];
    bdf.solve_to(2.0, &mut out, None).unwrap();
    let (y, yp) = (bdf.y().to_vec(), bdf.yp().to_vec());
    let before = bdf.stats().steps;
    bdf.reinit(bdf.t(), &y, &yp).unwrap();
    let t = bdf.t();
    bdf.solve_to(3.0, &mut out, None).unwrap();
    let restarted = bdf.stats().steps - before;
    let mut fresh = Bdf::new(Index1, NalgebraLu::<2>::new(), opts, t, &y, &yp).unwrap();
    fresh.solve_to(3.0, &mut out, None).unwrap();
    let new = fresh.stats().steps;
    println!("to t = 3: {restarted} steps restarted, {new} from a new start");
    assert!(restarted + 10 <= new, "{restarted} against {new}");
}

#[test]
fn stop_time_is_honoured_and_cleared() {
    let opts = Options::with_tolerances(1e-8, 1e-10);
    let (y0, yp0) = (Index1::exact(0.0), Index1::exact_p(0.0));
    let mut bdf = Bdf::new(Index1, NalgebraLu::<2>::new(), opts, 0.0, &y0, &yp0).unwrap();
    bdf.set_stop_time(1.5).unwrap();
    let mut out = [0.0; 2];
    let t = bdf.solve_to(4.0, &mut out, None).unwrap();
    assert_eq!(t, 1.5);
    assert_eq!(bdf.t(), 1.5);
    assert!(max_err(&out, &Index1::exact(1.5)) < 1e-6);
    let t = bdf.solve_to(4.0, &mut out, None).unwrap();
    assert_eq!(t, 4.0);
    assert!(max_err(&out, &Index1::exact(4.0)) < 1e-6);
}
