"""Simulated robots recorded as ROS bags by rosbags' own writers, for the import tests.

Truth is simulated here in Python, independently of kincal's C++ simulator: a
differential-drive robot (wheel radii, track, a control delay kincal is not told about)
and a unicycle (speed and turn scales, first-order lag), each driven by piecewise-constant
commands and seen by motion capture with Gaussian noise. Fixed seeds.
"""

import math
from dataclasses import dataclass, field

import numpy as np
from rosbags.rosbag1 import Writer as Writer1
from rosbags.rosbag2 import StoragePlugin, Writer as Writer2
from rosbags.typesys import Stores, get_types_from_msg, get_typestore

STORE = get_typestore(Stores.ROS2_HUMBLE)
# ackermann_msgs, as the ROS interface defines them (not in rosbags' standard store).
STORE.register(
    {
        **get_types_from_msg(
            "float32 steering_angle\nfloat32 steering_angle_velocity\nfloat32 speed\n"
            "float32 acceleration\nfloat32 jerk\n",
            "ackermann_msgs/msg/AckermannDrive",
        ),
        **get_types_from_msg(
            "std_msgs/Header header\nackermann_msgs/AckermannDrive drive\n", "ackermann_msgs/msg/AckermannDriveStamped"
        ),
    }
)
T = STORE.types


@dataclass
class Sim:
    """Commands (t, values) and measured poses (t, x, y, theta), seconds and SI units."""

    controls: list = field(default_factory=list)
    poses: list = field(default_factory=list)
    truth: dict = field(default_factory=dict)


def commands(rng, duration, hold, draw, period):
    """Piecewise-constant commands: a new draw every `hold` s (jittered), on the control
    stream's `period` grid: the robot acts on the messages it is sent, as recorded."""
    t, out = 0.0, []
    while t < duration:
        out.append((t, draw(rng)))
        t += round(hold * (0.6 + 0.8 * rng.random()) / period) * period
    return out


def held(cmds, t):
    v = cmds[0][1]
    for tc, c in cmds:
        if tc > t + 1e-9:
            break
        v = c
    return v


def simulate(step, cmds, duration, control_hz, pose_hz, rng, sigma_pos, sigma_theta):
    sim = Sim()
    dt = 1e-3
    x = np.zeros(3)
    state = None
    n = int(round(duration / dt))
    next_pose = 0.0
    for k in range(n + 1):
        t = k * dt
        if k % int(round(1.0 / (control_hz * dt))) == 0:
            sim.controls.append((t, held(cmds, t)))
        if t >= next_pose - 1e-9:
            z = (
                x[0] + rng.normal(0, sigma_pos),
                x[1] + rng.normal(0, sigma_pos),
                math.remainder(x[2] + rng.normal(0, sigma_theta), 2 * math.pi),
            )
            sim.poses.append((t, z))
            next_pose += 1.0 / pose_hz
        v, w, state = step(t, state)
        x = x + dt * np.array([v * math.cos(x[2] + 0.5 * w * dt), v * math.sin(x[2] + 0.5 * w * dt), w])
    return sim


def diffdrive(seed=3, duration=80.0):
    """Wheel rates from JointState; a 60 ms delay between command and wheels."""
    rng = np.random.default_rng(seed)
    truth = {"r_l": 0.0342, "r_r": 0.0336, "d": 0.1720, "delay_s": 0.060}

    def draw(g):
        v = g.uniform(0.05, 0.35) * (1 if g.random() < 0.8 else -1)
        w = g.uniform(-2.0, 2.0)
        return [(v - 0.5 * w * 0.172) / 0.034, (v + 0.5 * w * 0.172) / 0.034]

    cmds = commands(rng, duration, 1.5, draw, 1.0 / 50.0)

    def step(t, state):
        wl, wr = held(cmds, t - truth["delay_s"]) if t >= truth["delay_s"] else (0.0, 0.0)
        vl, vr = truth["r_l"] * wl, truth["r_r"] * wr
        return 0.5 * (vl + vr), (vr - vl) / truth["d"], state

    sim = simulate(step, cmds, duration, 50.0, 30.0, rng, 0.0005, 0.002)
    sim.truth = truth
    return sim


def unicycle(seed=4, duration=80.0):
    """cmd_vel Twist; the robot realises scaled speeds through a first-order lag."""
    rng = np.random.default_rng(seed)
    truth = {"k_v": 0.93, "k_omega": 1.06, "tau_s": 0.15}

    def draw(g):
        return [g.uniform(0.05, 0.4), g.uniform(-1.2, 1.2)]

    cmds = commands(rng, duration, 1.5, draw, 1.0 / 20.0)

    def step(t, state):
        v, w = state if state is not None else (0.0, 0.0)
        cv, cw = held(cmds, t)
        a = 1.0 - math.exp(-1e-3 / truth["tau_s"])  # exact for a command held over the step
        v += a * (truth["k_v"] * cv - v)
        w += a * (truth["k_omega"] * cw - w)
        return v, w, (v, w)

    sim = simulate(step, cmds, duration, 20.0, 50.0, rng, 0.0008, 0.003)
    sim.truth = truth
    return sim


CAR_TRUTH = {"k_v": 0.95, "k_steer": 0.6, "steer_offset": 0.02, "wheelbase": 0.33, "tau_s_steer": 0.1}


def car_run(rng, duration=4.0, pose_hz=60.0):
    """One run of a 1/10-scale car from a random place: AckermannDrive commands (speed,
    steering angle) on a 20 Hz grid; the car realises k_v x the speed and a steering
    angle k_steer x the command + offset through a first-order servo lag; rear-axle
    bicycle kinematics; motion capture with 0.5 mm / 2 mrad noise."""
    tr = CAR_TRUTH

    def draw(g):
        return [g.uniform(0.5, 2.0), g.uniform(-0.35, 0.35)]

    cmds = commands(rng, duration, 0.8, draw, 1.0 / 20.0)

    def step(t, state):
        phi = state if state is not None else tr["k_steer"] * cmds[0][1][1] + tr["steer_offset"]
        v_cmd, s_cmd = held(cmds, t)
        a = 1.0 - math.exp(-1e-3 / tr["tau_s_steer"])
        phi += a * (tr["k_steer"] * s_cmd + tr["steer_offset"] - phi)
        v = tr["k_v"] * v_cmd
        return v, v * math.tan(phi) / tr["wheelbase"], phi

    sim = simulate(step, cmds, duration, 20.0, pose_hz, rng, 0.0005, 0.002)
    start = np.array([rng.uniform(-2, 2), rng.uniform(-2, 2), rng.uniform(-3, 3)])
    c, s_ = math.cos(start[2]), math.sin(start[2])
    sim.poses = [
        (t, (start[0] + c * z[0] - s_ * z[1], start[1] + s_ * z[0] + c * z[1], math.remainder(z[2] + start[2], 2 * math.pi)))
        for t, z in sim.poses
    ]
    sim.truth = tr
    return sim


# --- ROS messages -------------------------------------------------------------------------


def stamp(t, t0=1_700_000_000.0):
    ns = int(round((t0 + t) * 1e9))
    return T["builtin_interfaces/msg/Time"](sec=ns // 1_000_000_000, nanosec=ns % 1_000_000_000), ns


def header(t, frame="world"):
    s, ns = stamp(t)
    return T["std_msgs/msg/Header"](stamp=s, frame_id=frame), ns


def quaternion(theta, tilt=0.0):
    # Yaw theta, then a small roll `tilt` about the body's x axis.
    cy, sy, cr, sr = math.cos(theta / 2), math.sin(theta / 2), math.cos(tilt / 2), math.sin(tilt / 2)
    return T["geometry_msgs/msg/Quaternion"](x=cy * sr, y=sy * sr, z=sy * cr, w=cy * cr)


def vec3(x=0.0, y=0.0, z=0.0):
    return T["geometry_msgs/msg/Vector3"](x=x, y=y, z=z)


def point(x, y, z=0.0):
    return T["geometry_msgs/msg/Point"](x=x, y=y, z=z)


def joint_state(t, wl, wr):
    h, ns = header(t, "")
    msg = T["sensor_msgs/msg/JointState"](
        header=h,
        name=["caster_joint", "left_wheel_joint", "right_wheel_joint"],
        position=np.zeros(3),
        velocity=np.array([0.0, wl, wr]),
        effort=np.zeros(0),
    )
    return msg, ns


def pose_stamped(t, z):
    h, ns = header(t)
    pose = T["geometry_msgs/msg/Pose"](position=point(z[0], z[1], 0.1), orientation=quaternion(z[2]))
    return T["geometry_msgs/msg/PoseStamped"](header=h, pose=pose), ns


def tf_message(t, z):
    h, ns = header(t)
    tr = T["geometry_msgs/msg/Transform"](translation=vec3(z[0], z[1], 0.1), rotation=quaternion(z[2]))
    robot = T["geometry_msgs/msg/TransformStamped"](header=h, child_frame_id="robot", transform=tr)
    other = T["geometry_msgs/msg/TransformStamped"](header=h, child_frame_id="wand", transform=tr)
    return T["tf2_msgs/msg/TFMessage"](transforms=[other, robot]), ns


def ackermann_stamped(t, speed, steer, clock_offset_s):
    s, _ = stamp(t + clock_offset_s)
    h = T["std_msgs/msg/Header"](stamp=s, frame_id="base_link")
    drive = T["ackermann_msgs/msg/AckermannDrive"](
        steering_angle=steer, steering_angle_velocity=0.0, speed=speed, acceleration=0.0, jerk=0.0
    )
    return T["ackermann_msgs/msg/AckermannDriveStamped"](header=h, drive=drive)


def joint_positions(t, angles):
    """A JointState with encoder angles only (no velocities), as many drivers publish."""
    h, ns = header(t, "")
    msg = T["sensor_msgs/msg/JointState"](
        header=h,
        name=["left_wheel_joint", "right_wheel_joint"],
        position=np.array(angles),
        velocity=np.zeros(0),
        effort=np.zeros(0),
    )
    return msg, ns


def twist(v, w):
    return T["geometry_msgs/msg/Twist"](linear=vec3(v), angular=vec3(0.0, 0.0, w))


def odometry(t, z):
    h, ns = header(t, "odom")
    cov = np.zeros(36)
    cov[0] = cov[7] = 0.0008**2
    cov[35] = 0.003**2
    pose = T["geometry_msgs/msg/PoseWithCovariance"](
        pose=T["geometry_msgs/msg/Pose"](position=point(z[0], z[1]), orientation=quaternion(z[2])), covariance=cov
    )
    tw = T["geometry_msgs/msg/TwistWithCovariance"](twist=twist(0.0, 0.0), covariance=np.zeros(36))
    return T["nav_msgs/msg/Odometry"](header=h, child_frame_id="base_link", pose=pose, twist=tw), ns


# --- writers ------------------------------------------------------------------------------


class BagWriter:
    """One interface over rosbags' ROS 1 and ROS 2 writers."""

    def __init__(self, path, kind):
        self.kind = kind
        if kind == "ros1":
            self.w = Writer1(path)
        else:
            plugin = StoragePlugin.MCAP if kind == "mcap" else StoragePlugin.SQLITE3
            self.w = Writer2(path, version=9, storage_plugin=plugin)
        self.conns = {}

    def __enter__(self):
        self.w.open()
        return self

    def __exit__(self, *exc):
        self.w.close()

    def write(self, topic, typ, msg, receive_ns):
        if topic not in self.conns:
            self.conns[topic] = self.w.add_connection(topic, typ, typestore=STORE)
        if self.kind == "ros1":
            data = STORE.serialize_ros1(msg, typ)
        else:
            data = STORE.serialize_cdr(msg, typ)
        self.w.write(self.conns[topic], receive_ns, data)


def in_time_order(*streams):
    """Merge (receive_ns, topic, type, msg) lists by receive time (a recorder's order)."""
    out = [e for s in streams for e in s]
    out.sort(key=lambda e: e[0])
    return out


def write_diffdrive(path, kind, sim, pose_style="pose_stamped", latency_s=0.004):
    controls = []
    for t, (wl, wr) in sim.controls:
        msg, ns = joint_state(t, wl, wr)
        controls.append((ns + int(latency_s * 1e9), "/joint_states", "sensor_msgs/msg/JointState", msg))
    poses = []
    for t, z in sim.poses:
        if pose_style == "tf":
            msg, ns = tf_message(t, z)
            poses.append((ns + int(latency_s * 1e9), "/tf", "tf2_msgs/msg/TFMessage", msg))
        else:
            msg, ns = pose_stamped(t, z)
            poses.append((ns + int(latency_s * 1e9), "/mocap/robot/pose", "geometry_msgs/msg/PoseStamped", msg))
    with BagWriter(path, kind) as w:
        for ns, topic, typ, msg in in_time_order(controls, poses):
            w.write(topic, typ, msg, ns)


def write_unicycle(path, kind, sim, latency_s=0.003):
    # A Twist has no header: its receive time is its stamp, so it is recorded as sent (a
    # transport delay would be a true delay between command and motion, and read as one).
    controls = []
    for t, (v, w) in sim.controls:
        _, ns = stamp(t)
        controls.append((ns, "/cmd_vel", "geometry_msgs/msg/Twist", twist(v, w)))
    poses = []
    for t, z in sim.poses:
        msg, ns = odometry(t, z)
        poses.append((ns + int(latency_s * 1e9), "/mocap/odom", "nav_msgs/msg/Odometry", msg))
    with BagWriter(path, kind) as w:
        for ns, topic, typ, msg in in_time_order(controls, poses):
            w.write(topic, typ, msg, ns)


def write_car_run(path, sim, t0_s, clock_offset_s=-8000.0, latency_s=0.004):
    """One run as a ROS 1 bag: /drive AckermannDriveStamped stamped by the car's own clock
    (clock_offset_s away from the recorder's), received as sent; /mocap/car/pose
    PoseStamped stamped by the recorder's clock, received latency_s later."""
    controls, poses = [], []
    for t, (v, steer) in sim.controls:
        _, ns = stamp(t0_s + t)
        controls.append((ns, "/drive", "ackermann_msgs/msg/AckermannDriveStamped", ackermann_stamped(t0_s + t, v, steer, clock_offset_s)))
    for t, z in sim.poses:
        msg, ns = pose_stamped(t0_s + t, z)
        poses.append((ns + int(latency_s * 1e9), "/mocap/car/pose", "geometry_msgs/msg/PoseStamped", msg))
    with BagWriter(path, "ros1") as w:
        for ns, topic, typ, msg in in_time_order(controls, poses):
            w.write(topic, typ, msg, ns)


def write_diffdrive_encoders(path, kind, sim, latency_s=0.004):
    """The diff drive with JointState positions only: each wheel's angle, the integral of
    its rate, wrapped to (-pi, pi] as continuous joints are reported."""
    controls, angles, last_t, rates = [], [0.0, 0.0], None, None
    for t, (wl, wr) in sim.controls:
        if last_t is not None:
            angles = [a + r * (t - last_t) for a, r in zip(angles, rates)]
        last_t, rates = t, (wl, wr)
        msg, ns = joint_positions(t, [math.remainder(a, 2 * math.pi) for a in angles])
        controls.append((ns + int(latency_s * 1e9), "/joint_states", "sensor_msgs/msg/JointState", msg))
    poses = []
    for t, z in sim.poses:
        msg, ns = pose_stamped(t, z)
        poses.append((ns + int(latency_s * 1e9), "/mocap/robot/pose", "geometry_msgs/msg/PoseStamped", msg))
    with BagWriter(path, kind) as w:
        for ns, topic, typ, msg in in_time_order(controls, poses):
            w.write(topic, typ, msg, ns)
