"""kincal render then kincal detect, as a user would try the detector (issue 34: the test
only matched four 'marker ? centre' lines and never checked where they were): every marker
the renderer placed is found once, its centre within 0.05 px of the true one (sub-pixel,
the thesis target at this size), and nothing else is reported.

    check_detect.py KINCAL OUT_DIR"""
import os
import re
import subprocess
import sys

CENTRE = r"\((-?[0-9.]+), (-?[0-9.]+)\) px"


def run(cmd):
    r = subprocess.run(cmd, capture_output=True, text=True)
    print(r.stdout, r.stderr, end="")
    if r.returncode != 0:
        raise SystemExit(f"check_detect: {' '.join(cmd)} exited {r.returncode}")
    return r.stdout


def main() -> int:
    kincal, out = sys.argv[1], sys.argv[2]
    os.makedirs(out, exist_ok=True)
    image = os.path.join(out, "render.png")
    truth = [(float(x), float(y)) for x, y in re.findall(r"true centre " + CENTRE, run(
        [kincal, "render", "--out", image, "--x", "0.05", "--y", "-0.02", "--theta", "0.7"]))]
    found = [(float(x), float(y)) for x, y in re.findall(r"marker \? centre " + CENTRE, run(
        [kincal, "detect", image, "--overlay", os.path.join(out, "detect.png")]))]
    assert len(truth) == 4, f"the renderer placed {len(truth)} markers, expected 4"
    assert len(found) == len(truth), f"found {len(found)} markers, rendered {len(truth)}"
    worst = 0.0
    for tx, ty in truth:
        d = min(((fx - tx) ** 2 + (fy - ty) ** 2) ** 0.5 for fx, fy in found)
        worst = max(worst, d)
        assert d <= 0.05, f"marker at ({tx}, {ty}): nearest detection {d:.3f} px away"
    print(f"check_detect: ok, {len(found)} markers, worst centre error {worst:.4f} px")
    return 0


if __name__ == "__main__":
    sys.exit(main())
