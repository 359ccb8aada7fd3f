#!/usr/bin/env python3
"""Wall time of one `emdae study` with --jobs N against --jobs 1 (issue 14).

Runs the two commands in turn (A B A B ...: a drift of the machine's speed
touches both alike), each RUNS times after one warm-up each, and prints
every pair's wall seconds, their ratio B/A (the speed-up), and the medians.
The machine's load average before and after is printed too: on a shared
machine another job's threads take the cores the second thread would use.

    python3 bench/study_jobs.py build/release/cli/emdae [--jobs 2] [--runs 5] \\
        -- examples/ring_impact.toml --schemes em,midpoint,galpha --t-end 4

Everything after `--` is handed to `emdae study` (with -q and an --out of
its own per command, in a temporary folder).
"""

import argparse
import os
import statistics
import subprocess
import sys
import tempfile
import time


def load_average():
    with open("/proc/loadavg", encoding="ascii") as f:
        return " ".join(f.read().split()[:3])


def wall_seconds(command):
    start = time.monotonic()
    subprocess.run(command, check=True, stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
    return time.monotonic() - start


def main():
    if "--" not in sys.argv:
        sys.exit(__doc__)
    split = sys.argv.index("--")
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("emdae")
    parser.add_argument("--jobs", type=int, default=2)
    parser.add_argument("--runs", type=int, default=5)
    options = parser.parse_args(sys.argv[1:split])
    study = sys.argv[split + 1:]
    with tempfile.TemporaryDirectory() as folder:
        def command(jobs):
            out = os.path.join(folder, f"jobs{jobs}")
            return [options.emdae, "study", *study, "-q", "--jobs", str(jobs), "--out", out]

        a, b = command(options.jobs), command(1)
        print(f"load average before: {load_average()}")
        wall_seconds(a)
        wall_seconds(b)
        pairs = []
        for i in range(options.runs):
            ta, tb = wall_seconds(a), wall_seconds(b)
            pairs.append((ta, tb))
            print(f"pair {i + 1}: --jobs {options.jobs} {ta:7.2f} s   --jobs 1 {tb:7.2f} s   "
                  f"speed-up {tb / ta:5.2f}")
        print(f"load average after:  {load_average()}")
        print(f"median: --jobs {options.jobs} {statistics.median(p[0] for p in pairs):.2f} s, "
              f"--jobs 1 {statistics.median(p[1] for p in pairs):.2f} s, "
              f"speed-up {statistics.median(p[1] / p[0] for p in pairs):.2f}")


if __name__ == "__main__":
    main()
