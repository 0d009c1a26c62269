#!/usr/bin/env python3
"""Reruns `kincal analyze` on one MR.CLAM robot and judges it by the motion-capture truth
(held-out error before and after, from the report) and by an independent fit of the same
data written apart from kincal (tests/mrclam_independent.py: the turn-rate gain and the
command delay from the motion-capture heading): the two must agree within 3 % and 30 ms.
The effects found and the bands are those of the real robot's known behaviour (a ~0.2 s
delay, speed lost in turns). Never skipped: without the data the test fails.

Usage: check_mrclam.py KINCAL DATASET_DIR OUT_DIR
"""
import json
import os
import subprocess
import sys

import mrclam_independent


def main() -> int:
    kincal, data, out = sys.argv[1:4]
    if not os.path.isdir(data):
        print(f"{data}: MR.CLAM dataset not found (shared/ must sit beside the repository)",
              file=sys.stderr)
        return 1
    subprocess.run([kincal, "analyze", "--mrclam", data, "--robot", "1", "--out", out, "--threads", "2"],
                   check=True, stdout=subprocess.DEVNULL)
    with open(os.path.join(out, "report.json")) as f:
        r = json.load(f)
    failures = []

    def check(cond, what):
        if not cond:
            failures.append(what)

    effects = r["after"]["effects"]
    p = {k: v["value"] for k, v in r["after"]["params"].items()}
    check("turn_slowdown" in effects, f"turn_slowdown not found (effects: {effects})")
    check(any(e.startswith(("time_offset", "actuator_lag")) for e in effects), f"no delay or lag found ({effects})")
    timing = p.get("delay_s", p.get("tau_s"))
    check(timing is not None and 0.15 <= timing <= 0.3, f"delay/lag {timing} s outside [0.15, 0.3]")
    check(1.3 <= p.get("c_slow", 0) <= 2.3, f"c_slow {p.get('c_slow')} outside [1.3, 2.3] s/rad")
    check(0.95 <= p["k_v"] <= 1.1, f"k_v {p['k_v']} outside [0.95, 1.1]")
    check(0.85 <= p["k_omega"] <= 1.0, f"k_omega {p['k_omega']} outside [0.85, 1.0]")
    b, a = r["before"]["heldout"]["pos_rms_m"], r["after"]["heldout"]["pos_rms_m"]
    check(a <= 0.6 * b, f"held-out position RMS {b:.4f} -> {a:.4f} m: less than 40 % gain")
    check(r["before"]["heldout"]["pos_rms_m"] < 0.02, "baseline held-out error above 2 cm")
    for e in r["effects"]:
        if e["accepted"]:
            check(e["heldout_gain"] > 0 or e["combined_gain"] > 0.02, f"{e['name']} accepted without held-out gain")
    ind = mrclam_independent.fit(data, 1)
    print(f"independent fit: k_omega {ind['k_omega']:.4f}, delay {ind['delay_s']:.3f} s "
          f"({ind['windows']} windows); kincal: k_omega {p['k_omega']:.4f}, delay {timing} s")
    check(abs(p["k_omega"] / ind["k_omega"] - 1) <= 0.03,
          f"k_omega {p['k_omega']:.4f} vs the independent fit's {ind['k_omega']:.4f}: beyond 3 %")
    check(timing is not None and abs(timing - ind["delay_s"]) <= 0.03,
          f"delay/lag {timing} s vs the independent fit's {ind['delay_s']:.3f} s: beyond 30 ms")
    for f in failures:
        print("FAIL: " + f)
    print(f"{10 - len(failures)} passed, {len(failures)} failed")
    return 1 if failures else 0


if __name__ == "__main__":
    sys.exit(main())
