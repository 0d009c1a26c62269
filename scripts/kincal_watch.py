#!/usr/bin/env python3
"""Watch a running kincald over LCM: parameters with +-sigma, model check, health, guidance.

Two tiers: the filter's real-time estimate (KINCAL_PARAMS, a line per second) and the batch
calibration (KINCAL_CALIBRATION: the whole run fitted as `kincal analyze` fits it, a line
per batch). The answer at the end (and what --expect checks) is the batch calibration when
there is one, and the watch says which it is.

    kincal_watch.py [--url URL] [--plot] [--timeout S] [--until-converged]
                    [--expect NAME=VALUE ...] [--lcm-types DIR]
    kincal_watch.py --log FILE.lcm [--png OUT.png] [--expect NAME=VALUE ...]

Prints one line per second with every parameter as value +- 1 sigma and the filter's
status, plus any health problem or model-check suspicion as it arrives, and each piece
of guidance (guidance.enabled): the least determined parameter, the motion to drive next
and the predicted driving time to the targets. --plot opens a
live matplotlib window with each parameter and its +-2 sigma band. --expect checks, when
the watch ends, that each named parameter lies within 3 sigma of the given value (exit
status 1 if not), which makes the script usable as an end-to-end test. --log reads the
parameters from a kincald recording instead of the network; --png saves the plot.

The LCM types come from the generated Python package `kincal` (installed with kincal, or
build/lcmgen/python in a build tree: --lcm-types). LCM's bindings: `pip install lcm`.
"""
import argparse
import math
import os
import select
import sys
import time


def import_types(path):
    from kincal_lcm_types import use_lcm_types

    use_lcm_types(path)
    try:
        from kincal import calibration_t, guidance_t, health_t, model_check_t, params_t  # noqa: F401
    except ImportError as e:
        sys.exit(f"kincal_watch: cannot import the kincal LCM types ({e}); pass --lcm-types DIR")
    return params_t, health_t, model_check_t, guidance_t, calibration_t


STATUS = {0: "initializing", 1: "converging", 2: "converged", 3: "DIVERGED", 4: "MODEL INADEQUATE"}


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--url", default=os.environ.get("LCM_DEFAULT_URL", ""), help="LCM URL (default: LCM's)")
    ap.add_argument("--params-channel", default="KINCAL_PARAMS")
    ap.add_argument("--health-channel", default="KINCAL_HEALTH")
    ap.add_argument("--model-check-channel", default="KINCAL_MODEL_CHECK")
    ap.add_argument("--guidance-channel", default="KINCAL_GUIDANCE")
    ap.add_argument("--calibration-channel", default="KINCAL_CALIBRATION")
    ap.add_argument("--lcm-types", default="", help="directory holding the generated 'kincal' package")
    ap.add_argument("--plot", action="store_true", help="live plot with +-2 sigma bands (matplotlib)")
    ap.add_argument("--timeout", type=float, default=0.0, help="stop after S seconds (0: never)")
    ap.add_argument("--idle-timeout", type=float, default=0.0,
                    help="stop when no parameters arrive for S seconds after the first (0: never)")
    ap.add_argument("--until-converged", action="store_true", help="stop when the daemon reports convergence")
    ap.add_argument("--log", default="", help="read a kincald LCM log instead of subscribing")
    ap.add_argument("--png", default="", help="save the parameter plot (+-2 sigma) to this file at the end")
    ap.add_argument("--expect", action="append", default=[], metavar="NAME=VALUE",
                    help="at the end, require NAME within 3 sigma of VALUE")
    args = ap.parse_args()
    try:
        import lcm
    except ImportError:
        sys.exit("kincal_watch: LCM's Python bindings are missing (pip install lcm, or scripts/setup's .venv)")
    params_t, health_t, model_check_t, guidance_t, calibration_t = import_types(args.lcm_types)

    expect = {}
    for e in args.expect:
        name, _, value = e.partition("=")
        try:
            expect[name] = float(value)
        except ValueError:
            sys.exit(f"kincal_watch: --expect {e}: expected NAME=VALUE")

    state = {"last": None, "history": [], "printed": 0.0, "received": 0, "last_rx": None,
             "calibration": None, "batches": []}

    def on_params(_channel, data):
        try:
            m = params_t.decode(data)
        except (ValueError, Exception) as exc:  # a malformed message is reported, not fatal
            print(f"kincal_watch: undecodable params message: {exc}", file=sys.stderr)
            return
        state["received"] += 1
        state["last_rx"] = time.monotonic()
        if m.source == params_t.SOURCE_BATCH:
            return  # the run's last message repeats the batch calibration (see on_calibration)
        state["last"] = m
        state["history"].append((m.utime * 1e-6, list(m.values), list(m.sigmas)))
        # Live: a line per second of wall time; from a log: per 5 s of recorded time.
        now = m.utime * 1e-6 if args.log else time.monotonic()
        if now - state["printed"] >= (5.0 if args.log else 1.0):
            state["printed"] = now
            cells = "  ".join(f"{n} = {v:.6g} +- {s:.2g} {u}" for n, v, s, u in
                              zip(m.names, m.values, m.sigmas, m.units))
            print(f"[{m.model}/{m.estimator} {STATUS.get(m.status, m.status)}, {m.update_count} updates]  {cells}",
                  flush=True)

    def on_health(_channel, data):
        try:
            h = health_t.decode(data)
        except Exception:
            return
        if not h.ok:
            print(f"health: {h.message}", flush=True)

    def on_check(_channel, data):
        try:
            c = model_check_t.decode(data)
        except Exception:
            return
        if not c.consistent and c.suspected_effect:
            print(f"model check: residuals suggest '{c.suspected_effect}' (confidence {c.confidence:.2f}): "
                  f"{c.evidence}", flush=True)

    def on_calibration(_channel, data):
        try:
            c = calibration_t.decode(data)
        except Exception as exc:
            print(f"kincal_watch: undecodable calibration message: {exc}", file=sys.stderr)
            return
        print(f"calibration: {describe_calibration(c)}", flush=True)
        if c.ok:
            state["calibration"] = c
            state["batches"].append((c.utime * 1e-6, list(c.names), list(c.values), list(c.sigmas)))

    def on_guidance(_channel, data):
        try:
            g = guidance_t.decode(data)
        except Exception:
            return
        print(f"guidance: {describe_guidance(g)}", flush=True)

    handlers = {args.params_channel: on_params, args.health_channel: on_health,
                 args.model_check_channel: on_check, args.guidance_channel: on_guidance,
                 args.calibration_channel: on_calibration}
    if args.log:
        try:
            log = lcm.EventLog(args.log, "r")
        except IOError as e:
            sys.exit(f"kincal_watch: {args.log}: {e}")
        state["printed"] = -1e18
        for event in log:
            h = handlers.get(event.channel)
            if h is not None:
                h(event.channel, event.data)
        return finish(args, state, expect)
    lc = lcm.LCM(args.url) if args.url else lcm.LCM()
    for channel, h in handlers.items():
        lc.subscribe(channel, h)

    fig = lines = None
    if args.plot:
        import matplotlib.pyplot as plt
        plt.ion()
        fig = plt.figure(figsize=(9, 6))
        lines = {}
    start = time.monotonic()
    last_draw = 0.0
    while True:
        ready, _, _ = select.select([lc.fileno()], [], [], 0.1)
        if ready:
            lc.handle()
        now = time.monotonic()
        m = state["last"]
        if args.timeout and now - start > args.timeout:
            break
        if args.idle_timeout and state["last_rx"] and now - state["last_rx"] > args.idle_timeout:
            break
        if args.until_converged and m is not None and m.status == 2:
            break
        if fig is not None and m is not None and now - last_draw > 0.5:
            last_draw = now
            draw(fig, lines, m, state["history"], state["batches"])
    return finish(args, state, expect)


def describe_guidance(g):
    """One line for a kincal.guidance_t."""
    if g.time_to_target_s < 0:
        left = ""
    elif g.time_to_target_s >= 1e9:
        left = "; more than 10 minutes of driving to the targets"
    else:
        left = f"; about {g.time_to_target_s:.3g} s of driving to the targets"
    return (f"{g.parameter} is least determined (sigma {g.sigma:.3g}, target {g.target:.3g}): "
            f"{g.motion} (then sigma {g.sigma_after:.3g}){left}")


def describe_calibration(c):
    """One line for a kincal.calibration_t."""
    if not c.ok:
        kept = f"batch {c.calibration_sequence} stays" if c.calibration_sequence else "none yet"
        return f"batch {c.sequence} failed ({c.error}); {kept}"
    cells = "  ".join(f"{n} = {v:.6g} +- {s:.2g} {u}" for n, v, s, u in
                      zip(c.names, c.values, c.sigmas, c.units))
    accepted = f", accepted {', '.join(c.accepted)}" if c.num_accepted else ""
    return (f"batch {c.sequence} ({c.model}, {c.num_poses} poses over "
            f"{(c.data_end_utime - c.data_begin_utime) * 1e-6:.0f} s, {c.compute_s:.1f} s{accepted}; "
            f"held-out {c.heldout_before_m * 1e3:.2f} -> {c.heldout_after_m * 1e3:.2f} mm)  {cells}")


def finish(args, state, expect):
    m = state["last"]
    c = state["calibration"]
    if m is None and c is None:
        print("kincal_watch: no parameters received", file=sys.stderr)
        return 1
    if c is not None:
        print(f"kincal_watch: the calibration is batch {c.sequence}'s (the whole run, as kincal analyze fits it)")
        m = c
    else:
        print("kincal_watch: no batch calibration yet: the answer is the filter's running estimate")
    ok = True
    for name, value in expect.items():
        if name not in m.names:
            print(f"kincal_watch: the daemon estimates no '{name}' (it has {', '.join(m.names)})", file=sys.stderr)
            ok = False
            continue
        i = m.names.index(name)
        z = (m.values[i] - value) / m.sigmas[i] if m.sigmas[i] > 0 else math.inf
        verdict = "ok" if abs(z) <= 3 else "OUTSIDE 3 sigma"
        print(f"{name}: {m.values[i]:.6g} +- {m.sigmas[i]:.2g} vs expected {value:.6g} ({z:+.1f} sigma) {verdict}")
        ok = ok and abs(z) <= 3
    last = state["last"]
    status = STATUS.get(last.status, last.status) if last is not None else "none"
    print(f"kincal_watch: {state['received']} parameter messages, last status {status}")
    if args.png and state["last"] is not None:
        import matplotlib
        if not args.plot:
            matplotlib.use("Agg")
        import matplotlib.pyplot as plt
        fig = plt.figure(figsize=(9, 6))
        draw(fig, {}, state["last"], state["history"], state["batches"], interactive=False)
        fig.savefig(args.png, dpi=110, bbox_inches="tight")
        print(f"kincal_watch: wrote {args.png}")
    return 0 if ok else 1


def draw(fig, lines, m, history, batches, interactive=True):
    import matplotlib.pyplot as plt
    n = len(m.names)
    if not fig.axes or len(fig.axes) != n:
        fig.clf()
        fig.subplots(n, 1, sharex=True)
    t0 = history[0][0]
    t = [h[0] - t0 for h in history if len(h[1]) == n]
    for i, ax in enumerate(fig.axes):
        v = [h[1][i] for h in history if len(h[1]) == n]
        s = [h[2][i] for h in history if len(h[2]) == n]
        ax.cla()
        ax.plot(t, v, color="C0")
        ax.fill_between(t, [a - 2 * b for a, b in zip(v, s)], [a + 2 * b for a, b in zip(v, s)], color="C0", alpha=0.25)
        pts = [(bt - t0, bv[bn.index(m.names[i])], bs[bn.index(m.names[i])])
               for bt, bn, bv, bs in batches if m.names[i] in bn]
        if pts:
            ax.errorbar([p[0] for p in pts], [p[1] for p in pts], yerr=[2 * p[2] for p in pts],
                        fmt="s", color="C2", capsize=3, label="batch calibration")
        ax.set_ylabel(f"{m.names[i]} [{m.units[i]}]")
    fig.axes[-1].set_xlabel("time [s]")
    fig.suptitle(f"kincald: {m.model}: the filter ({m.estimator}, {m.update_count} updates) and the "
                 f"batch calibrations, +-2 sigma")
    if interactive:
        plt.pause(0.001)


if __name__ == "__main__":
    sys.exit(main())
