"""The command line from the package: ``python -m dyncontact`` and the ``dyncontact`` console
script run the CLI's own code, so they print what the built CLI prints and exit with its codes."""
import subprocess
import sys
import sysconfig
from pathlib import Path


def module(*args, cwd=None):
    return subprocess.run([sys.executable, "-m", "dyncontact", *map(str, args)], cwd=cwd, capture_output=True,
                          text=True)


def test_python_m_dyncontact_is_the_cli(root, cli):
    """(Python) `check` of a fixture prints the CLI's report line for line; --version exits 0;
    a wrong command line exits 64 and a refused scene 1, as the CLI does."""
    scene = root / "fixtures" / "scenes" / "academic3d.toml"
    got, want = module("check", scene, cwd=root), cli("check", scene)
    assert (got.returncode, want.returncode) == (0, 0), got.stderr + want.stderr
    assert got.stdout == want.stdout
    assert module("--version").returncode == 0
    assert module("run", "--bogus").returncode == cli("run", "--bogus").returncode == 64
    bad = module("check", scene, "--set", "domain.cells=[0,1,1]", cwd=root)
    assert bad.returncode == 1 and "domain.cells" in bad.stderr, bad.stderr


def test_a_run_from_python_m_equals_the_clis(root, cli, tmp_path):
    """(Python) `run` through the package writes the CLI's history.csv bit for bit (the same
    code; the default scene to t = 0.02 s)."""
    got = module("run", "--set", "time.end=0.02", "--out", tmp_path / "py", cwd=root)
    want = cli("run", "--set", "time.end=0.02", "--out", tmp_path / "cli")
    assert (got.returncode, want.returncode) == (0, 0), got.stderr + want.stderr
    assert (tmp_path / "py" / "history.csv").read_bytes() == (tmp_path / "cli" / "history.csv").read_bytes()


def test_the_console_script_is_installed():
    """(Python) pip installs a `dyncontact` command beside the interpreter's scripts; it runs the
    CLI (its --version names the package's version)."""
    import dyncontact as dc

    script = Path(sysconfig.get_path("scripts")) / "dyncontact"
    assert script.is_file(), script
    p = subprocess.run([script, "--version"], capture_output=True, text=True)
    assert p.returncode == 0 and dc.__version__ in p.stdout, p.stdout + p.stderr


def test_ctrl_c_stops_a_run_from_python_m_as_the_clis(root, tmp_path):
    """(Python) SIGINT to `python -m dyncontact run` reaches the CLI's own handling (Python's
    is set aside): the run stops after its step, exit 130, summary `interrupted` with the steps
    done, checkpoint.json written — not a KeyboardInterrupt traceback. The run lasts to
    t = 1000 s; the signal goes once history.csv has 50 rows."""
    import json
    import signal
    import time

    out = tmp_path / "run"
    p = subprocess.Popen([sys.executable, "-m", "dyncontact", "run", "--set", "time.end=1000", "--set",
                          "output.every=0", "--out", str(out)], cwd=root, stdout=subprocess.PIPE,
                         stderr=subprocess.PIPE, text=True)
    try:
        start = time.monotonic()
        history = out / "history.csv"
        while not (history.is_file() and history.read_text().count("\n") > 50):
            assert p.poll() is None and time.monotonic() - start < 120, "the run ended or never wrote 50 rows"
            time.sleep(0.01)
        p.send_signal(signal.SIGINT)
        _, err = p.communicate(timeout=120)
    finally:
        if p.poll() is None:
            p.kill()
    assert p.returncode == 130, err
    assert "KeyboardInterrupt" not in err, err
    summary = json.loads((out / "summary.json").read_text())
    assert summary["status"] == "interrupted" and summary["steps_completed"] >= 49, summary
    assert (out / "checkpoint.json").is_file()
