"""Fixtures of the Python module's suite: the source tree, the emdae command
(EMDAE_CLI, set by ctest) and readers of the files it writes."""

import json
import os
import subprocess
from pathlib import Path

import numpy as np
import pytest

SOURCE = Path(os.environ.get("EMDAE_SOURCE_DIR", Path(__file__).resolve().parents[2]))
EXAMPLES = SOURCE / "examples"

# Small versions of the paper's scenes: the suite runs in about a minute.
RING_SHORT = {"time.dt": 0.05, "time.t_end": 7.0, "bodies[0].mesh.around": 32,
              "bodies[1].mesh.around": 32}
PENDULUM_SHORT = {"time.t_end": 2.0}


@pytest.fixture(scope="session")
def cli():
    path = os.environ.get("EMDAE_CLI")
    if not path:
        for guess in ("build/release/cli/emdae", "build/debug/cli/emdae"):
            if (SOURCE / guess).exists():
                path = str(SOURCE / guess)
                break
    if not path or not Path(path).exists():
        pytest.skip("the emdae command is not built (EMDAE_CLI)")
    return path


def set_args(overrides):
    """--set arguments for a dict of overrides, as emdae.load takes them."""
    args = []
    for key, value in overrides.items():
        args += ["--set", f"{key}={value!r}" if isinstance(value, float) else f"{key}={value}"]
    return args


def run_cli(cli, *args):
    return subprocess.run([cli, *map(str, args)], capture_output=True, text=True, check=False)


def read_history(path):
    """history.csv: its columns and an array of its rows (%.17g: exact)."""
    with open(path, encoding="utf-8") as f:
        columns = f.readline().strip().split(",")
    return columns, np.loadtxt(path, delimiter=",", skiprows=1, ndmin=2)


def read_summary(path):
    with open(path, encoding="utf-8") as f:
        return json.load(f)
