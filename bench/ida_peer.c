/*
 * Peer comparison driver: SUNDIALS IDA (dense direct solver, analytic Jacobian) on the same
 * problems, tolerances and error-control choices as dpc-core's BDF work-precision table
 * (dpc-core/examples/work_precision.rs). Written for this project; run through
 * bench/ida_peer.sh.
 *
 * Robertson (index 1) to t = 1e11, rtol = 1e-k, atol = [1e-8, 1e-14, 1e-6] * rtol / 1e-4,
 * compared with the Test Set for IVP Solvers reference at t = 1e11.
 * Pendulum (index 3, Cartesian, g = 9.81, L = 1, theta0 = 1 rad at rest) to t = 3 with
 * rtol = atol = 1e-k and u, v, lambda excluded from the error test (IDASetId + suppressalg,
 * the same choice as dpc-core's default HigherIndexControl::Exclude), compared with RK4 on the
 * angle ODE.
 * Transistor amplifier (index 1, Test Set transamp.F) to t = 0.2 with rtol = atol = 1e-k, all
 * eight components scored against the Test Set's reference (PSIDE at 1e-14).
 */
#include <math.h>
#include <stdio.h>
#include <time.h>

#include <ida/ida.h>
#include <nvector/nvector_serial.h>
#include <sunlinsol/sunlinsol_dense.h>
#include <sunmatrix/sunmatrix_dense.h>

#define G 9.81
#define REPS 20

static int rober_res(realtype t, N_Vector yy, N_Vector yp, N_Vector rr, void *ud) {
  realtype *y = N_VGetArrayPointer(yy), *p = N_VGetArrayPointer(yp), *r = N_VGetArrayPointer(rr);
  (void)t; (void)ud;
  r[0] = p[0] + 0.04 * y[0] - 1e4 * y[1] * y[2];
  r[1] = p[1] - 0.04 * y[0] + 1e4 * y[1] * y[2] + 3e7 * y[1] * y[1];
  r[2] = y[0] + y[1] + y[2] - 1.0;
  return 0;
}

static int rober_jac(realtype t, realtype cj, N_Vector yy, N_Vector yp, N_Vector rr, SUNMatrix J,
                     void *ud, N_Vector t1, N_Vector t2, N_Vector t3) {
  realtype *y = N_VGetArrayPointer(yy);
  (void)t; (void)yp; (void)rr; (void)ud; (void)t1; (void)t2; (void)t3;
  SM_ELEMENT_D(J, 0, 0) = 0.04 + cj;
  SM_ELEMENT_D(J, 0, 1) = -1e4 * y[2];
  SM_ELEMENT_D(J, 0, 2) = -1e4 * y[1];
  SM_ELEMENT_D(J, 1, 0) = -0.04;
  SM_ELEMENT_D(J, 1, 1) = 1e4 * y[2] + 6e7 * y[1] + cj;
  SM_ELEMENT_D(J, 1, 2) = 1e4 * y[1];
  SM_ELEMENT_D(J, 2, 0) = 1.0;
  SM_ELEMENT_D(J, 2, 1) = 1.0;
  SM_ELEMENT_D(J, 2, 2) = 1.0;
  return 0;
}

static int pend_res(realtype t, N_Vector yy, N_Vector yp, N_Vector rr, void *ud) {
  realtype *s = N_VGetArrayPointer(yy), *p = N_VGetArrayPointer(yp), *r = N_VGetArrayPointer(rr);
  (void)t; (void)ud;
  r[0] = p[0] - s[2];
  r[1] = p[1] - s[3];
  r[2] = p[2] + s[4] * s[0];
  r[3] = p[3] + s[4] * s[1] + G;
  r[4] = s[0] * s[0] + s[1] * s[1] - 1.0;
  return 0;
}

static int pend_jac(realtype t, realtype cj, N_Vector yy, N_Vector yp, N_Vector rr, SUNMatrix J,
                    void *ud, N_Vector t1, N_Vector t2, N_Vector t3) {
  realtype *s = N_VGetArrayPointer(yy);
  (void)t; (void)yp; (void)rr; (void)ud; (void)t1; (void)t2; (void)t3;
  SUNMatZero(J);
  SM_ELEMENT_D(J, 0, 0) = cj;
  SM_ELEMENT_D(J, 0, 2) = -1.0;
  SM_ELEMENT_D(J, 1, 1) = cj;
  SM_ELEMENT_D(J, 1, 3) = -1.0;
  SM_ELEMENT_D(J, 2, 2) = cj;
  SM_ELEMENT_D(J, 2, 0) = s[4];
  SM_ELEMENT_D(J, 2, 4) = s[0];
  SM_ELEMENT_D(J, 3, 3) = cj;
  SM_ELEMENT_D(J, 3, 1) = s[4];
  SM_ELEMENT_D(J, 3, 4) = s[1];
  SM_ELEMENT_D(J, 4, 0) = 2.0 * s[0];
  SM_ELEMENT_D(J, 4, 1) = 2.0 * s[1];
  return 0;
}


/* Transistor amplifier (Test Set transamp.F): F = M y' - phi(t, y), index 1, singular
 * non-diagonal M; the same equations as dpc-core/tests/common/testset_index1.rs. */
#define UB 6.0
#define UF 0.026
#define ALPHA 0.99
#define BETA 1e-6
#define R0 1000.0
#define RR 9000.0
static const double CAP[5] = {1e-6, 2e-6, 3e-6, 4e-6, 5e-6};
static const int MASS_R[14] = {0, 0, 1, 1, 2, 3, 3, 4, 4, 5, 6, 6, 7, 7};
static const int MASS_C[14] = {0, 1, 0, 1, 2, 3, 4, 3, 4, 5, 6, 7, 6, 7};
static double mass_v(int k) {
  static const int cap[14] = {0, 0, 0, 0, 1, 2, 2, 2, 2, 3, 4, 4, 4, 4};
  static const double sign[14] = {-1, 1, 1, -1, -1, -1, 1, 1, -1, -1, -1, 1, 1, -1};
  return sign[k] * CAP[cap[k]];
}

static int amp_res(realtype t, N_Vector yy, N_Vector yp, N_Vector rr, void *ud) {
  realtype *y = N_VGetArrayPointer(yy), *p = N_VGetArrayPointer(yp), *r = N_VGetArrayPointer(rr);
  (void)ud;
  double ue = 0.1 * sin(200.0 * M_PI * t);
  double g1 = BETA * (exp((y[1] - y[2]) / UF) - 1.0), g2 = BETA * (exp((y[4] - y[5]) / UF) - 1.0);
  r[0] = -((y[0] - ue) / R0);
  r[1] = -(y[1] / RR + (y[1] - UB) / RR + (1.0 - ALPHA) * g1);
  r[2] = -(y[2] / RR - g1);
  r[3] = -((y[3] - UB) / RR + ALPHA * g1);
  r[4] = -(y[4] / RR + (y[4] - UB) / RR + (1.0 - ALPHA) * g2);
  r[5] = -(y[5] / RR - g2);
  r[6] = -((y[6] - UB) / RR + ALPHA * g2);
  r[7] = -(y[7] / RR);
  for (int k = 0; k < 14; k++) r[MASS_R[k]] += mass_v(k) * p[MASS_C[k]];
  return 0;
}

static int amp_jac(realtype t, realtype cj, N_Vector yy, N_Vector yp, N_Vector rr, SUNMatrix J,
                   void *ud, N_Vector t1, N_Vector t2, N_Vector t3) {
  realtype *y = N_VGetArrayPointer(yy);
  (void)t; (void)yp; (void)rr; (void)ud; (void)t1; (void)t2; (void)t3;
  double d1 = BETA * exp((y[1] - y[2]) / UF) / UF, d2 = BETA * exp((y[4] - y[5]) / UF) / UF;
  SUNMatZero(J);
  for (int k = 0; k < 14; k++) SM_ELEMENT_D(J, MASS_R[k], MASS_C[k]) += cj * mass_v(k);
  SM_ELEMENT_D(J, 0, 0) -= 1.0 / R0;
  SM_ELEMENT_D(J, 1, 1) -= 2.0 / RR + (1.0 - ALPHA) * d1;
  SM_ELEMENT_D(J, 1, 2) -= -(1.0 - ALPHA) * d1;
  SM_ELEMENT_D(J, 2, 1) -= -d1;
  SM_ELEMENT_D(J, 2, 2) -= 1.0 / RR + d1;
  SM_ELEMENT_D(J, 3, 1) -= ALPHA * d1;
  SM_ELEMENT_D(J, 3, 2) -= -ALPHA * d1;
  SM_ELEMENT_D(J, 3, 3) -= 1.0 / RR;
  SM_ELEMENT_D(J, 4, 4) -= 2.0 / RR + (1.0 - ALPHA) * d2;
  SM_ELEMENT_D(J, 4, 5) -= -(1.0 - ALPHA) * d2;
  SM_ELEMENT_D(J, 5, 4) -= -d2;
  SM_ELEMENT_D(J, 5, 5) -= 1.0 / RR + d2;
  SM_ELEMENT_D(J, 6, 4) -= ALPHA * d2;
  SM_ELEMENT_D(J, 6, 5) -= -ALPHA * d2;
  SM_ELEMENT_D(J, 6, 6) -= 1.0 / RR;
  SM_ELEMENT_D(J, 7, 7) -= 1.0 / RR;
  return 0;
}

static void pend_state(double th, double om, double *s) {
  s[0] = sin(th);
  s[1] = -cos(th);
  s[2] = cos(th) * om;
  s[3] = sin(th) * om;
  s[4] = s[2] * s[2] + s[3] * s[3] - G * s[1];
}

/* Angle ODE theta'' = -g sin(theta) with classical RK4, 2^17 steps per time unit. */
static void pend_reference(double th0, double tend, double *s) {
  long n = (long)ceil(tend * 131072.0);
  double h = tend / n, th = th0, om = 0.0;
  for (long i = 0; i < n; i++) {
    double a1 = om, b1 = -G * sin(th);
    double a2 = om + 0.5 * h * b1, b2 = -G * sin(th + 0.5 * h * a1);
    double a3 = om + 0.5 * h * b2, b3 = -G * sin(th + 0.5 * h * a2);
    double a4 = om + h * b3, b4 = -G * sin(th + h * a3);
    th += h / 6.0 * (a1 + 2 * a2 + 2 * a3 + a4);
    om += h / 6.0 * (b1 + 2 * b2 + 2 * b3 + b4);
  }
  pend_state(th, om, s);
}

static double digits(const double *y, const double *ref, int from, int to) {
  double m = 0.0;
  for (int i = from; i < to; i++) {
    double e = fabs(y[i] - ref[i]) / fabs(ref[i]);
    if (e > m) m = e;
  }
  return -log10(m);
}

static double now(void) {
  struct timespec ts;
  clock_gettime(CLOCK_MONOTONIC, &ts);
  return ts.tv_sec + 1e-9 * ts.tv_nsec;
}

/* One solve (problem 0 Robertson, 1 pendulum, 2 transistor amplifier); returns steps (negative
 * on failure), writes the final state into out and the error-test failures into netf. */
static long solve(SUNContext ctx, int problem, double rtol, double *out, long *netf) {
  int pendulum = problem == 1;
  int n = problem == 2 ? 8 : pendulum ? 5 : 3;
  double tend = problem == 2 ? 0.2 : pendulum ? 3.0 : 1e11;
  N_Vector yy = N_VNew_Serial(n, ctx), yp = N_VNew_Serial(n, ctx), atol = N_VNew_Serial(n, ctx);
  realtype *y = N_VGetArrayPointer(yy), *p = N_VGetArrayPointer(yp), *a = N_VGetArrayPointer(atol);
  void *mem = IDACreate(ctx);
  if (problem == 2) {
    double half = UB / 2.0;
    double y0[8] = {0.0, half, half, UB, half, half, UB, 0.0};
    double p0[8] = {51.338775, 51.338775, -half / (CAP[1] * RR), -24.9757667, -24.9757667,
                    -half / (CAP[3] * RR), -10.00564453, -10.00564453};
    for (int i = 0; i < n; i++) { y[i] = y0[i]; p[i] = p0[i]; a[i] = rtol; }
    IDAInit(mem, amp_res, 0.0, yy, yp);
  } else if (pendulum) {
    pend_state(1.0, 0.0, y);
    p[0] = 0.0; p[1] = 0.0; p[2] = -y[4] * y[0]; p[3] = -y[4] * y[1] - G; p[4] = 0.0;
    for (int i = 0; i < n; i++) a[i] = rtol;
    IDAInit(mem, pend_res, 0.0, yy, yp);
  } else {
    y[0] = 1.0; y[1] = 0.0; y[2] = 0.0;
    p[0] = -0.04; p[1] = 0.04; p[2] = 0.0;
    double s = rtol / 1e-4;
    a[0] = 1e-8 * s; a[1] = 1e-14 * s; a[2] = 1e-6 * s;
    IDAInit(mem, rober_res, 0.0, yy, yp);
  }
  IDASVtolerances(mem, rtol, atol);
  SUNMatrix A = SUNDenseMatrix(n, n, ctx);
  SUNLinearSolver LS = SUNLinSol_Dense(yy, A, ctx);
  IDASetLinearSolver(mem, LS, A);
  IDASetJacFn(mem, problem == 2 ? amp_jac : pendulum ? pend_jac : rober_jac);
  IDASetMaxNumSteps(mem, 1000000);
  IDASetStopTime(mem, tend);
  if (pendulum) {
    N_Vector id = N_VNew_Serial(n, ctx);
    realtype *d = N_VGetArrayPointer(id);
    d[0] = 1.0; d[1] = 1.0; d[2] = 0.0; d[3] = 0.0; d[4] = 0.0;
    IDASetId(mem, id);
    IDASetSuppressAlg(mem, SUNTRUE);
    N_VDestroy(id);
  }
  realtype tret;
  int flag = IDASolve(mem, tend, &tret, yy, yp, IDA_NORMAL);
  long nst = -1;
  IDAGetNumSteps(mem, &nst);
  IDAGetNumErrTestFails(mem, netf);
  if (flag < 0) nst = -nst;
  for (int i = 0; i < n; i++) out[i] = y[i];
  IDAFree(&mem);
  SUNLinSolFree(LS);
  SUNMatDestroy(A);
  N_VDestroy(yy);
  N_VDestroy(yp);
  N_VDestroy(atol);
  return nst;
}

int main(void) {
  SUNContext ctx;
  SUNContext_Create(NULL, &ctx);
  const double rober_ref[3] = {0.2083340149701255e-7, 0.8333360770334713e-13, 0.9999999791665050};
  double pend_ref[5];
  pend_reference(1.0, 3.0, pend_ref);
  printf("| problem | rtol | steps | significant digits | time [ms] |\n|---|---|---|---|---|\n");
  const double amp_ref[8] = {-0.5562145012262709e-2, 0.3006522471903042e+1,
                             0.2849958788608128e+1, 0.2926422536206241e+1,
                             0.2704617865010554e+1, 0.2761837778393145e+1,
                             0.4770927631616772e+1, 0.1236995868091548e+1};
  for (int problem = 0; problem <= 2; problem++) {
    for (int k = 4; k <= 10; k += problem == 2 ? 2 : 1) {
      double rtol = pow(10.0, -k), out[8];
      long netf = 0;
      long nst = solve(ctx, problem, rtol, out, &netf);
      int reps = problem == 2 ? 3 : REPS;
      double t0 = now();
      for (int r = 0; r < reps; r++) solve(ctx, problem, rtol, out, &netf);
      double ms = (now() - t0) / reps * 1e3;
      if (problem == 1)
        printf("| IDA pendulum (t=3) | 1e-%d | %ld | %.2f (x,y) / %.2f (all) | %.3f |\n", k, nst,
               digits(out, pend_ref, 0, 2), digits(out, pend_ref, 0, 5), ms);
      else if (problem == 0)
        printf("| IDA Robertson (t=1e11) | 1e-%d | %ld | %.2f | %.3f |\n", k, nst,
               digits(out, rober_ref, 0, 3), ms);
      else
        printf("| IDA transistor amplifier (t=0.2) | 1e-%d | %ld (%ld error-test failures) | %.2f | %.3f |\n",
               k, nst, netf, digits(out, amp_ref, 0, 8), ms);
    }
  }
  SUNContext_Free(&ctx);
  return 0;
}
