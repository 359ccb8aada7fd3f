#!/usr/bin/env python3
"""A Newton iteration of whole `emdae run`s at 512 dofs against its floor
(issue 14: within 1.5x of one assembly + one factorization + one solve).

The floor: `bench_assembly floor/svk/discrete/ring_impact` (the paper's two
rings, 512 dofs, no contact: the em residual and Jacobian through the slot
map, a KLU refactorization on the kept analysis, one solve), its CPU time
per repetition. The runs (summary.json's cpu_seconds: the time loop with
its recording, no start-up, no report):

  - free rings: examples/free_ring.toml with 128 elements around instead of
    64 (512 dofs, as the two rings; no contact, no chord step kept: every
    iteration is a Newton iteration with its Jacobian);
  - ring impact: examples/ring_impact.toml (512 dofs; the contact window's
    location trials, active-set changes, mortar terms, chord steps).

Each round times the floor and then each run, so that they see the same
load; the table gives per round the run's CPU time per Newton iteration
(KINSOL's count, chord steps included) and per Jacobian set-up
(lu_factorizations + lu_refactorizations), each over the round's floor.

    python3 bench/iteration_floor.py [--rounds 5] [--build build/release]
        [--markdown F]
"""
import argparse
import json
import statistics
import subprocess
import sys
import tempfile
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent

RUNS = [
    ("free rings (512 dofs)", "examples/free_ring.toml",
     ["--set", "bodies[0].mesh.around=128"]),
    ("ring impact (512 dofs)", "examples/ring_impact.toml", []),
]


def floor_us(build):
    out = subprocess.run(
        [str(build / "bench" / "bench_assembly"),
         "--benchmark_filter=^floor/svk/discrete/ring_impact$",
         "--benchmark_min_time=1", "--benchmark_format=json"],
        check=True, capture_output=True, text=True).stdout
    bm = json.loads(out)["benchmarks"][0]
    unit = {"ns": 1e-3, "us": 1.0, "ms": 1e3, "s": 1e6}[bm["time_unit"]]
    return bm["cpu_time"] * unit


def run(build, scene, extra, out):
    subprocess.run(
        [str(build / "cli" / "emdae"), "run", str(ROOT / scene), "-q", "--out", out,
         "--set", "output.vtu_every=0", *extra, "--force"],
        check=True, capture_output=True, text=True)
    s = json.loads((Path(out) / "summary.json").read_text())
    lin = s["linear_solver"]
    setups = lin["lu_factorizations"] + lin["lu_refactorizations"]
    us = s["cpu_seconds"] * 1e6
    return s["dofs"], us / s["newton_iterations"], us / setups


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--rounds", type=int, default=5)
    ap.add_argument("--build", default=str(ROOT / "build" / "release"))
    ap.add_argument("--markdown", help="also write the table to this file")
    a = ap.parse_args()
    build = Path(a.build)
    rows = {name: [] for name, _, _ in RUNS}
    floors = []
    with tempfile.TemporaryDirectory() as tmp:
        for r in range(a.rounds):
            f = floor_us(build)
            floors.append(f)
            for name, scene, extra in RUNS:
                dofs, per_it, per_setup = run(build, scene, extra, str(Path(tmp) / "out"))
                rows[name].append((dofs, per_it, per_setup, f))
                print(f"round {r + 1}: {name}: floor {f:.1f} us, {per_it:.1f} us per iteration "
                      f"({per_it / f:.2f}), {per_setup:.1f} us per set-up ({per_setup / f:.2f})",
                      file=sys.stderr)
    lines = [
        "| run | dofs | floor µs (per round) | µs per iteration | iteration / floor "
        "(median) | µs per Jacobian set-up | set-up / floor (median) |",
        "|---|---|---|---|---|---|---|",
    ]
    for name, vals in rows.items():
        it = [v[1] / v[3] for v in vals]
        su = [v[2] / v[3] for v in vals]
        lines.append(
            f"| {name} | {vals[0][0]} | {' / '.join(f'{v[3]:.0f}' for v in vals)} | "
            f"{' / '.join(f'{v[1]:.0f}' for v in vals)} | "
            f"{' / '.join(f'{x:.2f}' for x in it)} (**{statistics.median(it):.2f}**) | "
            f"{' / '.join(f'{v[2]:.0f}' for v in vals)} | "
            f"{' / '.join(f'{x:.2f}' for x in su)} (**{statistics.median(su):.2f}**) |")
    table = "\n".join(lines)
    print(table)
    if a.markdown:
        Path(a.markdown).write_text(table + "\n")


if __name__ == "__main__":
    main()
