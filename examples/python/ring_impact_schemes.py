#!/usr/bin/env python3
"""The paper's ring impact (examples/ring_impact.toml) with all four schemes,
and their energy errors against time in one PNG.

    PYTHONPATH=build/release/python /usr/bin/python3 examples/python/ring_impact_schemes.py \
        [--t-end 20] [--around 64] [--out ring_impact_schemes.png]

em keeps the energy to round-off through the impacts; midpoint, generalized-α
and IDA do not (README: the table of what each scheme shows).
"""

import argparse
import time
from pathlib import Path

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402

import emdae  # noqa: E402

HERE = Path(__file__).resolve().parent


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--t-end", type=float, default=20.0, help="end of the run (20: the paper's)")
    parser.add_argument("--around", type=int, default=64,
                        help="elements around each ring (64: the paper's)")
    parser.add_argument("--out", default="ring_impact_schemes.png", help="the PNG to write")
    args = parser.parse_args()

    scene = emdae.load(HERE.parent / "ring_impact.toml",
                       {"time.t_end": args.t_end, "bodies[0].mesh.around": args.around,
                        "bodies[1].mesh.around": args.around})
    fig, ax = plt.subplots(figsize=(8, 4.5))
    for scheme in ["em", "midpoint", "galpha", "ida"]:
        start = time.perf_counter()
        result = emdae.run(scene, scheme=scheme, keep_states=False)
        wall = time.perf_counter() - start
        cpu = result.summary["cpu_seconds"]  # the integration's CPU time
        h = result.history
        # The relative energy error of each row; round-off shows as 1e-16.
        ax.semilogy(h["t"], h["energy_error"] + 1e-16, label=f"{scheme} ({cpu:.1f} s CPU)")
        print(f"{scheme:<9} {result.end:<9} energy error max "
              f"{result.summary['energy_rel_error_max']:.3e}  CPU {cpu:.1f} s, wall {wall:.1f} s")
    contact = h["active_contacts"] > 0
    if contact.any():
        ax.axvspan(h["t"][contact][0], h["t"][contact][-1], color="0.9", label="contact (ida's run)")
    ax.set_xlabel("t")
    ax.set_ylabel("|H - H0| / E")
    ax.set_title("two-ring impact (paper 5.2): energy error per scheme")
    ax.legend()
    fig.tight_layout()
    fig.savefig(args.out, dpi=120)
    print(f"wrote {args.out}")


if __name__ == "__main__":
    main()
