#!/usr/bin/env python3
"""All four schemes on the hard-case catalogue (issue 11, docs/contact.md).

Runs every scene of examples/hard (or those named) with each scheme at the
scene's own step and settings, and prints one markdown row per run: the
scene's checks (pass/fail: energy, momenta or their balance, gaps,
penetration), the figures behind them, contact events, steps, Newton
iterations (IDA: its internal steps) and CPU time. A run that exceeds the
time limit is reported as such, not hidden.

  bench/hard_catalogue.py [--emdae build/release/cli/emdae]
                          [--schemes em,midpoint,galpha,ida]
                          [--scenes blocks_face_to_face,...]
                          [--timeout 600] [--markdown FILE]

"pass" means every [tolerances] check of the scene passed (the checks are
em's promise: energy to 1e-9 or better, momenta to round-off; midpoint,
generalized-alpha and IDA are not expected to meet the energy check through
impacts, and the table says by how much they miss it).
"""
import argparse
import glob
import json
import os
import subprocess
import sys
import tempfile
import time

HERE = os.path.dirname(os.path.abspath(__file__))
ROOT = os.path.dirname(HERE)


def run(emdae, scene, scheme, out, timeout):
    args = [emdae, "run", scene, "--scheme", scheme, "--out", out, "-q",
            "--set", "output.vtu_every=0"]
    start = time.time()
    try:
        res = subprocess.run(args, capture_output=True, text=True, timeout=timeout)
    except subprocess.TimeoutExpired:
        return {"status": f"not finished in {timeout:.0f} s"}
    wall = time.time() - start
    summary = os.path.join(out, "summary.json")
    if res.returncode not in (0, 3, 4) or not os.path.exists(summary):
        msg = res.stderr.strip().splitlines()[-1] if res.stderr.strip() else "failed"
        return {"status": f"error: {msg}"}
    with open(summary) as f:
        s = json.load(f)
    checks = s.get("checks", {})
    failed = [k for k, c in checks.items() if isinstance(c, dict) and c.get("result") == "fail"]

    def check(*names, fallback=()):
        for n in names:
            if n in checks and "value" in checks[n]:
                return checks[n]["value"]
        for n in fallback:
            if s.get(n) is not None:
                return s[n]
        return None

    return {
        "status": s.get("status", "?") if res.returncode == 3 else ("pass" if not failed else "fail: " + ", ".join(failed)),
        # What the scene checks: the balance with loads and supports where
        # it has them, else the conserved quantity.
        "energy": check("energy_rel", "energy_balance_rel", fallback=("energy_rel_error_max",)),
        "p": check("linear_momentum", "linear_momentum_balance", fallback=("linear_momentum_balance_error_max", "linear_momentum_error_max")),
        "J": check("angular_momentum_rel", "angular_momentum_balance_rel",
                   fallback=("angular_momentum_balance_rel_error_max",
                             "angular_momentum_rel_error_max")),
        "gap": s.get("gap_violation_max"),
        "pen": s.get("penetration_max"),
        "events": s.get("contact_events"),
        "steps": s.get("steps"),
        "newton": s.get("newton_iterations"),
        "cpu": s.get("cpu_seconds", wall),
    }


def fmt(x, spec=".1e"):
    return "–" if x is None else format(x, spec)


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--emdae", default=os.path.join(ROOT, "build", "release", "cli", "emdae"))
    ap.add_argument("--schemes", default="em,midpoint,galpha,ida")
    ap.add_argument("--scenes", default="")
    ap.add_argument("--timeout", type=float, default=600.0)
    ap.add_argument("--markdown")
    a = ap.parse_args()
    scenes = sorted(glob.glob(os.path.join(ROOT, "examples", "hard", "*.toml")))
    if a.scenes:
        wanted = a.scenes.split(",")
        scenes = [s for s in scenes if os.path.basename(s)[:-5] in wanted]
    header = ("| scene | scheme | checks | energy | momentum p / J | max gap | penetration "
              "| events | steps | Newton it. | CPU s |")
    lines = [header, "|" + "---|" * 11]
    print(header, flush=True)
    with tempfile.TemporaryDirectory() as tmp:
        for scene in scenes:
            name = os.path.basename(scene)[:-5]
            for scheme in a.schemes.split(","):
                r = run(a.emdae, scene, scheme, os.path.join(tmp, f"{name}-{scheme}"), a.timeout)
                if "energy" not in r:
                    line = f"| {name} | {scheme} | {r['status']} |" + " |" * 8
                else:
                    line = (f"| {name} | {scheme} | {r['status']} | {fmt(r['energy'])} | "
                            f"{fmt(r['p'])} / {fmt(r['J'])} | {fmt(r['gap'])} | {fmt(r['pen'])} | "
                            f"{r['events']} | {r['steps']} | {r['newton']} | {fmt(r['cpu'], '.1f')} |")
                lines.append(line)
                print(line, flush=True)
    if a.markdown:
        with open(a.markdown, "w") as f:
            f.write("\n".join(lines) + "\n")
    return 0


if __name__ == "__main__":
    sys.exit(main())
