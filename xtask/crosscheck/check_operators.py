"""Cross-check of dyncontact's assembled operators against scikit-fem.

usage: python check_operators.py DIR [--reference PREFIX]

DIR is what `dyncontact export-operators SCENE --out DIR` wrote: mesh.vtu, M.mtx, K.mtx,
C.mtx (all 2N DOFs, interleaved 2*node + component, nothing eliminated), f.txt (load vector at
t = params["t"]) and params.json. This script reassembles M, K, C and f on the same mesh and
node numbering with scikit-fem (ElementVector(ElementTriP1())) and compares entry by entry.

Tolerance: max|A_py - A_rust| / max|A_py| <= 1e-12 for each quantity. The cross-check scenes
use loads linear in x, y, so both codes integrate every term exactly (P1 x P1 mass and
linear load x P1 basis are quadratics; the stiffness integrands are constant); the two results
then differ only by the rounding of a handful of additions and products per entry, i.e. a few
ulp (~1e-16 relative to the largest entry). 1e-12 leaves a wide margin for that while any
modelling slip (a wrong Lame constant, plane-stress reduction, mass or quadrature weight, a
mis-numbered DOF) shows up at 1e-3 or far above.

With --reference PREFIX the scikit-fem results are also written, in the interleaved DOF order,
as PREFIX_M.mtx, PREFIX_K.mtx, PREFIX_C.mtx (Matrix Market, exact zeros dropped, shortest
round-trip floats) and PREFIX_f.txt (one float per line), so a Rust test can compare against
them without Python.
"""
import argparse
import functools
import json
import re
import sys
from pathlib import Path

import meshio
import numpy as np
import scipy.io
import scipy.sparse as sp
import skfem
from skfem import (Basis, BilinearForm, ElementTriP1, ElementVector, FacetBasis, LinearForm,
                   MeshTri, asm)
from skfem.helpers import dot
from skfem.models.elasticity import lame_parameters, linear_elasticity

TOL = 1e-12
INTORDER = 4  # exact for the quadratic integrands above (and then some)


# --- load expressions -----------------------------------------------------------------------
# The scene grammar (src/model/expr.rs) is close to Python's: translate `^`, `if(c, a, b)` and
# the function names, evaluate with numpy so that x, y are arrays of quadrature points.
# `&&` / `||` are not translated (their precedence differs); the cross-check scenes don't use them.
def _reduce(f):
    return lambda *a: functools.reduce(f, a)


NAMES = {
    "pi": np.pi, "e": np.e,
    "sin": np.sin, "cos": np.cos, "tan": np.tan, "asin": np.arcsin, "acos": np.arccos,
    "atan": np.arctan, "sinh": np.sinh, "cosh": np.cosh, "tanh": np.tanh, "exp": np.exp,
    "ln": np.log, "log": np.log, "log10": np.log10, "sqrt": np.sqrt, "abs": np.abs,
    "sign": np.sign, "floor": np.floor, "ceil": np.ceil, "atan2": np.arctan2, "pow": np.power,
    "min": _reduce(np.minimum), "max": _reduce(np.maximum),
    "if_": lambda c, a, b: np.where(np.asarray(c) != 0, a, b),
}


def evaluate(src, x, y, t):
    if "&&" in src or "||" in src:
        raise NotImplementedError(f"expression {src!r}: && and || are not supported here")
    py = re.sub(r"\bif\s*\(", "if_(", src.replace("^", "**"))
    val = eval(py, {"__builtins__": {}}, {**NAMES, "x": x, "y": y, "t": t})  # noqa: S307
    return np.broadcast_to(np.asarray(val, dtype=float), np.shape(x))


def vector_load(exprs, t):
    """LinearForm of the vector field (exprs[0], exprs[1]) in x, y at time t."""
    @LinearForm
    def form(v, w):
        x, y = w.x
        return evaluate(exprs[0], x, y, t) * v.value[0] + evaluate(exprs[1], x, y, t) * v.value[1]
    return form


# --- helpers ----------------------------------------------------------------------------------
def plane_reduce(lam, mu, plane):
    """In-plane first Lame constant: plane stress eliminates eps_zz, lam* = 2 lam mu/(lam+2mu)."""
    if plane == "stress":
        return 2.0 * lam * mu / (lam + 2.0 * mu) if lam + 2.0 * mu > 0 else 0.0
    return lam


def max_abs(a):
    if sp.issparse(a):
        a = sp.coo_array(a)
        return float(np.abs(a.data).max(initial=0.0))
    return float(np.abs(a).max(initial=0.0))


def write_mtx(path, a, header):
    a = sp.coo_array(sp.csr_array(a))
    a.sum_duplicates()
    a.eliminate_zeros()
    order = np.lexsort((a.col, a.row))
    lines = ["%%MatrixMarket matrix coordinate real general"]
    lines += [f"% {h}" for h in header]
    lines.append(f"{a.shape[0]} {a.shape[1]} {a.nnz}")
    lines += [f"{a.row[k] + 1} {a.col[k] + 1} {float(a.data[k])!r}" for k in order]
    Path(path).write_text("\n".join(lines) + "\n")


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("dir", type=Path)
    ap.add_argument("--reference", help="write the scikit-fem operators as PREFIX_{M,K,C}.mtx, PREFIX_f.txt")
    args = ap.parse_args()
    d = args.dir
    prm = json.loads((d / "params.json").read_text())

    # mesh with dyncontact's node numbering (MeshTri only sorts the vertices inside a triangle)
    m = meshio.read(d / "mesh.vtu")
    p = np.ascontiguousarray(m.points[:, :2].T)
    tri = np.ascontiguousarray(m.cells_dict["triangle"].T.astype(np.int64))
    mesh = MeshTri(p, tri)
    n = p.shape[1]
    elem = ElementVector(ElementTriP1())
    basis = Basis(mesh, elem, intorder=INTORDER)
    assert basis.N == 2 * n, (basis.N, n)
    # skfem's DOF of (node k, component c) is nodal_dofs[c, k]; dyncontact's is 2k + c
    perm = np.empty(2 * n, dtype=np.int64)
    perm[0::2] = basis.nodal_dofs[0]
    perm[1::2] = basis.nodal_dofs[1]

    def interleave(a):
        return sp.csr_array(a)[perm][:, perm] if sp.issparse(a) else np.asarray(a)[perm]

    # operators: Lame constants from (E, nu) by scikit-fem, plane reduction as in spec/model.md
    plane = prm["plane"]
    lam, mu = lame_parameters(prm["young"], prm["poisson"])
    lam = plane_reduce(lam, mu, plane)
    theta, zeta = prm["theta"], prm["zeta"]
    theta = plane_reduce(theta, zeta, plane)
    rho = prm["density"]

    @BilinearForm
    def mass(u, v, w):
        return rho * dot(u, v)

    M = asm(mass, basis)
    if prm["mass"] == "lumped":
        M = sp.diags_array(np.asarray(M.sum(axis=1)).ravel())  # row sums onto the diagonal
    elif prm["mass"] != "consistent":
        raise ValueError(f"unknown mass kind {prm['mass']!r}")
    K = asm(linear_elasticity(lam, mu), basis)
    C = asm(linear_elasticity(theta, zeta), basis)

    # load vector: body force on the triangles, tractions on the listed boundary edges
    t = prm.get("t", 0.0)
    f = asm(vector_load(prm["body"], t), basis)
    facet_of = {tuple(sorted(map(int, e))): k for k, e in enumerate(mesh.facets.T)}
    for tr in prm["tractions"]:
        if not tr["edges"]:
            continue
        facets = np.array([facet_of[tuple(sorted(e))] for e in tr["edges"]], dtype=np.int64)
        fb = FacetBasis(mesh, elem, facets=facets, intorder=INTORDER)
        f = f + asm(vector_load(tr["value"], t), fb)

    py = {"M": interleave(M), "K": interleave(K), "C": interleave(C), "f": interleave(f)}
    rust = {q: scipy.io.mmread(d / f"{q}.mtx") for q in "MKC"}
    rust["f"] = np.loadtxt(d / "f.txt", ndmin=1)

    passed = failed = skipped = 0
    for q in ["M", "K", "C", "f"]:
        a, b = py[q], rust[q]
        if a.shape != b.shape:
            print(f"{q}: FAIL shape skfem {a.shape} vs rust {b.shape}")
            failed += 1
            continue
        scale = max_abs(a)
        if q == "C" and scale == 0.0 and max_abs(b) == 0.0:
            print(f"{q}: skipped (zero in both: no viscosity)")
            skipped += 1
            continue
        diff = max_abs(a - b)
        rel = diff / scale if scale > 0 else (0.0 if diff == 0 else np.inf)
        ok = bool(rel <= TOL)
        passed += ok
        failed += not ok
        print(f"{q}: rel diff {rel:.3e}  (max|A_py| = {scale:.6e})  {'ok' if ok else 'FAIL'}")

    if args.reference:
        header = [f"scikit-fem {skfem.__version__} reference for dyncontact (xtask crosscheck)",
                  f"scene {d.name}: plane {plane}, mass {prm['mass']}; DOF 2*node + component, all nodes"]
        for q in "MKC":
            write_mtx(f"{args.reference}_{q}.mtx", py[q], header)
        Path(f"{args.reference}_f.txt").write_text("".join(f"{float(v)!r}\n" for v in py["f"]))

    print(f"{passed} passed, {failed} failed, {skipped} skipped")
    sys.exit(1 if failed else 0)


if __name__ == "__main__":
    main()
