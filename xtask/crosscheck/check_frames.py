"""Readability check of a `dyncontact run` output folder with meshio (the README, "Outputs").

usage: python check_frames.py DIR

Parses DIR/series.pvd with ElementTree, reads every frame it lists with meshio and checks:
the PVD lists exactly the files in DIR/frames, timesteps strictly increase from t >= 0, every
frame has the same points and triangles, point data displacement and velocity (N x 3, z = 0),
contact_pressure, friction, contact_status (one value per node), cell data stress (one 4-vector
per triangle; in 3-D tetrahedra, points off z = 0 and a 6-vector of stress per tetrahedron), all
finite. The first frame is the initial state of the cross-check scene
(u0 = 0, so its displacement must be exactly 0) and the last one must have moved (the loads are
not zero). These are structural checks: no numerical tolerance is involved, since the VTU
writer prints shortest round-trip floats and meshio reads back the exact f64 values.
"""
import sys
import xml.etree.ElementTree as ET
from pathlib import Path

import meshio
import numpy as np


def main():
    d = Path(sys.argv[1])
    root = ET.parse(d / "series.pvd").getroot()
    entries = root.findall("./Collection/DataSet")
    times = [float(e.get("timestep")) for e in entries]
    files = [e.get("file") for e in entries]
    problems = []

    def check(cond, msg):
        if not cond:
            problems.append(msg)
        return cond

    check(len(entries) >= 2, f"series.pvd lists {len(entries)} frames, expected at least 2")
    check(times and times[0] >= 0.0, f"first timestep {times[:1]} < 0")
    check(all(b > a for a, b in zip(times, times[1:])), f"timesteps not strictly increasing: {times}")
    on_disk = sorted(str(p.relative_to(d)) for p in (d / "frames").glob("*.vtu"))
    check(sorted(files) == on_disk, f"PVD lists {len(files)} files, frames/ has {len(on_disk)}: {files} vs {on_disk}")

    ref = None
    for k, (t, f) in enumerate(zip(times, files)):
        where = f"{f} (t = {t:g})"
        try:
            m = meshio.read(d / f)
        except Exception as e:  # missing or unreadable: report it with the others
            check(False, f"{where}: meshio cannot read it: {type(e).__name__}: {e}")
            continue
        n = m.points.shape[0]
        # 2-D frames hold triangles (z = 0), 3-D frames tetrahedra
        kind = "tetra" if "tetra" in m.cells_dict else "triangle"
        solid = kind == "tetra"
        tri = m.cells_dict.get(kind)
        if not check(tri is not None and len(m.cells) == 1, f"{where}: expected one triangle or tetrahedron block"):
            continue
        nc = tri.shape[0]
        if ref is None:
            ref = (m.points, tri)
        check(np.array_equal(m.points, ref[0]) and np.array_equal(tri, ref[1]), f"{where}: mesh differs from the first frame")
        check(np.isfinite(m.points).all() and (solid or np.allclose(m.points[:, 2], 0.0)), f"{where}: bad points")
        pd = m.point_data
        for name, shape in [("displacement", (n, 3)), ("velocity", (n, 3)), ("contact_pressure", (n,)),
                            ("friction", (n,)), ("contact_status", (n,))]:
            if not check(name in pd, f"{where}: point_data has no {name!r} (has {sorted(pd)})"):
                continue
            a = pd[name]
            if len(shape) == 1 and a.ndim == 2 and a.shape[1] == 1:
                a = a[:, 0]  # a scalar field may come back as N x 1
            check(a.shape == shape, f"{where}: {name} shape {pd[name].shape}, expected {shape}")
            check(np.isfinite(a).all(), f"{where}: {name} not finite")
            if len(shape) == 2 and a.shape == shape and not solid:
                check(np.all(a[:, 2] == 0.0), f"{where}: {name} has a non-zero z component")
        if "contact_status" in pd:
            s = pd["contact_status"]
            check(np.issubdtype(s.dtype, np.integer), f"{where}: contact_status dtype {s.dtype} is not integer")
        stress = m.cell_data.get("stress")
        if check(stress is not None and len(stress) == 1, f"{where}: cell_data has no stress block (has {sorted(m.cell_data)})"):
            comps = 6 if solid else 4
            check(stress[0].shape == (nc, comps), f"{where}: stress shape {stress[0].shape}, expected ({nc}, {comps})")
            check(np.isfinite(stress[0]).all(), f"{where}: stress not finite")
        if k == 0 and "displacement" in pd:
            check(np.all(pd["displacement"] == 0.0), f"{where}: initial displacement is not 0 (u0 = 0 in the scene)")
        if k == len(files) - 1 and "displacement" in pd:
            check(np.abs(pd["displacement"]).max() > 0.0, f"{where}: final displacement is 0 although loads act")

    for p in problems:
        print(f"FAIL {p}")
    print(f"frames: {len(files)} listed in series.pvd, t = {times[0]:g} .. {times[-1]:g}" if files else "frames: none")
    print(f"{0 if problems else 1} passed, {1 if problems else 0} failed")
    sys.exit(1 if problems else 0)


if __name__ == "__main__":
    main()
