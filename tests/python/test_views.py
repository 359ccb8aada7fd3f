"""Results reach numpy as views of what the run recorded: no copy per step."""

import numpy as np
import pytest

import emdae
from conftest import EXAMPLES, PENDULUM_SHORT


@pytest.fixture(scope="module")
def result():
    return emdae.run(emdae.load(EXAMPLES / "double_pendulum.toml", PENDULUM_SHORT))


def test_history_columns_are_views_of_one_table(result):
    table = result.history_table
    assert table.shape == (201, len(result.columns))
    assert table.base is not None and not table.flags.writeable
    for name, column in result.history.items():
        assert np.shares_memory(column, table), name
        assert column.base is not None
    # The table is read-only: what the run recorded stays what it recorded.
    with pytest.raises(ValueError):
        table[0, 0] = 1.0


def test_states_are_views_and_outlive_the_result():
    result = emdae.run(emdae.load(EXAMPLES / "double_pendulum.toml", PENDULUM_SHORT))
    q = result.positions()
    v = result.velocities("lower")
    t = result.times
    del result  # the arrays keep the recording alive
    assert q.shape == (201, 2, 2) and v.shape == (201, 2) and t.shape == (201,)
    assert t[-1] == pytest.approx(2.0)
    assert np.isfinite(q).all()


def test_positions_start_at_the_scene_and_end_at_the_final_state(result):
    q = result.positions()
    assert np.array_equal(q[0], [[0.6, -0.8], [1.6, -0.8]])
    assert np.array_equal(q[-1].ravel(), result.final_positions)
    assert np.array_equal(result.velocities()[-1].ravel(), result.final_velocities)
    with pytest.raises(emdae.InputError, match="no body or particle named 'middle'"):
        result.positions("middle")


def test_summary_is_a_dict_with_the_runs_figures(result):
    s = result.summary
    assert s["scene"] == "double_pendulum" and s["scheme"] == "em" and s["steps"] == 200
    assert s["energy_rel_error_max"] < 1e-11
    assert s["energy_rel_error_max"] == result.history["energy_error"].max()
    assert result.contact is None
    assert result.out_dir is None


def test_keep_states_false_keeps_only_the_history():
    r = emdae.run(emdae.load(EXAMPLES / "double_pendulum.toml", PENDULUM_SHORT),
                  keep_states=False)
    assert r.history_table.shape[0] == 201
    with pytest.raises(emdae.InputError, match="keep_states"):
        r.positions()


def test_overrides_change_any_key_like_set():
    scene = emdae.load(EXAMPLES / "double_pendulum.toml")
    assert scene.settings.time.t_end == 10.0
    shorter = scene.with_overrides({"time.t_end": 1.5, "scheme.name": "midpoint",
                                    "particles[1].mass": 2})
    assert shorter.settings.time.t_end == 1.5 and shorter.settings.scheme == "midpoint"
    assert shorter.overrides == ["time.t_end=1.5", "scheme.name=midpoint", "particles[1].mass=2"]
    # A list of --set assignments works too, and text scenes take them alike.
    text = (EXAMPLES / "double_pendulum.toml").read_text()
    same = emdae.load_text(text, "pendulum.toml", ["time.t_end=1.5", "scheme.name=midpoint",
                                                   "particles[1].mass=2"])
    a, b = emdae.run(shorter), emdae.run(same)
    assert np.array_equal(a.history_table, b.history_table)
    default = emdae.load(None, {"time.t_end": 0.5})
    assert default.builtin and default.name == "ring_impact"
