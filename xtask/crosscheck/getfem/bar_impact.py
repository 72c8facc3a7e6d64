"""GetFEM cross-check of the dynamic contact solve: B.1, the elastic bar hitting a rigid wall
(frictionless Signorini), on the singular mass. Run by `cargo xtask crosscheck` with Debian's
python3-getfem (system Python); usage:

    /usr/bin/python3 bar_impact.py --dyncontact BIN --scene bar_impact_singular.toml --out DIR

Both codes solve the same bar (1.0 × 0.1, NX × 1 cells cut along the lower-left → upper-right
diagonal, E = 1, ν = 0, ρ = 1, v0 = −0.1, wall at x = 0) with P1 elements and plane strain:

* dyncontact: the energy-consistent midpoint rule with the exact constraint and the modified mass
  (R.1: least-squares redistribution of the contact nodes' mass within two edges);
* GetFEM: its linear elasticity brick, the mass matrix integrated with the vertex rule
  (IM_NC(2,1): ρ|T|/3 per vertex) made singular by moving each contact node's mass to its
  neighbour at x = h, its nodal contact brick with a rigid obstacle (Alart–Curnier), and Newmark
  β = ¼, γ = ½ written out around one solve per step: (4M/k² + K) u¹ = 4M/k² (u⁰ + k v⁰) + M a⁰ + r.

With the lumped mass GetFEM's Newmark energy grows 8–10× over this run (an end-point displacement
constraint on massive nodes), which is why the comparison is made on singular masses. The two
mass redistributions differ at O(h), the schemes at O(k²); each tolerance below says how it
follows from the refinement (h and k halved together: NX = 100, k = 2.5e-3 → 200, 1.25e-3),
measured when the check was written:

                                    coarse      fine       tolerance
  mean F_n over [0.1, 1.9] (rel.)   3.9e-4      1.6e-4     1e-3 at both: both are ρ c v0 H to the
                                                           mesh's dispersion; 2.5× margin
  per-step F_n difference (mean,    4.9e-3      7.5e-4     ≤ 1e-2 at the coarse level and falling
  of ρ c v0 H)                                             by ≥ 2× (the rate of an O(h) difference)
  GetFEM energy drift (of E0)       1.2e-5      2.6e-6     ≤ 1e-4 and falling (an O(k²) defect)
  kinetic energy difference (of E0) 3.6e-3      1.4e-3     ≤ 1e-2 and falling
  release time difference           0.050       0.000      ≤ 2h/c + 2k at the fine level

Exits 1 if any comparison fails; prints the table and both codes' wall times.
"""
import argparse
import csv
import re
import subprocess
import sys
import time
from pathlib import Path

import numpy as np
import getfem as gf

gf.util('trace level', 0)  # GetFEM's assembly traces would drown the report

L, H, RHO_C_V0_H = 1.0, 0.1, 0.01
E0 = 0.5 * (L * H) * 0.1 ** 2
LEFT = 1


def bar_mesh(nx):
    """The bar's mesh as dyncontact builds it: NX × 1 cells cut along the lower-left → upper-right
    diagonal; region LEFT (the contact side x = 0) marked."""
    xs, ys = np.linspace(0.0, L, nx + 1), np.array([0.0, H])
    m = gf.Mesh('empty', 2)
    for i in range(nx):
        p00, p10 = [xs[i], ys[0]], [xs[i + 1], ys[0]]
        p01, p11 = [xs[i], ys[1]], [xs[i + 1], ys[1]]
        m.add_convex(gf.GeoTrans('GT_PK(2,1)'), np.array([p00, p10, p11]).T)
        m.add_convex(gf.GeoTrans('GT_PK(2,1)'), np.array([p00, p11, p01]).T)
    faces = m.outer_faces()
    pts = m.pts()
    left = [[cv, f] for cv, f in zip(faces[0], faces[1])
            if np.all(np.abs(pts[0, m.pid_in_faces(np.array([[cv], [f]]))]) < 1e-12)]
    m.set_region(LEFT, np.array(left).T)
    return m


def vertex_mass(mf, mim_vertex, nx, singular):
    """GetFEM's mass matrix integrated with the vertex rule (ρ|T|/3 per vertex, so lumped); with
    `singular`, each contact node's mass is moved to its neighbour at x = h (a singular mass)."""
    M = gf.asm_mass_matrix(mim_vertex, mf)
    if singular:
        n, dn, h = mf.nbdof(), mf.basic_dof_nodes(), L / nx
        for d in range(n):
            if abs(dn[0, d]) < 1e-12:
                partner = next(e for e in range(n)
                               if abs(dn[0, e] - h) < 1e-12 and abs(dn[1, e] - dn[1, d]) < 1e-12 and e % 2 == d % 2)
                M[partner, partner] = M[partner, partner] + M[d, d]
                M[d, d] = 0.0
    return M


def getfem_run(nx, k, T):
    """B.1 with GetFEM on the singular mass; per step: t, F_n, kinetic, elastic, contact nodes."""
    m = bar_mesh(nx)
    mf = gf.MeshFem(m, 2)
    mf.set_classical_fem(1)
    mim = gf.MeshIm(m, gf.Integ('IM_TRIANGLE(2)'))
    mim_vertex = gf.MeshIm(m, gf.Integ('IM_NC(2,1)'))
    n = mf.nbdof()
    M = vertex_mass(mf, mim_vertex, nx, True)
    lam, mu = 0.0, 0.5  # E = 1, ν = 0
    elastic = gf.Model('real')
    elastic.add_fem_variable('u', mf)
    elastic.add_initialized_data('lambda', [lam])
    elastic.add_initialized_data('mu', [mu])
    elastic.add_isotropic_linearized_elasticity_brick(mim, 'u', 'lambda', 'mu')
    elastic.assembly('build_matrix')
    K = elastic.tangent_matrix()

    md = gf.Model('real')
    md.add_fem_variable('u', mf)
    md.add_initialized_data('lambda', [lam])
    md.add_initialized_data('mu', [mu])
    md.add_isotropic_linearized_elasticity_brick(mim, 'u', 'lambda', 'mu')
    Mk = gf.Spmat('copy', M)
    Mk.scale(4.0 / k ** 2)
    md.add_explicit_matrix('u', 'u', Mk)
    rhs_brick = md.add_explicit_rhs('u', np.zeros(n))
    md.add_variable('lambda_n', len(mf.basic_dof_on_region(LEFT)) // 2)
    md.add_initialized_data('r', [1.0])
    md.add_nodal_contact_with_rigid_obstacle_brick(mim, 'u', 'lambda_n', 'r', LEFT, 'x', 1)

    u, v, a = np.zeros(n), np.zeros(n), np.zeros(n)
    v[0::2] = -0.1
    rows = []
    quad = lambda A, x: float(x @ A.mult(x))
    for s in range(int(round(T / k))):
        md.set_private_rhs(rhs_brick, M.mult(4.0 / k ** 2 * (u + k * v)) + M.mult(a))
        md.set_variable('u', u)
        md.solve('max_res', 1e-12, 'max_iter', 100)
        u1, ln = md.variable('u'), md.variable('lambda_n')
        a1 = 4.0 * (u1 - u - k * v) / k ** 2 - a
        v = v + 0.5 * k * (a + a1)
        u, a = u1, a1
        rows.append(((s + 1) * k, -float(np.sum(ln)), 0.5 * quad(M, v), 0.5 * quad(K, u), int(np.sum(np.abs(ln) > 0))))
    return np.array(rows)


def run_scene(binary, text, out, columns):
    """Run dyncontact on the scene `text` in `out`; per step (step 0 dropped) the `columns` of
    its history.csv."""
    out.mkdir(parents=True, exist_ok=True)
    scene = out / 'scene.toml'
    scene.write_text(text)
    subprocess.run([binary, 'run', str(scene), '--out', str(out / 'run')], check=True, capture_output=True)
    with open(out / 'run' / 'history.csv') as f:
        rows = list(csv.DictReader(f))[1:]
    return np.array([[float(r[c]) for c in columns] for r in rows])


def dyncontact_run(binary, scene_text, nx, k, out):
    """B.1 with dyncontact at NX cells and step k; per step: t, F_n, kinetic, elastic, contact nodes."""
    text = re.sub(r'cells = \[\d+, 1\]', f'cells = [{nx}, 1]', scene_text)
    text = re.sub(r'step = [0-9.e-]+', f'step = {k!r}', text)
    return run_scene(binary, text, out, ['t', 'normal_force', 'kinetic', 'elastic', 'contact_nodes'])


def compare(g, d):
    t = g[:, 0]
    sel = (t > 0.1) & (t < 1.9)
    release = lambda x: x[x[:, 4] > 0, 0].max()
    return {
        'mean_fn': abs(g[sel, 1].mean() - d[sel, 1].mean()) / RHO_C_V0_H,
        'step_fn': float(np.mean(np.abs(g[sel, 1] - d[sel, 1]))) / RHO_C_V0_H,
        'drift': abs(g[-1, 2] + g[-1, 3] - E0) / E0,
        'kinetic': float(np.max(np.abs(g[:, 2] - d[:, 2]))) / E0,
        'release': abs(release(g) - release(d)),
    }


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument('--dyncontact', required=True)
    ap.add_argument('--scene', required=True)
    ap.add_argument('--out', required=True)
    args = ap.parse_args()
    scene_text = Path(args.scene).read_text()
    levels = [(100, 2.5e-3), (200, 1.25e-3)]
    res, times = [], []
    for nx, k in levels:
        t0 = time.time()
        d = dyncontact_run(args.dyncontact, scene_text, nx, k, Path(args.out) / f'dyncontact_{nx}')
        t1 = time.time()
        g = getfem_run(nx, k, 3.0)
        t2 = time.time()
        res.append(compare(g, d))
        times.append((t1 - t0, t2 - t1))
    (c, f), (nx_f, k_f) = res, levels[1]
    print('B.1 on the singular mass, dyncontact vs GetFEM (coarse 100 cells / 2.5e-3 → fine 200 / 1.25e-3):')
    for key, label in [('mean_fn', 'mean F_n over [0.1, 1.9], of ρ c v0 H'), ('step_fn', 'per-step F_n difference, of ρ c v0 H'),
                       ('drift', 'GetFEM energy drift, of E0'), ('kinetic', 'kinetic energy difference, of E0'),
                       ('release', 'release time difference [s]')]:
        print(f'  {label:<40} {c[key]:.2e} → {f[key]:.2e}')
    for (nx, k), (td, tg) in zip(levels, times):
        print(f'  wall time at {nx} cells, k = {k}: dyncontact {td:.2f} s (process, incl. output), GetFEM {tg:.2f} s')
    checks = [
        ('mean F_n agrees to 1e-3 of ρ c v0 H', c['mean_fn'] <= 1e-3 and f['mean_fn'] <= 1e-3),
        ('per-step F_n difference ≤ 1e-2 and falls ≥ 2× under refinement', c['step_fn'] <= 1e-2 and f['step_fn'] * 2 <= c['step_fn']),
        ('GetFEM energy drift ≤ 1e-4 of E0 and falls', c['drift'] <= 1e-4 and f['drift'] < c['drift']),
        ('kinetic energy difference ≤ 1e-2 of E0 and falls', c['kinetic'] <= 1e-2 and f['kinetic'] < c['kinetic']),
        ('release times agree to 2h/c + 2k at the fine level', f['release'] <= 2 * (L / nx_f) + 2 * k_f),
    ]
    failed = [name for name, ok in checks if not ok]
    for name, ok in checks:
        print(f'  {"ok  " if ok else "FAIL"} {name}')
    sys.exit(1 if failed else 0)


if __name__ == '__main__':
    main()
