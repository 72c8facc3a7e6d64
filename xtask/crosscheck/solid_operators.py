"""scikit-fem reference operators of a 3-D box for dyncontact's tetrahedra.

usage: python solid_operators.py OUT_PREFIX [MESH.msh]

Builds the box [0, 1] x [0, 0.5] x [0, 0.5] with 4 x 2 x 2 cells, each cut into the six
tetrahedra sharing its main diagonal (the Kuhn subdivision: one tetrahedron per order of the
steps in x, y, z along the diagonal), with dyncontact's node numbering (k (ny+1) + j)(nx+1) + i,
assembles M (consistent and row-lumped), K and C with scikit-fem (ElementVector(ElementTetP1()),
linear_elasticity with the 3-D Lame constants, no plane reduction) and writes them as
OUT_PREFIX_{consistent,lumped}_M.mtx, OUT_PREFIX_K.mtx, OUT_PREFIX_C.mtx in the interleaved DOF
order 3*node + component (Matrix Market, shortest round-trip floats). tests/verification/solid.rs compares
dyncontact's assembly entry by entry (1e-12 relative: every integrand is a polynomial the
quadrature integrates exactly, so the two differ by a few ulp). The subdivision is written here
independently of src/mesh/solid.rs: a different set of tetrahedra changes K. With MESH.msh the
same operators of that (unstructured) Gmsh mesh, read by meshio in the file's node order.
"""
import itertools
import sys
from pathlib import Path

import numpy as np
import scipy.sparse as sp
import skfem
from skfem import Basis, BilinearForm, ElementTetP1, ElementVector, MeshTet, asm
from skfem.helpers import dot
from skfem.models.elasticity import lame_parameters, linear_elasticity

from check_operators import write_mtx

SIZE, CELLS = (1.0, 0.5, 0.5), (4, 2, 2)
YOUNG, POISSON, THETA, ZETA, RHO = 1000.0, 0.3, 2.0, 1.5, 1.3


def kuhn_box(size, cells):
    nx, ny, nz = cells
    idx = lambda i, j, k: (k * (ny + 1) + j) * (nx + 1) + i  # noqa: E731
    pts = [(size[0] * i / nx, size[1] * j / ny, size[2] * k / nz)
           for k in range(nz + 1) for j in range(ny + 1) for i in range(nx + 1)]
    tets = []
    for k, j, i in itertools.product(range(nz), range(ny), range(nx)):
        for order in itertools.permutations(range(3)):
            p = [i, j, k]
            t = [idx(*p)]
            for axis in order:
                p[axis] += 1
                t.append(idx(*p))
            tets.append(t)
    return np.array(pts).T, np.array(tets, dtype=np.int64).T


def main():
    prefix = sys.argv[1]
    if len(sys.argv) > 2:
        # an unstructured Gmsh mesh, read with meshio in the file's node order (dyncontact's too)
        import meshio
        m = meshio.read(sys.argv[2])
        p, t = m.points.T, m.cells_dict["tetra"].T.astype(np.int64)
        what = f"Gmsh mesh {Path(sys.argv[2]).name}"
    else:
        p, t = kuhn_box(SIZE, CELLS)
        what = f"box {SIZE} with {CELLS} cells, Kuhn subdivision"
    mesh = MeshTet(np.ascontiguousarray(p), np.ascontiguousarray(t))
    vol = float(np.sum(Basis(mesh, ElementTetP1()).dx))
    if len(sys.argv) <= 2:
        assert abs(vol - np.prod(SIZE)) <= 1e-14, vol
    n = p.shape[1]
    basis = Basis(mesh, ElementVector(ElementTetP1()), intorder=2)
    perm = np.empty(3 * n, dtype=np.int64)
    for c in range(3):
        perm[c::3] = basis.nodal_dofs[c]

    def interleave(a):
        return sp.csr_array(a)[perm][:, perm]

    @BilinearForm
    def mass(u, v, w):
        return RHO * dot(u, v)

    lam, mu = lame_parameters(YOUNG, POISSON)
    M = asm(mass, basis)
    out = {
        "consistent_M": M,
        "lumped_M": sp.diags_array(np.asarray(M.sum(axis=1)).ravel()),
        "K": asm(linear_elasticity(lam, mu), basis),
        "C": asm(linear_elasticity(THETA, ZETA), basis),
    }
    header = [f"scikit-fem {skfem.__version__} reference for dyncontact (xtask crosscheck, solid_operators.py)",
              f"{what}; E {YOUNG}, nu {POISSON}, theta {THETA}, zeta {ZETA}, rho {RHO}",
              "DOF 3*node + component, all nodes"]
    for name, a in out.items():
        write_mtx(f"{prefix}_{name}.mtx", interleave(a), header)
    print(f"solid operators: {n} nodes, {t.shape[1]} tetrahedra, volume {vol}; wrote {prefix}_{{consistent_M,lumped_M,K,C}}.mtx")


if __name__ == "__main__":
    main()
