"""dc.run, dc.Simulation: the results' contents, bit-identical histories against the CLI (2-D and
3-D), a solver failure as SolverError, Ctrl-C as KeyboardInterrupt after the checkpoint, and the
GIL released while the solver runs."""
import csv
import json
import os
import signal
import threading
import time

import meshio
import numpy as np
import pytest

import dyncontact as dc

SHORT = {"time.end": 0.05}


def read_csv(path):
    with open(path, newline="") as f:
        rows = list(csv.reader(f))
    return rows[0], rows[1:]


def test_run_in_memory_has_every_item():
    scene = dc.Scene.default().with_set(SHORT)
    res = dc.run(scene, out=None, progress=False)
    assert res.out is None
    assert list(res.history) == dc.history_columns()
    for name, col in res.history.items():
        assert col.dtype == np.float64 and col.shape == (101,), name
    assert res.history["t"][0] == 0.0 and res.history["t"][-1] == pytest.approx(0.05)
    assert res.history["normal_force"].max() > 0
    assert res.summary["status"] == "completed" and res.summary["steps_completed"] == 100
    assert res.summary["scene_file"] == "<embedded academic scene>" and res.summary["overrides"] == ["time.end=0.05"]
    # contact.csv: one row per Γ3 node of every stored frame (every 10 steps: 11 frames)
    assert [s for s, _ in res.frames] == list(range(0, 101, 10))
    assert res.contact["node"].dtype == np.int64 and res.contact["status"].dtype.kind == "U"
    assert len(res.contact["step"]) == 11 * 32 and set(res.contact["status"]) <= {"separated", "stick", "slip"}
    mesh = res.mesh
    assert isinstance(mesh, meshio.Mesh) and mesh.points.shape == (561, 3) and mesh.cells[0].type == "triangle"
    f = res.fields(-1)
    assert f["u"].shape == (561, 2) and f["v"].shape == (561, 2) and f["stress"].shape == (1024, 6)
    assert f["contact_status"].shape == (561,) and np.abs(f["u"]).max() > 0
    assert res.fields(0)["u"].max() == 0.0
    assert isinstance(res.frame(-1), meshio.Mesh)


def test_run_with_out_writes_the_clis_folder(tmp_path, cli):
    scene = dc.Scene.default().with_set(SHORT)
    res = dc.run(scene, out=tmp_path / "py")
    p = cli("run", "--set", "time.end=0.05", "--out", tmp_path / "cli")
    assert p.returncode == 0, p.stderr
    for name in ("history.csv", "contact.csv", "scene.toml"):
        assert (tmp_path / "py" / name).read_bytes() == (tmp_path / "cli" / name).read_bytes(), name
    ref = dc.run(scene)
    for name, col in ref.history.items():
        assert res.history[name].tobytes() == col.tobytes(), name
    for name, col in ref.contact.items():
        assert np.array_equal(res.contact[name], col), name
    assert res.frames == ref.frames
    for i in (0, -1):
        a, b = res.fields(i), ref.fields(i)
        assert a.keys() == b.keys()
        for k in a:
            assert np.array_equal(a[k], b[k]), (i, k)
    assert res.summary["status"] == "completed" and res.summary["effective_scene"] == "scene.toml"


# hertz and column_impact3d hold exact zeros of negative sign in memory (the compliance energy at
# t = 0, max_penetration and contact components at some steps); the files write them `0`
@pytest.mark.parametrize(
    "scene,sets",
    [
        ("fixtures/scenes/academic.toml", {"time.end": 0.05}),
        ("fixtures/scenes/academic3d.toml", {"time.end": 0.01}),
        ("fixtures/scenes/hertz.toml", {"domain.cells": [16, 8], "time.end": 0.05}),
        ("fixtures/scenes/column_impact3d.toml", {"domain.cells": [10, 1, 1], "time.end": 0.3}),
        ("fixtures/scenes/academic.toml", {"domain.plane": "stress", "time.end": 0.05}),
    ],
    ids=["2d", "3d", "hertz-signed-zeros", "column3d-signed-zeros", "2d-plane-stress-eps-zz"],
)
def test_history_equals_the_clis_bit_for_bit(root, cli, tmp_path, monkeypatch, scene, sets):
    monkeypatch.chdir(root)
    args = [a for k, v in sets.items() for a in ("--set", f"{k}={v}".replace(" ", ""))]
    p = cli("run", scene, *args, "--out", tmp_path / "cli")
    assert p.returncode == 0, p.stderr
    header, rows = read_csv(tmp_path / "cli" / "history.csv")
    res = dc.run(dc.Scene.from_file(scene).with_set(sets))
    assert list(res.history) == header
    for j, name in enumerate(header):
        expected = np.array([float(r[j]) for r in rows], dtype=np.float64)
        assert res.history[name].tobytes() == expected.tobytes(), name
    header, rows = read_csv(tmp_path / "cli" / "contact.csv")
    assert list(res.contact) == header
    for j, name in enumerate(header):
        got = res.contact[name]
        expected = [r[j] for r in rows]
        if name == "status":
            assert list(got) == expected
        else:
            want = np.array([float(x) for x in expected]).astype(got.dtype)
            assert got.tobytes() == want.tobytes(), name


def test_plane_stress_fields_are_the_frames_stress(tmp_path):
    """(Python) In plane stress with the template's θ = 2, ζ = 1.5 (not proportional to the
    elasticity: ε_zz is a variable per triangle), `fields(i)["stress"]` is the frame's stress as
    written, value for value (both read ε_zz), with σ_zz = 0; it is not plane strain's."""
    scene = dc.Scene.default().with_set({"domain.plane": "stress", "time.end": 0.05})
    res = dc.run(scene, out=tmp_path / "py", progress=False)
    step = res.frames[-1][0]
    frame = meshio.read(tmp_path / "py" / "frames" / f"frame_{step:05d}.vtu")
    stress = res.fields(-1)["stress"]
    assert np.array_equal(frame.cell_data["stress"][0], stress)
    assert np.all(stress[:, 2] == 0.0) and np.abs(stress[:, 0]).max() > 0
    strain = dc.run(dc.Scene.default().with_set({"time.end": 0.05}), out=None, progress=False)
    assert not np.allclose(strain.fields(-1)["stress"][:, :2], stress[:, :2])


def test_simulation_takes_a_scene_file_as_run_does(root):
    path = root / "fixtures/scenes/academic.toml"
    sim = dc.Simulation(str(path))
    assert sim.dimension == 2 and sim.n_steps == 2000
    assert dc.Simulation(path).n_steps == 2000
    with pytest.raises(TypeError):
        dc.Simulation(3)


def test_simulation_steps_are_the_run(root):
    scene = dc.Scene.default().with_set({"time.end": 0.02})
    ref = dc.run(scene)
    sim = dc.Simulation(scene)
    assert sim.n_steps == 40 and sim.step_index == 0 and sim.dimension == 2
    first = sim.initial_record()
    assert first.t == 0.0 and first.u.shape == (561, 2)
    records = list(sim.steps())
    assert [r.step for r in records] == list(range(1, 41))
    assert sim.step_index == 40 and sim.step() is None
    t = np.array([first.t] + [r.t for r in records])
    force = np.array([first.normal_force] + [r.normal_force for r in records])
    assert t.tobytes() == ref.history["t"].tobytes()
    assert force.tobytes() == ref.history["normal_force"].tobytes()
    # the record of t = 0 after the steps is still t = 0's
    again = sim.initial_record()
    assert again.t == 0.0 and np.array_equal(again.u, first.u) and again.history == first.history
    last = records[-1]
    assert last.u.shape == (561, 2) and last.v.shape == (561, 2)
    assert np.array_equal(last.u, ref.fields(-1)["u"]) and np.array_equal(last.v, ref.fields(-1)["v"])
    for name, x in last.history.items():
        assert x == ref.history[name][-1], name
    assert set(last.energy) >= {"kinetic", "elastic", "energy_residual"}


FAILING = {"time.end": 0.05, "solver.max_newton_iterations": 1}


def test_solver_failure_is_a_solver_error(cli, tmp_path):
    p = cli("run", "--set", "time.end=0.05", "--set", "solver.max_newton_iterations=1", "--out", tmp_path / "cli")
    assert p.returncode == 2
    scene = dc.Scene.default().with_set(FAILING)
    with pytest.raises(dc.SolverError) as e:
        dc.run(scene)
    err = e.value
    assert isinstance(err, RuntimeError)
    assert "error: " + str(err) == p.stderr.splitlines()[0]
    assert err.step == 2 and err.time == pytest.approx(1e-3)
    r = err.residuals
    assert r["kind"] == "solver" and r["solver"] == "newton" and r["iterations"] == 1 and r["inner_residual"] > 0
    # with a folder: the files of the steps before stay, summary.json says failed
    with pytest.raises(dc.SolverError):
        dc.run(scene, out=tmp_path / "py")
    summary = json.loads((tmp_path / "py" / "summary.json").read_text())
    assert summary["status"] == "failed" and summary["steps_completed"] == 1
    # the time loop raises at the same step and ends
    sim = dc.Simulation(scene)
    steps = sim.steps()
    assert next(steps).step == 1
    with pytest.raises(dc.SolverError) as e:
        next(steps)
    assert e.value.step == 2
    with pytest.raises(StopIteration):
        next(steps)


def test_energy_guard_failure():
    scene = dc.Scene.default().with_set(
        {"time.end": 0.01, "solver.energy_residual_limit": 1e-30, "solver.energy_residual_action": "fail"}
    )
    with pytest.raises(dc.SolverError) as e:
        dc.run(scene)
    assert e.value.step == 1 and e.value.residuals["energy_residual_limit"] == 1e-30


def test_ctrl_c_raises_keyboard_interrupt_after_the_checkpoint(tmp_path):
    scene = dc.Scene.default().with_set({"time.end": 100.0})  # far longer than the test waits
    out = tmp_path / "run"
    timer = threading.Timer(1.0, lambda: os.kill(os.getpid(), signal.SIGINT))
    timer.start()
    start = time.monotonic()
    with pytest.raises(KeyboardInterrupt) as e:
        dc.run(scene, out=out)
    timer.cancel()
    assert time.monotonic() - start < 30
    assert "checkpoint.json holds it" in str(e.value)
    summary = json.loads((out / "summary.json").read_text())
    assert summary["status"] == "interrupted"
    checkpoint = json.loads((out / "checkpoint.json").read_text())
    assert checkpoint["step"] == summary["steps_completed"] > 0
    # in memory: the same stop, without a folder (and without a word of a checkpoint)
    timer = threading.Timer(0.5, lambda: os.kill(os.getpid(), signal.SIGINT))
    timer.start()
    with pytest.raises(KeyboardInterrupt) as e:
        dc.run(scene)
    timer.cancel()
    assert "nothing was written" in str(e.value) and "checkpoint" not in str(e.value)


def test_an_exception_of_the_users_signal_handler_is_raised_as_it_is():
    """A SIGALRM handler that raises TimeoutError stops the run with TimeoutError, not a
    KeyboardInterrupt."""
    scene = dc.Scene.default().with_set({"time.end": 100.0})

    def on_alarm(signum, frame):
        raise TimeoutError("the user's deadline")

    previous = signal.signal(signal.SIGALRM, on_alarm)
    try:
        signal.setitimer(signal.ITIMER_REAL, 0.5)
        with pytest.raises(TimeoutError, match="the user's deadline"):
            dc.run(scene)
    finally:
        signal.setitimer(signal.ITIMER_REAL, 0)
        signal.signal(signal.SIGALRM, previous)


def test_bad_arguments_are_named():
    """Wrong types and values of run's arguments are refused naming the argument; a bad frame
    index names the frames there are."""
    with pytest.raises(TypeError, match="dyncontact.Scene"):
        dc.run(3)
    with pytest.raises(ValueError, match="out"):
        dc.run(dc.Scene.default().with_set({"time.end": 0.01}), out="")
    with pytest.raises(ValueError, match="jobs"):
        dc.sweep({"name": "b", "base": "default", "axis": [{"key": "time.end", "values": [0.01]}]}, jobs=-1)
    res = dc.run(dc.Scene.default().with_set({"time.end": 0.01, "domain.cells": [8, 4]}))
    n = len(res.frames)
    assert np.array_equal(res.fields(-n)["u"], res.fields(0)["u"])
    with pytest.raises(IndexError, match=f"frame {n} out of range: {n} stored frames"):
        res.fields(n)


def test_the_gil_is_released_while_the_solver_runs():
    # the whole default run (2,000 steps, ~0.4 s here): long enough for tens of ticks on a
    # machine several times faster (0.25 s of it took ~0.1 s, the bound a faster one could miss)
    scene = dc.Scene.default()
    ticks = []
    done = threading.Event()

    def count():
        while not done.is_set():
            ticks.append(time.monotonic())
            time.sleep(0.005)

    thread = threading.Thread(target=count)
    thread.start()
    start = time.monotonic()
    try:
        dc.run(scene)
    finally:
        end = time.monotonic()
        done.set()
        thread.join()
    during = [t for t in ticks if start < t < end]
    # a call holding the GIL for the whole run would leave the thread at most one tick; one
    # releasing it leaves about one per 5 ms (fewer on a loaded machine): 10 is ≥ 50 ms of run
    assert len(during) >= 10, (len(during), end - start)


def test_stop_and_resume_equal_a_straight_run(tmp_path):
    scene = dc.Scene.default().with_set(SHORT)
    with pytest.raises(KeyboardInterrupt):
        dc.run(scene, out=tmp_path / "r", _stop_after=40)  # the CLI's --stop-after, as a Ctrl-C after step 40
    summary = json.loads((tmp_path / "r" / "summary.json").read_text())
    assert summary["status"] == "interrupted" and summary["steps_completed"] == 40
    res = dc.resume(tmp_path / "r")
    assert res.summary["status"] == "completed" and res.history["step"][-1] == 100
    dc.run(scene, out=tmp_path / "s")
    for name in ("history.csv", "contact.csv"):
        assert (tmp_path / "r" / name).read_bytes() == (tmp_path / "s" / name).read_bytes(), name
    with pytest.raises(OSError, match="nothing to resume"):
        dc.resume(tmp_path / "s")  # completed, and no later time.end
    # a completed run extends with a later time.end: as a straight run to it
    ext = dc.resume(tmp_path / "s", set={"time.end": 0.08})
    assert ext.summary["status"] == "completed" and ext.history["step"][-1] == 160
    dc.run(dc.Scene.default().with_set({"time.end": 0.08}), out=tmp_path / "t")
    assert (tmp_path / "s" / "history.csv").read_bytes() == (tmp_path / "t" / "history.csv").read_bytes()


def test_run_warnings_are_python_warnings():
    # k = 1e-3 exceeds (C.k) (3.47e-4) and its sharp form (Ck.1) (~5.8e-4), so the run warns
    with pytest.warns(dc.DyncontactWarning, match=r"\(C\.k\) limit"):
        res = dc.run(dc.Scene.default().with_set({"time.end": 0.005, "time.step": 1e-3}))
    assert any("(C.k) limit" in w for w in res.summary["warnings"])
