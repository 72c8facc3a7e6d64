"""dc.refine: the same refinement study as `dyncontact refine` (the same library), refine.csv's
rows as dicts, and its refusals as SceneError with the key named.

The B.2 compliant layer is refined as the README's example does (25/50/100 cells, k = 1e-3 …
2.5e-4, t = 0.04): the rows must equal the CLI's refine.csv field for field (no timing column),
and the penetration must be asymptotic with an order near 1 (h and k refined together)."""
import csv

import pytest

import dyncontact as dc

LAYER = {"domain.cells": [25, 1], "time.step": 1e-3, "time.end": 0.04}


def test_refine_equals_the_clis_refine_csv(root, cli, tmp_path):
    scene = dc.Scene.from_file(root / "fixtures/scenes/compliant_layer.toml").with_set(LAYER)
    rows = dc.refine(scene, out=tmp_path / "py", jobs=1)
    p = cli("refine", "fixtures/scenes/compliant_layer.toml", "--set", "domain.cells=[25,1]", "--set",
            "time.step=1e-3", "--set", "time.end=0.04", "--out", tmp_path / "cli", "--jobs", "1")
    assert p.returncode == 0, p.stderr
    with open(tmp_path / "cli" / "refine.csv", newline="") as f:
        expected = list(csv.DictReader(f))
    assert [r["figure"] for r in rows] == [r["figure"] for r in expected]
    for got, want in zip(rows, expected):
        assert got.keys() == want.keys()
        for k, w in want.items():
            if k == "asymptotic":
                assert got[k] == (w == "true"), (got["figure"], k)
            elif k in ("figure", "note"):
                assert got[k] == w, (got["figure"], k)
            else:
                assert got[k] == (None if w == "" else float(w)), (got["figure"], k)
    pen = next(r for r in rows if r["figure"] == "max_penetration")
    # measured 1.07 (README): P1 and the joint refinement give order 1 in h
    assert pen["asymptotic"] and 0.5 <= pen["order"] <= 2.0, pen
    assert any(r["figure"] == "normal_impulse_w4" for r in rows)


def test_refine_refusals_name_the_key(root, tmp_path):
    gmsh = dc.Scene.from_file(root / "fixtures/scenes/gmsh_square.toml")
    with pytest.raises(dc.SceneError) as e:
        dc.refine(gmsh, out=tmp_path / "g")
    assert e.value.key == "domain.file"
    layer = dc.Scene.from_file(root / "fixtures/scenes/compliant_layer.toml").with_set(LAYER)
    with pytest.raises(dc.SceneError) as e:
        dc.refine(layer, windows=3, out=tmp_path / "w")
    assert e.value.key == "--windows" and "40" in str(e.value)
    with pytest.raises(dc.SceneError) as e:
        dc.refine(layer, what="x", out=tmp_path / "x")
    assert e.value.key == "--what"  # as --windows, --levels, --ratio: the CLI option names
