#!/usr/bin/env python3
"""Markdown tables from the JSON output of bench_assembly and bench_contact_search.

Usage:
  summarize_bench.py element   RUN1.json [RUN2.json ...]
  summarize_bench.py assembly  RUN1.json [RUN2.json ...]
  summarize_bench.py search    RUN1.json [RUN2.json ...]
  summarize_bench.py study     DIR1 [DIR2 ...]   (study_work_precision --out DIRs)

Each table shows every run side by side (r1 / r2 / ...), CPU time, so that the
run-to-run spread on a shared machine is visible. Uses the "median" aggregate
when the run had --benchmark_repetitions, the single iteration run otherwise.
Also prints least-squares scaling exponents (log time over log size).
"""
import json
import math
import re
import sys
from collections import defaultdict

UNIT = {"ns": 1e-9, "us": 1e-6, "ms": 1e-3, "s": 1.0}


def load(path):
    with open(path) as f:
        data = json.load(f)
    out = {}
    for b in data["benchmarks"]:
        if b.get("run_type") == "aggregate" and b.get("aggregate_name") != "median":
            continue
        if b.get("error_occurred"):
            print(f"<!-- {path}: {b['name']}: {b.get('error_message')} -->")
        name = b.get("run_name", b["name"])
        b["cpu_s"] = b["cpu_time"] * UNIT[b["time_unit"]]
        out[name] = b
    return out, data.get("context", {})


def fit_exponent(xs, ys):
    lx = [math.log(x) for x in xs]
    ly = [math.log(y) for y in ys]
    n = len(lx)
    mx, my = sum(lx) / n, sum(ly) / n
    sxx = sum((a - mx) ** 2 for a in lx)
    sxy = sum((a - mx) * (b - my) for a, b in zip(lx, ly))
    return sxy / sxx


def fmt_time(s):
    if s != s:
        return "–"
    if s >= 1:
        return f"{s:.2f} s"
    if s >= 1e-3:
        return f"{s * 1e3:.1f} ms"
    if s >= 1e-6:
        return f"{s * 1e6:.2f} µs"
    return f"{s * 1e9:.0f} ns"


def runs_cell(vals, f):
    return " / ".join(f(v) for v in vals)


def element(paths):
    runs = [load(p)[0] for p in paths]
    print("| material | gradient | force only, per element | force + 8x8 Jacobian, per element |")
    print("|---|---|---|---|")
    for mat in ("svk", "neohooke"):
        for kind in ("exact", "midpoint", "discrete"):
            a = [r[f"element/{mat}/{kind}"]["cpu_s"] for r in runs]
            b = [r[f"element/{mat}/{kind}/jac"]["cpu_s"] for r in runs]
            print(f"| {mat} | {kind} | {runs_cell(a, fmt_time)} | {runs_cell(b, fmt_time)} |")


def assembly(paths):
    runs = [load(p)[0] for p in paths]
    pat = re.compile(r"^(newton|residual)/(\w+)/(\w+)/nx:(\d+)/ny:(\d+)(?:/min_time:[\d.]+)?$")
    table = defaultdict(dict)  # (what, mat, kind) -> dofs -> [bench per run]
    for i, r in enumerate(runs):
        for name, b in r.items():
            m = pat.match(name)
            if not m:
                continue
            what, mat, kind, nx, ny = m.groups()[:5]
            dofs = 2 * (int(nx) + 1) * (int(ny) + 1)
            table[(what, mat, kind)].setdefault(dofs, [None] * len(runs))[i] = b
    for mat in ("svk", "neohooke"):
        print(f"\n**{mat}**, one Newton iteration (residual + Jacobian triplets + CSC), CPU time per run (r1 / r2)\n")
        print("| dofs | gradient | iteration | per element | per dof | residual | Jacobian triplets | CSC | first Jacobian of a step | residual alone, per dof |")
        print("|---:|---|---:|---:|---:|---:|---:|---:|---:|---:|")
        for kind in ("exact", "midpoint", "discrete"):
            rows = table[("newton", mat, kind)]
            res = table[("residual", mat, kind)]
            for dofs in sorted(rows):
                bs = [b for b in rows[dofs] if b]
                rs = [b for b in res.get(dofs, []) if b]
                print(f"| {dofs} | {kind} | {runs_cell([b['cpu_s'] for b in bs], fmt_time)} "
                      f"| {runs_cell([b['per_elem'] for b in bs], fmt_time)} "
                      f"| {runs_cell([b['per_dof'] for b in bs], fmt_time)} "
                      f"| {runs_cell([b['res_s'] for b in bs], fmt_time)} "
                      f"| {runs_cell([b['jac_s'] for b in bs], fmt_time)} "
                      f"| {runs_cell([b['csc_s'] for b in bs], fmt_time)} "
                      f"| {runs_cell([b.get('jac_fresh_s', float('nan')) for b in bs], fmt_time)} "
                      f"| {runs_cell([b['per_dof'] for b in rs], fmt_time)} |")
    print("\nScaling exponent p of CPU time ~ dofs^p (least squares over all sizes; per run)\n")
    print("| material | gradient | Newton iteration | Jacobian triplets | CSC | first Jacobian of a step | residual alone |")
    print("|---|---|---|---|---|---|---|")
    for mat in ("svk", "neohooke"):
        for kind in ("exact", "midpoint", "discrete"):
            cells = []
            for what, key in (("newton", "cpu_s"), ("newton", "jac_s"), ("newton", "csc_s"),
                              ("newton", "jac_fresh_s"), ("residual", "cpu_s")):
                rows = table[(what, mat, kind)]
                ps = []
                for i in range(len(runs)):
                    pts = [(d, rows[d][i][key]) for d in sorted(rows) if rows[d][i] and key in rows[d][i]]
                    if len(pts) > 2:
                        ps.append(fit_exponent([p[0] for p in pts], [p[1] for p in pts]))
                cells.append(" / ".join(f"{p:.3f}" for p in ps))
            print(f"| {mat} | {kind} | " + " | ".join(cells) + " |")


def search(paths):
    runs = [load(p)[0] for p in paths]
    for scene in ("strips", "rings"):
        print(f"\n**{scene}**, CPU time per slave segment (r1 / r2), medians of 3 repetitions\n")
        print("| segments n | prepare | grid only | of which build (per master seg.) | brute force | box tests / slave: grid | brute | pairs (node x segment) | brute / prepare |")
        print("|---:|---:|---:|---:|---:|---:|---:|---:|---:|")
        ns = sorted({int(re.search(r"n:(\d+)", k).group(1)) for k in runs[0] if k.startswith(f"prepare/{scene}")})
        for n in ns:
            p = [r[f"prepare/{scene}/n:{n}"] for r in runs]
            g = [r[f"grid/{scene}/n:{n}"] for r in runs]
            b = [r[f"brute/{scene}/n:{n}"] for r in runs]
            ratio = [bb["cpu_s"] / pp["cpu_s"] for bb, pp in zip(b, p)]
            print(f"| {n} | {runs_cell([x['per_slave'] for x in p], fmt_time)} "
                  f"| {runs_cell([x['per_slave'] for x in g], fmt_time)} "
                  f"| {runs_cell([x.get('build_per_master', float('nan')) for x in g], fmt_time)} "
                  f"| {runs_cell([x['per_slave'] for x in b], fmt_time)} "
                  f"| {p[0]['tests_per_slave']:.2f} | {b[0]['tests_per_slave']:.0f} "
                  f"| {p[0]['pairs']:.0f} | {runs_cell(ratio, lambda v: f'{v:.2f}')} |")
        for what in ("prepare", "grid", "brute"):
            ps = []
            for r in runs:
                xs = [n for n in ns]
                ys = [r[f"{what}/{scene}/n:{n}"]["cpu_s"] for n in ns]
                ps.append(fit_exponent(xs, ys))
            print(f"\n{scene} {what}: total time ~ n^p, p = " + " / ".join(f"{p:.2f}" for p in ps), end="")
        print()


def read_dat(path):
    rows = []
    with open(path) as f:
        for line in f:
            if line.startswith("#") or not line.strip():
                continue
            rows.append(line.split())
    return rows


def study(dirs):
    for name in ("pendulum", "ring"):
        runs = [read_dat(f"{d}/work_precision_{name}.dat") for d in dirs]
        print(f"\n**{name}** (CPU s per run: r1 / r2)\n")
        print("| scheme | dt / tol | error at t_end | max energy error | CPU s | Newton iterations | steps |")
        print("|---|---|---:|---:|---:|---:|---:|")
        for i, r in enumerate(runs[0]):
            scheme, dt, tol, err, een, cpu, newton, steps, cut, ok = r
            param = f"tol {float(tol):.0e}" if scheme == "ida" else f"dt {float(dt):.4g}"
            cpus = " / ".join(f"{float(run[i][5]):.3g}" for run in runs)
            flag = "" if ok == "1" else " (failed)"
            print(f"| {scheme} | {param} | {float(err):.2e}{flag} | {float(een):.2e} | {cpus} | {newton} | {steps} |")
    runs = [read_dat(f"{d}/impact_summary.dat") for d in dirs]
    print("\n**two-ring impact** (CPU s per run: r1 / r2)\n")
    print("| scheme | energy | linear momentum | angular momentum | max active gap | min inactive gap | max active | "
          "contact window | contact events | steps | Newton | CPU s |")
    print("|---|---:|---:|---:|---:|---:|---:|---|---:|---:|---:|---:|")
    for i, r in enumerate(runs[0]):
        (scheme, een, lin, ang, agap, igap, nact, t0, t1, ev, steps, newton, cut, cpu, ok) = r
        cpus = " / ".join(f"{float(run[i][13]):.2f}" for run in runs)
        print(f"| {scheme} | {float(een):.2e} | {float(lin):.2e} | {float(ang):.2e} | {float(agap):.2e} | "
              f"{float(igap):.2e} | {nact} | [{float(t0):.2f}, {float(t1):.2f}] | {ev} | {steps} | {newton} | {cpus} |")


def main():
    modes = {"element": element, "assembly": assembly, "search": search, "study": study}
    if len(sys.argv) < 3 or sys.argv[1] not in modes:
        print(__doc__)
        sys.exit(2)
    modes[sys.argv[1]](sys.argv[2:])


if __name__ == "__main__":
    main()
