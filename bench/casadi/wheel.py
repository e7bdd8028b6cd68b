"""The paper's rolling wheel (models/src/wheel.rs) in CasADi, for the peer benchmark.

Generates C for what a Newton step of an implicit integrator needs, for the plant and for its
tracking DAE (W = s + 5 on theta and psi):

* ``wheel_res``: the residual F(x', x, u);
* ``wheel_res_iter``: the residual and the iteration matrix dF/dx + c dF/dx' (CasADi's
  sparse output: only the structural non-zeros, column-compressed);
* ``tracking_res_iter``: the tracking DAE's residual and iteration matrix
  [dG/dX + c dG/dX' | dG/dU] in the unknowns [X; U] = [theta, psi, dphi, dtheta, dpsi, u1, u2]
  with the inputs w = (w_theta, w_psi).

Parameters are the model's defaults, folded into the code as constants (the peer at its best:
dpc's generated code reads them at run time). Usage: ``python wheel.py OUT_DIR``.
"""

import sys
import os
import casadi as ca

# The model's default parameters (models/src/wheel.rs).
m, r, i_r, i_n, g = 1.0, 1.0, 0.5, 0.25, 9.81
a1 = i_n + m * r**2
a2 = i_r + m * r**2
a3 = m * r**2 + i_n - i_r
a4 = 2.0 * m * r**2 + i_n
W_ROOT = 5.0  # W(s) = s + 5 on both outputs

x = ca.SX.sym("x", 5)
xdot = ca.SX.sym("xdot", 5)
u = ca.SX.sym("u", 2)
w = ca.SX.sym("w", 2)
c = ca.SX.sym("c")
theta, psi, dphi, dtheta, dpsi = (x[i] for i in range(5))
d_theta, d_psi, d_dphi, d_dtheta, d_dpsi = (xdot[i] for i in range(5))
u1, u2 = u[0], u[1]
s, co = ca.sin(theta), ca.cos(theta)

# Residual rows in the form `lhs - rhs`, as dpc normalises them.
F = ca.vertcat(
    d_theta - dtheta,
    d_psi - dpsi,
    (i_r * s**2 + a1 * co**2) * d_dphi + a1 * co * d_dpsi
    - (i_n * dtheta * dpsi * s + 2.0 * a3 * dphi * dtheta * co * s + u1 * s),
    a2 * d_dtheta
    - (-a1 * dphi * dpsi * s - a3 * dphi**2 * co * s - m * g * r * co),
    a1 * co * d_dphi + (i_n + m * r**2) * d_dpsi - (a4 * dphi * dtheta * s + u2),
)
J = ca.jacobian(F, x) + c * ca.jacobian(F, xdot)

# Tracking DAE: unknowns [x; u], rows F plus W(d/dt) h = w with der(theta) = dtheta
# substituted (the stabilised Hirschorn step).
G = ca.vertcat(F, dtheta + W_ROOT * theta - w[0], dpsi + W_ROOT * psi - w[1])
y = ca.vertcat(x, u)
JG = ca.jacobian(G, y) + c * ca.horzcat(ca.jacobian(G, xdot), ca.SX(7, 2))

functions = [
    ca.Function("wheel_res", [x, xdot, u], [F]),
    ca.Function("wheel_res_iter", [x, xdot, u, c], [F, J]),
    ca.Function("tracking_res_iter", [x, xdot, u, w, c], [G, JG]),
]

out_dir = sys.argv[1] if len(sys.argv) > 1 else "generated"
os.makedirs(out_dir, exist_ok=True)
gen = ca.CodeGenerator("wheel_casadi.c", {"with_header": True})
for f in functions:
    gen.add(f)
cwd = os.getcwd()
os.chdir(out_dir)
try:
    gen.generate()
finally:
    os.chdir(cwd)

# The structural patterns, for the benchmark's check that both evaluate the same matrix.
with open(os.path.join(out_dir, "patterns.txt"), "w") as fh:
    fh.write("casadi %s\n" % ca.__version__)
    for name, mat in [("wheel", J), ("tracking", JG)]:
        sp = mat.sparsity()
        fh.write("%s %d nnz\n" % (name, sp.nnz()))
print("CasADi %s: wrote %s/wheel_casadi.c" % (ca.__version__, out_dir))
