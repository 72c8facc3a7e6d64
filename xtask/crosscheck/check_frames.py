"""Readability check of a `dyncontact run` output folder with meshio and VTK (the README, "Outputs").

usage: python check_frames.py DIR

Parses DIR/series.pvd with ElementTree, reads every frame it lists with meshio and checks:
the PVD lists exactly the files in DIR/frames, timesteps strictly increase from t >= 0, every
frame has the same points and triangles, point data displacement, velocity and friction (N x 3,
z = 0 in 2-D), contact_pressure, contact_status (one value per node), cell data stress (one
6-component symmetric tensor per cell, triangles in 2-D, tetrahedra in 3-D with points off
z = 0), all finite. The first frame is the initial state of the cross-check scene
(u0 = 0, so its displacement must be exactly 0) and the last one must have moved (the loads are
not zero).

The last frame is also read with VTK's own reader (vtkXMLUnstructuredGridReader, the one
ParaView uses): its stress array must have 6 components named XX, YY, ZZ, XY, YZ, XZ (VTK's
symmetric-tensor order), displacement, velocity and friction 3 components named x, y, z, and
every array VTK reads must equal meshio's. These are structural checks: no numerical tolerance
is involved, since the arrays are inline binary f64 and both readers get the exact values back.
"""
import sys
import xml.etree.ElementTree as ET
from pathlib import Path

import meshio
import numpy as np

TENSOR = ["XX", "YY", "ZZ", "XY", "YZ", "XZ"]
VECTOR = ["x", "y", "z"]


def vtk_read_back(path, m, check, where):
    """Read one frame with VTK's XML reader and compare its arrays with meshio's `m`."""
    try:
        import vtk
        from vtk.util.numpy_support import vtk_to_numpy
    except ImportError as e:
        check(False, f"{where}: VTK's Python module is missing ({e}); pip install -r requirements.txt")
        return
    reader = vtk.vtkXMLUnstructuredGridReader()
    reader.SetFileName(str(path))
    reader.Update()
    grid = reader.GetOutput()
    if not check(grid is not None and grid.GetNumberOfPoints() == m.points.shape[0],
                 f"{where}: VTK reads {grid.GetNumberOfPoints() if grid else 0} points, meshio {m.points.shape[0]}"):
        return
    check(np.array_equal(vtk_to_numpy(grid.GetPoints().GetData()), m.points), f"{where}: VTK's points differ from meshio's")

    def names(a):
        return [a.GetComponentName(k) for k in range(a.GetNumberOfComponents())]

    stress = grid.GetCellData().GetArray("stress")
    if check(stress is not None, f"{where}: VTK finds no cell array 'stress'"):
        check(stress.GetNumberOfComponents() == 6, f"{where}: VTK reads {stress.GetNumberOfComponents()} stress components, expected 6")
        check(names(stress) == TENSOR, f"{where}: VTK's stress component names {names(stress)}, expected {TENSOR}")
        check(np.array_equal(vtk_to_numpy(stress), m.cell_data["stress"][0]), f"{where}: VTK's stress differs from meshio's")
    pd = grid.GetPointData()
    for name in ["displacement", "velocity", "friction", "contact_pressure", "compliance_pressure", "lambda",
                 "contact_status"]:
        a = pd.GetArray(name)
        if not check(a is not None, f"{where}: VTK finds no point array {name!r}"):
            continue
        if name in ("displacement", "velocity", "friction"):
            check(names(a) == VECTOR, f"{where}: VTK's {name} component names {names(a)}, expected {VECTOR}")
        ours = m.point_data.get(name)
        check(ours is not None and np.array_equal(vtk_to_numpy(a).reshape(ours.shape), ours),
              f"{where}: VTK's {name} differs from meshio's")
    print(f"vtk {vtk.vtkVersion.GetVTKVersion()}: {where} stress {names(stress) if stress else None}, "
          f"{grid.GetNumberOfCells()} cells, arrays equal to meshio's")


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
                            ("friction", (n, 3)), ("contact_status", (n,))]:
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
            check(stress[0].shape == (nc, 6), f"{where}: stress shape {stress[0].shape}, expected ({nc}, 6)")
            check(np.isfinite(stress[0]).all(), f"{where}: stress not finite")
            if not solid and stress[0].shape == (nc, 6):
                check(np.all(stress[0][:, 4:] == 0.0), f"{where}: a 2-D stress has non-zero YZ or XZ")
        if k == 0 and "displacement" in pd:
            check(np.all(pd["displacement"] == 0.0), f"{where}: initial displacement is not 0 (u0 = 0 in the scene)")
        if k == len(files) - 1 and "displacement" in pd:
            check(np.abs(pd["displacement"]).max() > 0.0, f"{where}: final displacement is 0 although loads act")
        if k == len(files) - 1:
            vtk_read_back(d / f, m, check, where)

    for p in problems:
        print(f"FAIL {p}")
    print(f"frames: {len(files)} listed in series.pvd, t = {times[0]:g} .. {times[-1]:g}" if files else "frames: none")
    print(f"{0 if problems else 1} passed, {1 if problems else 0} failed")
    sys.exit(1 if problems else 0)


if __name__ == "__main__":
    main()
