"""GetFEM side of the planned GetFEM cross-check, first case: B.1 (frictionless Signorini bar).

PROTOTYPE — not yet run by `cargo xtask crosscheck`. It needs Debian's python3-getfem (run with
/usr/bin/python3). Usage: /usr/bin/python3 bar_impact_prototype.py NX K OUT.csv
The bar 1.0 × 0.1 (NX × 1 cells, each cut along its lower-left→upper-right diagonal as
dyncontact's rectangle), E = 1, ν = 0, ρ = 1, v0 = −0.1 toward the wall x = 0; P1, plane strain,
lumped mass by the vertex rule (IM_NC(2,1): ρ|T|/3), GetFEM's nodal contact brick with a rigid
obstacle (Alart–Curnier), Newmark β = ¼, γ = ½ written out around a static solve per step:
(4M/k² + K) u¹ = 4M/k² (u⁰ + k v⁰) + M a⁰ + contact. Writes t, −Σλ_n, Σλ_n, kinetic, elastic,
contact nodes per step.

Measured against `dyncontact run fixtures/scenes/bar_impact.toml` (k = 2.5e-3 and 1.25e-3): the
mean normal force over [0.1, 1.9] is 0.0101 / 0.0102 (dyncontact 0.00999 / 0.0100, closed form
0.01); release at 1.97 / 1.98 (dyncontact 2.01, closed form 2.0); 0.05 s window averages differ by
15% of 0.01 in the mean and ~80% at most, not shrinking with k; GetFEM's energy grows from 5e-4 to
4.8e-3 / 3.9e-3 (Newmark with the constraint on the end-point displacement), dyncontact's ends at
4.96e-4 (the 0.8% constraint dissipation). Wall time 2.0 / 8.9 s against 0.08 / 0.15 s.
"""
import numpy as np, getfem as gf, time, sys
# bar 1.0 x 0.1, cells nx x 1, E=1, nu=0, rho=1, v0=-0.1 toward the wall x=0 (contact on left)
nx = int(sys.argv[1]) if len(sys.argv) > 1 else 100
k = float(sys.argv[2]) if len(sys.argv) > 2 else 2.5e-3
T = 3.0
L, H = 1.0, 0.1
xs = np.linspace(0, L, nx + 1); ys = np.linspace(0, H, 2)
m = gf.Mesh('empty', 2)
def node(i, j): return np.array([xs[i], ys[j]])
for j in range(1):
    for i in range(nx):
        p00, p10, p01, p11 = node(i, j), node(i+1, j), node(i, j+1), node(i+1, j+1)
        m.add_convex(gf.GeoTrans('GT_PK(2,1)'), np.array([p00, p10, p11]).T)
        m.add_convex(gf.GeoTrans('GT_PK(2,1)'), np.array([p00, p11, p01]).T)
mf = gf.MeshFem(m, 2); mf.set_classical_fem(1)
mim = gf.MeshIm(m, gf.Integ('IM_TRIANGLE(2)'))
mim_v = gf.MeshIm(m, gf.Integ('IM_NC(2,1)'))   # vertex rule: lumped mass rho|T|/3
LEFT = 1
fb = m.outer_faces()
pts = m.pts()
left_faces = [f for f in fb.T if True]
# region from faces whose both points have x = 0
cvids, fids = fb[0], fb[1]
sel = []
for cv, f in zip(cvids, fids):
    ptsid = m.pid_in_faces(np.array([[cv], [f]]))
    if np.all(np.abs(pts[0, ptsid]) < 1e-12):
        sel.append([cv, f])
m.set_region(LEFT, np.array(sel).T)
M = gf.asm_mass_matrix(mim_v, mf)
E, nu = 1.0, 0.0
lam, mu = E*nu/((1+nu)*(1-2*nu)), E/(2*(1+nu))
K = gf.asm_linear_elasticity(mim, mf, mf, np.repeat(lam, mf.nbdof()), np.repeat(mu, mf.nbdof())) if False else None
md = gf.Model('real')
md.add_fem_variable('u', mf)
md.add_initialized_data('lambda', [lam]); md.add_initialized_data('mu', [mu])
md.add_isotropic_linearized_elasticity_brick(mim, 'u', 'lambda', 'mu')
n = mf.nbdof()
Md = M.full() if hasattr(M, 'full') else None
Mmat = gf.Spmat('copy', M)
# Newmark beta=1/4 gamma=1/2 by hand: (4M/k^2 + K) u1 = 4M/k^2 (u0 + k v0) + M a0 + contact
Mk = gf.Spmat('copy', M); Mk.scale(4.0 / k**2)
md.add_explicit_matrix('u', 'u', Mk)
md.add_initialized_data('rhs', np.zeros(n))
ib_rhs = md.add_explicit_rhs('u', np.zeros(n))
ldof = mf.basic_dof_on_region(LEFT)
nb_contact = len(ldof) // 2
md.add_variable('lambda_n', nb_contact)
md.add_initialized_data('r', [1.0])
md.add_nodal_contact_with_rigid_obstacle_brick(mim, 'u', 'lambda_n', 'r', LEFT, 'x', 1)
u = np.zeros(n); v = np.zeros(n); v[0::2] = -0.1
a = np.zeros(n)
rhs_ind = md.brick_list() if False else None

md2 = gf.Model('real'); md2.add_fem_variable('u', mf)
md2.add_initialized_data('lambda', [lam]); md2.add_initialized_data('mu', [mu])
md2.add_isotropic_linearized_elasticity_brick(mim, 'u', 'lambda', 'mu')
md2.assembly('build_matrix'); Kmat = md2.tangent_matrix()
def quad(A, x): return float(x @ (A.mult(x)))
steps = int(round(T / k))
out = []
t0 = time.time()
for s_ in range(steps):
    rhs = M.mult(4.0 / k**2 * (u + k * v)) + M.mult(a)
    md.set_private_rhs(ib_rhs, rhs)
    md.set_variable('u', u)
    md.solve('max_res', 1e-12, 'max_iter', 100)
    u1 = md.variable('u'); ln = md.variable('lambda_n')
    a1 = 4.0 * (u1 - u - k * v) / k**2 - a
    v1 = v + 0.5 * k * (a + a1)
    u, v, a = u1, v1, a1
    out.append(((s_ + 1) * k, -float(np.sum(ln)), float(np.sum(ln)), 0.5 * quad(M, v), 0.5 * quad(Kmat, u), int(np.sum(np.abs(ln) > 0))))
wall = time.time() - t0
np.savetxt(sys.argv[3] if len(sys.argv) > 3 else 'gf_b1.csv', np.array(out), delimiter=',', header='t,fn_neg,fn,kinetic,elastic,contact', comments='')
print('steps', steps, 'wall', round(wall, 3), 'max fn', max(o[2] for o in out), min(o[2] for o in out))
