#!/usr/bin/env python3
"""Plot the predicted sigma of every parameter against driving time, planned and usual.

Usage: plot_plan.py PLAN.json OUT.png
PLAN.json is written by `kincal plan`. One panel per parameter (log scale): the plan and
each usual motion (square, circle each way, figure-eight, the thesis's 99 runs), the
prior sigma at t = 0 and the target sigma where one was given. The image is written to a
temporary file and renamed.
"""
import json
import math
import os
import sys

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402


def main() -> int:
    if len(sys.argv) != 3:
        print(__doc__, file=sys.stderr)
        return 2
    try:
        with open(sys.argv[1], encoding="utf-8") as f:
            d = json.load(f)
        names, units, targets = d["params"], d["units"], d["targets"]
        motions = [d["plan"]] + list(d["usual"])
    except (OSError, ValueError, KeyError, TypeError) as e:
        print(f"plot_plan.py: {sys.argv[1]}: not a kincal plan.json ({e})", file=sys.stderr)
        return 1
    n = len(names)
    cols = min(3, n)
    rows = math.ceil(n / cols)
    fig, axes = plt.subplots(rows, cols, figsize=(4.2 * cols, 3.2 * rows), squeeze=False)
    for i, name in enumerate(names):
        ax = axes[i // cols][i % cols]
        for k, m in enumerate(motions):
            sig = [s[i] for s in m["sigma"]]
            style = dict(lw=2.4, color="black") if k == 0 else dict(lw=1.2, alpha=0.85)
            label = m["name"] + ("" if m.get("stays_in", True) else " (leaves view)")
            if m.get("stays_in", True) and not m.get("every_robot_stays_in", True):
                # Safe at the design point only: dotted, as the plan could not drive it.
                label += " (a robot within the prior leaves)"
                style["ls"] = ":"
            ax.plot(m["t_s"], sig, label=label, **style)
        if targets[i] > 0:
            ax.axhline(targets[i], color="red", ls="--", lw=1, label="target")
        ax.set_yscale("log")
        ax.set_title(f"{name} ({units[i]})")
        ax.set_xlabel("driving time (s)")
        ax.set_ylabel("predicted sigma")
        ax.grid(True, which="both", alpha=0.3)
    for j in range(n, rows * cols):
        axes[j // cols][j % cols].axis("off")
    axes[0][0].legend(fontsize=7)
    fig.suptitle(f"{d['model']}: predicted sigma against driving time "
                 f"(poses {d['pose_rate_hz']} Hz)")
    fig.tight_layout()
    tmp = sys.argv[2] + ".tmp.png"
    fig.savefig(tmp, dpi=90)
    os.replace(tmp, sys.argv[2])
    return 0


if __name__ == "__main__":
    sys.exit(main())
