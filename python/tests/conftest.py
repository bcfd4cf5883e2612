"""Shared fixtures of the Python tests: the repository, the CLI binary, a scratch folder."""
import os
import subprocess
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[2]


@pytest.fixture(scope="session")
def root():
    return ROOT


@pytest.fixture(scope="session")
def woven_bin():
    exe = Path(os.environ.get("WOVEN_BINARY", ROOT / "build" / "woven"))
    if not exe.exists():
        pytest.fail(f"the woven binary {exe} is missing (build it, or set WOVEN_BINARY)")
    return exe


@pytest.fixture(scope="session")
def cli(woven_bin):
    def run(*args):
        return subprocess.run([str(woven_bin), *map(str, args)], check=True, capture_output=True, text=True).stdout
    return run
