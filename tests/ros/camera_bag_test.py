"""A camera bag through kincald: rendered target frames (CompressedImage jpeg), wheel
speeds (JointState) and CameraInfo, written by rosbags' own writer, imported, replayed by
kincald; the estimate lands within 3 sigma of the simulated robot's truth and agrees with
the estimate kincald made from the same frames directly. Image encodings are converted to
the right grey levels.

The frames come from kincald's simulated camera (its recording); everything between the
recording and the replay goes through ROS messages.
Run by ctest with the venv's Python: KINCAL_BIN, KINCALD_BIN, KINCAL_LCM_TYPES,
KINCAL_CONFIG_DIR.
"""

import json
import os
import subprocess
import sys
import tempfile
import unittest

import numpy as np

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import ros_bags  # noqa: E402

KINCAL = os.environ.get("KINCAL_BIN", "kincal")
KINCALD = os.environ.get("KINCALD_BIN", "kincald")
CONFIG = os.environ.get("KINCAL_CONFIG_DIR", os.path.join(os.path.dirname(__file__), "..", "..", "config"))
TYPES = os.environ.get("KINCAL_LCM_TYPES")
TRUTH = {"r_l": 0.0310, "r_r": 0.0313, "d": 0.148}  # config/sim_daemon.yaml

DAEMON_YAML = """\
source: {source}
sim:
  scenario: {config}/sim_daemon.yaml
camera:
  intrinsics: "{intrinsics}"
  nadir_height_m: 2.0
target:
  layout: {config}/target_large.yaml
  height_m: 0.10
pose:
  method: ground_plane
  sigma_px: 0.05
robot:
  model: diffdrive
  guess: {{r_l: 0.034, r_r: 0.029, d: 0.160}}
  guess_sigma_fraction: 0.15
filter:
  type: dd2
  pose_psd: [1.0e-7, 1.0e-7, 1.0e-6]
  max_pose_gap_s: 0.5
record:
  frame_encoding: jpeg
# The checkpoints compared below are the filter's: this test is about the frames and the
# controls surviving the bag, judged at the filter's precision (the batch calibration
# subsamples the poses into prediction windows, so one pose more or less moves it further).
calibration:
  enabled: false
"""


def run(*cmd):
    r = subprocess.run(list(cmd), capture_output=True, text=True, timeout=900)
    if r.returncode != 0:
        raise AssertionError(f"{' '.join(cmd)} failed ({r.returncode}):\n{r.stdout}\n{r.stderr}")
    return r


def lcm_types():
    sys.path.insert(0, TYPES)
    from kincal import controls_t, frame_t

    return controls_t, frame_t


def camera_info(t):
    h, ns = ros_bags.header(t, "camera")
    info = ros_bags.T["sensor_msgs/msg/CameraInfo"](
        header=h, height=480, width=640, distortion_model="plumb_bob", d=np.zeros(5),
        k=np.array([500.0, 0, 319.5, 0, 500.0, 239.5, 0, 0, 1]), r=np.eye(3).ravel(),
        p=np.array([500.0, 0, 319.5, 0, 0, 500.0, 239.5, 0, 0, 0, 1, 0]), binning_x=0, binning_y=0,
        roi=ros_bags.T["sensor_msgs/msg/RegionOfInterest"](x_offset=0, y_offset=0, height=0, width=0, do_rectify=False),
    )
    return info, ns


def recording_to_bag(log_path, bag_path):
    """kincald's recording (MJPG frames, controls) as a ROS 2 mcap bag."""
    import lcm

    controls_t, frame_t = lcm_types()
    log = lcm.EventLog(log_path, "r")
    t0 = None
    with ros_bags.BagWriter(bag_path, "mcap") as w:
        for ev in log:
            if ev.channel == "KINCAL_FRAME":
                f = frame_t.decode(ev.data)
                t0 = f.utime if t0 is None else t0
                s, ns = ros_bags.stamp((f.utime - t0) * 1e-6)
                h = ros_bags.T["std_msgs/msg/Header"](stamp=s, frame_id="camera")
                img = ros_bags.T["sensor_msgs/msg/CompressedImage"](
                    header=h, format="jpeg", data=np.frombuffer(bytes(f.data), np.uint8))
                w.write("/camera/image_raw/compressed", "sensor_msgs/msg/CompressedImage", img, ns + 2_000_000)
                if f.sequence % 30 == 0:
                    info, _ = camera_info((f.utime - t0) * 1e-6)
                    w.write("/camera/camera_info", "sensor_msgs/msg/CameraInfo", info, ns + 2_000_000)
            elif ev.channel == "KINCAL_CONTROLS" and t0 is not None:
                c = controls_t.decode(ev.data)
                msg, ns = ros_bags.joint_state((c.sender_utime - t0) * 1e-6, c.values[0], c.values[1])
                w.write("/joint_states", "sensor_msgs/msg/JointState", msg, ns + 1_000_000)


def checkpoint(path):
    with open(path) as f:
        c = json.load(f)
    cov = np.array(c["covariance"])
    return {n: (v, float(np.sqrt(cov[i, i]))) for i, (n, v) in enumerate(zip(c["names"], c["values"]))}


class CameraBag(unittest.TestCase):
    def test_frames_and_camera_info_replayed_through_kincald(self):
        with tempfile.TemporaryDirectory(prefix="kincal_camera_bag_") as d:
            p = lambda name: os.path.join(d, name)  # noqa: E731
            with open(p("sim.yaml"), "w") as f:
                f.write(DAEMON_YAML.format(source="sim", config=CONFIG, intrinsics=""))
            run(KINCALD, "--config", p("sim.yaml"), "--duration", "25", "--fast", "--record", p("sim.lcm"),
                "--checkpoint", p("direct.json"), "-q")
            recording_to_bag(p("sim.lcm"), p("camera_bag"))
            os.unlink(p("sim.lcm"))
            r = run(KINCAL, "import", p("camera_bag"), "--out", p("imported.lcm"), "--model", "diffdrive",
                    "--controls", "/joint_states", "--joints", "left_wheel_joint,right_wheel_joint",
                    "--images", "/camera/image_raw/compressed", "--camera-info", "/camera/camera_info",
                    "--intrinsics-out", p("camera.yaml"))
            self.assertIn("frames -> KINCAL_FRAME, stamps: header", r.stdout)
            with open(p("replay.yaml"), "w") as f:
                f.write(DAEMON_YAML.format(source="replay", config=CONFIG, intrinsics=p("camera.yaml")))
            run(KINCALD, "--config", p("replay.yaml"), "--replay", p("imported.lcm"), "--fast",
                "--checkpoint", p("replayed.json"), "-q")
            direct, replayed = checkpoint(p("direct.json")), checkpoint(p("replayed.json"))
            print(f"direct {direct}\nreplayed through the bag {replayed}", file=sys.stderr)
            for n, truth in TRUTH.items():
                v, s = replayed[n]
                self.assertLess(abs(v - truth), 3 * s, f"{n}: {v} +- {s}, truth {truth}")
                # The same frames, decoded once more: the same estimate within a fraction of sigma.
                self.assertLess(abs(v - direct[n][0]), 0.5 * s, f"{n}: replayed {v}, direct {direct[n][0]}")


class Encodings(unittest.TestCase):
    """mono8, bgr8, rgb8 and yuv422 images become the grey levels kincald expects."""

    def test_each_encoding(self):
        import lcm

        _, frame_t = lcm_types()
        h, w = 4, 6
        grey = (np.arange(h * w, dtype=np.uint8) * 9).reshape(h, w)
        rgb = np.stack([grey, grey, grey], axis=-1)
        uyvy = np.zeros((h, 2 * w), np.uint8)
        uyvy[:, 1::2] = grey
        uyvy[:, 0::2] = 128
        images = {
            "mono8": (grey, w),
            "bgr8": (rgb, 3 * w),
            "rgb8": (rgb, 3 * w),
            "yuv422": (uyvy, 2 * w),
        }
        with tempfile.TemporaryDirectory(prefix="kincal_encodings_") as d:
            bag = os.path.join(d, "images.bag")
            with ros_bags.BagWriter(bag, "ros1") as wr:
                for i, (enc, (data, step)) in enumerate(images.items()):
                    hd, ns = ros_bags.header(0.1 * i, "camera")
                    msg = ros_bags.T["sensor_msgs/msg/Image"](
                        header=hd, height=h, width=w, encoding=enc, is_bigendian=0, step=step,
                        data=np.ascontiguousarray(data).ravel())
                    wr.write("/image", "sensor_msgs/msg/Image", msg, ns)
            out = os.path.join(d, "images.lcm")
            run(KINCAL, "import", bag, "--out", out, "--images", "/image")
            frames = [frame_t.decode(ev.data) for ev in lcm.EventLog(out, "r") if ev.channel == "KINCAL_FRAME"]
            self.assertEqual(len(frames), 4)
            for f, enc in zip(frames, images):
                self.assertEqual((f.width, f.height, f.stride, f.pixel_format), (w, h, w, "GREY"), enc)
                got = np.frombuffer(bytes(f.data), np.uint8).reshape(h, w)
                self.assertTrue(np.array_equal(got, grey), f"{enc}: {got} != {grey}")


if __name__ == "__main__":
    unittest.main()
