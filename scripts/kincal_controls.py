#!/usr/bin/env python3
"""Publish a robot's controls to kincald as kincal.controls_t, from Python or from CSV lines.

A robot driver that does not run ROS connects to kincald with this. Two ways:

  * import it:
        from kincal_controls import ControlsPublisher
        pub = ControlsPublisher("diffdrive")          # LCM's default URL, KINCAL_CONTROLS
        pub.publish([omega_l, omega_r], sender_time_s=robot_clock_s)

  * pipe CSV lines into it, `t,<controls>` with t in seconds on the robot's own clock:
        robot_driver | kincal_controls.py --model diffdrive
    A first line `t,omega_l,omega_r` (any order of the model's names) is read as a header.

Stamps, as docs/daemon.md ("Time") says: `sender_utime` is the robot's own stamp (t, or
the publisher's clock when none is given), in microseconds on any clock of the robot's;
`utime` is the time of sending on this host's realtime clock. kincald stamps each message
on receipt and, with `robot.control_stamp: mapped` (its default), maps the robot's stamps
onto its receive clock, so transport jitter does not reach the filter.

`--listen` does the reverse: it prints the controls_t messages it receives on `--channel`
as the same CSV lines (t = sender_utime in seconds), to watch what a robot sends, or to
chain two channels (`kincal_controls.py --listen --channel A ... | kincal_controls.py ...`).

A line that cannot be read (wrong number of fields, not a number, not finite, time going
back) is skipped with a message naming the line, and counted; the count is printed at the
end. The exit status is 1 when any line was skipped.
"""

import argparse
import math
import sys
import time

CONTROL_NAMES = {
    "diffdrive": ["omega_l", "omega_r"],
    "unicycle": ["v", "omega"],
    "ackermann": ["omega", "phi"],
    "tricycle": ["steer", "drive"],
}


def import_types(path=None):
    from kincal_lcm_types import use_lcm_types

    use_lcm_types(path)
    from kincal import controls_t

    return controls_t


class ControlsPublisher:
    """kincal.controls_t for one model on one LCM channel."""

    def __init__(self, model, url="", channel="KINCAL_CONTROLS", lcm_types=None, names=None):
        import lcm

        if model not in CONTROL_NAMES:
            raise ValueError(f"model '{model}': expected one of {', '.join(sorted(CONTROL_NAMES))}")
        self.model, self.channel = model, channel
        self.names = list(names or CONTROL_NAMES[model])
        if sorted(self.names) != sorted(CONTROL_NAMES[model]):
            raise ValueError(f"controls {self.names}: model {model} has {CONTROL_NAMES[model]}")
        self.lc = lcm.LCM(url) if url else lcm.LCM()
        self.msg = import_types(lcm_types)()
        self.msg.schema_version, self.msg.model = 1, model
        self.msg.num_controls, self.msg.names = len(self.names), self.names

    def publish(self, values, sender_time_s=None):
        """values in the order of self.names, SI units; sender_time_s on the robot's clock."""
        if len(values) != len(self.names):
            raise ValueError(f"{len(values)} values for {len(self.names)} controls {self.names}")
        now_us = int(time.time() * 1e6)
        self.msg.utime = now_us
        self.msg.sender_utime = now_us if sender_time_s is None else int(round(sender_time_s * 1e6))
        self.msg.values = [float(v) for v in values]
        self.lc.publish(self.channel, self.msg.encode())


def parse_line(line, n, last_t):
    """(t, values) or raises ValueError naming what is wrong."""
    fields = [f.strip() for f in line.split(",")]
    if len(fields) != n + 1:
        raise ValueError(f"{len(fields)} fields, expected t and {n} controls")
    nums = [float(f) for f in fields]
    if not all(math.isfinite(x) for x in nums):
        raise ValueError("a value is not finite")
    if last_t is not None and nums[0] < last_t:
        raise ValueError(f"time goes back ({nums[0]} after {last_t})")
    return nums[0], nums[1:]


def pipe(args, stdin=sys.stdin):
    names = CONTROL_NAMES[args.model]
    pub = None
    order = list(range(len(names)))
    skipped, sent, last_t = 0, 0, None
    for number, raw in enumerate(stdin, 1):
        line = raw.strip()
        if not line or line.startswith("#"):
            continue
        if number == 1 and line.split(",")[0].strip() == "t":
            header = [f.strip() for f in line.split(",")[1:]]
            if sorted(header) != sorted(names):
                print(f"kincal_controls: line 1: header {header}, expected t and {names}", file=sys.stderr)
                return 1
            order = [header.index(nm) for nm in names]
            continue
        try:
            t, values = parse_line(line, len(names), last_t)
        except ValueError as e:
            skipped += 1
            print(f"kincal_controls: line {number} skipped: {e}: {line[:80]}", file=sys.stderr)
            continue
        pub = pub or ControlsPublisher(args.model, args.url, args.channel, args.lcm_types)
        pub.publish([values[i] for i in order], t)
        sent, last_t = sent + 1, t
    print(f"kincal_controls: {sent} messages sent on {args.channel}, {skipped} lines skipped", file=sys.stderr)
    return 1 if skipped else 0


def listen(args, out=sys.stdout):
    """controls_t on args.channel -> `t,<names>` lines; ends after args.idle_timeout s
    without a message (0: never)."""
    import lcm
    import select

    controls_t = import_types(args.lcm_types)
    names = CONTROL_NAMES[args.model]
    lc = lcm.LCM(args.url) if args.url else lcm.LCM()
    print("t," + ",".join(names), file=out, flush=True)

    def handle(channel, data):
        m = controls_t.decode(data)
        by_name = dict(zip(m.names, m.values))
        if m.model != args.model or sorted(by_name) != sorted(names):
            print(f"kincal_controls: {channel}: a {m.model} message with {list(m.names)} ignored", file=sys.stderr)
            return
        t = (m.sender_utime or m.utime) * 1e-6
        print(f"{t:.6f}," + ",".join(repr(by_name[n]) for n in names), file=out, flush=True)

    lc.subscribe(args.channel, handle)
    while True:
        ready, _, _ = select.select([lc.fileno()], [], [], args.idle_timeout or None)
        if not ready:
            return 0
        lc.handle()


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--model", required=True, choices=sorted(CONTROL_NAMES))
    ap.add_argument("--url", default="", help="LCM URL (default: LCM's own default)")
    ap.add_argument("--channel", default="KINCAL_CONTROLS")
    ap.add_argument("--lcm-types", help="folder holding the kincal LCM Python package")
    ap.add_argument("--listen", action="store_true", help="print received controls_t as CSV lines instead")
    ap.add_argument("--idle-timeout", type=float, default=0.0, help="--listen: stop after this many s without a message")
    args = ap.parse_args()
    try:
        return listen(args) if args.listen else pipe(args)
    except BrokenPipeError:
        return 0


if __name__ == "__main__":
    sys.exit(main())
