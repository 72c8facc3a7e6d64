"""dc.sweep: a sweep file and a dict, returning sweep.csv's rows, as `dyncontact sweep` does."""
import csv

import pytest

import dyncontact as dc

TIMING = {"wall_time_s"}


def test_sweep_file_equals_the_clis(root, cli, tmp_path, monkeypatch):
    monkeypatch.chdir(root)
    rows = dc.sweep("fixtures/sweeps/penalty.toml", out=tmp_path / "py", jobs=1, set={"time.end": 0.01})
    p = cli("sweep", "fixtures/sweeps/penalty.toml", "--out", tmp_path / "cli", "--jobs", "1", "--set", "time.end=0.01")
    assert p.returncode == 0, p.stderr
    with open(tmp_path / "cli" / "sweep.csv", newline="") as f:
        expected = list(csv.DictReader(f))
    assert len(rows) == len(expected) == 7
    # a column with a label that is not a number (eps: "exact", "1e-2", ...) stays text
    text = {k for row in expected for k, v in row.items() if v != "" and not _is_number(v)}
    assert "eps" in text
    for got, want in zip(rows, expected):
        assert got.keys() == want.keys()
        assert got["status"] == "completed"
        for k in got:
            if k not in TIMING:
                w = want[k]
                assert got[k] == (w if k in text else None if w == "" else float(w) if _is_number(w) else w), k


def _is_number(text):
    try:
        float(text)
        return True
    except ValueError:
        return False


def test_sweep_dict_and_errors(tmp_path):
    spec = {
        "name": "eps",
        "base": "default",
        "mode": "grid",
        "axis": [{"key": "contact.penalty", "values": [1e-3, 1e-4]}],
        "set": {"contact.enforcement": "penalty", "time.end": 0.01},
    }
    rows = dc.sweep(spec, out=tmp_path / "sw", jobs=1)
    assert [r["contact.penalty"] for r in rows] == [1e-3, 1e-4]
    assert all(r["status"] == "completed" and r["max_penetration"] is not None for r in rows)
    # a second call skips the completed points and returns the same figures
    again = dc.sweep(spec, out=tmp_path / "sw", jobs=1)
    assert [r["max_penetration"] for r in again] == [r["max_penetration"] for r in rows]
    bad = dict(spec, axis=[{"key": "contact.penaltyy", "values": [1e-3]}])
    with pytest.raises(dc.SceneError) as e:
        dc.sweep(bad, out=tmp_path / "bad", jobs=1)
    assert "penaltyy" in str(e.value) and e.value.key == "contact.penaltyy"


def test_a_sweep_written_from_python_runs_under_snakemake(tmp_path):
    """(Python, sweeps) The Snakefile of a sweep written by dc.sweep runs: config.yaml names this
    interpreter with ``-m dyncontact`` (the interpreter alone, what the process's executable is,
    cannot run ``sweep point``), and Snakemake run afresh in the folder reruns both points and
    collects a sweep.csv equal to the in-process one but for the wall times (the runs are
    deterministic: every figure the same text)."""
    import json
    import subprocess
    import sys

    # the cross-check's venv has it (xtask/crosscheck/requirements.txt); a plain
    # `pip install dyncontact[test]` does not (Snakemake 9 needs Python ≥ 3.11)
    pytest.importorskip("snakemake")
    spec = {
        "name": "eps",
        "base": "default",
        "axis": [{"key": "contact.penalty", "values": [1e-3, 1e-4]}],
        "set": {"contact.enforcement": "penalty", "time.end": 0.01},
    }
    out = tmp_path / "sw"
    dc.sweep(spec, out=out, jobs=1)
    config = (out / "config.yaml").read_text()
    line = next(l for l in config.splitlines() if l.startswith("dyncontact: "))
    assert json.loads(line[len("dyncontact: "):]) == [sys.executable, "-m", "dyncontact"], config
    with open(out / "sweep.csv", newline="") as f:
        in_process = list(csv.DictReader(f))
    # Snakemake reruns a point whose marker is gone, and the collector when sweep.csv is
    for marker in (out / "points").glob("*.done"):
        marker.unlink()
    (out / "sweep.csv").unlink()
    p = subprocess.run([sys.executable, "-m", "snakemake", "--cores", "1"], cwd=out, capture_output=True, text=True)
    assert p.returncode == 0, p.stdout + p.stderr
    assert len(list((out / "points").glob("*.done"))) == 2
    with open(out / "sweep.csv", newline="") as f:
        by_snakemake = list(csv.DictReader(f))
    assert len(by_snakemake) == len(in_process) == 2
    for got, want in zip(by_snakemake, in_process):
        assert got["status"] == "completed"
        assert {k: v for k, v in got.items() if k not in TIMING} == {k: v for k, v in want.items() if k not in TIMING}


def test_a_column_of_labels_stays_text(tmp_path):
    """An axis labelled "exact", "1e-2" keeps its labels as text in every row (not 0.01 beside
    "exact"); numeric columns stay floats."""
    spec = {
        "name": "labels",
        "base": "default",
        "axis": [{
            "name": "eps",
            "sets": [{"contact.enforcement": "exact"},
                     {"contact.enforcement": "penalty", "contact.penalty": 1e-2}],
            "labels": ["exact", "1e-2"],
        }],
        "set": {"time.end": 0.01, "domain.cells": [8, 4]},
    }
    rows = dc.sweep(spec, out=tmp_path / "sw", jobs=1)
    assert [r["eps"] for r in rows] == ["exact", "1e-2"]
    assert all(isinstance(r["max_penetration"], float) for r in rows)


def test_an_empty_cell_is_none_in_a_text_column(tmp_path):
    """A failed point gives `reason` text, so the column is text; the completed point's empty
    reason is None there too (it was '' beside None in sweeps without a failure)."""
    spec = {
        "name": "fail",
        "base": "default",
        "axis": [{"key": "solver.max_newton_iterations", "values": [1, 50]}],
        "set": {"domain.cells": [8, 4], "time.end": 0.3, "solver.newton_tolerance": 1e-15},
    }
    rows = dc.sweep(spec, out=tmp_path / "sw", jobs=1)
    statuses = [r["status"] for r in rows]
    assert "failed" in statuses, statuses
    for r in rows:
        assert (r["reason"] is None) == (r["status"] == "completed"), r
