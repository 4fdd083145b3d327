"""Shared fixtures of the Python module's tests: the source tree's data and the built apps."""
import os
import subprocess
from pathlib import Path

import pytest

SOURCE = Path(os.environ.get("GEOHAZ_SOURCE_DIR", Path(__file__).resolve().parents[2]))
BIN = Path(os.environ.get("GEOHAZ_BIN_DIR_BUILD", SOURCE / "build" / "apps"))


@pytest.fixture
def data():
    return SOURCE / "data"


def app(name, *args, cwd=None):
    """Run a built app; returns the CompletedProcess (text)."""
    return subprocess.run([str(BIN / name / name), *map(str, args)], capture_output=True, text=True, cwd=cwd)


def app_error(proc, name):
    """The message after '<app>: input error: ' on the app's stderr."""
    assert proc.returncode == 2, (proc.returncode, proc.stderr)
    line = proc.stderr.strip().splitlines()[-1]
    prefix = f"{name}: input error: "
    assert line.startswith(prefix), line
    return line[len(prefix):]
