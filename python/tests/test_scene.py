"""dc.Scene: the constructors, with_set by --set's rules, check, and bad scenes raising
SceneError with the key and the command line's message."""
import pytest

import dyncontact as dc

ACADEMIC = "fixtures/scenes/academic.toml"


def test_default_and_from_file(root, monkeypatch):
    monkeypatch.chdir(root)
    s = dc.Scene.default()
    assert s.name == "academic" and s.source == "<embedded academic scene>" and s.overrides == []
    f = dc.Scene.from_file(ACADEMIC)
    assert f.source == ACADEMIC
    assert dc.Scene.from_file(root / "fixtures/scenes/academic3d.toml").check()["dimension"] == 3


def test_from_toml_and_from_dict_equal_the_default():
    a = dc.Scene.from_toml(dc.DEFAULT_SCENE)
    assert a.to_toml() == dc.DEFAULT_SCENE
    tomllib = pytest.importorskip("tomllib")  # Python >= 3.11
    d = dc.Scene.from_dict(tomllib.loads(dc.DEFAULT_SCENE)).with_set({"time.end": 0.01})
    ref = dc.run(dc.Scene.default().with_set({"time.end": 0.01}))
    assert d.source == "<dict>"
    for name, column in dc.run(d).history.items():
        assert column.tobytes() == ref.history[name].tobytes(), name


def test_with_set_follows_set(root, cli):
    s = dc.Scene.default().with_set({"contact.compliance": 2000.0, "time.end": 0.3})
    assert s.overrides == ["contact.compliance=2000.0", "time.end=0.3"]
    assert "compliance = 2000.0" in s.to_toml()
    # a str value is the text after `=`: TOML when it reads as TOML, else a string
    t = dc.Scene.default().with_set({"domain.cells": "[8, 4]", "time.scheme": "trapezoid"})
    assert t.check()["nodes"] == 9 * 5 and 'scheme = "trapezoid"' in t.to_toml()
    assert dc.Scene.default().with_set(["domain.cells=[8,4]"]).check()["nodes"] == 45
    # with_set returns a new scene
    assert dc.Scene.default().overrides == []


def test_check_reports_sizes_and_limit():
    info = dc.Scene.default().check()
    assert info["dimension"] == 2 and info["nodes"] == 561 and info["triangles"] == 1024
    assert info["fits"] is True
    assert info["ck_step_limit"] == pytest.approx(3.4722e-4, rel=1e-4)
    assert info["memory_estimate_bytes"] > 0 and any("memory" in line for line in info["lines"])
    assert isinstance(info["memory_estimate_bytes"], int) and isinstance(info["output_estimate_bytes"], int)
    # the time-dependent tractions are checked at each of the 2000 times the steps sample them
    assert "loads          : finite at each of the 2000 times the steps sample them" in info["lines"]


def test_check_refuses_a_load_infinite_at_a_load_time_only():
    """1/(t - 0.00075) is finite at t = 0, T and every t_n of k = 5e-4, infinite at the load
    time t_1 + k/2 of the second step: check() raises as `dyncontact check` exits 1."""
    s = dc.Scene.default().with_set({"loads.body": ["0", "1/(t-0.00075)"]})
    with pytest.raises(dc.SceneError) as e:
        s.check()
    assert e.value.key == "loads.body" and "t = 0.00075" in str(e.value)
    # run() and Simulation() refuse it before the first step, as `dyncontact run` does
    for start in (dc.run, dc.Simulation):
        with pytest.raises(dc.SceneError) as e:
            start(s)
        assert e.value.key == "loads.body" and "t = 0.00075" in str(e.value)


def test_numpy_values_are_toml_values():
    """numpy arrays and scalars set keys as the lists and numbers they hold."""
    import numpy as np

    a = dc.Scene.default().with_set({"domain.cells": np.array([8, 4]), "time.end": np.float64(0.1)})
    b = dc.Scene.default().with_set({"domain.cells": [8, 4], "time.end": 0.1})
    assert a.to_toml() == b.to_toml()


BAD = [
    {"contact.compliancee": 1.0},          # an unknown key
    {"material.young": -1.0},              # a value out of range
    {"time.end": "soon"},                  # a wrong type (a string where a number goes)
    {"contact.friction.law": "magic"},     # an unknown variant
    {"domain.cells": [8]},                 # a wrong length
    {"contact..compliance": 1.0},          # not a key path
]


@pytest.mark.parametrize("values", BAD, ids=[next(iter(b)) for b in BAD])
def test_with_set_errors_are_the_clis(root, cli, monkeypatch, values):
    monkeypatch.chdir(root)
    ((key, value),) = values.items()
    text = value if isinstance(value, str) else repr(value).replace("'", '"')
    p = cli("check", ACADEMIC, "--set", f"{key}={text}")
    assert p.returncode == 1, p.stderr
    expected = p.stderr.splitlines()[0]
    assert expected.startswith("error: ")
    with pytest.raises(dc.SceneError) as e:
        dc.Scene.from_file(ACADEMIC).with_set(values)
    assert isinstance(e.value, ValueError)
    assert "error: " + str(e.value) == expected
    if key != "contact..compliance":
        assert e.value.key is not None and e.value.key.startswith(key.split(".")[0])
    else:
        assert e.value.key == key


def test_bad_scene_file_names_the_key(tmp_path):
    bad = dc.DEFAULT_SCENE.replace("[material]", "[material]\nyoungg = 3.0", 1)
    with pytest.raises(dc.SceneError) as e:
        dc.Scene.from_toml(bad, name="bad.toml")
    assert e.value.key == "material.youngg" and "unknown field `youngg`" in str(e.value)
    with pytest.raises(dc.SceneError) as e:
        dc.Scene.from_toml("[domain\n", name="broken.toml")
    assert e.value.key is None and str(e.value).startswith("broken.toml: TOML parse error")
    with pytest.raises(dc.SceneError):
        dc.Scene.from_file(tmp_path / "missing.toml")


def test_a_dotted_key_in_from_dict_is_named():
    """from_dict takes tables: a with_set key given to it is refused naming it and the fix."""
    d = {"name": "x", "domain": {"kind": "rectangle", "size": [2.0, 1.0], "cells": [8, 4]},
         "material": {"density": 1.0, "young": 1000.0, "poisson": 0.3},
         "time": {"end": 0.01, "step": 1e-3}, "contact.compliance": 5.0}
    with pytest.raises(dc.SceneError) as e:
        dc.Scene.from_dict(d)
    assert e.value.key == "contact.compliance" and "with_set" in str(e.value)


def test_numpy_values_keep_their_kind_and_floats_their_text():
    """A size-1 array stays a list, np.bool_ a bool, and floats in lists keep their shortest text."""
    import numpy as np

    s = dc.Scene.default().with_set({"domain.cells": np.array([8]).tolist() + [4]})
    assert "cells = [8, 4]" in s.to_toml()
    s = dc.Scene.default().with_set({"output.trajectory": np.bool_(True)})
    assert s.overrides[-1] == "output.trajectory=true"
    s = dc.Scene.default().with_set({"domain.size": [np.float64(2.0), 1e-300]})
    assert s.overrides[-1] == "domain.size=[2.0, 1e-300]"


def test_a_scene_pickles():
    """A scene crosses process boundaries (multiprocessing): pickled and read back it is the
    same scene, overrides and all."""
    import pickle

    s = dc.Scene.default().with_set({"time.end": 0.02, "domain.cells": [8, 4]})
    back = pickle.loads(pickle.dumps(s))
    assert back.to_toml() == s.to_toml() and back.overrides == s.overrides and back.source == s.source


def test_an_int_beyond_i64_names_the_range():
    """A Python int beyond TOML's i64 arrives as a float: at a whole-number key the error names
    the range; at a real key it is the float it means."""
    with pytest.raises(dc.SceneError) as e:
        dc.Scene.default().with_set({"output.every": 10**20}).check()
    assert e.value.key == "output.every" and "9223372036854775807" in str(e.value)
    assert dc.Scene.default().with_set({"material.young": 10**20}).check()["fits"] is True



def test_check_of_a_scene_too_large_still_gives_its_sizes(root):
    """A 400³ box would not fit: check() gives the estimate's sizes (counted without building
    the mesh: 401³ nodes, 6 · 400³ tetrahedra) and says why there is no (C.k) limit."""
    big = dc.Scene.from_file(root / "fixtures/scenes/academic3d.toml").with_set({"domain.cells": [400, 400, 400]})
    info = big.check()
    assert info["fits"] is False and info["refused"]
    assert info["nodes"] == 401**3 and info["tetrahedra"] == 6 * 400**3
    assert info["velocity_unknowns"] == 3 * 401**3 and info["contact_nodes"] > 0
    assert info["ck_step_limit"] is None and "not computed" in info["ck_note"]
