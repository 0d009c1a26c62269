#!/usr/bin/env python3
"""Plot the thesis reproduction's per-run estimates against Table 6-5.

Usage: plot_thesis.py RESULTS.json OUT.png [FILTER]
RESULTS.json is written by `kincal reproduce thesis --json`. One panel per parameter
(R_L, R_R, D) against the experiment number: the simulated per-run estimates of FILTER
(default dd2) with their 1-sigma bars, Table 6-5's estimates, the simulated truth and the
nominal robot; a fourth panel gives each run's speed and turn-rate error of the
simulation and of the thesis, the statistics the wheel-rate errors were tuned to.
"""
import json
import sys

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402


def rates(p, c):
    v = 0.5 * (p[0] * c[0] + p[1] * c[1])
    w = (p[1] * c[1] - p[0] * c[0]) / p[2]
    return v, w


def main() -> int:
    if len(sys.argv) not in (3, 4):
        print(__doc__, file=sys.stderr)
        return 2
    try:
        with open(sys.argv[1]) as f:
            j = json.load(f)
        name = sys.argv[3] if len(sys.argv) == 4 else "dd2"
        runs = j["per_run"][name]
        table = j["thesis_table_6_5"]
        controls = j["controls"]
        truth = [j["truth"][k] for k in ("r_l", "r_r", "d")]
        nominal = [j["nominal"][k] for k in ("r_l", "r_r", "d")]
    except (OSError, ValueError, KeyError) as e:
        print(f"plot_thesis.py: {sys.argv[1]}: cannot read per-run results ({e!r}); expected "
              "the JSON of `kincal reproduce thesis --json` with per-run estimates",
              file=sys.stderr)
        return 1
    k = list(range(1, len(runs) + 1))
    fig, axes = plt.subplots(4, 1, figsize=(10, 11), sharex=True)
    labels = ("R_L (mm)", "R_R (mm)", "D (mm)")
    for i, ax in enumerate(axes[:3]):
        ax.errorbar(k, [1e3 * r["value"][i] for r in runs],
                    yerr=[1e3 * r["sigma"][i] for r in runs], fmt="o", ms=3, capsize=2,
                    label=f"simulated, {name} (1 sigma)")
        ax.plot(k, [1e3 * t[i] for t in table[: len(k)]], "x", color="tab:red", ms=4,
                label="thesis, Table 6-5")
        ax.axhline(1e3 * truth[i], color="k", lw=1, label="simulated truth")
        ax.axhline(1e3 * nominal[i], color="gray", lw=1, ls="--", label="nominal (Table 6-1)")
        ax.set_ylabel(labels[i])
        lo, hi = sorted(1e3 * t[i] for t in table)[2], sorted(1e3 * t[i] for t in table)[-3]
        pad = 0.3 * (hi - lo)
        ax.set_ylim(lo - pad, hi + pad)
        ax.grid(alpha=0.3)
    axes[0].legend(fontsize=8, ncol=2)
    ax = axes[3]
    for src, rows, ref, style in (("simulated", [r["value"] for r in runs], truth, "o"),
                                  ("thesis", table[: len(k)], nominal, "x")):
        dv, dw = [], []
        for p, c in zip(rows, controls):
            v, w = rates(p, c)
            v0, w0 = rates(ref, c)
            dv.append(100 * (v - v0) / v0)
            dw.append(100 * (w - w0) / w0)
        ax.plot(k, dv, style, ms=3, label=f"{src}: speed error")
        ax.plot(k, dw, style, ms=3, label=f"{src}: turn-rate error")
    ax.set_ylim(-1.0, 1.0)
    ax.set_ylabel("per-run error (%)")
    ax.set_xlabel("experiment (Table 6-4)")
    ax.legend(fontsize=8, ncol=2)
    ax.grid(alpha=0.3)
    fig.suptitle(f"Per-experiment calibration, {j.get('world', '?')} world, against Table 6-5")
    fig.tight_layout()
    fig.savefig(sys.argv[2], dpi=110)
    return 0


if __name__ == "__main__":
    sys.exit(main())
