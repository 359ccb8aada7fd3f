"""The scripts of examples/python run and write their PNG (on small versions
of their scenes)."""

import os
import subprocess
import sys
from pathlib import Path

import emdae
from conftest import EXAMPLES

# The scripts import the package this suite imports.
PACKAGE_PARENT = str(Path(emdae.__file__).resolve().parents[1])


def run_example(script, tmp_path, *args):
    env = dict(os.environ, MPLBACKEND="Agg", PYTHONPATH=PACKAGE_PARENT)
    out = tmp_path / "plot.png"
    r = subprocess.run([sys.executable, str(EXAMPLES / "python" / script), "--out", str(out),
                        *args], capture_output=True, text=True, env=env, cwd=tmp_path,
                       check=False)
    assert r.returncode == 0, r.stderr
    assert out.exists() and out.read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"
    return r.stdout


def test_ring_impact_schemes_plots_the_four_schemes(tmp_path):
    out = run_example("ring_impact_schemes.py", tmp_path, "--t-end", "6.5", "--around", "16")
    lines = [ln.split() for ln in out.splitlines() if "energy error max" in ln]
    assert [ln[0] for ln in lines] == ["em", "midpoint", "galpha", "ida"]
    # em conserves the energy through the impact.
    assert float(lines[0][5]) < 1e-9


def test_step_size_study_plots_error_against_cpu_time(tmp_path):
    out = run_example("step_size_study.py", tmp_path, "--t-end", "0.5", "--schemes", "em,ida",
                      "--dts", "0.02,0.01", "--reference-dt", "0.001")
    assert out.count("error") == 5  # em at two steps, ida at three tolerances
