"""A progress callback that stops the run, one that raises, and what is kept."""

import numpy as np
import pytest

import emdae
from conftest import EXAMPLES, PENDULUM_SHORT, read_history, read_summary


def test_returning_false_ends_the_run_and_keeps_what_it_wrote(tmp_path):
    seen = []

    def progress(p):
        seen.append(p["step"])
        assert p["t_end"] == 2.0 and p["steps"] == 200
        return p["step"] < 50

    scene = emdae.load(EXAMPLES / "double_pendulum.toml", PENDULUM_SHORT)
    result = emdae.run(scene, out_dir=tmp_path, progress=progress)
    assert result.end == "interrupted" and not result.finished
    assert "interrupted at t = 0.5" in result.status
    assert seen == list(range(1, 51))
    # The history ends at the step that stopped it, in memory and on disk.
    assert result.history["t"][-1] == pytest.approx(0.5)
    assert result.history_table.shape[0] == 51
    _, rows = read_history(tmp_path / "history.csv")
    assert np.array_equal(result.history_table, rows)
    summary = read_summary(tmp_path / "summary.json")
    assert summary["status"] == result.status and summary["steps"] == 50
    assert (tmp_path / "report.html").exists()
    # The state it stopped in is the last row's.
    assert np.array_equal(result.positions()[-1].ravel(), result.final_positions)


def test_an_exception_in_the_callback_ends_the_run_and_is_raised(tmp_path):
    class Enough(Exception):
        pass

    def progress(p):
        if p["step"] >= 25:
            raise Enough("enough")

    scene = emdae.load(EXAMPLES / "double_pendulum.toml", PENDULUM_SHORT)
    with pytest.raises(Enough):
        emdae.run(scene, out_dir=tmp_path, progress=progress)
    summary = read_summary(tmp_path / "summary.json")
    assert summary["status"].startswith("interrupted at t = 0.2")
    _, rows = read_history(tmp_path / "history.csv")
    assert rows[-1, 0] == pytest.approx(0.25)


def test_a_run_that_fails_numerically_is_a_result_not_an_exception():
    # Two Newton iterations cannot solve the midpoint step of a stiff pendulum.
    scene = emdae.load(EXAMPLES / "double_pendulum.toml",
                       dict(PENDULUM_SHORT, **{"scheme.newton_max_iterations": 1,
                                               "time.dt": 0.5, "time.min_dt": 0.5,
                                               "time.t_end": 2.0}))
    result = emdae.run(scene, scheme="midpoint")
    assert result.end == "failed"
    assert result.status != "ok"


def test_ctrl_c_ends_the_run_as_a_keyboard_interrupt_and_keeps_the_output(tmp_path):
    import os
    import signal

    def progress(p):
        if p["step"] == 30:
            os.kill(os.getpid(), signal.SIGINT)

    scene = emdae.load(EXAMPLES / "double_pendulum.toml", PENDULUM_SHORT)
    with pytest.raises(KeyboardInterrupt):
        emdae.run(scene, out_dir=tmp_path, progress=progress)
    summary = read_summary(tmp_path / "summary.json")
    assert summary["status"].startswith("interrupted at t = 0.3")
