"""dyncontact from Python: the solver for dynamic viscoelastic contact (normal compliance with a
penetration bound, nonmonotone slip-rate-dependent friction; Barboteu–Bartosz–Kalita 2015) as a
library — the same Rust code as the ``dyncontact`` command line, so histories equal the CLI's
bit for bit.

    import dyncontact as dc
    scene = dc.Scene.default().with_set({"time.end": 0.3})
    res = dc.run(scene)                    # writes nothing; out="DIR" writes the run folder
    res.history["normal_force"]            # numpy arrays, one per history.csv column
    for rec in dc.Simulation(scene).steps():
        rec.t, rec.u, rec.normal_force
    rows = dc.sweep("fixtures/sweeps/penalty.toml", out="sw", jobs=2)
    table = dc.refine(scene, out="ref")    # refine.csv: each figure's order, f_ext, GCI

Errors are exceptions: SceneError (a ValueError, with .key), SolverError (a RuntimeError, with
.step, .time, .residuals); Ctrl-C during a run raises KeyboardInterrupt once the current step
has finished (after writing a checkpoint when the run has a folder).
"""
from __future__ import annotations

import csv
import json
import os
import xml.etree.ElementTree as ET
from pathlib import Path
from typing import Any, Dict, List, Optional, Tuple, Union

import numpy as np

from . import _dyncontact as _native
from ._dyncontact import DEFAULT_SCENE, Scene, Simulation, StepRecord, __version__, history_columns
from ._errors import SceneError, SolverError

__all__ = [
    "DEFAULT_SCENE",
    "DyncontactWarning",
    "Result",
    "Scene",
    "SceneError",
    "Simulation",
    "SolverError",
    "StepRecord",
    "history_columns",
    "refine",
    "resume",
    "run",
    "sweep",
    "__version__",
]

PathLike = Union[str, "os.PathLike[str]"]

# contact.csv columns that are integers (the others are reals, `status` is text)
_CONTACT_INTEGERS = ("step", "node")


def _read_csv(path: Path) -> Tuple[List[str], List[List[str]]]:
    with open(path, newline="") as f:
        rows = list(csv.reader(f))
    return rows[0], rows[1:]


def _contact_table(columns: Dict[str, Any]) -> Dict[str, np.ndarray]:
    """contact.csv's columns as numpy arrays: int64 step and node, str status, float64 else."""
    out = {}
    for name, values in columns.items():
        if name == "status":
            out[name] = np.array(values, dtype=str)
        elif name in _CONTACT_INTEGERS:
            out[name] = np.asarray(values, dtype=np.float64).astype(np.int64)
        else:
            out[name] = np.asarray(values, dtype=np.float64)
    return out


class Result:
    """What ``dc.run`` returns: the run's tables, summary, mesh and frames.

    Attributes:
        history: dict of numpy float64 arrays, one per history.csv column (``t``,
            ``normal_force``, ``kinetic``, ..., counts as floats), one value per step from t = 0.
        contact: contact.csv as a dict of numpy arrays (``step`` and ``node`` int64, ``status``
            str, the rest float64): one row per Γ3 node of every stored frame.
        summary: summary.json as a dict (``status``, ``steps_completed``, ``model``,
            ``timing``, iteration totals, ``max_abs_energy_residual``, ``warnings``, ...; a run
            with ``out=None`` has no ``run_id``-based folder: ``effective_scene`` is None).
        out: the run folder, or None for a run that wrote nothing.
        frames: the stored frames as (step, t) pairs (every ``output.every`` steps and the last).
    """

    def __init__(self, history, contact, summary, mesh, frames, out=None, frame_fields=None):
        # a run with a folder reads history.csv and contact.csv when first asked for
        self._history = history
        self._contact = contact
        self.summary: Dict[str, Any] = summary
        self.out: Optional[Path] = out
        self.frames: List[Tuple[int, float]] = frames
        self._mesh = mesh
        self._frame_fields = frame_fields
        self._dim = int(mesh["dimension"])

    @property
    def history(self) -> Dict[str, np.ndarray]:
        """history.csv as a dict of float64 arrays, one per column (see the class)."""
        if callable(self._history):
            self._history = self._history()
        return self._history

    @property
    def contact(self) -> Dict[str, np.ndarray]:
        """contact.csv as a dict of numpy arrays (see the class)."""
        if callable(self._contact):
            self._contact = self._contact()
        return self._contact

    @property
    def mesh(self):
        """The reference configuration as a ``meshio.Mesh`` (points with 3 coordinates, z = 0 in
        2-D; ``triangle`` cells in 2-D, ``tetra`` in 3-D)."""
        import meshio

        return meshio.Mesh(self._mesh["points"], [(self._mesh["cell_type"], self._mesh["cells"])])

    def fields(self, i: int) -> Dict[str, np.ndarray]:
        """The fields of stored frame ``i`` (an index into ``frames``; -1 is the last) as a dict
        of numpy arrays: ``u``, ``v`` and ``friction`` shaped (nodes, d); ``contact_pressure``
        (q + λ), ``compliance_pressure`` (q), ``lambda`` and ``contact_status`` (0 separated,
        1 stick, 2 slip, 3 contact without friction, -1 off Γ3) per node; ``stress`` shaped
        (cells, 6) in VTK's order XX, YY, ZZ, XY, YZ, XZ. The values of the VTU frame."""
        if not self.frames:
            raise IndexError("this run stored no frames (output.every = 0)")
        n = len(self.frames)
        if not -n <= i < n:
            raise IndexError(
                f"frame {i} out of range: {n} stored frames (steps {self.frames[0][0]} … {self.frames[-1][0]}; "
                f"-1 is the last)"
            )
        step, _ = self.frames[i]
        if self._frame_fields is not None:
            f = self._frame_fields[i if i >= 0 else len(self.frames) + i]
            return {k: v for k, v in f.items() if k not in ("step", "t")}
        import meshio

        m = meshio.read(self.out / "frames" / f"frame_{step:05d}.vtu")
        d, p = self._dim, m.point_data
        return {
            "u": np.ascontiguousarray(p["displacement"][:, :d]),
            "v": np.ascontiguousarray(p["velocity"][:, :d]),
            "contact_pressure": p["contact_pressure"].reshape(-1),
            "compliance_pressure": p["compliance_pressure"].reshape(-1),
            "lambda": p["lambda"].reshape(-1),
            "friction": np.ascontiguousarray(p["friction"][:, :d]),
            "contact_status": p["contact_status"].reshape(-1),
            "stress": m.cell_data["stress"][0],
        }

    def frame(self, i: int):
        """Stored frame ``i`` as a ``meshio.Mesh``: the reference mesh with the frame's fields
        as point data (``displacement`` and ``velocity`` padded to 3 components, as in the VTU
        files) and ``stress`` as cell data; ``meshio.write`` it to any format meshio knows."""
        import meshio

        f = self.fields(i)
        pad = lambda a: np.pad(a, ((0, 0), (0, 3 - a.shape[1])))  # noqa: E731
        point_data = {
            "displacement": pad(f["u"]),
            "velocity": pad(f["v"]),
            "contact_pressure": f["contact_pressure"],
            "compliance_pressure": f["compliance_pressure"],
            "lambda": f["lambda"],
            "friction": pad(f["friction"]),
            "contact_status": f["contact_status"],
        }
        return meshio.Mesh(
            self._mesh["points"],
            [(self._mesh["cell_type"], self._mesh["cells"])],
            point_data=point_data,
            cell_data={"stress": [f["stress"]]},
        )

    def __repr__(self) -> str:
        n = len(next(iter(self.history.values()), ()))
        where = f", out={str(self.out)!r}" if self.out else ""
        return f"Result(scene={self.summary.get('scene')!r}, status={self.summary.get('status')!r}, rows={n}{where})"


def _scene(scene: Union[Scene, PathLike]) -> Scene:
    if isinstance(scene, Scene):
        return scene
    if not isinstance(scene, (str, os.PathLike)):
        raise TypeError(f"scene: expected a dyncontact.Scene or the path of a scene file, got {type(scene).__name__}")
    return Scene.from_file(os.fspath(scene))


def _jobs(jobs: Optional[int]) -> Optional[int]:
    if jobs is not None and (not isinstance(jobs, int) or isinstance(jobs, bool) or jobs < 1):
        raise ValueError(f"jobs: must be an integer >= 1 (or None: the number of cores), got {jobs!r}")
    return jobs


def run(
    scene: Union[Scene, PathLike],
    out: Optional[PathLike] = None,
    progress: bool = False,
    checkpoint_every: Optional[int] = None,
    _stop_after: Optional[int] = None,
) -> Result:
    """Run a scene to its end time and return a :class:`Result` (history, contact, summary,
    mesh, frames).

    Args:
        scene: a :class:`Scene` (or the path of a scene file).
        out: None (default): write nothing, keep everything in memory. A folder: write the run
            folder there exactly as ``dyncontact run SCENE --out OUT`` does (history.csv,
            contact.csv, frames/, series.pvd, summary.json, plots/, scene.toml, and checkpoint.json
            of the last step, so :func:`resume` with a later ``time.end`` extends the run) and
            read the results back from it.
        progress: show a progress bar (on a terminal).
        checkpoint_every: with ``out``, write OUT/checkpoint.json every N steps too.

    The run's warnings (summary.json's ``warnings``, which the CLI prints) are issued as
    :class:`DyncontactWarning`.

    Returns:
        Result: ``.history`` (dict of float64 arrays per history.csv column), ``.contact``,
        ``.summary`` (dict), ``.mesh`` (meshio.Mesh), ``.fields(i)``, ``.frame(i)``.

    Raises:
        SceneError: the scene is refused (``.key`` names the key).
        SolverError: a step failed (``.step``, ``.time``, ``.residuals``).
        KeyboardInterrupt: Ctrl-C; the run stops after its current step (with ``out``: the
            folder is valid up to that step and checkpoint.json holds it).
        OSError: the folder is not a run's to write, or an output cannot be written.

    The GIL is released while the solver runs. The history equals the CLI's bit for bit.
    """
    result = _run(scene, out, progress, checkpoint_every, _stop_after)
    _warn(result.summary)
    return result


def _run(scene, out, progress, checkpoint_every, _stop_after) -> Result:
    s = _scene(scene)
    if out is not None and os.fspath(out) == "":
        raise ValueError("out: an empty path; give the run's folder, or None to write nothing")
    if checkpoint_every is not None and (not isinstance(checkpoint_every, int) or checkpoint_every < 1):
        raise ValueError(f"checkpoint_every: must be an integer >= 1 (or None), got {checkpoint_every!r}")
    if out is None:
        r = _native.run_memory(s, progress)
        frames = [(int(f["step"]), float(f["t"])) for f in r["frames"]]
        return Result(
            r["history"], _contact_table(r["contact"]), json.loads(r["summary"]), r["mesh"], frames,
            frame_fields=r["frames"],
        )
    out = Path(out)
    r = _native.run_folder(s, os.fspath(out), progress, checkpoint_every, False, _stop_after)
    return _read_folder(out, r["mesh"])


def resume(
    out: PathLike,
    set: Optional[Dict[str, Any]] = None,
    progress: bool = False,
    checkpoint_every: Optional[int] = None,
) -> Result:
    """Continue the run in folder ``out`` from its checkpoint.json, as ``dyncontact run --resume
    OUT`` does: its scene is OUT/scene.toml (the effective scene the run wrote); ``set``
    ({"time.end": T} with a later T) extends a finished run. Returns the :class:`Result` of the
    whole run (its files hold every step from t = 0).

    Raises:
        OSError: the folder cannot be resumed (no checkpoint, files that do not belong
            together, other inputs, a completed run without a later time.end); nothing in it
            changed.
        and as :func:`run`.
    """
    out = Path(out)
    scene = Scene.from_file(os.fspath(out / "scene.toml"))
    if set:
        scene = scene.with_set(set)
    r = _native.run_folder(scene, os.fspath(out), progress, checkpoint_every, True, None)
    result = _read_folder(out, r["mesh"])
    _warn(result.summary)
    return result


class DyncontactWarning(UserWarning):
    """A warning of a run (summary.json's ``warnings``: what the CLI prints as ``warning: ...``),
    e.g. a time step beyond the (C.k) limit or fixed-point cap hits."""


def _warn(summary: Dict[str, Any]) -> None:
    import warnings

    for w in summary.get("warnings") or []:
        warnings.warn(w, DyncontactWarning, stacklevel=3)


def _read_history(out: Path) -> Dict[str, np.ndarray]:
    # float() of the shortest round-trip text gives back the f64 the run wrote
    header, rows = _read_csv(out / "history.csv")
    return {name: np.array([float(r[j]) for r in rows], dtype=np.float64) for j, name in enumerate(header)}


def _read_contact(out: Path) -> Dict[str, np.ndarray]:
    header, rows = _read_csv(out / "contact.csv")
    return _contact_table({name: [r[j] for r in rows] for j, name in enumerate(header)})


def _read_folder(out: Path, mesh) -> Result:
    history = lambda: _read_history(out)  # noqa: E731
    contact = lambda: _read_contact(out)  # noqa: E731
    summary = json.loads((out / "summary.json").read_text())
    frames = []
    pvd = out / "series.pvd"
    if pvd.is_file():
        for ds in ET.parse(pvd).getroot().iter("DataSet"):
            name = Path(ds.get("file", ""))
            frames.append((int(name.stem.split("_")[-1]), float(ds.get("timestep", "nan"))))
    return Result(history, contact, summary, mesh, frames, out=out)


def _value(text: str) -> Any:
    if text == "":
        return None
    try:
        return float(text)
    except ValueError:
        return text


def sweep(
    sweep: Union[PathLike, Dict[str, Any]],
    out: Optional[PathLike] = None,
    jobs: Optional[int] = None,
    set: Optional[Dict[str, Any]] = None,
    plan_only: bool = False,
    oversubscribe: bool = False,
    progress: bool = False,
) -> List[Dict[str, Any]]:
    """Run a sweep as ``dyncontact sweep SWEEP --out OUT --jobs N`` does and return sweep.csv's
    rows.

    Args:
        sweep: the path of a sweep file, or a dict of its tables (``{"name": ..., "base":
            "default", "axis": [{"key": "contact.penalty", "values": [...]}], "set": {...}}``;
            a relative ``base`` is read from the current folder).
        out: the sweep folder (default: out/<sweep name>); points already completed with the
            same scene are skipped.
        jobs: points run at once (default: the number of cores; more needs ``oversubscribe``).
        set: overrides of every point, ``{KEY: VALUE}`` as ``--set`` (after the sweep's own).
        plan_only: validate every point and write the folder without running (returns []).

    Returns:
        list of dict: one per point, sweep.csv's columns (``point``, the axes, ``status``,
        ``wall_time_s``, the figures); numbers as float, empty cells as None, and a column of
        axis labels that are not all numbers (``"exact"``, ``"1e-2"``) as text.

    Raises:
        SceneError: the sweep or a point's scene is refused.
        KeyboardInterrupt: Ctrl-C; running points stop after their step, finished ones stay.
    """
    if not isinstance(sweep, (dict, str, os.PathLike)):
        raise TypeError(f"sweep: expected the path of a sweep file or a dict of its tables, got {type(sweep).__name__}")
    target = sweep if isinstance(sweep, dict) else os.fspath(sweep)
    folder = None if out is None else os.fspath(out)
    path = _native.run_sweep(target, folder, _jobs(jobs), set, plan_only, oversubscribe, progress)
    if plan_only or not Path(path).is_file():
        return []
    with open(path, newline="") as f:
        rows = list(csv.DictReader(f))
    # a column of labels stays text when any of its labels is not a number ("exact", "1e-2")
    text = {k for row in rows for k, v in row.items() if v != "" and isinstance(_value(v), str)}
    # an empty cell is None in every column, text or number
    return [{k: (None if v == "" else v if k in text else _value(v)) for k, v in row.items()} for row in rows]


def refine(
    scene: Scene,
    levels: int = 3,
    ratio: float = 2.0,
    what: str = "both",
    windows: Optional[int] = None,
    out: Optional[PathLike] = None,
    jobs: Optional[int] = None,
    progress: bool = False,
) -> List[Dict[str, Any]]:
    """Solution verification as ``dyncontact refine SCENE --levels N --ratio R --what W
    --windows W --out OUT --jobs J`` does, and return refine.csv's rows.

    The scene (with its ``with_set`` overrides) runs on ``levels`` levels: level l has
    ``domain.cells`` times ``ratio**l`` in every direction (``what="h"``), ``time.step`` divided
    by ``ratio**l`` (``"k"``) or both (``"both"``). Every solution figure of sweep.csv and the
    contact impulses (``normal_impulse``, ``friction_impulse_x`` ... over the run and over
    ``windows`` equal windows, ``..._w1`` ...; default 4, or 3, 2, 1 when 4 does not divide the
    coarsest level's steps) get the observed order (G.1), Richardson's extrapolation (G.2) and
    the grid convergence index (G.3) from the three finest levels; the solver's costs
    (iterations, steps) have rows with their values per level and no estimate.

    Args:
        scene: the scene to refine (a rectangle or box with ``domain.cells``).
        out: the study's folder (default: out/<scene name>-refine); levels already completed
            with the same scene are not run again.
        jobs: levels run at once (default: the number of cores).

    Returns:
        list of dict: one per figure, refine.csv's columns (``figure``, ``level_0`` ...,
        ``order``, ``extrapolated``, ``gci``, ``asymptotic`` as bool, ``note``); numbers as
        float, empty cells as None.

    Raises:
        SceneError: the scene or an option is refused (``.key`` names it: ``domain.cells``,
            ``time.step``, ``--levels``, ``--windows`` ...).
        KeyboardInterrupt: Ctrl-C; running levels stop after their step, finished ones stay.
    """
    folder = None if out is None else os.fspath(out)
    path = _native.run_refine(_scene(scene), levels, ratio, what, windows, folder, _jobs(jobs), progress)
    with open(path, newline="") as f:
        rows = []
        for row in csv.DictReader(f):
            r: Dict[str, Any] = {k: (v if k in ("figure", "note") else _value(v)) for k, v in row.items()}
            r["asymptotic"] = row["asymptotic"] == "true"
            rows.append(r)
        return rows
