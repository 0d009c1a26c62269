#!/usr/bin/env python3
"""kincal import: a ROS 1 or ROS 2 bag to a kincal LCM log.

`kincal import` runs this program with the venv's Python (rosbags and LCM's bindings come
from PyPI there; `scripts/setup` makes it). It reads a ROS 1 `.bag` or a ROS 2 bag folder
(`metadata.yaml` with `.db3` or `.mcap` files) through `rosbags`, one message at a time,
and writes a standard LCM event log that `kincal analyze --log` and `kincald --replay`
read:

  controls  geometry_msgs/Twist, TwistStamped  -> kincal.controls_t (unicycle: v, omega)
            sensor_msgs/JointState             -> kincal.controls_t (diffdrive: omega_l,
                                                  omega_r from the two named joints: their
                                                  velocities, or their positions (encoder
                                                  angles) differenced when there are none)
            ackermann_msgs/AckermannDriveStamped,
            AckermannDrive                     -> kincal.controls_t (bicycle: v, steer)
  poses     geometry_msgs/PoseStamped, PoseWithCovarianceStamped, TransformStamped,
            tf2_msgs/TFMessage (one child frame), nav_msgs/Odometry -> kincal.pose_t
  frames    sensor_msgs/Image (mono8, bgr8, rgb8, yuv422, yuv422_yuy2) and
            CompressedImage (jpeg, png)        -> kincal.frame_t
  camera    sensor_msgs/CameraInfo (plumb_bob) -> the intrinsics file `kincal` reads

Stamps: the message header's stamp where the type has one and it is set, otherwise the
bag's receive time; `--stamps` forces one. The summary says which was used per topic. Two
clocks: when the controls' and the poses' header stamps differ from their receive times by
amounts more than 1 s apart (a robot computer stamping commands on its own clock, the
motion capture on another), both streams use their receive times (one machine received
them) and the summary says so with both offsets.

Several bags (`kincal import A.bag B.bag ...`, or a folder of bags): each bag is one run of
one recording, in the order given (a folder's bags by name), its start marked by a
kincal.run_t on KINCAL_RUN. A bag that starts before the previous one ends (each on its own
clock) is moved to start 1 s after it, and the summary says so. Every bag must have the
requested topics with the same types.
"""

import argparse
import math
import os
import sys
import tempfile
import time
from pathlib import Path

ACKERMANN_TYPES = {"ackermann_msgs/msg/AckermannDriveStamped", "ackermann_msgs/msg/AckermannDrive"}
CONTROL_TYPES = {
    "geometry_msgs/msg/Twist",
    "geometry_msgs/msg/TwistStamped",
    "sensor_msgs/msg/JointState",
} | ACKERMANN_TYPES
# ackermann_msgs (the ROS interface every car-like robot is driven by), for bags that do
# not carry their message definitions (ROS 2 bags before Iron).
ACKERMANN_MSGS = {
    "ackermann_msgs/msg/AckermannDrive": "float32 steering_angle\nfloat32 steering_angle_velocity\n"
    "float32 speed\nfloat32 acceleration\nfloat32 jerk\n",
    "ackermann_msgs/msg/AckermannDriveStamped": "std_msgs/Header header\nackermann_msgs/AckermannDrive drive\n",
}
MODEL_CONTROLS = {
    "diffdrive": ({"sensor_msgs/msg/JointState"}, ["omega_l", "omega_r"]),
    "unicycle": ({"geometry_msgs/msg/Twist", "geometry_msgs/msg/TwistStamped"}, ["v", "omega"]),
    "bicycle": (ACKERMANN_TYPES, ["v", "steer"]),
}
RUN_CHANNEL = "KINCAL_RUN"
RUN_GAP_NS = 1_000_000_000  # a bag that would start earlier is moved to this after the last
CLOCKS_APART_NS = 1_000_000_000  # header-minus-receive offsets further apart: two clocks
POSE_TYPES = {
    "geometry_msgs/msg/PoseStamped",
    "geometry_msgs/msg/PoseWithCovarianceStamped",
    "geometry_msgs/msg/TransformStamped",
    "tf2_msgs/msg/TFMessage",
    "nav_msgs/msg/Odometry",
}
IMAGE_TYPES = {"sensor_msgs/msg/Image", "sensor_msgs/msg/CompressedImage"}
INFO_TYPE = "sensor_msgs/msg/CameraInfo"
CONTROLS_CHANNEL, POSE_CHANNEL, FRAME_CHANNEL = "KINCAL_CONTROLS", "KINCAL_POSE", "KINCAL_FRAME"


class ImportError_(Exception):
    """Bad input: the message names the topic, the message and what was expected."""


def fail(msg):
    raise ImportError_(msg)


# --- bag access -------------------------------------------------------------------------


def typestore():
    from rosbags.typesys import Stores, get_typestore, get_types_from_msg

    store = get_typestore(Stores.ROS2_HUMBLE)
    extra = {}
    for name, text in ACKERMANN_MSGS.items():
        extra.update(get_types_from_msg(text, name))
    store.register(extra)
    return store


def bag_paths(paths):
    """The bags named: files and ROS 2 bag folders as given, a folder of bags by name."""
    out = []
    for path in paths:
        p = Path(path)
        if p.is_dir() and not (p / "metadata.yaml").exists():
            inner = sorted(q for q in p.iterdir() if q.suffix == ".bag" or (q / "metadata.yaml").exists())
            if not inner:
                fail(f"{path}: a folder with neither metadata.yaml (a ROS 2 bag) nor bags in it")
            out += [str(q) for q in inner]
        else:
            out.append(path)
    return out


def open_bag(path):
    from rosbags.highlevel import AnyReader

    p = Path(path)
    if not p.exists():
        fail(f"{path}: no such file or folder")
    if p.is_dir() and not (p / "metadata.yaml").exists():
        fail(f"{path}: a ROS 2 bag folder needs metadata.yaml")
    if p.is_file() and p.suffix != ".bag":
        fail(f"{path}: expected a ROS 1 .bag file or a ROS 2 bag folder")
    # Bags without embedded definitions (some ROS 2 bags) use the standard types.
    return AnyReader([p], default_typestore=typestore())


def topics_of(reader):
    """{topic: (msgtype, message count)} over all connections."""
    out = {}
    for c in reader.connections:
        t, n = c.topic, c.msgcount
        prev = out.get(t)
        if prev and prev[0] != c.msgtype:
            fail(f"topic {t}: two types ({prev[0]}, {c.msgtype}); kincal needs one per topic")
        out[t] = (c.msgtype, (prev[1] if prev else 0) + n)
    return out


def list_bag(reader, out=sys.stdout):
    """Topics with types, counts and rates, then a suggested mapping."""
    topics = topics_of(reader)
    span = max((reader.end_time - reader.start_time) * 1e-9, 1e-9)
    print(f"{len(topics)} topics over {span:.1f} s", file=out)
    for t, (typ, n) in sorted(topics.items()):
        print(f"  {t:<32} {typ:<44} {n:>8} msgs  {n / span:8.1f} Hz", file=out)
    print("suggested: " + suggest(topics), file=out)


def suggest(topics):
    args = []
    by_type = {}
    for t, (typ, n) in sorted(topics.items()):
        if n > 0:
            by_type.setdefault(typ, []).append(t)
    joints = by_type.get("sensor_msgs/msg/JointState")
    twists = by_type.get("geometry_msgs/msg/TwistStamped") or by_type.get("geometry_msgs/msg/Twist")
    cars = by_type.get("ackermann_msgs/msg/AckermannDriveStamped") or by_type.get("ackermann_msgs/msg/AckermannDrive")
    if cars:
        args += ["--model bicycle", f"--controls {cars[0]}"]
    elif joints:
        args += ["--model diffdrive", f"--controls {joints[0]}", "--joints LEFT,RIGHT"]
    elif twists:
        args += ["--model unicycle", f"--controls {twists[0]}"]
    for typ in sorted(POSE_TYPES):
        if typ in by_type:
            args.append(f"--poses {by_type[typ][0]}")
            if typ == "tf2_msgs/msg/TFMessage":
                args.append("--tf-frame CHILD_FRAME")
            break
    for typ in sorted(IMAGE_TYPES):
        if typ in by_type:
            args.append(f"--images {by_type[typ][0]}")
            break
    if INFO_TYPE in by_type:
        args += [f"--camera-info {by_type[INFO_TYPE][0]}", "--intrinsics-out camera.yaml"]
    return " ".join(args) if args else "(no topic kincal reads)"


# --- conversions --------------------------------------------------------------------------


def stamp_ns(msg):
    """The header stamp in ns, or None when the type has no header or it is unset."""
    header = getattr(msg, "header", None)
    if header is None:
        return None
    ns = int(header.stamp.sec) * 1_000_000_000 + int(header.stamp.nanosec)
    return ns if ns > 0 else None


def planar(q, where, tilt_stats):
    """Yaw of a quaternion (x, y, z, w); the tilt of its z axis is checked."""
    n = math.sqrt(q.x * q.x + q.y * q.y + q.z * q.z + q.w * q.w)
    if not (n > 0.5 and n < 1.5):
        fail(f"{where}: orientation quaternion has norm {n:.3g}, expected 1")
    x, y, z, w = q.x / n, q.y / n, q.z / n, q.w / n
    cos_tilt = max(-1.0, min(1.0, 1.0 - 2.0 * (x * x + y * y)))
    tilt_stats.add(math.acos(cos_tilt), where)
    return math.atan2(2.0 * (w * z + x * y), 1.0 - 2.0 * (y * y + z * z))


class TiltStats:
    def __init__(self, limit_rad):
        self.limit, self.over, self.worst, self.first = limit_rad, 0, 0.0, None

    def add(self, tilt, where):
        self.worst = max(self.worst, tilt)
        if tilt > self.limit:
            self.over += 1
            self.first = self.first or where


def pose_of(msg, typ, args, where, tilt):
    """(x, y, theta, cov3x3 or None, the message carrying the stamp) or None when the
    message holds no pose for the requested frame (a tf message about other frames)."""
    cov = None
    if typ == "tf2_msgs/msg/TFMessage":
        for tr in msg.transforms:
            if tr.child_frame_id.lstrip("/") == args.tf_frame.lstrip("/"):
                return pose_of(tr, "geometry_msgs/msg/TransformStamped", args, where, tilt)
        return None
    if typ == "geometry_msgs/msg/TransformStamped":
        p, q = msg.transform.translation, msg.transform.rotation
    elif typ == "geometry_msgs/msg/PoseStamped":
        p, q = msg.pose.position, msg.pose.orientation
    else:  # PoseWithCovarianceStamped, Odometry: (x, y, z, roll, pitch, yaw) 6x6
        p, q = msg.pose.pose.position, msg.pose.pose.orientation
        c = [float(v) for v in msg.pose.covariance]
        cov = [c[i * 6 + k] for i in (0, 1, 5) for k in (0, 1, 5)]
    theta = planar(q, where, tilt)
    return float(p.x), float(p.y), theta, cov, msg


def joint_values(msg, field, joints, where):
    """The named joints' velocities or positions (`field`) from a JointState."""
    names = list(msg.name)
    values = list(getattr(msg, field))
    if len(values) != len(names):
        fail(f"{where}: {len(names)} joint names but {len(values)} {field} values (--joint-field {field})")
    out = []
    for j in joints:
        if j not in names:
            fail(f"{where}: joint '{j}' not in the message (it has {', '.join(names)})")
        out.append(float(values[names.index(j)]))
    return out


def controls_of(msg, typ, args, where):
    """The model's control values, in the model's order (JointState positions: see
    EncoderRates)."""
    if typ == "sensor_msgs/msg/JointState":
        if args.joint_field is None:  # velocities when the driver publishes them
            args.joint_field = "velocity" if len(msg.velocity) > 0 else "position"
        return joint_values(msg, args.joint_field, args.joint_names, where)
    if typ in ACKERMANN_TYPES:
        drive = msg.drive if typ == "ackermann_msgs/msg/AckermannDriveStamped" else msg
        return [float(drive.speed), float(drive.steering_angle)]
    twist = msg.twist if typ == "geometry_msgs/msg/TwistStamped" else msg
    return [float(twist.linear.x), float(twist.angular.z)]


GREY_WEIGHTS = (0.299, 0.587, 0.114)  # ITU-R BT.601 luma, R G B


def frame_of(msg, typ, where):
    """(width, height, stride, pixel_format, bytes) for kincal.frame_t."""
    import numpy as np

    data = bytes(msg.data)
    if typ == "sensor_msgs/msg/CompressedImage":
        fmt = msg.format.lower()
        if "jpeg" in fmt or "jpg" in fmt:
            w, h = jpeg_size(data, where)
            return w, h, 0, "MJPG", data
        if "png" in fmt:
            w, h = png_size(data, where)
            return w, h, 0, "PNG", data
        fail(f"{where}: compressed format '{msg.format}', expected jpeg or png")
    w, h, step, enc = int(msg.width), int(msg.height), int(msg.step), msg.encoding.lower()
    if w <= 0 or h <= 0 or step <= 0 or len(data) < step * h:
        fail(f"{where}: image {w}x{h}, step {step}, {len(data)} bytes: sizes do not agree")
    rows = np.frombuffer(data, np.uint8)[: step * h].reshape(h, step)
    if enc in ("mono8", "8uc1"):
        return w, h, w, "GREY", rows[:, :w].tobytes()
    if enc in ("bgr8", "rgb8"):
        px = rows[:, : 3 * w].reshape(h, w, 3).astype(np.float32)
        r, g, b = (2, 1, 0) if enc == "bgr8" else (0, 1, 2)
        grey = GREY_WEIGHTS[0] * px[..., r] + GREY_WEIGHTS[1] * px[..., g] + GREY_WEIGHTS[2] * px[..., b]
        return w, h, w, "GREY", np.clip(grey + 0.5, 0, 255).astype(np.uint8).tobytes()
    if enc in ("yuv422", "uyvy"):  # ROS's yuv422 is U Y V Y: every second byte is luma
        return w, h, w, "GREY", rows[:, 1 : 2 * w : 2].tobytes()
    if enc in ("yuv422_yuy2", "yuyv"):
        return w, h, 2 * w, "YUYV", rows[:, : 2 * w].tobytes()
    fail(f"{where}: encoding '{msg.encoding}', expected mono8, bgr8, rgb8, yuv422 or yuv422_yuy2")


def jpeg_size(data, where):
    i = 2
    if data[:2] != b"\xff\xd8":
        fail(f"{where}: not a JPEG (no SOI marker)")
    while i + 9 < len(data):
        if data[i] != 0xFF:
            i += 1
            continue
        marker = data[i + 1]
        if marker in (0xC0, 0xC1, 0xC2, 0xC3, 0xC5, 0xC6, 0xC7, 0xC9, 0xCA, 0xCB, 0xCD, 0xCE, 0xCF):
            return int.from_bytes(data[i + 7 : i + 9], "big"), int.from_bytes(data[i + 5 : i + 7], "big")
        if marker in (0xD8, 0x01) or 0xD0 <= marker <= 0xD7:
            i += 2
            continue
        i += 2 + int.from_bytes(data[i + 2 : i + 4], "big")
    fail(f"{where}: JPEG without a frame header")


def png_size(data, where):
    if data[:8] != b"\x89PNG\r\n\x1a\n" or data[12:16] != b"IHDR":
        fail(f"{where}: not a PNG")
    return int.from_bytes(data[16:20], "big"), int.from_bytes(data[20:24], "big")


def write_intrinsics(msg, path, where):
    """sensor_msgs/CameraInfo to the OpenCV YAML file `kincal camcal` writes."""
    model = (msg.distortion_model or "plumb_bob").lower()
    d = [float(v) for v in msg.d]
    if model == "rational_polynomial" and all(v == 0.0 for v in d[5:]):
        d = d[:5]
    elif model != "plumb_bob":
        fail(f"{where}: distortion model '{msg.distortion_model}', expected plumb_bob")
    d = (d + [0.0] * 5)[:5]
    k = [float(v) for v in msg.k]
    if int(msg.width) <= 0 or int(msg.height) <= 0 or not k[0] > 0 or not k[4] > 0:
        fail(f"{where}: camera info without size or focal length (K = {k})")
    text = (
        "%YAML:1.0\n---\n"
        f"# from {where}\n"
        f"image_width: {int(msg.width)}\nimage_height: {int(msg.height)}\n"
        "camera_matrix: !!opencv-matrix\n   rows: 3\n   cols: 3\n   dt: d\n"
        f"   data: [ {', '.join(repr(v) for v in k)} ]\n"
        "distortion_coefficients: !!opencv-matrix\n   rows: 1\n   cols: 5\n   dt: d\n"
        f"   data: [ {', '.join(repr(v) for v in d)} ]\n"
    )
    write_atomically(path, text.encode())


def write_atomically(path, data):
    if os.path.islink(path):
        fail(f"{path}: is a symbolic link; kincal never writes through one")
    d = os.path.dirname(os.path.abspath(path))
    fd, tmp = tempfile.mkstemp(prefix=".kincal_import.", dir=d)
    try:
        with os.fdopen(fd, "wb") as f:
            f.write(data)
            f.flush()
            os.fsync(f.fileno())
        os.replace(tmp, path)
    except BaseException:
        os.unlink(tmp)
        raise


# --- the import -------------------------------------------------------------------------


def import_types(path):
    from kincal_lcm_types import use_lcm_types

    use_lcm_types(path)
    try:
        from kincal import controls_t, frame_t, pose_t, run_t  # noqa: F401
    except ImportError as e:
        fail(f"cannot import the kincal LCM types ({e}); pass --lcm-types DIR (build/lcmgen/python)")
    return controls_t, pose_t, frame_t, run_t


class Stream:
    """One requested topic: its role, type, stamp policy and last stamp."""

    def __init__(self, role, topic, typ, count):
        self.role, self.topic, self.type, self.count = role, topic, typ, count
        self.policy = None  # "header" or "receive", fixed by the first message
        self.last_ns = None
        self.written = 0
        self.encoder = None  # JointState positions: EncoderRates

    def stamp(self, msg, receive_ns, forced, index):
        where = f"topic {self.topic}, message {index}"
        header = stamp_ns(msg)
        if self.policy is None:
            if forced == "header" and header is None:
                fail(f"{where} ({self.type}): no header stamp; use --stamps receive or auto")
            self.policy = forced if forced != "auto" else ("header" if header is not None else "receive")
        if self.policy == "header" and header is None:
            fail(f"{where}: header stamp missing (zero) where earlier messages had one")
        ns = header if self.policy == "header" else receive_ns
        if self.last_ns is not None and ns < self.last_ns:
            fail(
                f"{where}: time goes back by {(self.last_ns - ns) * 1e-9:.6f} s "
                f"({self.policy} stamps must not decrease)"
            )
        self.last_ns = ns
        return ns


def select_streams(reader, args):
    topics = topics_of(reader)
    wanted = [
        ("controls", args.controls, CONTROL_TYPES),
        ("poses", args.poses, POSE_TYPES),
        ("frames", args.images, IMAGE_TYPES),
        ("camera_info", args.camera_info, {INFO_TYPE}),
    ]
    streams = {}
    for role, topic, types in wanted:
        if not topic:
            continue
        if topic not in topics:
            fail(f"topic {topic}: not in the bag (it has {', '.join(sorted(topics)) or 'no topics'})")
        typ, n = topics[topic]
        if typ not in types:
            fail(f"topic {topic}: type {typ} cannot be read as {role}; expected one of {', '.join(sorted(types))}")
        if n == 0:
            fail(f"topic {topic}: empty (no messages)")
        streams[topic] = Stream(role, topic, typ, n)
    return streams


def check_args(args):
    if not (args.controls or args.poses or args.images):
        fail("nothing to import: give --controls, --poses and/or --images (see --list)")
    if args.controls and not args.model:
        fail("--controls needs --model (diffdrive with JointState, unicycle with Twist, bicycle with AckermannDrive)")
    if args.model == "diffdrive":
        args.joint_names = [j for j in (args.joints or "").split(",") if j]
        if len(args.joint_names) != 2:
            fail("--model diffdrive needs --joints LEFT,RIGHT (the wheel joints' names)")
    if args.camera_info and not args.intrinsics_out:
        fail("--camera-info needs --intrinsics-out FILE.yaml")
    if not args.out:
        fail("give --out LOG (or --list)")


def check_model_type(stream, model):
    if model not in MODEL_CONTROLS:
        fail(
            f"--model {model}: import reads controls for diffdrive (JointState), unicycle (Twist) "
            "or bicycle (AckermannDriveStamped, AckermannDrive)"
        )
    want = MODEL_CONTROLS[model][0]
    if stream.type not in want:
        fail(f"topic {stream.topic}: {stream.type} are not {model} controls; expected {' or '.join(sorted(want))}")


class EncoderRates:
    """Wheel rates from encoder angles (JointState positions): the rate over each interval
    is its angle difference over its duration (exact for the increment), held from the
    interval's start as every control is; a continuous joint's wrap at +-pi is unwrapped."""

    def __init__(self):
        self.prev = None  # (utime, sender_utime, positions)
        self.last_rates = None

    def add(self, utime, sender_utime, positions, where):
        out = None
        if self.prev is not None:
            t0, s0, p0 = self.prev
            dt = (utime - t0) * 1e-6
            if dt <= 0:
                fail(f"{where}: encoder positions at a repeated time; rates need increasing stamps")
            rates = [math.remainder(b - a, 2 * math.pi) / dt if abs(b - a) > math.pi else (b - a) / dt for a, b in zip(p0, positions)]
            out = (t0, s0, rates)
            self.last_rates = rates
        self.prev = (utime, sender_utime, positions)
        return out

    def finish(self):
        """The last sample holds the last interval's rate to the end."""
        if self.prev is None or self.last_rates is None:
            return None
        return (self.prev[0], self.prev[1], self.last_rates)


class Writer:
    """kincal LCM messages into an event log; each bag's times moved by `shift_us`."""

    def __init__(self, log, types, model):
        self.log, self.model = log, model
        self.controls_t, self.pose_t, self.frame_t, self.run_t = types
        self.names = MODEL_CONTROLS.get(model, (None, []))[1]
        self.shift_us = 0
        self.last_utime = None

    def run(self, utime, index, source):
        m = self.run_t()
        m.schema_version, m.utime, m.index, m.source = 1, utime, index, source
        self.log.write_event(utime, RUN_CHANNEL, m.encode())

    def event(self, utime, channel, data):
        utime += self.shift_us
        self.last_utime = utime if self.last_utime is None else max(self.last_utime, utime)
        self.log.write_event(utime, channel, data)
        return utime

    def controls(self, utime, sender_utime, values):
        m = self.controls_t()
        m.schema_version, m.utime, m.sender_utime, m.model = 1, utime, sender_utime, self.model
        m.num_controls, m.names, m.values = len(values), self.names, values
        m.utime = utime + self.shift_us
        self.event(utime, CONTROLS_CHANNEL, m.encode())

    def pose(self, utime, x, y, theta, cov):
        m = self.pose_t()
        m.schema_version, m.utime, m.source_utime, m.target_id = 1, utime, utime, 0
        m.x, m.y, m.theta = x, y, theta
        m.covariance = cov if cov else [0.0] * 9
        m.reprojection_rms_px, m.valid = 0.0, 1
        m.utime = m.source_utime = utime + self.shift_us
        self.event(utime, POSE_CHANNEL, m.encode())

    def frame(self, utime, seq, w, h, stride, fmt, data):
        m = self.frame_t()
        m.schema_version, m.utime, m.device_utime, m.sequence = 1, utime, utime, seq
        m.width, m.height, m.stride, m.pixel_format = w, h, stride, fmt
        m.size, m.data = len(data), data
        m.utime = m.device_utime = utime + self.shift_us
        self.event(utime, FRAME_CHANNEL, m.encode())


def convert(reader, streams, args, writer, tilt):
    total = sum(s.count for s in streams.values())
    conns = [c for c in reader.connections if c.topic in streams]
    done, last_report, index = 0, time.monotonic(), {}
    for conn, receive_ns, raw in reader.messages(connections=conns):
        s = streams[conn.topic]
        index[s.topic] = index.get(s.topic, 0) + 1
        where = f"topic {s.topic}, message {index[s.topic]}"
        try:
            msg = reader.deserialize(raw, conn.msgtype)
        except Exception as e:  # rosbags raises several types for damaged data
            fail(f"{where} ({conn.msgtype}): cannot be decoded ({e})")
        one(s, msg, receive_ns, args, writer, tilt, where, index[s.topic])
        done += 1
        if time.monotonic() - last_report > 2.0:
            last_report = time.monotonic()
            print(f"kincal import: {100.0 * done / total:5.1f} % ({done} of {total} messages)", file=sys.stderr)


def one(s, msg, receive_ns, args, writer, tilt, where, i):
    if s.role == "camera_info":
        if s.written == 0:
            write_intrinsics(msg, args.intrinsics_out, where)
        s.written += 1
        return
    if s.role == "poses":
        got = pose_of(msg, s.type, args, where, tilt)
        if got is None:
            return
        x, y, theta, cov, carrier = got  # a tf message's stamp is its transform's
        utime = s.stamp(carrier, receive_ns, args.stamps, i) // 1000
        for v in (x, y, theta):
            if not math.isfinite(v):
                fail(f"{where}: pose is not finite")
        writer.pose(utime, x, y, theta, cov)
    elif s.role == "controls":
        values = controls_of(msg, s.type, args, where)
        if not all(math.isfinite(v) for v in values):
            fail(f"{where}: controls are not finite ({values})")
        utime = s.stamp(msg, receive_ns, args.stamps, i) // 1000
        header = stamp_ns(msg)
        sender = header // 1000 if header else 0
        if s.type == "sensor_msgs/msg/JointState" and args.joint_field == "position":
            s.encoder = s.encoder or EncoderRates()
            got = s.encoder.add(utime, sender, values, where)
            if got is not None:
                writer.controls(*got)
        else:
            writer.controls(utime, sender, values)
    else:
        utime = s.stamp(msg, receive_ns, args.stamps, i) // 1000
        writer.frame(utime, i - 1, *frame_of(msg, s.type, where))
    s.written += 1


def first_messages(reader, streams, limit=200):
    """{topic: [(header_ns or None, receive_ns), ...]}: the first `limit` controls and poses."""
    wanted = {t for t, s in streams.items() if s.role in ("controls", "poses")}
    seen = {t: [] for t in wanted}
    conns = [c for c in reader.connections if c.topic in wanted]
    if not conns:  # frames only (rosbags reads every connection when given none)
        return seen
    for conn, receive_ns, raw in reader.messages(connections=conns):
        if len(seen[conn.topic]) >= limit:
            if all(len(v) >= limit for v in seen.values()):
                break
            continue
        try:
            msg = reader.deserialize(raw, conn.msgtype)
        except Exception:  # the conversion names the damaged message
            break
        if streams[conn.topic].type == "tf2_msgs/msg/TFMessage":
            got = pose_of(msg, "tf2_msgs/msg/TFMessage", ARGS_FOR_TF[0], "", TiltStats(math.pi))
            header = stamp_ns(got[4]) if got else None
        else:
            header = stamp_ns(msg)
        seen[conn.topic].append((header, receive_ns))
    return seen


ARGS_FOR_TF = [None]  # the arguments, for reading a tf message's stamp in the first pass


def check_clocks(streams, seen, args, notes):
    """Two clocks: header stamps offset from the receive times by amounts more than 1 s
    apart between controls and poses. With --stamps auto both then use receive times."""
    offsets = {}
    for topic, pairs in seen.items():
        diffs = sorted(h - r for h, r in pairs if h is not None)
        if diffs and len(diffs) == len(pairs):
            offsets[topic] = diffs[len(diffs) // 2]
    roles = {streams[t].role: t for t in offsets}
    if "controls" not in roles or "poses" not in roles:
        return
    oc, op = offsets[roles["controls"]], offsets[roles["poses"]]
    if abs(oc - op) <= CLOCKS_APART_NS:
        return
    said = (
        f"two clocks: the header stamps of {roles['controls']} are {oc * 1e-9:+.3f} s from their receive "
        f"times, those of {roles['poses']} {op * 1e-9:+.3f} s"
    )
    if args.stamps == "auto":
        for t in seen:
            streams[t].policy = "receive"
    if any(n.startswith("two clocks") for n in notes):
        return  # said once per import (the first bag's offsets)
    if args.stamps == "auto":
        notes.append(said + ": both use their receive times (one machine received both)")
    else:
        notes.append(said + f": --stamps {args.stamps} keeps them as asked")


def bag_start_ns(streams, seen, args):
    """The earliest stamp of the bag's controls and poses under each stream's policy."""
    starts = []
    for topic, pairs in seen.items():
        if not pairs:
            continue
        h, r = pairs[0]
        policy = streams[topic].policy or (args.stamps if args.stamps != "auto" else ("header" if h else "receive"))
        starts.append(h if policy == "header" and h else r)
    return min(starts) if starts else None


def summarise(streams, tilt, args):
    for s in streams.values():
        what = {"controls": CONTROLS_CHANNEL, "poses": POSE_CHANNEL, "frames": FRAME_CHANNEL}.get(s.role)
        dest = f"-> {what}" if what else f"-> {args.intrinsics_out}"
        print(f"  {s.topic} ({s.type}): {s.written} {s.role} {dest}, stamps: {s.policy or 'none'}")
        if s.role == "poses" and s.written == 0:
            fail(f"topic {s.topic}: no pose for frame '{args.tf_frame}' in {s.count} messages")
    if tilt.over:
        print(
            f"kincal import: warning: {tilt.over} poses tilted more than {args.max_tilt_deg:g} deg "
            f"(worst {math.degrees(tilt.worst):.1f} deg, first at {tilt.first}); the planar pose "
            f"keeps only the heading",
            file=sys.stderr,
        )


def same_streams(first, streams, bag):
    """Every bag of one import has the first bag's topics with the same types."""
    for t, s in first.items():
        if t not in streams or streams[t].type != s.type:
            got = streams[t].type if t in streams else "no such topic"
            fail(f"{bag}: topic {t} is {got}, the first bag's is {s.type}: bags of one robot expected")


def import_bag(bag, index, args, writer, tilt, first, notes):
    """One bag as run `index` of the log; returns its streams."""
    with open_bag(bag) as reader:
        streams = select_streams(reader, args)
        for s in streams.values():
            if s.role == "controls":
                check_model_type(s, args.model)
            if s.role == "poses" and s.type == "tf2_msgs/msg/TFMessage" and not args.tf_frame:
                fail(f"topic {s.topic}: tf needs --tf-frame CHILD (the tracked body's frame)")
        if first is not None:
            same_streams(first, streams, bag)
        seen = first_messages(reader, streams)
        check_clocks(streams, seen, args, notes)
        start = bag_start_ns(streams, seen, args)
        if args.multi and start is not None:
            start_us = start // 1000
            writer.shift_us = 0
            if writer.last_utime is not None and start_us < writer.last_utime + RUN_GAP_NS // 1000:
                writer.shift_us = writer.last_utime + RUN_GAP_NS // 1000 - start_us
                notes.append(
                    f"{bag}: starts {writer.shift_us * 1e-6:.3f} s too early to follow the previous bag "
                    "(its own clock, or out of order): moved to start 1 s after it"
                )
            writer.run(start_us + writer.shift_us, index, bag)
        convert(reader, streams, args, writer, tilt)
        for st in streams.values():
            if st.encoder is not None and (last := st.encoder.finish()) is not None:
                writer.controls(*last)
            st.encoder = None
    return streams


def run(args):
    import lcm

    if args.list:
        for bag in bag_paths(args.bag):
            with open_bag(bag) as reader:
                if len(args.bag) > 1 or bag != args.bag[0]:
                    print(f"{bag}:")
                list_bag(reader)
        return
    check_args(args)
    bags = bag_paths(args.bag)
    args.multi = len(bags) > 1
    ARGS_FOR_TF[0] = args
    types = import_types(args.lcm_types)
    tilt = TiltStats(math.radians(args.max_tilt_deg))
    out = os.path.abspath(args.out)
    if os.path.islink(out):
        fail(f"{args.out}: is a symbolic link; kincal never writes through one")
    fd, tmp = tempfile.mkstemp(prefix=".kincal_import.", suffix=".lcm", dir=os.path.dirname(out))
    os.close(fd)
    try:
        log = lcm.EventLog(tmp, "w", overwrite=True)
        writer, first, notes, totals = Writer(log, types, args.model), None, [], {}
        for i, bag in enumerate(bags):
            streams = import_bag(bag, i, args, writer, tilt, first, notes)
            first = first or streams
            for t, st in streams.items():
                if t in totals:
                    totals[t].written += st.written
                else:
                    totals[t] = st
        log.close()
        what = f"{len(bags)} bags (one run each)" if args.multi else bags[0]
        print(f"kincal import: {what} -> {args.out}")
        summarise(totals, tilt, args)
        for n in notes:
            print(f"kincal import: note: {n}")
        os.replace(tmp, out)
    except BaseException:
        os.unlink(tmp)
        raise


def parse(argv):
    ap = argparse.ArgumentParser(prog="kincal import", description=__doc__.splitlines()[0])
    ap.add_argument("bag", nargs="+", help="ROS 1 .bag files, ROS 2 bag folders, or a folder of bags: one run each")
    ap.add_argument("--list", action="store_true", help="list topics, types, counts, rates; suggest a mapping")
    ap.add_argument("--out", help="the LCM log to write")
    ap.add_argument("--model", help="diffdrive (JointState controls), unicycle (Twist) or bicycle (AckermannDrive)")
    ap.add_argument("--controls", help="controls topic")
    ap.add_argument("--joints", help="diffdrive: LEFT,RIGHT wheel joint names in the JointState")
    ap.add_argument("--joint-field", choices=("velocity", "position"),
                    help="JointState field the wheel rates come from (default: velocity when published, "
                    "else position: encoder angles differenced over each interval)")
    ap.add_argument("--poses", help="measured pose topic (PoseStamped, PoseWithCovarianceStamped, TransformStamped, tf, Odometry)")
    ap.add_argument("--tf-frame", help="with tf poses: the tracked body's child frame")
    ap.add_argument("--images", help="camera frames topic (Image or CompressedImage)")
    ap.add_argument("--camera-info", help="CameraInfo topic")
    ap.add_argument("--intrinsics-out", help="with --camera-info: the intrinsics file to write")
    ap.add_argument("--stamps", choices=("auto", "header", "receive"), default="auto",
                    help="auto: header stamps where set, else receive time (default)")
    ap.add_argument("--max-tilt-deg", type=float, default=5.0, help="warn when a pose tilts more (default 5)")
    ap.add_argument("--lcm-types", help="folder holding the kincal LCM Python package")
    return ap.parse_args(argv)


def main(argv=None):
    args = parse(argv if argv is not None else sys.argv[1:])
    try:
        run(args)
    except ImportError_ as e:
        print(f"kincal import: error: {e}", file=sys.stderr)
        return 1
    except Exception as e:  # the bag library's own errors: name the bag
        print(f"kincal import: error: {' '.join(args.bag)}: {type(e).__name__}: {e}", file=sys.stderr)
        return 1
    return 0


if __name__ == "__main__":
    sys.exit(main())
