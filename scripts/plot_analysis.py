#!/usr/bin/env python3
"""Plots for `kincal analyze`: residuals over time and against the commanded motion,
before and after each accepted effect.

Usage: plot_analysis.py DIR   (reads DIR/residuals.csv, writes DIR/residuals_time.png and
DIR/residuals_vs.png)
"""
import csv
import json
import math
import os
import sys
from collections import OrderedDict

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402


def load(path):
    steps = OrderedDict()
    with open(path, newline="") as f:
        for line, row in enumerate(csv.DictReader(f), start=2):
            try:
                s = steps.setdefault(row["step"], {"t": [], "held": [], "pos": [], "heading": []})
                s["t"].append(float(row["t_s"]))
                s["held"].append(row["heldout"] == "1")
                s["pos"].append(math.hypot(float(row["along_m"]), float(row["cross_m"])))
                s["heading"].append(float(row["heading_rad"]))
            except (KeyError, ValueError) as e:
                sys.exit(f"{path}:{line}: bad row ({e})")
    return steps


def rolling_rms(t, v, width):
    out, j, acc = [], 0, 0.0
    for i in range(len(t)):
        acc += v[i] * v[i]
        while t[i] - t[j] > width:
            acc -= v[j] * v[j]
            j += 1
        out.append(math.sqrt(max(acc, 0.0) / (i - j + 1)))
    return out


def main() -> int:
    if len(sys.argv) != 2:
        print(__doc__, file=sys.stderr)
        return 2
    d = sys.argv[1]
    steps = load(os.path.join(d, "residuals.csv"))
    with open(os.path.join(d, "report.json")) as f:
        report = json.load(f)
    split = report["span_s"]["split"]
    horizon = report["horizon_s"]
    fig, axes = plt.subplots(2, 1, figsize=(10, 6), sharex=True)
    for name, s in steps.items():
        width = max(10.0, 10 * horizon)
        axes[0].plot(s["t"], rolling_rms(s["t"], s["pos"], width), lw=1, label=name)
        axes[1].plot(s["t"], rolling_rms(s["t"], s["heading"], width), lw=1, label=name)
    for ax in axes:
        ax.axvline(split, color="k", ls="--", lw=1)
        ax.grid(alpha=0.3)
    axes[0].set_ylabel(f"position error [m]\n(RMS over {width:.0f} s)")
    axes[1].set_ylabel("heading error [rad]")
    axes[1].set_xlabel("window start [s]  (dashed: fit | held out)")
    axes[0].legend(fontsize=8, loc="upper left")
    fig.suptitle(f"{report['model']}: {horizon:g} s open-loop prediction error, before and after each effect")
    fig.tight_layout()
    fig.savefig(os.path.join(d, "residuals_time.png"), dpi=100)
    plt.close(fig)

    first, last = next(iter(steps)), list(steps)[-1]
    fig, axes = plt.subplots(1, 2, figsize=(10, 4))
    for name in dict.fromkeys([first, last]):
        s = steps[name]
        axes[0].hist(s["pos"], bins=60, alpha=0.5, label=name)
        axes[1].hist(s["heading"], bins=60, alpha=0.5, label=name)
    axes[0].set_xlabel("position error [m]")
    axes[1].set_xlabel("heading error [rad]")
    axes[0].legend(fontsize=8)
    fig.suptitle("Distribution of the prediction error, before and after")
    fig.tight_layout()
    fig.savefig(os.path.join(d, "residuals_vs.png"), dpi=100)
    plt.close(fig)
    return 0


if __name__ == "__main__":
    sys.exit(main())
