#!/usr/bin/env python3
"""cli.plan: `kincal plan` on the reference case writes plan.csv (t and the model's
controls, within the limits), plan.json (every motion's curve) and plan.png, and the plan
reaches the targets before every usual motion that stays in; plan.json and the summary
say how the plan does for the robots within the prior. --prior sets the prior's sigma.

Usage: check_plan.py KINCAL OUT_DIR
"""
import csv
import json
import os
import subprocess
import sys


def main() -> int:
    kincal, out = sys.argv[1], sys.argv[2]
    cmd = [kincal, "plan", "--model", "diffdrive",
           "--effects", "actuator_lag,time_offset,lever_arm",
           "--init", "r_l=0.03,r_r=0.03,d=0.3,tau_s=0.1",
           "--arena=-1.5,-1,1.5,1", "--pose-sigma", "0.002,0.002,0.005", "--pose-rate", "15",
           "--duration", "30", "--limits", "omega_l=20,omega_r=20,accel=40", "--rate", "20",
           "--targets", "r_l=3e-5,r_r=3e-5,d=3e-4,tau_s=0.003,delay_s=0.003,dx=0.002,dy=0.002",
           "--out", out]
    r = subprocess.run(cmd, capture_output=True, text=True)
    print(r.stdout, r.stderr)
    if r.returncode != 0:
        return 1
    with open(os.path.join(out, "plan.csv"), newline="") as f:
        rows = list(csv.reader(f))
    assert rows[0] == ["t", "omega_l", "omega_r"], rows[0]
    for row in rows[1:]:
        assert all(abs(float(x)) <= 20.0 + 1e-9 for x in row[1:]), row
    assert float(rows[-1][0]) >= 29.9, rows[-1]
    with open(os.path.join(out, "plan.json")) as f:
        d = json.load(f)
    assert d["params"][:3] == ["r_l", "r_r", "d"], d["params"]
    assert d["plan"]["stays_in"], "the plan left the arena"
    plan = d["plan"]["time_to_target_s"]
    usual = [m["time_to_target_s"] for m in d["usual"] if m["stays_in"]]
    # all() over an empty list is True: without a usual motion inside, nothing was compared.
    assert usual, "no usual motion stayed inside the arena: nothing to compare the plan with"
    assert plan is not None and all(plan < u for u in usual), (plan, usual)
    # The robots within the prior: the design point's time is the plan's own, each
    # speed-up is the usual motion's time over the plan's, and the summary names the
    # robot where it is least.
    within = d["within_prior"]
    assert within and within[0]["robot"] == "the design point", within[:1]
    assert within[0]["plan_s"] == plan, (within[0], plan)
    for w in within:
        expected = w["usual_s"] / w["plan_s"] if w["plan_s"] else 0.0
        assert abs(w["speedup"] - expected) < 1e-9, w
    least = min(within, key=lambda w: w["speedup"])
    assert f"least at {least['robot']} (" in r.stdout, least
    assert os.path.getsize(os.path.join(out, "plan.png")) > 10000
    print(f"check_plan: plan {plan} s, usual {sorted(usual)}")
    return check_prior(kincal, out + "_prior")


def check_prior(kincal: str, out: str) -> int:
    """--prior: the named parameter's sigma is the plan's prior (plan.json), the others
    keep the generic one."""
    generic, told = prior_sigma(kincal, out, []), prior_sigma(kincal, out, ["--prior", "k_v=0.02"])
    assert told == [0.02, generic[1]] and generic[0] != 0.02, (generic, told)
    print(f"check_plan: prior sigma {generic} generic, {told} with --prior k_v=0.02")
    return 0


def prior_sigma(kincal: str, out: str, extra: list) -> list:
    cmd = [kincal, "plan", "--model", "unicycle", "--arena=-1,-1,1,1", "--limits", "v=1,omega=2",
           "--duration", "5", "--no-plot", "--out", out] + extra
    r = subprocess.run(cmd, capture_output=True, text=True)
    assert r.returncode == 0, (cmd, r.stdout, r.stderr)
    with open(os.path.join(out, "plan.json")) as f:
        return json.load(f)["prior_sigma"]


if __name__ == "__main__":
    sys.exit(main())
