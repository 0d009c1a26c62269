#!/usr/bin/env python3
"""Careless and hostile invocations of kincal (issue 16), as a table: every output is
written whole or not at all, never through a symbolic link; a command whose output was not
written, or whose input or option is bad, exits non-zero with a message naming the file,
field or option and what was expected. Each row: a command, the exit code expected (0 or
non-zero), a text its output must contain, and checks on the files afterwards.

usage: check_hostile.py KINCAL SOURCE_DIR SCRATCH_DIR KINCALD
"""
import os
import shutil
import subprocess
import sys

kincal, source, scratch, kincald = sys.argv[1], sys.argv[2], sys.argv[3], sys.argv[4]
shutil.rmtree(scratch, ignore_errors=True)
os.makedirs(scratch)
victim = os.path.join(scratch, "victim.txt")


def plant(path):
    """A symbolic link at `path` pointing at a file that must survive."""
    with open(victim, "w") as f:
        f.write("precious")
    if os.path.lexists(path):
        os.remove(path)
    os.symlink(victim, path)


def victim_intact():
    with open(victim) as f:
        return f.read() == "precious"


def run(name, args, ok, text=None, check=None, env=None, program=None):
    p = subprocess.run([program or kincal] + args, capture_output=True, text=True, env=env, timeout=600)
    out = p.stdout + p.stderr
    problems = []
    if (p.returncode == 0) != ok:
        problems.append(f"exit {p.returncode}, expected {'0' if ok else 'non-zero'}")
    if text and text not in out:
        problems.append(f"output lacks {text!r}")
    if check:
        problems += [c for c in check() if c]
    print(f"{'ok  ' if not problems else 'FAIL'} {name}" + ("" if not problems else ": " + "; ".join(problems)))
    if problems:
        print("     output: " + out.strip().replace("\n", "\n             ")[:1500])
    return not problems


results = []
sim = os.path.join(scratch, "sim")
results.append(run("simulate --export", ["simulate", "--config", f"{source}/config/sim_unicycle_hidden.yaml",
                                         "--duration", "60", "--export", sim], True))
csv = ["--controls", f"{sim}/controls.csv", "--poses", f"{sim}/poses.csv"]

# Bad options and inputs: non-zero, named.
bad_inputs = [
    ("analyze --threads 0", csv + ["--threads", "0"], "--threads must be >= 1"),
    ("analyze --threads -5", csv + ["--threads", "-5"], "--threads must be >= 1"),
    ("analyze --max-effects -1", csv + ["--max-effects", "-1"], "--max-effects must be >= 0"),
    ("analyze --init k_v=nan", csv + ["--init", "k_v=nan"], "'nan' is not a finite number"),
    ("analyze --effects with a broken spec", csv + ["--effects", "dead_band[v"], "dead_band[v"),
    ("analyze a directory as controls", ["--controls", scratch, "--poses", f"{sim}/poses.csv"],
     "cannot open recording file: Is a directory"),
    ("analyze /dev/zero as poses", ["--controls", f"{sim}/controls.csv", "--poses", "/dev/zero"],
     "line longer than 65536 bytes"),
    ("analyze --max-rows 0", csv + ["--max-rows", "0"], "--max-rows: a number >= 1 expected, not '0'"),
    ("analyze a recording longer than --max-rows", csv + ["--max-rows", "10"],
     "controls.csv: more than 10 lines, the most read from one file"),
]
for name, args, text in bad_inputs:
    results.append(run(name, ["analyze", "--model", "unicycle"] + args + ["--out", f"{scratch}/bad"],
                       False, text))
results.append(run("camcal --image-size 99999999999x480",
                   ["camcal", "--points", f"{source}/tests/data/calib_points.csv", "--image-size",
                    "99999999999x480", "--out", f"{scratch}/c.yaml"], False,
                   "each side must be 1 to 16384 pixels"))

# camcal --images: an empty folder, and an image of 20000 x 20000 pixels (a 2.3 GB decode).
empty_dir = os.path.join(scratch, "no_images")
os.makedirs(empty_dir)
results.append(run("camcal --images on an empty folder",
                   ["camcal", "--images", empty_dir, "--board", "chessboard:9x6:0.025", "--out", f"{scratch}/e.yaml"],
                   False, "no images in the folder"))
huge_dir = os.path.join(scratch, "huge_image")
os.makedirs(huge_dir)
import struct
import zlib
def chunk(kind, data):
    return struct.pack(">I", len(data)) + kind + data + struct.pack(">I", zlib.crc32(kind + data) & 0xffffffff)
with open(os.path.join(huge_dir, "huge.png"), "wb") as f:  # a valid header, a tiny body
    f.write(b"\x89PNG\r\n\x1a\n" + chunk(b"IHDR", struct.pack(">IIBBBBB", 20000, 20000, 8, 0, 0, 0, 0)) +
            chunk(b"IDAT", zlib.compress(b"\0" * 20001)) + chunk(b"IEND", b""))
results.append(run("camcal --images with a 20000x20000 PNG",
                   ["camcal", "--images", huge_dir, "--board", "chessboard:9x6:0.025", "--out", f"{scratch}/h.yaml"],
                   False, "larger than 67108864 pixels"))

# kincald: a simulated run's length is bounded and must be a number of seconds (nan is
# refused with the command line, as every floating-point option of kincal's is).
for value, said in [("-5", "--duration: expected seconds > 0"),
                    ("nan", "--duration: a finite number expected, not 'nan'"),
                    ("1e10", "--duration: expected seconds > 0")]:
    results.append(run(f"kincald --duration {value}", ["--duration", value, "--fast", "--lcm-url", "memq://"],
                       False, said, program=kincald))
empty_log = os.path.join(scratch, "empty.lcm")
open(empty_log, "w").close()
results.append(run("kincald --replay of an empty log", ["--replay", empty_log, "--fast", "--lcm-url", "memq://"],
                   False, "the log is empty (0 bytes)", program=kincald))
results.append(run("kincald --replay of a directory", ["--replay", scratch, "--fast", "--lcm-url", "memq://"],
                   False, "is a directory, expected an LCM log file", program=kincald))

# analyze: links planted at every output and at the temporaries are replaced, never followed.
out = os.path.join(scratch, "analysis")
os.makedirs(out)
for f in ["report.json", "report.html", "residuals.csv.tmp"]:
    plant(os.path.join(out, f))
results.append(run("analyze over planted links", ["analyze", "--model", "unicycle"] + csv +
                   ["--effects", "none", "--out", out], True, "wrote",
                   lambda: [None if victim_intact() else "a link's target was overwritten",
                            None if not os.path.islink(f"{out}/report.json") else "report.json is still a link",
                            None if not os.path.exists(f"{out}/residuals.csv.tmp") else "a temporary was left"]))

# analyze into a folder it cannot write: non-zero, the file named.
ro = os.path.join(scratch, "readonly")
os.makedirs(ro)
os.chmod(ro, 0o555)
if os.geteuid() != 0:  # root writes anywhere; the full-disk row below covers root
    results.append(run("analyze into a read-only folder", ["analyze", "--model", "unicycle"] + csv +
                       ["--effects", "none", "--out", ro], False, "report was not written"))

# export --out through a link.
ck = os.path.join(scratch, "ck.json")
with open(ck, "w") as f:
    f.write('{"format": "kincal-checkpoint", "version": 1, "model": "unicycle", "effects": [],'
            ' "filter": "dd2", "utime": 1, "update_count": 5, "names": ["k_v", "k_omega"],'
            ' "units": ["1", "1"], "values": [0.9, 0.8], "covariance": [[1e-4, 0], [0, 1e-4]]}')
yaml_out = os.path.join(scratch, "robot.yaml")
plant(yaml_out)
results.append(run("export --out over a link", ["export", "--checkpoint", ck, "--out", yaml_out], True, "wrote",
                   lambda: [None if victim_intact() else "the link's target was overwritten"]))
results.append(run("export to a missing folder", ["export", "--checkpoint", ck, "--out",
                                                   f"{scratch}/none/robot.yaml"], False,
                   "No such file or directory"))

# camcal --json into a missing folder: non-zero (it wrote nothing and said nothing).
points = f"{source}/tests/data/calib_points.csv"
results.append(run("camcal --json to a missing folder",
                   ["camcal", "--points", points, "--image-size", "640x480", "--out", f"{scratch}/cam.yaml",
                    "--json", f"{scratch}/none/cam.json"], False, "No such file or directory"))
plant(f"{scratch}/cam2.yaml")
results.append(run("camcal --out over a link",
                   ["camcal", "--points", points, "--image-size", "640x480", "--out", f"{scratch}/cam2.yaml"],
                   True, None, lambda: [None if victim_intact() else "the link's target was overwritten"]))

# A full disk: a 64 kB tmpfs in a private mount namespace (root only, as in CI).
if os.geteuid() == 0 and shutil.which("unshare"):
    full = os.path.join(scratch, "full")
    os.makedirs(full)
    script = (f"mount -t tmpfs -o size=64k tmpfs {full} && "
              f"dd if=/dev/zero of={full}/filler bs=4k count=15 2>/dev/null; "
              f"{kincal} analyze --model unicycle {' '.join(csv)} --effects none --out {full}/a; "
              f"echo rc=$?; echo files:; ls -a {full}/a")
    p = subprocess.run(["unshare", "-m", "sh", "-c", script], capture_output=True, text=True, timeout=600)
    out = p.stdout + p.stderr
    left = out.split("files:")[-1].split()
    good = ("rc=0" not in out and "report was not written" in out and
            not any(f.endswith(".tmp") or f == "report.json" for f in left))
    print(f"{'ok  ' if good else 'FAIL'} analyze on a full disk")
    if not good:
        print("     output: " + out.strip()[:1500])
    results.append(good)

failed = results.count(False)
print(f"{len(results) - failed} passed, {failed} failed")
sys.exit(1 if failed else 0)
