#!/usr/bin/env python3
"""How a long history reaches numpy from Python: a 10^5-step run of a small
particle system (two masses on a spring, scheme em), then the time to get
every history column and the states as numpy arrays (views of what the run
recorded), against reading the same figures from history.csv.

    PYTHONPATH=build/release/python /usr/bin/python3 bench/python_history.py [--steps 100000]

Prints a table; docs/python.md records its output.
"""

import argparse
import os
import tempfile
import time

import numpy as np

import emdae


def best_of(f, repeat=5):
    times = []
    for _ in range(repeat):
        start = time.perf_counter()
        value = f()
        times.append(time.perf_counter() - start)
    return min(times), value


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--steps", type=int, default=100000)
    args = parser.parse_args()

    model = emdae.Model(2)
    model.add_particle("a", 1.0, [0.0, 0.0], [0.0, 1.0])
    model.add_particle("b", 2.0, [1.0, 0.0], [0.0, -0.5])
    model.add_spring("a", "b", 100.0, 0.8)
    settings = emdae.RunSettings()
    settings.time.dt = 1e-3
    settings.time.t_end = args.steps * settings.time.dt
    settings.output.vtu_every = 0

    rows = []
    with tempfile.TemporaryDirectory() as out:
        start = time.perf_counter()
        result = emdae.run(model, settings, out_dir=out)
        run_seconds = time.perf_counter() - start
        assert result.finished and result.summary["steps"] == args.steps

        def columns():
            return {name: c for name, c in result.history.items()}

        def states():
            return result.positions(), result.velocities()

        t_cols, cols = best_of(columns)
        t_states, (q, v) = best_of(states)
        t_csv, table = best_of(lambda: np.loadtxt(os.path.join(out, "history.csv"),
                                                  delimiter=",", skiprows=1), repeat=1)
        # What a Python-level loop over the rows would cost, for scale.
        t_loop, _ = best_of(lambda: np.array([[r for r in row] for row in table.tolist()]),
                            repeat=1)
        assert np.array_equal(table, result.history_table)
        nbytes = result.history_table.nbytes
        start = time.perf_counter()
        bare = emdae.run(model, settings, keep_states=False)
        bare_seconds = time.perf_counter() - start
        assert np.array_equal(bare.history_table, result.history_table)
        rows = [
            ("run (10^5 steps, em, recorded)", run_seconds, "history, states and files"),
            ("the same run, no files, no states", bare_seconds, "history only"),
            (f"all {len(cols)} history columns as arrays", t_cols,
             f"{result.history_table.shape[0]} rows, {nbytes / 1e6:.1f} MB, views"),
            ("positions and velocities as arrays", t_states, f"{q.shape}, views"),
            ("np.loadtxt(history.csv), for comparison", t_csv, ""),
            ("Python loop over the rows, for comparison", t_loop, ""),
        ]
        assert all(np.shares_memory(c, result.history_table) for c in cols.values())
    print(f"{'what':<44}{'seconds':>12}  note")
    for what, seconds, note in rows:
        print(f"{what:<44}{seconds:>12.6f}  {note}")


if __name__ == "__main__":
    main()
