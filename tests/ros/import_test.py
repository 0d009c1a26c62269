"""kincal import and export on bags written by rosbags' own writers (ROS 1 .bag, ROS 2
.db3 and .mcap): parameters recovered within 3 sigma of the simulated truth, hidden
effects found, ros2_control parameters exported, and bad bags refused with a clear error.

Run by ctest with the venv's Python: KINCAL_BIN names the kincal executable, KINCALD_BIN
kincald (which replays an imported log from its poses).
"""

import json
import math
import os
import subprocess
import sys
import tempfile
import unittest

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import ros_bags  # noqa: E402

KINCAL = os.environ.get("KINCAL_BIN", "kincal")
KINCALD = os.environ.get("KINCALD_BIN", "kincald")


def kincal(*args, ok=True):
    r = subprocess.run([KINCAL, *args], capture_output=True, text=True, timeout=600)
    if ok and r.returncode != 0:
        raise AssertionError(f"kincal {' '.join(args)} failed ({r.returncode}):\n{r.stdout}\n{r.stderr}")
    return r


def read_ros2_params(path, controller):
    """{key: number} under CONTROLLER: ros__parameters: in the export (its own small
    format: one `key: value  # comment` per line), checked line by line."""
    params, inside = {}, False
    with open(path) as f:
        for line in f:
            text = line.split("#", 1)[0].rstrip()
            if not text:
                continue
            if not line.startswith(" "):
                inside = text == f"{controller}:"
            elif inside and text.strip() != "ros__parameters:":
                key, value = text.strip().split(":", 1)
                params[key] = float(value)
    return params


class Fixture(unittest.TestCase):
    def setUp(self):
        self._tmp = tempfile.TemporaryDirectory(prefix="kincal_ros_")
        self.dir = self._tmp.name

    def tearDown(self):
        self._tmp.cleanup()

    def path(self, name):
        return os.path.join(self.dir, name)

    def analyze(self, log, model, init, effects="auto"):
        out = self.path("analysis")
        kincal("analyze", "--log", log, "--model", model, "--init", init, "--effects", effects, "--out", out)
        with open(os.path.join(out, "report.json")) as f:
            return json.load(f), os.path.join(out, "report.json")

    def assert_within_3_sigma(self, report, truth, names):
        params = report["after"]["params"]
        for n in names:
            p = params[n]
            err = p["value"] - truth[n]
            self.assertLess(abs(err), 3.0 * p["sigma"], f"{n}: {p['value']:.6g} +- {p['sigma']:.2g}, truth {truth[n]}")


class DiffDrive(Fixture):
    def check_diffdrive(self, kind, bag_name, pose_style, pose_args):
        sim = ros_bags.diffdrive()
        bag = self.path(bag_name)
        ros_bags.write_diffdrive(bag, kind, sim, pose_style)
        log = self.path("robot.lcm")
        r = kincal("import", bag, "--out", log, "--model", "diffdrive", "--controls", "/joint_states",
                   "--joints", "left_wheel_joint,right_wheel_joint", *pose_args)
        self.assertIn("stamps: header", r.stdout)
        report, report_path = self.analyze(log, "diffdrive", "r_l=0.034,r_r=0.034,d=0.17")
        self.assertIn("time_offset", report["after"]["effects"], report["after"]["effects"])
        self.assert_within_3_sigma(report, sim.truth, ["r_l", "r_r", "d", "delay_s"])
        before = report["before"]["heldout"]["pos_rms_m"]
        after = report["after"]["heldout"]["pos_rms_m"]
        self.assertLess(after, 0.5 * before, f"held-out position RMS {before} -> {after}")
        return sim, report_path

    def test_ros1_bag_joint_states_and_mocap_pose(self):
        sim, report = self.check_diffdrive("ros1", "robot.bag", "pose_stamped", ["--poses", "/mocap/robot/pose"])
        # Round trip: the exported controller parameters give the true wheels and track.
        yaml_path = self.path("robot_kinematics.yaml")
        kincal("export", "--report", report, "--format", "ros2_control", "--out", yaml_path)
        p = read_ros2_params(yaml_path, "diff_drive_controller")
        with open(yaml_path) as f:
            text = f.read()
        self.assertIn("sigma", text)
        r = p["wheel_radius"]
        self.assertAlmostEqual(r * p["left_wheel_radius_multiplier"], sim.truth["r_l"], delta=1e-4)
        self.assertAlmostEqual(r * p["right_wheel_radius_multiplier"], sim.truth["r_r"], delta=1e-4)
        self.assertAlmostEqual(p["wheel_separation"] * p["wheel_separation_multiplier"], sim.truth["d"], delta=1e-3)
        # With the user's nominal values kept, the calibration is in the multipliers.
        kincal("export", "--report", report, "--format", "ros2_control", "--nominal",
               "wheel_radius=0.034,wheel_separation=0.17", "--out", yaml_path)
        q = read_ros2_params(yaml_path, "diff_drive_controller")
        self.assertEqual(q["wheel_radius"], 0.034)
        self.assertEqual(q["wheel_separation"], 0.17)
        self.assertAlmostEqual(0.034 * q["left_wheel_radius_multiplier"], r * p["left_wheel_radius_multiplier"], delta=1e-9)
        self.assertAlmostEqual(0.17 * q["wheel_separation_multiplier"], p["wheel_separation"] * p["wheel_separation_multiplier"], delta=1e-9)

    def test_ros2_db3_joint_states_and_tf(self):
        self.check_diffdrive("db3", "robot_db3", "tf", ["--poses", "/tf", "--tf-frame", "robot"])


class Unicycle(Fixture):
    def test_ros2_mcap_cmd_vel_and_odometry(self):
        sim = ros_bags.unicycle()
        bag = self.path("robot_mcap")
        ros_bags.write_unicycle(bag, "mcap", sim)
        log = self.path("robot.lcm")
        r = kincal("import", bag, "--out", log, "--model", "unicycle", "--controls", "/cmd_vel", "--poses", "/mocap/odom")
        self.assertIn("/cmd_vel (geometry_msgs/msg/Twist)", r.stdout)
        self.assertIn("stamps: receive", r.stdout)  # a Twist has no header
        report, _ = self.analyze(log, "unicycle", "k_v=1,k_omega=1")
        self.assertIn("actuator_lag", report["after"]["effects"], report["after"]["effects"])
        truth = dict(sim.truth)
        self.assert_within_3_sigma(report, truth, ["k_v", "k_omega", "tau_s"])


class Listing(Fixture):
    def test_list_shows_topics_counts_rates_and_a_mapping(self):
        sim = ros_bags.diffdrive(duration=10.0)
        bag = self.path("robot.bag")
        ros_bags.write_diffdrive(bag, "ros1", sim)
        r = kincal("import", bag, "--list")
        self.assertRegex(r.stdout, r"/joint_states\s+sensor_msgs/msg/JointState\s+501 msgs\s+50\.\d Hz")
        self.assertIn("--model diffdrive --controls /joint_states --joints LEFT,RIGHT", r.stdout)
        self.assertIn("--poses /mocap/robot/pose", r.stdout)


class Car(Fixture):
    """Issue 33: a 1/10-scale car, thirty 4 s ROS 1 bags of AckermannDriveStamped commands
    (stamped by the car's clock, 8,000 s off) and motion-capture poses; steering gain 0.6,
    offset 0.02 rad and a 0.1 s steering lag, the wheelbase held from the drawing."""

    def write_bags(self, folder, runs=30):
        import numpy as np

        os.makedirs(folder)
        rng = np.random.default_rng(33)
        sims = []
        for k in range(runs):
            sim = ros_bags.car_run(rng)
            ros_bags.write_car_run(os.path.join(folder, f"run_{k:02d}.bag"), sim, t0_s=10.0 * k)
            sims.append(sim)
        return sims

    def test_thirty_bags_to_parameters_in_three_commands(self):
        folder = self.path("bags")
        self.write_bags(folder)
        r = kincal("import", "--list", os.path.join(folder, "run_00.bag"))
        self.assertIn("--model bicycle --controls /drive", r.stdout)
        log = self.path("car.lcm")
        bags = sorted(os.path.join(folder, b) for b in os.listdir(folder))
        r = kincal("import", *bags, "--out", log, "--model", "bicycle", "--controls", "/drive",
                   "--poses", "/mocap/car/pose")
        self.assertIn("30 bags (one run each)", r.stdout)
        self.assertIn("two clocks", r.stdout)
        self.assertIn("-8000.0", r.stdout)  # the commands' offset, said
        self.assertIn("stamps: receive", r.stdout)
        out = self.path("analysis")
        kincal("analyze", "--log", log, "--model", "bicycle", "--fix", "wheelbase=0.33", "--out", out)
        with open(os.path.join(out, "report.json")) as f:
            report = json.load(f)
        self.assertEqual(len(report["runs"]), 30)
        self.assertEqual([x["index"] for x in report["runs"] if x["heldout"]], list(range(3, 31, 3)))
        self.assertEqual(report["after"]["fixed"], ["wheelbase=0.33"])
        self.assertTrue(any(e.startswith("actuator_lag") for e in report["after"]["effects"]), report["after"]["effects"])
        truth = dict(ros_bags.CAR_TRUTH)
        self.assert_within_3_sigma(report, truth, ["k_v", "k_steer", "steer_offset"])
        lag = [p for n, p in report["after"]["params"].items() if n.startswith("tau_s")]
        self.assertLess(abs(lag[0]["value"] - truth["tau_s_steer"]), 3 * lag[0]["sigma"] + 0.01, lag)
        dr = report["dead_reckoning"]
        self.assertLess(dr["after"]["rms_m"], dr["before"]["rms_m"])
        yaml_path = self.path("car_kinematics.yaml")
        kincal("export", "--report", os.path.join(out, "report.json"), "--format", "ros2_control",
               "--nominal", "wheel_radius=0.05", "--out", yaml_path)
        p = read_ros2_params(yaml_path, "ackermann_steering_controller")
        self.assertEqual(p["wheelbase"], 0.33)
        k_v = report["after"]["params"]["k_v"]
        self.assertAlmostEqual(p["traction_wheels_radius"], 0.05 * k_v["value"], delta=1e-9)
        self.check_kincald_agrees(log, report, truth)
        # A folder of bags is the same import.
        log2 = self.path("car2.lcm")
        kincal("import", folder, "--out", log2, "--model", "bicycle", "--controls", "/drive", "--poses", "/mocap/car/pose")
        with open(log, "rb") as a, open(log2, "rb") as b:
            self.assertEqual(a.read(), b.read())

    def check_kincald_agrees(self, log, report, truth):
        """kincald replays the imported log (no frames: its poses are the measurements) with
        the wheelbase held and effects found as it runs: the truth within 3 sigma, the
        steering lag found, and the calibration analyze's within their sigmas."""
        config, checkpoint = self.path("car_kincald.yaml"), self.path("car_checkpoint.json")
        with open(config, "w") as f:
            f.write("robot:\n  model: bicycle\n  effects: auto\n"
                    "  guess: {k_v: 1.0, k_steer: 1.0, steer_offset: 0.0, wheelbase: 0.33}\n"
                    "  fixed: {wheelbase: 0.33}\nlcm:\n  url: memq://\n")
        r = subprocess.run([KINCALD, "-c", config, "--replay", log, "--speed", "0", "--checkpoint", checkpoint],
                           capture_output=True, text=True, timeout=600)
        self.assertEqual(r.returncode, 0, r.stderr)
        self.assertIn("has no frames: its", r.stderr + r.stdout)
        self.assertIn("poses of its 30 runs;", r.stdout)  # the bags are runs, never joined
        with open(checkpoint) as f:
            c = json.load(f)
        self.assertEqual(c["source"], "batch")
        self.assertTrue(any(e.startswith("actuator_lag") for e in c["effects"]), c["effects"])
        sigma = {n: math.sqrt(c["covariance"][i][i]) for i, n in enumerate(c["names"])}
        value = dict(zip(c["names"], c["values"]))
        for n in ("k_v", "k_steer", "steer_offset"):
            self.assertLess(abs(value[n] - truth[n]), 3 * sigma[n], f"kincald {n}: {value[n]} +- {sigma[n]}")
            a = report["after"]["params"][n]
            self.assertLess(abs(value[n] - a["value"]), 3 * max(sigma[n], a["sigma"]),
                            f"{n}: kincald {value[n]} +- {sigma[n]}, analyze {a['value']} +- {a['sigma']}")
        self.assertEqual(value["wheelbase"], 0.33)

    def test_bags_of_different_robots_are_refused_and_nothing_written(self):
        folder = self.path("bags")
        self.write_bags(folder, runs=2)
        other = self.path("other.bag")
        ros_bags.write_diffdrive(other, "ros1", ros_bags.diffdrive(duration=3.0))
        log = self.path("car.lcm")
        r = kincal("import", os.path.join(folder, "run_00.bag"), other, "--out", log, "--model", "bicycle",
                   "--controls", "/drive", "--poses", "/mocap/car/pose", ok=False)
        self.assertNotEqual(r.returncode, 0)
        self.assertIn("topic /drive: not in the bag", r.stderr)
        self.assertFalse(os.path.exists(log))


class Encoders(Fixture):
    """A diff drive whose JointState has encoder angles and no velocities: the rates come
    from the angle differences, and the wheels come back within 3 sigma."""

    def test_joint_positions_only(self):
        sim = ros_bags.diffdrive()
        bag = self.path("robot.bag")
        ros_bags.write_diffdrive_encoders(bag, "ros1", sim)
        log = self.path("robot.lcm")
        kincal("import", bag, "--out", log, "--model", "diffdrive", "--controls", "/joint_states",
               "--joints", "left_wheel_joint,right_wheel_joint", "--poses", "/mocap/robot/pose")
        report, _ = self.analyze(log, "diffdrive", "r_l=0.034,r_r=0.034,d=0.17")
        self.assert_within_3_sigma(report, sim.truth, ["r_l", "r_r", "d"])
        r = kincal("import", bag, "--out", log, "--model", "diffdrive", "--controls", "/joint_states",
                   "--joints", "left_wheel_joint,right_wheel_joint", "--joint-field", "velocity", ok=False)
        self.assertIn("2 joint names but 0 velocity values", r.stderr)


class LargeBag(Fixture):
    """Streaming: importing five times the frames takes no more memory."""

    def write_frames(self, path, n):
        import numpy as np

        rng = np.random.default_rng(1)
        frame = rng.integers(0, 255, 320 * 240, dtype=np.uint8)
        with ros_bags.BagWriter(path, "ros1") as w:
            for i in range(n):
                h, ns = ros_bags.header(i / 30.0, "camera")
                msg = ros_bags.T["sensor_msgs/msg/Image"](
                    header=h, height=240, width=320, encoding="mono8", is_bigendian=0, step=320, data=frame)
                w.write("/image", "sensor_msgs/msg/Image", msg, ns)

    def peak_rss_mb(self, bag):
        import resource

        out = self.path("frames.lcm")
        r = subprocess.run(
            [sys.executable, "-c",
             "import resource, subprocess, sys; subprocess.run(sys.argv[1:], check=True, capture_output=True); "
             "print(resource.getrusage(resource.RUSAGE_CHILDREN).ru_maxrss)",
             KINCAL, "import", bag, "--out", out, "--images", "/image"],
            capture_output=True, text=True, timeout=600)
        self.assertEqual(r.returncode, 0, r.stderr)
        os.unlink(out)
        del resource
        return int(r.stdout.strip()) / 1024.0

    def test_memory_is_flat_in_the_bag_size(self):
        small, large = self.path("small.bag"), self.path("large.bag")
        self.write_frames(small, 150)
        self.write_frames(large, 750)  # 58 MB of frames
        rss_small = self.peak_rss_mb(small)
        rss_large = self.peak_rss_mb(large)
        self.assertLess(rss_large, rss_small + 20.0, f"peak RSS {rss_small:.0f} MB -> {rss_large:.0f} MB")


class BadBags(Fixture):
    """Each bad bag exits non-zero, names the topic and the message, and writes nothing."""

    def write(self, kind, messages, extra_topics=()):
        bag = self.path("bad.bag" if kind == "ros1" else "bad_db3")
        with ros_bags.BagWriter(bag, kind) as w:
            for topic, typ in extra_topics:
                w.conns[topic] = w.w.add_connection(topic, typ, typestore=ros_bags.STORE)
            for ns, topic, typ, msg in messages:
                w.write(topic, typ, msg, ns)
        return bag

    def poses(self, times, zero_at=None):
        out = []
        for i, t in enumerate(times):
            msg, ns = ros_bags.pose_stamped(t, (0.1 * t, 0.0, 0.0))
            if i == zero_at:
                msg.header.stamp.sec, msg.header.stamp.nanosec = 0, 0
            receive_ns = ros_bags.stamp(0.1 * i)[1] + 10**6  # recorded in order, 1 ms late
            out.append((receive_ns, "/pose", "geometry_msgs/msg/PoseStamped", msg))
        return out

    def refused(self, bag, *args, expect):
        log = self.path("out.lcm")
        r = kincal("import", bag, "--out", log, *args, ok=False)
        self.assertNotEqual(r.returncode, 0, r.stdout)
        for text in expect:
            self.assertIn(text, r.stderr)
        self.assertFalse(os.path.exists(log), "a refused import left a log behind")
        self.assertEqual([f for f in os.listdir(self.dir) if f.startswith(".kincal_import")], [])

    def test_time_going_back(self):
        bag = self.write("ros1", self.poses([0.0, 0.1, 0.2, 0.15, 0.3]))
        self.refused(bag, "--poses", "/pose", expect=["topic /pose, message 4", "time goes back by 0.05"])

    def test_stamp_missing(self):
        bag = self.write("db3", self.poses([0.0, 0.1, 0.2, 0.3], zero_at=2))
        self.refused(bag, "--poses", "/pose", expect=["topic /pose, message 3", "header stamp missing"])

    def test_unknown_type(self):
        s = ros_bags.T["std_msgs/msg/String"](data="hello")
        bag = self.write("ros1", [(10**9, "/chatter", "std_msgs/msg/String", s)])
        self.refused(bag, "--poses", "/chatter", expect=["topic /chatter", "std_msgs/msg/String", "geometry_msgs/msg/PoseStamped"])

    def test_empty_topic(self):
        bag = self.write("db3", self.poses([0.0, 0.1]), extra_topics=[("/joint_states", "sensor_msgs/msg/JointState")])
        self.refused(bag, "--poses", "/pose", "--model", "diffdrive", "--controls", "/joint_states",
                     "--joints", "l,r", expect=["topic /joint_states: empty"])

    def test_missing_joint(self):
        sim = ros_bags.diffdrive(duration=2.0)
        bag = self.path("robot.bag")
        ros_bags.write_diffdrive(bag, "ros1", sim)
        self.refused(bag, "--model", "diffdrive", "--controls", "/joint_states", "--joints", "left,right_wheel_joint",
                     "--poses", "/mocap/robot/pose", expect=["topic /joint_states, message 1", "joint 'left' not in the message"])

    def test_not_a_bag(self):
        p = self.path("notes.txt")
        with open(p, "w") as f:
            f.write("hello\n")
        self.refused(p, "--poses", "/pose", expect=["notes.txt", "expected a ROS 1 .bag file or a ROS 2 bag folder"])

    def test_output_through_a_symlink(self):
        bag = self.write("ros1", self.poses([0.0, 0.1]))
        target = self.path("elsewhere.lcm")
        os.symlink(target, self.path("out.lcm"))
        r = kincal("import", bag, "--out", self.path("out.lcm"), "--poses", "/pose", ok=False)
        self.assertNotEqual(r.returncode, 0)
        self.assertIn("symbolic link", r.stderr)
        self.assertFalse(os.path.exists(target))

    def test_tilted_poses_are_warned_about(self):
        out = []
        for i in range(20):
            msg, ns = ros_bags.pose_stamped(0.1 * i, (0.0, 0.0, 0.3))
            msg.pose.orientation = ros_bags.quaternion(0.3, tilt=math.radians(12.0) if i >= 5 else 0.0)
            out.append((ns, "/pose", "geometry_msgs/msg/PoseStamped", msg))
        bag = self.write("ros1", out)
        log = self.path("out.lcm")
        r = kincal("import", bag, "--out", log, "--poses", "/pose")
        self.assertIn("15 poses tilted more than 5 deg (worst 12.0 deg, first at topic /pose, message 6)", r.stderr)
        self.assertTrue(os.path.exists(log))


if __name__ == "__main__":
    unittest.main()
