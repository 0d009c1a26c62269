#!/usr/bin/env python3
"""Renders tilted views of a board with `kincal render`, calibrates them with
`kincal camcal --images`, and checks the intrinsics against the renderer's camera
(fx = fy = 820, cx = 319.5, cy = 239.5, no distortion) within 3 sigma, and the rms against
OpenCV's. Usage: check_camcal_images.py KINCAL OUTDIR BOARD"""
import json
import os
import subprocess
import sys


def main() -> int:
    kincal, out, board = sys.argv[1:4]
    imgs = os.path.join(out, "views")
    os.makedirs(imgs, exist_ok=True)
    views = [(-0.12, -0.08, 0.1, 0.45), (-0.10, -0.05, -0.3, -0.4), (-0.05, -0.1, 0.6, 0.35),
             (-0.15, -0.02, -0.5, -0.3), (-0.08, -0.06, 0.3, 0.5), (-0.11, -0.09, -0.2, -0.45),
             (-0.09, -0.04, 0.5, 0.3), (-0.1, -0.07, -0.6, -0.5)]
    for i, (x, y, th, tilt) in enumerate(views):
        subprocess.run([kincal, "render", "--board", board, "--camera-height", "0.6",
                        "--x", str(x), "--y", str(y), "--theta", str(th), "--tilt", str(tilt), "--seed", str(i + 1),
                        "--out", os.path.join(imgs, f"view{i}.png")], check=True, stdout=subprocess.DEVNULL)
    subprocess.run([kincal, "camcal", "--images", imgs, "--board", board,
                    "--out", os.path.join(out, "cam.yaml"), "--json", os.path.join(out, "cam.json")],
                   check=True, stdout=subprocess.DEVNULL)
    with open(os.path.join(out, "cam.json")) as f:
        r = json.load(f)
    truth = {"fx": 820, "fy": 820, "cx": 319.5, "cy": 239.5}
    failed = 0
    if r["views"] < 6:
        print(f"FAIL: only {r['views']} views with a detected board")
        failed += 1
    for k, t in truth.items():
        if abs(r[k] - t) > 3 * r["sigma"][k] + 1e-9:
            print(f"FAIL: {k} = {r[k]} +- {r['sigma'][k]}, truth {t}")
            failed += 1
    if abs(r["rms_px"] - r["opencv"]["rms_px"]) > 1e-3:
        print(f"FAIL: rms {r['rms_px']} vs OpenCV {r['opencv']['rms_px']}")
        failed += 1
    print(f"{len(truth) + 2 - failed} passed, {failed} failed")
    return 1 if failed else 0


if __name__ == "__main__":
    sys.exit(main())
