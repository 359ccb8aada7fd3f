#!/usr/bin/env python3
"""The cost of impacts against mesh refinement (issue 11, docs/performance.md).

Runs the two-ring impact of examples/hard at three refinements (the paper's
64 x 1 rings, 512 dofs; 256 x 4, 5 120 dofs; 512 x 9, 20 480 dofs) with each
impact treatment of em, and prints one table row per run:

  - Newton iterations per step before the first contact (the rings fly
    rigidly), during the contact window, and after separation (the rings
    fly apart vibrating: the free-flight figure the contact steps are held
    against), with the largest step;
  - contact events (entries and exits), steps, CPU seconds per step;
  - the energy error and the largest active gap.

Iteration counts are deterministic; CPU times are of one run on a shared
machine (compare them within one table, not across tables).

  bench/impact_cost.py [--emdae build/release/cli/emdae] [--quick]
                       [--levels 512,5k,20k] [--treatments locate,...]
                       [--t-end 16] [--markdown FILE]

--quick runs the coarse level only. Treatments: locate, velocity_update,
none (standard mass) and modified (modified mass on both surfaces, impact
location for entries).
"""
import argparse
import csv
import json
import os
import subprocess
import sys
import tempfile

HERE = os.path.dirname(os.path.abspath(__file__))
ROOT = os.path.dirname(HERE)

LEVELS = {  # name: (around, through) of each ring
    "512": (64, 1),
    "5k": (256, 4),
    "20k": (512, 9),
}


def run(emdae, level, treatment, out, t_end):
    around, through = LEVELS[level]
    scene = os.path.join(ROOT, "examples", "hard", "ring_impact_refined_5k.toml")
    args = [emdae, "run", scene, "--out", out,
            "--set", "output.vtu_every=0", "--t-end", str(t_end),
            "--set", f"bodies[0].mesh.around={around}", "--set", f"bodies[0].mesh.through={through}",
            "--set", f"bodies[1].mesh.around={around}", "--set", f"bodies[1].mesh.through={through}"]
    if treatment == "modified":
        args += ["--set", "contacts[0].modified_mass=true"]
    else:
        args += ["--set", f'scheme.impact="{treatment}"']
    res = subprocess.run(args, capture_output=True, text=True)
    if res.returncode not in (0, 4):
        return {"failed": res.stderr.strip().splitlines()[-1] if res.stderr else "failed"}
    with open(os.path.join(out, "summary.json")) as f:
        s = json.load(f)
    with open(os.path.join(out, "history.csv")) as f:
        rows = list(csv.DictReader(f))[1:]
    first, last = s["contact_window"]
    before = [int(r["newton_iterations"]) for r in rows if float(r["t"]) < first]
    during = [int(r["newton_iterations"]) for r in rows if first <= float(r["t"]) <= last + 1e-9]
    after = [int(r["newton_iterations"]) for r in rows if float(r["t"]) > last + 1e-9]
    mean = lambda x: sum(x) / len(x) if x else float("nan")
    return {
        "dofs": s["dofs"], "steps": s["steps"], "events": s.get("contact_events", 0),
        "before": mean(before), "during": mean(during), "after": mean(after),
        "max": max(during) if during else 0,
        "cpu_per_step": s["cpu_seconds"] / max(1, s["steps"]),
        "energy": s["energy_rel_error_max"], "gap": s.get("gap_violation_max", 0.0),
        "window": (first, last),
    }


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--emdae", default=os.path.join(ROOT, "build", "release", "cli", "emdae"))
    ap.add_argument("--quick", action="store_true")
    ap.add_argument("--levels", default="512,5k,20k")
    ap.add_argument("--treatments", default="locate,velocity_update,modified")
    ap.add_argument("--t-end", type=float, default=16.0,
                    help="end time (the refined rings part at t ~ 10..12)")
    ap.add_argument("--markdown")
    a = ap.parse_args()
    levels = ["512"] if a.quick else a.levels.split(",")
    header = ("| treatment | dofs | steps | iterations/step before / during / after contact "
              "| max | during / after | events | CPU ms/step | energy | max active gap |")
    lines = [header, "|" + "---|" * 10]
    print(header, flush=True)
    with tempfile.TemporaryDirectory() as tmp:
        for treatment in a.treatments.split(","):
            for level in levels:
                r = run(a.emdae, level, treatment, os.path.join(tmp, f"{treatment}-{level}"), a.t_end)
                if "failed" in r:
                    line = f"| {treatment} | {level} | failed: {r['failed']} |"
                else:
                    line = (f"| {treatment} | {r['dofs']} | {r['steps']} | {r['before']:.2f} / "
                            f"{r['during']:.2f} / {r['after']:.2f} | {r['max']} | "
                            f"{r['during'] / r['after']:.2f} | {r['events']} | "
                            f"{1e3 * r['cpu_per_step']:.1f} | {r['energy']:.1e} | {r['gap']:.1e} |")
                lines.append(line)
                print(line, flush=True)
    if a.markdown:
        with open(a.markdown, "w") as f:
            f.write("\n".join(lines) + "\n")


if __name__ == "__main__":
    sys.exit(main())
