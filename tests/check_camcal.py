#!/usr/bin/env python3
"""Runs `kincal camcal` on tests/data/calib_points.csv (made by make_calib_points.py from a
known camera) and checks: every intrinsic within 3 sigma of the truth, rms equal to
cv::calibrateCamera's. Usage: check_camcal.py KINCAL POINTS OUTDIR"""
import json
import os
import subprocess
import sys

TRUTH = {"fx": 820, "fy": 820, "cx": 321.3, "cy": 238.7, "k1": -0.12, "k2": 0.05, "p1": 0.0007, "p2": -0.0004}


def main() -> int:
    kincal, points, out = sys.argv[1:4]
    os.makedirs(out, exist_ok=True)
    subprocess.run([kincal, "camcal", "--points", points, "--image-size", "640x480",
                    "--out", os.path.join(out, "cam.yaml"), "--json", os.path.join(out, "cam.json")],
                   check=True, stdout=subprocess.DEVNULL)
    with open(os.path.join(out, "cam.json")) as f:
        r = json.load(f)
    failed = 0
    for k, t in TRUTH.items():
        if abs(r[k] - t) > 3 * r["sigma"][k]:
            print(f"FAIL: {k} = {r[k]} +- {r['sigma'][k]}, truth {t}")
            failed += 1
    if abs(r["rms_px"] - r["opencv"]["rms_px"]) > 1e-3:
        print(f"FAIL: rms {r['rms_px']} vs OpenCV {r['opencv']['rms_px']}")
        failed += 1
    print(f"{len(TRUTH) + 1 - failed} passed, {failed} failed")
    return 1 if failed else 0


if __name__ == "__main__":
    sys.exit(main())
