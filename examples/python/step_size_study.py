#!/usr/bin/env python3
"""A step-size study (emdae study) of a scene, and its work-precision diagram:
the error at t_end against the CPU time of each run, one line per scheme.

    PYTHONPATH=build/release/python /usr/bin/python3 examples/python/step_size_study.py \
        [--scene examples/double_pendulum.toml] [--t-end 5] [--out step_size_study.png]
"""

import argparse
from pathlib import Path

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402

import emdae  # noqa: E402

HERE = Path(__file__).resolve().parent


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--scene", default=str(HERE.parent / "double_pendulum.toml"))
    parser.add_argument("--schemes", default="em,midpoint,galpha,ida")
    parser.add_argument("--dts", default="0.04,0.02,0.01,0.005")
    parser.add_argument("--t-end", type=float, default=5.0)
    # Fine enough that the reference's own error (order 2: ~1e-7 here) stays
    # below the smallest error of the runs, so the curves measure the runs.
    parser.add_argument("--reference-dt", type=float, default=1e-4)
    parser.add_argument("--out", default="step_size_study.png", help="the PNG to write")
    args = parser.parse_args()

    study = emdae.study(args.scene, args.schemes.split(","), dts=args.dts.split(","),
                        t_end=args.t_end, reference_dt=args.reference_dt,
                        measures=["positions"])
    fig, (left, right) = plt.subplots(1, 2, figsize=(10, 4.2))
    for scheme in study["schemes"]:
        runs = [r for r in study["runs"] if r["scheme"] == scheme and r["error"] is not None]
        if not runs:
            continue
        cpu = [max(r["cpu_seconds"], 1e-4) for r in runs]
        error = [r["error"] for r in runs]
        axis = [r["tol"] if r["tol"] is not None else r["dt"] for r in runs]
        right.loglog(cpu, error, "o-", label=scheme)
        left.loglog(axis, error, "o-", label=scheme + (" (against tol)" if scheme == "ida" else ""))
        for r in runs:
            print(f"{scheme:<9} dt {r['dt']:<8g} tol {r['tol'] or '-':<8} error {r['error']:.3e} "
                  f"cpu {r['cpu_seconds']:.4f} s")
    left.set_xlabel("dt (ida: rtol = atol)")
    left.set_ylabel("max |q - q_ref| at t_end")
    left.set_title("convergence")
    right.set_xlabel("CPU seconds")
    right.set_title("work-precision")
    for ax in (left, right):
        ax.grid(True, which="both", alpha=0.3)
        ax.legend()
    fig.suptitle(f"{study['scene']}: step-size study to t = {study['t_end']:g}")
    fig.tight_layout()
    fig.savefig(args.out, dpi=120)
    print(f"wrote {args.out}")


if __name__ == "__main__":
    main()
