"""The academic example from Python, as a notebook user would write it: run the default scene
(a shortened time.end), plot its energies and forces with matplotlib, a small penalty sweep
(P_eps -> P as eps -> 0, the ε-study of fixtures/sweeps/penalty.toml on three points), and the
last frame to meshio.

    python3 -m pip install ./python matplotlib
    python3 examples/python/academic.py [OUT_DIR]

`cargo xtask verify` runs it (its figures and files go to a temporary folder unless OUT_DIR is
given).
"""
import sys
import tempfile
from pathlib import Path

import matplotlib

matplotlib.use("Agg")  # no display: write files
import matplotlib.pyplot as plt  # noqa: E402
import meshio  # noqa: E402
import numpy as np  # noqa: E402

import dyncontact as dc  # noqa: E402

out = Path(sys.argv[1]) if len(sys.argv) > 1 else Path(tempfile.mkdtemp(prefix="dyncontact-academic-"))
out.mkdir(parents=True, exist_ok=True)

# the scene: the embedded default (Ex-A of model.md §5.2), the first 0.3 s
scene = dc.Scene.default().with_set({"time.end": 0.3})
info = scene.check()
print(f"{scene.name}: {info['nodes']} nodes, {info['steps']} steps, (C.k) limit k <= {info['ck_step_limit']:.3e}")

res = dc.run(scene)  # writes nothing; dc.run(scene, out="DIR") writes the CLI's run folder
h = res.history
print(f"status {res.summary['status']}, max |(E.1) residual| {np.abs(h['energy_residual']).max():.2e}")

# energies: the terms of the balance (E.1)
fig, (top, bottom) = plt.subplots(2, 1, sharex=True, figsize=(7, 6))
for term in ("kinetic", "elastic", "compliance", "external_work", "viscous_dissipation", "friction_dissipation",
             "constraint_dissipation"):
    top.plot(h["t"], h[term], label=term.replace("_", " "))
top.set_ylabel("energy [J/m]")
top.legend(fontsize=7)
bottom.plot(h["t"], h["normal_force"], label="normal force")
bottom.plot(h["t"], h["tangential_force"], label="tangential force")
bottom.set_xlabel("t [s]")
bottom.set_ylabel("force [N/m]")
bottom.legend(fontsize=7)
fig.savefig(out / "academic.png", dpi=100)
plt.close(fig)

# the ε-study in small: the exact problem P and the penalty problem P_eps for two eps
rows = dc.sweep(
    {
        "name": "penalty-small",
        "base": "default",
        "axis": [
            {
                "name": "eps",
                "sets": [
                    {"contact.enforcement": "exact"},
                    {"contact.enforcement": "penalty", "contact.penalty": 1e-3},
                    {"contact.enforcement": "penalty", "contact.penalty": 1e-4},
                ],
                "labels": ["exact", "1e-3", "1e-4"],
            }
        ],
        "set": {"time.end": 0.1},
    },
    out=out / "sweep",
    jobs=2,
)
for r in rows:
    print(f"  {r['eps']:>6}: max penetration {r['max_penetration']:.4e}, "
          f"constraint dissipation {r['constraint_dissipation']:.4e} ({r['status']})")
assert all(r["status"] == "completed" for r in rows)

# the last frame to meshio (any format meshio writes: VTU, XDMF, ...)
frame = res.frame(-1)
meshio.write(out / "last.vtu", frame)
back = meshio.read(out / "last.vtu")
assert np.array_equal(back.point_data["displacement"][:, :2], res.fields(-1)["u"])
print(f"last frame (t = {res.frames[-1][1]:.3f}) written to {out / 'last.vtu'}; figures in {out}")
