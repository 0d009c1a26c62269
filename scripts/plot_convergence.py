#!/usr/bin/env python3
"""Plot parameter convergence with +-2 sigma bands from `kincal simulate --csv`.

Usage: plot_convergence.py CONVERGENCE.csv OUT.png
CSV columns: t_s,name,value,sigma,truth (one row per parameter per update).
"""
import csv
import math
import sys
from collections import defaultdict

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402


def main() -> int:
    if len(sys.argv) != 3:
        print(__doc__, file=sys.stderr)
        return 2
    series = defaultdict(lambda: {"t": [], "v": [], "s": [], "truth": math.nan})
    with open(sys.argv[1], newline="") as f:
        for line, row in enumerate(csv.DictReader(f), start=2):
            try:
                d = series[row["name"]]
                d["t"].append(float(row["t_s"]))
                d["v"].append(float(row["value"]))
                d["s"].append(float(row["sigma"]))
                d["truth"] = float(row["truth"])
            except (KeyError, ValueError) as e:
                print(f"{sys.argv[1]}:{line}: bad row ({e})", file=sys.stderr)
                return 1
    if not series:
        print(f"{sys.argv[1]}: no data", file=sys.stderr)
        return 1
    fig, axes = plt.subplots(len(series), 1, figsize=(8, 2.4 * len(series)), sharex=True)
    axes = axes if len(series) > 1 else [axes]
    for ax, (name, d) in zip(axes, series.items()):
        lo = [v - 2 * s for v, s in zip(d["v"], d["s"])]
        hi = [v + 2 * s for v, s in zip(d["v"], d["s"])]
        ax.fill_between(d["t"], lo, hi, alpha=0.3, label="±2σ")
        ax.plot(d["t"], d["v"], lw=1.2, label="estimate")
        if not math.isnan(d["truth"]):
            ax.axhline(d["truth"], color="k", ls="--", lw=1, label="truth")
        # Zoom on the converged part: the first seconds span the whole prior.
        tail = d["v"][len(d["v"]) // 10 :]
        if tail:
            span = max(max(tail) - min(tail), 8 * d["s"][-1], 1e-12)
            mid = d["truth"] if not math.isnan(d["truth"]) else tail[-1]
            ax.set_ylim(mid - 2 * span, mid + 2 * span)
        ax.set_ylabel(name)
        ax.grid(alpha=0.3)
    axes[0].legend(loc="upper right", fontsize=8)
    axes[-1].set_xlabel("time [s]")
    fig.suptitle("Online calibration: estimate ±2σ against the simulated truth")
    fig.tight_layout()
    fig.savefig(sys.argv[2], dpi=110)
    print(f"wrote {sys.argv[2]}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
