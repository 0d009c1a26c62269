#!/usr/bin/env python3
"""Writes the seed corpora in fuzz/corpus/<target>: small valid inputs of every format the
harnesses decode (LCM types from build/lcmgen/python, LCM's Python bindings).

    .venv/bin/python fuzz/make_seed_corpus.py build/lcmgen/python
"""
import io
import os
import struct
import sys
import tempfile

sys.path.insert(0, sys.argv[1])
import lcm  # noqa: E402
from kincal import controls_t, frame_t, params_t, pose_t  # noqa: E402

root = os.path.join(os.path.dirname(os.path.abspath(__file__)), "corpus")
repo = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))


def put(target, name, data):
    d = os.path.join(root, target)
    os.makedirs(d, exist_ok=True)
    with open(os.path.join(d, name), "wb") as f:
        f.write(data if isinstance(data, bytes) else data.encode())


def controls(t, model="diffdrive", values=(1.0, 2.0)):
    m = controls_t()
    m.schema_version = 1
    m.utime = t
    m.sender_utime = t
    m.model = model
    m.num_controls = 2
    m.names = ["omega_l", "omega_r"] if model == "diffdrive" else ["v", "omega"]
    m.values = list(values)
    return m.encode()


def frame(t, w=8, h=6, fmt="GREY"):
    m = frame_t()
    m.schema_version = 1
    m.utime = t
    m.device_utime = t
    m.sequence = t // 33333
    m.width, m.height, m.stride = w, h, w
    m.pixel_format = fmt
    m.data = bytes((x * 37) % 256 for x in range(w * h))
    m.size = len(m.data)
    return m.encode()


def pose(t):
    m = pose_t()
    m.schema_version = 1
    m.utime = t
    m.x, m.y, m.theta = 0.1, -0.2, 0.3
    m.covariance = [1e-6, 0, 0, 0, 1e-6, 0, 0, 0, 1e-5]
    m.valid = 1
    return m.encode()


def params():
    m = params_t()
    m.schema_version = 1
    m.utime = 1
    m.model = "diffdrive"
    m.estimator = "dd2"
    m.num_params = 2
    m.names = ["r_l", "r_r"]
    m.units = ["m", "m"]
    m.values = [0.031, 0.0313]
    m.sigmas = [1e-5, 1e-5]
    m.covariance = [[1e-10, 0.0], [0.0, 1e-10]]
    m.update_count = 3
    m.status = 1
    m.source = 0
    return m.encode()


# LCM logs: a few controls, frames and poses.
with tempfile.TemporaryDirectory() as tmp:
    path = os.path.join(tmp, "log.lcm")
    log = lcm.EventLog(path, "w", overwrite=True)
    for k in range(6):
        t = 1_700_000_000_000_000 + k * 33_333
        log.write_event(t, "KINCAL_CONTROLS", controls(t))
        log.write_event(t, "KINCAL_FRAME", frame(t))
        log.write_event(t, "KINCAL_POSE", pose(t))
    log.close()
    put("lcm_log", "small.lcm", open(path, "rb").read())

put("controls", "diffdrive", controls(5))
put("controls", "unicycle", controls(5, "unicycle"))
put("controls", "nan", controls(5, values=(float("nan"), 1.0)))
put("lcm_messages", "params", params())
put("lcm_messages", "frame", frame(7))
put("lcm_messages", "pose", pose(7))

c = open(os.path.join(repo, "tests/data/controls.csv")).read()
p = open(os.path.join(repo, "tests/data/poses.csv")).read()
put("csv", "small", bytes([128]) + ("\n".join(c.splitlines()[:20]) + "\n").encode() + ("\n".join(p.splitlines()[:20]) + "\n").encode())
# The same rows as other systems' tools save them: quoted fields and '+' signs with a lone
# CR (Excel for Mac), and UTF-16 with CRLF (a spreadsheet's "Unicode text"). The first byte
# is chosen so that the harness cuts the input where the poses file begins.
c20 = "\n".join(c.splitlines()[:20]) + "\n"
p20 = "\n".join(p.splitlines()[:20]) + "\n"
quoted = "\r".join('"' + '","'.join(("+" + v if v[:1].isdigit() else v) for v in row.split(",")) + '"'
                   for row in c20.splitlines()).encode()
p16 = b"\xff\xfe" + p20.replace("\n", "\r\n").encode("utf-16-le")
size = 1 + len(quoted) + len(p16)
first = next(b for b in range(256) if 1 + b * size // 256 >= 1 + len(quoted))
assert 1 + first * size // 256 == 1 + len(quoted), "no first byte cuts the seed at its seam"
put("csv", "other_systems", bytes([first]) + quoted + p16)
put("mrclam", "small", bytes([100]) + b"# Time [sec] Forward Velocity [m/s] Angular Velocity[rad/s]\n"
    b"1248272272.841 0.0 0.0\n1248272272.900 0.1 0.02\n" b"# Time [sec] x [m] y [m] orientation [rad]\n"
    b"1248272272.844 3.0 -1.1 2.3\n1248272272.861 3.0 -1.1 2.3\n")
for name in ("kincald_sim.yaml", "kincald_v4l2.yaml", "sim_daemon.yaml", "target_thesis.yaml"):
    put("yaml", name, open(os.path.join(repo, "config", name), "rb").read())
put("checkpoint", "ck.json", '{"format": "kincal-checkpoint", "version": 1, "model": "diffdrive", "effects": [], '
    '"filter": "dd2", "utime": 5, "update_count": 2, "names": ["r_l"], "units": ["m"], "values": [0.031], '
    '"covariance": [[1e-10]]}')
# Frames: header bytes (format, width-1, height-1, stride factor, stride pad) + data.
put("frame", "grey", bytes([0, 7, 5, 1, 0]) + bytes(range(48)))
put("frame", "yuyv", bytes([1, 7, 5, 2, 0]) + bytes(range(96)))
put("frame", "bgr", bytes([4, 3, 3, 3, 0]) + bytes(range(48)))
try:
    import numpy as np
    import matplotlib.image  # noqa: F401
    from PIL import Image  # Debian's matplotlib brings Pillow
    img = Image.fromarray(np.arange(48, dtype=np.uint8).reshape(6, 8))
    for fmt, code in (("PNG", 3), ("JPEG", 2)):
        b = io.BytesIO()
        img.save(b, format=fmt)
        put("frame", fmt.lower(), bytes([code, 7, 5, 0, 0]) + b.getvalue())
except ImportError:
    pass
print("seed corpora written to", root)
