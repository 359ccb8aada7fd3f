"""compare and study as functions that return their tables."""

import numpy as np
import pytest

import emdae
from conftest import EXAMPLES, read_summary


def test_compare_returns_each_schemes_summary_as_the_command_writes_it(tmp_path):
    scene_file = EXAMPLES / "double_pendulum.toml"
    table = emdae.compare(scene_file, ["em", "midpoint"], t_end=1.0, out_dir=tmp_path)
    assert table["exit_code"] == 0
    assert [r["scheme"] for r in table["runs"]] == ["em", "midpoint"]
    em, midpoint = (r["summary"] for r in table["runs"])
    assert em == read_summary(tmp_path / "em" / "summary.json")
    assert (tmp_path / "compare.html").exists()
    assert em["energy_rel_error_max"] < 1e-11 and midpoint["status"] == "ok"
    # The same run from emdae.run gives the same figures.
    run = emdae.run(emdae.load(scene_file, {"time.t_end": 1.0}), scheme="midpoint")
    assert run.summary["energy_rel_error_max"] == midpoint["energy_rel_error_max"]


def test_compare_without_out_dir_leaves_nothing():
    table = emdae.compare(emdae.load(EXAMPLES / "double_pendulum.toml"), ["em"], t_end=0.5)
    assert table["out_dir"] is None and table["runs"][0]["summary"]["steps"] == 50


def test_study_returns_errors_and_cpu_times_with_order_two_for_em(tmp_path):
    scene_file = EXAMPLES / "double_pendulum.toml"
    study = emdae.study(scene_file, ["em", "midpoint"], dts=[0.04, 0.02, 0.01], t_end=1.0,
                        measures=["positions"], out_dir=tmp_path)
    assert study["exit_code"] == 0 and study["complete"]
    runs = [r for r in study["runs"] if r["scheme"] == "em"]
    assert [r["dt"] for r in runs] == [0.04, 0.02, 0.01]
    errors = np.array([r["error"] for r in runs])
    assert (np.diff(errors) < 0).all()
    order = np.log(errors[0] / errors[-1]) / np.log(4)
    assert order == pytest.approx(2.0, abs=0.2)
    assert all(r["cpu_seconds"] >= 0 for r in runs)
    assert (tmp_path / "study.html").exists()
    assert any(row["scheme"] == "midpoint" for row in study["table"])


def _without_cpu(x):
    if isinstance(x, dict):
        return {k: _without_cpu(v) for k, v in x.items() if "cpu" not in k and k != "messages"}
    if isinstance(x, list):
        return [_without_cpu(v) for v in x]
    return x


def test_study_on_two_threads_gives_the_figures_of_one(tmp_path):
    # Runs at once end in another order; the figures (but the CPU times) and
    # the table do not change, to the last bit.
    scene_file = EXAMPLES / "elastic_pendulum.toml"
    args = dict(dts=[0.01, 0.005], tols=[1e-4], t_end=1.0)
    one = emdae.study(scene_file, ["em", "midpoint", "ida"], jobs=1, out_dir=tmp_path / "one",
                      **args)
    two = emdae.study(scene_file, ["em", "midpoint", "ida"], jobs=2, out_dir=tmp_path / "two",
                      **args)
    assert one["exit_code"] == 0 and one["complete"] and len(one["runs"]) == 5
    assert all(r["status"] == "ok" for r in one["runs"])
    del one["out_dir"], two["out_dir"]
    assert _without_cpu(one) == _without_cpu(two)


def test_jobs_must_be_a_positive_whole_number():
    for jobs in (0, -1, 1.5, True):
        with pytest.raises(emdae.InputError, match="jobs"):
            emdae.compare(EXAMPLES / "double_pendulum.toml", ["em"], t_end=0.1, jobs=jobs)
