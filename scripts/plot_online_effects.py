#!/usr/bin/env python3
"""Plots what kincald estimated online, from a log it recorded (--record): every parameter
over time, the filter's (the real-time tier, KINCAL_PARAMS) with its +-2 sigma band and
each batch calibration (the whole run so far fitted as `kincal analyze` fits it,
KINCAL_CALIBRATION) with +-2 sigma bars, the truth where it is known (--truth
name=value), and the moments the daemon added an effect (robot.effects: auto), with the
adaptive noise the filter needed below.

  plot_online_effects.py LOG OUT.png [--truth r_l=0.031 ...] [--lcm-types DIR]
"""
import argparse
import math
import sys

import lcm


def import_types(path):
    from kincal_lcm_types import use_lcm_types

    use_lcm_types(path)
    from kincal import calibration_t, model_check_t, params_t  # noqa: E402
    return params_t, model_check_t, calibration_t


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("log")
    ap.add_argument("png")
    ap.add_argument("--truth", action="append", default=[], help="name=value")
    ap.add_argument("--lcm-types", default="")
    ap.add_argument("--params-channel", default="KINCAL_PARAMS")
    ap.add_argument("--check-channel", default="KINCAL_MODEL_CHECK")
    ap.add_argument("--calibration-channel", default="KINCAL_CALIBRATION")
    args = ap.parse_args()
    params_t, model_check_t, calibration_t = import_types(args.lcm_types)
    truth = {}
    for t in args.truth:
        name, _, value = t.partition("=")
        truth[name] = float(value)

    series = {}  # name -> (t, value, sigma, unit): the filter's
    batches = {}  # name -> (t, value, sigma): each good batch calibration
    noise = ([], [])
    added = []
    t0 = None
    for e in lcm.EventLog(args.log, "r"):
        if e.channel == args.params_channel:
            m = params_t.decode(e.data)
            t0 = m.utime if t0 is None else t0
            if m.source == params_t.SOURCE_BATCH:
                continue  # the run's last message: the batch calibration, plotted below
            for i in range(m.num_params):
                s = series.setdefault(m.names[i], ([], [], [], m.units[i]))
                s[0].append((m.utime - t0) * 1e-6)
                s[1].append(m.values[i])
                s[2].append(m.sigmas[i])
        elif e.channel == args.calibration_channel and t0 is not None:
            c = calibration_t.decode(e.data)
            if not c.ok:
                print(f"batch {c.sequence} failed: {c.error}")
                continue
            for i in range(c.num_params):
                b = batches.setdefault(c.names[i], ([], [], []))
                b[0].append((c.utime - t0) * 1e-6)
                b[1].append(c.values[i])
                b[2].append(c.sigmas[i])
        elif e.channel == args.check_channel and t0 is not None:
            c = model_check_t.decode(e.data)
            noise[0].append((c.utime - t0) * 1e-6)
            noise[1].append(c.adaptive_noise)
            added = [(c.effects_added[k], (c.added_utime[k] - t0) * 1e-6,
                      c.heldout_before_m[k], c.heldout_after_m[k]) for k in range(c.num_added)]
    if not series:
        sys.exit(f"{args.log}: no {args.params_channel} messages")

    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    names = list(series)
    fig, axes = plt.subplots(len(names) + 1, 1, figsize=(9, 2.2 * (len(names) + 1)), sharex=True)
    for ax, name in zip(axes, names):
        t, v, s, unit = series[name]
        lo = [a - 2 * b for a, b in zip(v, s)]
        hi = [a + 2 * b for a, b in zip(v, s)]
        ax.fill_between(t, lo, hi, color="tab:blue", alpha=0.25, label="+-2 sigma")
        ax.plot(t, v, color="tab:blue", lw=1.2, label="filter (real time)")
        if name in batches:
            bt, bv, bs = batches[name]
            ax.errorbar(bt, bv, yerr=[2 * x for x in bs], fmt="s", color="tab:green", ms=5,
                        capsize=3, label="batch calibration (whole run, +-2 sigma)")
        if name in truth:
            ax.axhline(truth[name], color="k", ls="--", lw=1, label="truth")
            span = max(abs(truth[name]) * 0.3, 1e-9)
            ax.set_ylim(truth[name] - span, truth[name] + span)
        ax.set_ylabel(f"{name} [{unit}]")
        for eff, ta, before, after in added:
            ax.axvline(ta, color="tab:red", lw=1)
    axes[0].legend(loc="upper right", fontsize=8)
    for eff, ta, before, after in added:
        axes[0].annotate(f"+{eff}\nheld-out {before * 1e3:.1f} -> {after * 1e3:.1f} mm",
                         (ta, axes[0].get_ylim()[1]), fontsize=8, color="tab:red",
                         va="top", ha="left", xytext=(4, -4), textcoords="offset points")
    ax = axes[-1]
    ax.semilogy(noise[0], [max(n, 1e-3) for n in noise[1]], color="tab:orange")
    ax.set_ylabel("adaptive noise\n[meas. var / frame]")
    ax.set_xlabel("time since the first estimate [s]")
    for eff, ta, _, _ in added:
        ax.axvline(ta, color="tab:red", lw=1)
    fig.suptitle("kincald: the filter and the batch calibration (+-2 sigma), truth, effects added")
    fig.tight_layout()
    fig.savefig(args.png, dpi=110)
    final = ", ".join(f"{n} {b[1][-1]:.5g} +- {b[2][-1]:.2g}" for n, b in batches.items())
    print(f"wrote {args.png}" + "".join(f"; added {e} at {t:.1f} s" for e, t, _, _ in added) +
          (f"; last batch calibration: {final}" if final else ""))


if __name__ == "__main__":
    main()
