"""Shared fixtures of the Python package's tests: the repository root and the CLI binary (the
test build's, given by `cargo xtask verify` in DYNCONTACT_BIN, else target/{debug,release})."""
import os
import subprocess
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[2]


def cli_binary():
    given = os.environ.get("DYNCONTACT_BIN")
    if given:
        return Path(given)
    for profile in ("debug", "release"):
        p = ROOT / "target" / profile / "dyncontact"
        if p.is_file():
            return p
    return None


@pytest.fixture(scope="session")
def root():
    return ROOT


@pytest.fixture(scope="session")
def cli():
    """Run the dyncontact CLI from the repository root: cli(*args) -> CompletedProcess."""
    binary = cli_binary()
    if binary is None:
        pytest.fail("no dyncontact binary: build it (cargo build) or set DYNCONTACT_BIN")

    def run(*args):
        return subprocess.run([str(binary), *map(str, args)], cwd=ROOT, capture_output=True, text=True)

    return run
