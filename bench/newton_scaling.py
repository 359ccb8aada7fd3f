#!/usr/bin/env python3
"""Time per Newton iteration and peak memory of whole `emdae run`s against the
dofs, per linear solver (issue 14: exponent <= 1.25 from 10^4 to 10^6 dofs,
<= 3 kB per dof at 10^6).

The scene: a square SVK block of nx x nx Q1 elements (side 1, E = 100,
nu = 0.3, rho = 1) spinning at 1/s and translating, em, dt = 0.01, Newton
tolerance 1e-10, no output but the summary. Each size and solver runs twice,
to t = dt (one step: the first Jacobian, the pattern, the solver's analysis
or first hierarchy, the mass factorization at the stepper's construction)
and to t = (1 + K) dt; the time per Newton iteration is the difference of
the two runs' loop CPU time (summary.json's cpu_seconds) over the difference
of their Newton iterations: the steady state of K steps. The peak memory is
the longer run's maximum resident set (os.wait4), per dof.

    python3 bench/newton_scaling.py [--sizes 70,126,224,400,708]
        [--solvers amg,auto] [--lu-max 400] [--extra-steps 3] [--markdown F]
        [--floor] [--jacobian-reuse auto|N]

--floor adds, for each size and solver, the floor of one iteration on the
same block and solver (bench/newton_floor: one assembly of the residual and
the Jacobian as StepProblem makes them, one set-up of the linear solver and
one solve, the first iteration's analysis left out) and the ratio of the
run's time per iteration to it (issue 14: within 1.2x at 10^5 dofs). The
floor runs right after the two runs of its row, so that the three see the
same load. With --floor the runs use Newton's method (jacobian_reuse = 1,
a set-up in every iteration as in the floor) unless --jacobian-reuse says
otherwise; "auto" lets a run reuse Jacobians and go below the floor.

"auto" is the default choice: "amg" on these squares from 10^4 flops per
unknown (docs/performance.md §13), KLU below.
Solvers other than amg run up to --lu-max elements across (UMFPACK at 10^6
dofs needs ~6 kB per dof and minutes per run).
"""
import argparse
import json
import math
import os
import subprocess
import sys
import tempfile
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent


def scene(nx, solver, steps, reuse="auto"):
    dt = 0.01
    reuse = f'"{reuse}"' if reuse == "auto" else reuse
    return f"""[scene]
name = "spin_block_{nx}"
description = "a spinning SVK square of {nx} x {nx} elements (bench/newton_scaling.py)"
[time]
dt = {dt}
t_end = {dt * steps:.10g}
[scheme]
name = "em"
newton_tolerance = 1e-10
linear_solver = "{solver}"
jacobian_reuse = {reuse}
[output]
vtu_every = 0
[[bodies]]
name = "block"
angular_velocity = 1.0
velocity = [0.1, 0.0]
mesh = {{ type = "rectangle", origin = [0.0, 0.0], width = 1.0, height = 1.0, nx = {nx}, ny = {nx} }}
material = {{ model = "svk", young = 100.0, poisson = 0.3, density = 1.0 }}
"""


def run(emdae, folder, nx, solver, steps, reuse="auto"):
    path = folder / f"block_{nx}_{solver}_{steps}.toml"
    path.write_text(scene(nx, solver, steps, reuse))
    out = folder / f"out_{nx}_{solver}_{steps}"
    cmd = [str(emdae), "run", str(path), "-q", "--out", str(out), "--force",
           "--set", "limits.max_memory_mb=64000"]
    p = subprocess.Popen(cmd, stdout=subprocess.PIPE, stderr=subprocess.STDOUT)
    _, status, usage = os.wait4(p.pid, 0)
    text = p.stdout.read().decode()
    if status != 0:
        sys.exit(f"{' '.join(cmd)} failed:\n{text}")
    s = json.loads((out / "summary.json").read_text())
    return s, usage.ru_maxrss * 1024  # bytes


def fit(points):
    xs = [math.log(d) for d, _ in points]
    ys = [math.log(t) for _, t in points]
    n = len(xs)
    mx, my = sum(xs) / n, sum(ys) / n
    sxx = sum((x - mx) ** 2 for x in xs)
    return sum((x - mx) * (y - my) for x, y in zip(xs, ys)) / sxx if sxx > 0 else float("nan")


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--emdae", default=str(ROOT / "build/release/cli/emdae"))
    ap.add_argument("--sizes", default="70,126,224,400,708")
    ap.add_argument("--solvers", default="amg,auto")
    ap.add_argument("--lu-max", type=int, default=400)
    ap.add_argument("--extra-steps", type=int, default=3)
    ap.add_argument("--markdown")
    ap.add_argument("--floor", action="store_true")
    ap.add_argument("--jacobian-reuse", default=None,
                    help='the scene\'s jacobian_reuse: "auto" (the default) or 1 (Newton\'s '
                         "method: a set-up in every iteration, as the floor has)")
    a = ap.parse_args()
    if a.jacobian_reuse is None:
        a.jacobian_reuse = "1" if a.floor else "auto"
    if a.jacobian_reuse != "auto" and not a.jacobian_reuse.isdigit():
        sys.exit(f"--jacobian-reuse: \"auto\" or a count, not {a.jacobian_reuse!r}")
    floor_exe = Path(a.emdae).resolve().parent.parent / "bench" / "newton_floor"
    if a.floor and not os.access(floor_exe, os.X_OK):
        sys.exit(f"--floor needs {floor_exe}: cmake --build build/release --target newton_floor")
    sizes = [int(x) for x in a.sizes.split(",")]
    solvers = a.solvers.split(",")
    rows, per_solver = [], {s: [] for s in solvers}
    header = ("| solver | nx | dofs | Newton iterations (1 step / 1 + K) | CPU s (1 / 1 + K) "
              "| CPU ms per iteration (steady) | µs per iteration per dof | peak MB | kB per dof |")
    columns = 9
    if a.floor:
        header += (" floor ms (assembly + set-up + solve) | iteration / floor |")
        columns += 2
    print(f"jacobian_reuse = {a.jacobian_reuse}")
    print(header)
    print("|" + "---|" * columns)
    with tempfile.TemporaryDirectory(prefix="emdae_scaling_") as tmp:
        folder = Path(tmp)
        for nx in sizes:
            for solver in solvers:
                if solver != "amg" and nx > a.lu_max:
                    continue
                s1, _ = run(a.emdae, folder, nx, solver, 1, a.jacobian_reuse)
                sk, peak = run(a.emdae, folder, nx, solver, 1 + a.extra_steps, a.jacobian_reuse)
                dofs = sk["dofs"]
                its = sk["newton_iterations"] - s1["newton_iterations"]
                cpu = sk["cpu_seconds"] - s1["cpu_seconds"]
                per_it = cpu / its
                per_solver[solver].append((dofs, per_it))
                row = (f"| {solver} | {nx} | {dofs} | {s1['newton_iterations']} / "
                       f"{sk['newton_iterations']} | {s1['cpu_seconds']:.2f} / {sk['cpu_seconds']:.2f} "
                       f"| {1e3 * per_it:.1f} | {1e6 * per_it / dofs:.2f} | {peak / 2**20:.0f} "
                       f"| {peak / 1024 / dofs:.2f} |")
                if a.floor:
                    p = subprocess.run([str(floor_exe), str(nx), solver, str(a.extra_steps + 2)],
                                       capture_output=True, text=True)
                    fl = p.stdout.split()
                    v = dict(zip(fl[0::2], fl[1::2]))
                    if p.returncode != 0 or "floor_s" not in v:
                        row += f" failed: {(p.stdout + p.stderr).strip()[-80:]} | – |"
                    else:
                        asm, setup, solve = (float(v[k]) for k in ("asm_s", "setup_s", "solve_s"))
                        floor = asm + setup + solve
                        row += (f" {1e3 * floor:.1f} ({1e3 * asm:.1f} + {1e3 * setup:.1f} + "
                                f"{1e3 * solve:.1f}, {v['solver']}) | {per_it / floor:.2f} |")
                print(row, flush=True)
                rows.append(row)
    lines = [header, "|" + "---|" * columns] + rows + [""]
    for solver, pts in per_solver.items():
        window = [(d, t) for d, t in pts if 0.9e4 <= d <= 1.1e6]
        if len(window) >= 2:
            line = (f"{solver}: time per Newton iteration ∝ dofs^{fit(window):.3f} "
                    f"({window[0][0]} to {window[-1][0]} dofs, {len(window)} sizes)")
            print(line)
            lines.append(line + "  ")
    if a.markdown:
        Path(a.markdown).write_text("\n".join(lines) + "\n")


if __name__ == "__main__":
    main()
