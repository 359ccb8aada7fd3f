"""The Python results equal the command line's to the last digit on the same
scene: history, summary (but for the CPU time) and contact table."""

import numpy as np
import pytest

import emdae
from conftest import EXAMPLES, PENDULUM_SHORT, RING_SHORT, read_history, read_summary, run_cli, \
    set_args


def without_cpu(summary):
    """The summary but for what a second run cannot repeat (CPU seconds)."""
    if isinstance(summary, dict):
        return {k: without_cpu(v) for k, v in summary.items() if "cpu" not in k}
    if isinstance(summary, list):
        return [without_cpu(v) for v in summary]
    return summary


@pytest.mark.parametrize("scheme", ["em", "midpoint", "galpha", "ida"])
def test_ring_impact_history_summary_and_contact_equal_the_command_line(cli, tmp_path, scheme):
    scene_file = EXAMPLES / "ring_impact.toml"
    out_cli = tmp_path / "cli"
    r = run_cli(cli, "run", scene_file, "--scheme", scheme, "--out", out_cli, "-q",
                *set_args(RING_SHORT))
    assert r.returncode in (0, 4), r.stderr
    columns, rows = read_history(out_cli / "history.csv")

    scene = emdae.load(scene_file, RING_SHORT)
    out_py = tmp_path / "py"
    result = emdae.run(scene, scheme=scheme, out_dir=out_py)
    assert result.end == "finished"
    assert result.columns == columns
    table = result.history_table
    assert table.shape == rows.shape
    # To the last digit: not close, equal.
    assert np.array_equal(table, rows)
    # And the files the Python run wrote are the command line's, byte for byte.
    assert (out_py / "history.csv").read_bytes() == (out_cli / "history.csv").read_bytes()

    assert without_cpu(result.summary) == without_cpu(read_summary(out_cli / "summary.json"))

    contact = result.contact
    lines = (out_cli / "contact.csv").read_text().splitlines()
    assert lines[0] == "pair,node,x,y,gap,pressure,weight,force"
    rows = [ln.split(",") for ln in lines[1:]]
    assert contact["pair"] == [r[0] for r in rows]
    assert contact["node"].tolist() == [int(r[1]) for r in rows]
    for k, name in enumerate(("x", "y", "gap", "pressure", "weight", "force")):
        assert np.array_equal(contact[name], np.array([float(r[2 + k]) for r in rows])), name


def test_contact_happens_in_the_short_ring_impact():
    result = emdae.run(emdae.load(EXAMPLES / "ring_impact.toml", RING_SHORT))
    assert result.history["active_contacts"].max() > 0
    # em conserves energy through the impact (the located impact).
    assert np.abs(result.history["energy_error"]).max() < 1e-9
    assert result.summary["energy_rel_error_max"] == result.history["energy_error"].max()


def test_output_every_keeps_the_rows_history_csv_has(cli, tmp_path):
    overrides = dict(PENDULUM_SHORT, **{"output.every": 7})
    scene_file = EXAMPLES / "double_pendulum.toml"
    r = run_cli(cli, "run", scene_file, "--scheme", "midpoint", "--out", tmp_path, "-q",
                *set_args(overrides))
    assert r.returncode in (0, 4), r.stderr
    _, rows = read_history(tmp_path / "history.csv")
    result = emdae.run(emdae.load(scene_file, overrides), scheme="midpoint")
    assert np.array_equal(result.history_table, rows)
    # The initial state, every 7th step and the last (200 steps).
    assert list(result.history["t"][:3] / 0.01) == pytest.approx([0, 7, 14])
    assert result.history["t"][-1] == pytest.approx(2.0)
    assert result.positions().shape == (rows.shape[0], 2, 2)


def test_static_analysis_equals_the_command_line(cli, tmp_path):
    scene_file = EXAMPLES / "patch_test.toml"
    r = run_cli(cli, "run", scene_file, "--out", tmp_path, "-q")
    if r.returncode not in (0, 4):
        pytest.fail(r.stderr)
    _, rows = read_history(tmp_path / "history.csv")
    result = emdae.run(emdae.load(scene_file))
    assert np.array_equal(result.history_table, rows)
    assert without_cpu(result.summary) == without_cpu(read_summary(tmp_path / "summary.json"))
