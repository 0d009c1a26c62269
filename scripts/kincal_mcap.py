#!/usr/bin/env python3
"""kincal export --format mcap: a kincald recording (LCM log) as MCAP for Foxglove.

`kincal export --format mcap --log RUN.lcm --out RUN.mcap` runs this program with the
venv's Python (foxglove-sdk writes the MCAP with Foxglove's well-known schemas). Every
event of the log becomes one message on the topic "/" + its LCM channel, stamped with the
event's time (log time) and the message's utime (the schema's timestamp):

  kincal.preview_t   -> foxglove.CompressedImage (jpeg)
  kincal.frame_t     -> foxglove.CompressedImage (MJPG: jpeg, PNG: png) or RawImage (GREY:
                        mono8, YUYV: yuyv, BGR3: bgr8, RGB3: rgb8)
  kincal.markers_t   -> foxglove.ImageAnnotations in the camera's pixels: identified markers
                        green, unassigned blobs red, the target's outline (the identified
                        markers' convex hull) and its id
  kincal.pose_t      -> foxglove.PoseInFrame (frame "floor"; invalid poses: JSON beside)
  kincal.truth_t     -> JSON (the simulator's true parameters, for plots beside the
                        estimate) and foxglove.PoseInFrame on "/<channel>/pose" (where the
                        tracked point truly stands, frame "floor"; none while carried)
  everything else    -> JSON (params, calibration, model check, health, guidance, controls,
                        runs), one object per message with the LCM type's fields

and, derived: "/<markers channel>/preview" (the same annotations on the preview's pixels,
for the frame the preview shows) and "/tf" (foxglove.FrameTransform floor -> robot, one per
valid pose). Channels are recognised by their LCM type, whatever their names. `kincal view
--foxglove` serves the same topics live (Exporter on a WebSocket server's context).

The MCAP is written to a temporary file beside --out and renamed over it (never through a
symbolic link); an input that is not a kincal recording, or a damaged one, is a named
error and nothing is written.
"""

import argparse
import json
import math
import os
import sys
import tempfile

from kincal_lcm_log import LogError, read_events_at
from kincal_lcm_types import message_types, use_lcm_types
from kincal_markers import target_outline

# Colours of the overlay (RGBA in 0..1), as `kincal view` draws them.
IDENTIFIED = (0.1, 0.85, 0.2, 1.0)
UNASSIGNED = (0.95, 0.2, 0.2, 1.0)
OUTLINE = (0.2, 0.6, 1.0, 1.0)
# Markers kept for the preview's annotations: the preview names a frame a few frames back.
MARKERS_KEPT = 64


class ExportError(Exception):
    pass


def fields(msg):
    """An LCM message as a dict of plain values (bytes as their length)."""
    out = {}
    for name in msg.__slots__:
        v = getattr(msg, name)
        if isinstance(v, (bytes, bytearray)):
            out[name + "_bytes"] = len(v)
        elif isinstance(v, (list, tuple)):
            out[name] = [list(x) if isinstance(x, (list, tuple)) else x for x in v]
        else:
            out[name] = v
    return out


def timestamp(utime):
    from foxglove.messages import Timestamp
    utime = max(int(utime), 0)
    return Timestamp(sec=utime // 1_000_000, nsec=(utime % 1_000_000) * 1000)


def color(rgba):
    from foxglove.messages import Color
    return Color(r=float(rgba[0]), g=float(rgba[1]), b=float(rgba[2]), a=float(rgba[3]))


def annotations(m, scale=1, axes=None):
    """markers_t as ImageAnnotations on an image `scale` times smaller than the camera's, with
    the target's axes when given (preview_t's: origin, x end, y end in camera pixels).
    Foxglove's pixel origin is the top-left pixel's corner: the centre of pixel u is u + 0.5."""
    from foxglove.messages import (CircleAnnotation, ImageAnnotations, Point2,
                                   PointsAnnotation, PointsAnnotationType, TextAnnotation)
    ts = timestamp(m.utime)
    circles = []
    for i in range(m.num_markers):
        x, y = (m.u[i] + 0.5) / scale, (m.v[i] + 0.5) / scale
        circles.append(CircleAnnotation(timestamp=ts, position=Point2(x=x, y=y), diameter=12.0,
                                        thickness=2.0, fill_color=color((0, 0, 0, 0)),
                                        outline_color=color(IDENTIFIED if m.id[i] >= 0 else UNASSIGNED)))
    points, texts = [], []
    outline, target = target_outline(m)
    if outline:
        hull = [((u + 0.5) / scale, (v + 0.5) / scale) for u, v in outline]
        points.append(PointsAnnotation(timestamp=ts, type=PointsAnnotationType.LineLoop,
                                       points=[Point2(x=x, y=y) for x, y in hull],
                                       outline_color=color(OUTLINE),
                                       thickness=2.0))
        cx = sum(p[0] for p in hull) / len(hull)
        cy = min(p[1] for p in hull) - 8.0
        texts.append(TextAnnotation(timestamp=ts, position=Point2(x=cx, y=cy), text=f"target {target}",
                                    font_size=12.0, text_color=color(OUTLINE),
                                    background_color=color((0, 0, 0, 0.5))))
    if axes:
        o = Point2(x=(axes[0][0] + 0.5) / scale, y=(axes[0][1] + 0.5) / scale)
        for (u, v), rgba in zip(axes[1:], (UNASSIGNED, IDENTIFIED)):  # x red, y green
            points.append(PointsAnnotation(timestamp=ts, type=PointsAnnotationType.LineList,
                                           points=[o, Point2(x=(u + 0.5) / scale, y=(v + 0.5) / scale)],
                                           outline_color=color(rgba), thickness=2.0))
    return ImageAnnotations(circles=circles, points=points, texts=texts)


def floor_pose(m):
    """A message's planar pose (its utime, x, y, theta) as a PoseInFrame in frame "floor"."""
    from foxglove.messages import Pose, PoseInFrame, Vector3
    return PoseInFrame(timestamp=timestamp(m.utime), frame_id="floor",
                       pose=Pose(position=Vector3(x=m.x, y=m.y, z=0.0), orientation=quaternion(m.theta)))


def quaternion(theta):
    from foxglove.messages import Quaternion
    return Quaternion(x=0.0, y=0.0, z=math.sin(theta / 2), w=math.cos(theta / 2))


class Exporter:
    """One pass over the log; channels made on first use."""

    def __init__(self, context):
        self.context = context
        self.types = message_types()
        self.channels = {}
        self.counts = {}
        self.markers = {}  # frame_sequence -> markers_t (the last MARKERS_KEPT)
        self.markers_channel = None

    def channel(self, topic, kind, type_name=None):
        if topic in self.channels:
            return self.channels[topic]
        import foxglove
        from foxglove import channels as fc
        if kind == "json":
            schema = foxglove.Schema(name=type_name, encoding="jsonschema",
                                     data=json.dumps({"type": "object", "title": type_name}).encode())
            ch = foxglove.Channel(topic, schema=schema, message_encoding="json", context=self.context)
        else:
            ch = getattr(fc, kind + "Channel")(topic, context=self.context)
        self.channels[topic] = ch
        return ch

    def log(self, topic, kind, msg, log_time, type_name=None):
        self.channel(topic, kind, type_name).log(msg, log_time=log_time)
        self.counts[topic] = self.counts.get(topic, 0) + 1

    def event(self, channel, data, log_time):
        cls = self.types.get(bytes(data[:8]))
        if cls is None:
            raise ExportError(f"channel {channel!r}: not a kincal message (unknown LCM type)")
        try:
            m = cls.decode(data)
        except Exception as e:  # the generated decoder's errors are ValueError or struct.error
            raise ExportError(f"channel {channel!r}: a {cls.__name__} that does not decode: {e}") from e
        self.message(channel, m, log_time)

    def message(self, channel, m, log_time):
        """A decoded kincal message onto its topics (also `kincal view --foxglove`'s path)."""
        getattr(self, "on_" + type(m).__name__, self.on_json)(channel, m, log_time)

    def on_json(self, channel, m, log_time):
        name = "kincal." + type(m).__name__
        self.log("/" + channel, "json", fields(m), log_time, name)

    def on_preview_t(self, channel, m, log_time):
        from foxglove.messages import CompressedImage
        self.log("/" + channel, "CompressedImage",
                 CompressedImage(timestamp=timestamp(m.utime), frame_id="camera", data=bytes(m.data),
                                 format=m.format), log_time)
        mk = self.markers.get(m.frame_sequence)
        if mk is not None and self.markers_channel is not None:
            axes = list(zip(m.axes_u, m.axes_v)) if m.num_axes == 3 else None
            self.log("/" + self.markers_channel + "/preview", "ImageAnnotations",
                     annotations(mk, max(m.scale, 1), axes), log_time)

    def on_frame_t(self, channel, m, log_time):
        from foxglove.messages import CompressedImage, RawImage
        fmt = m.pixel_format
        if fmt in ("MJPG", "PNG"):
            self.log("/" + channel, "CompressedImage",
                     CompressedImage(timestamp=timestamp(m.utime), frame_id="camera", data=bytes(m.data),
                                     format="jpeg" if fmt == "MJPG" else "png"), log_time)
            return
        enc = {"GREY": "mono8", "YUYV": "yuyv", "BGR3": "bgr8", "RGB3": "rgb8"}.get(fmt)
        if enc is None:
            raise ExportError(f"channel {channel!r}: frame format {fmt!r} has no Foxglove image encoding")
        self.log("/" + channel, "RawImage",
                 RawImage(timestamp=timestamp(m.utime), frame_id="camera", width=m.width, height=m.height,
                          encoding=enc, step=m.stride, data=bytes(m.data)), log_time)

    def on_markers_t(self, channel, m, log_time):
        self.markers_channel = channel
        self.markers[m.frame_sequence] = m
        if len(self.markers) > MARKERS_KEPT:
            self.markers.pop(next(iter(self.markers)))
        self.log("/" + channel, "ImageAnnotations", annotations(m), log_time)

    def on_truth_t(self, channel, m, log_time):
        self.on_json(channel, m, log_time)
        if m.on_floor:
            self.log("/" + channel + "/pose", "PoseInFrame", floor_pose(m), log_time)

    def on_pose_t(self, channel, m, log_time):
        from foxglove.messages import FrameTransform, Vector3
        if not m.valid:
            self.log("/" + channel + "/invalid", "json", fields(m), log_time, "kincal.pose_t")
            return
        ts = timestamp(m.utime)
        self.log("/" + channel, "PoseInFrame", floor_pose(m), log_time)
        self.log("/tf", "FrameTransform",
                 FrameTransform(timestamp=ts, parent_frame_id="floor", child_frame_id="robot",
                                translation=Vector3(x=m.x, y=m.y, z=0.0), rotation=quaternion(m.theta)),
                 log_time)


def read_events(path):
    """(channel, data, log time in ns) of every event; a damaged log is an ExportError."""
    try:
        for channel, data, utime, _ in read_events_at(path):
            yield channel, data, utime * 1000
    except LogError as e:
        raise ExportError(str(e)) from e


def export(log_path, out_path, types=None):
    """Writes out_path from log_path; returns {topic: messages}."""
    if not use_lcm_types(types):
        raise ExportError("kincal's LCM Python types were not found (set KINCAL_LCM_TYPES)")
    import foxglove
    if not os.path.isfile(log_path):
        raise ExportError(f"{log_path}: no such file")
    if os.path.islink(out_path):
        raise ExportError(f"{out_path}: is a symbolic link; not written through it")
    out_dir = os.path.dirname(os.path.abspath(out_path))
    fd, tmp = tempfile.mkstemp(prefix=".kincal_mcap_", suffix=".tmp", dir=out_dir)
    os.close(fd)
    os.unlink(tmp)  # open_mcap creates it (refusing to overwrite)
    context = foxglove.Context()
    try:
        writer = foxglove.open_mcap(tmp, context=context)
        exporter = Exporter(context)
        try:
            for channel, data, t in read_events(log_path):
                exporter.event(channel, data, t)
        finally:
            writer.close()
        os.replace(tmp, out_path)
    except BaseException:
        if os.path.exists(tmp):
            os.unlink(tmp)
        raise
    return exporter.counts


def main(argv=None):
    ap = argparse.ArgumentParser(prog="kincal export --format mcap",
                                 description="A kincald recording (LCM log) as MCAP for Foxglove.")
    ap.add_argument("--log", required=True, help="kincald's LCM log")
    ap.add_argument("--out", required=True, help="the MCAP file to write")
    ap.add_argument("--lcm-types", help="folder holding the kincal LCM Python package")
    a = ap.parse_args(argv)
    try:
        counts = export(a.log, a.out, a.lcm_types)
    except ExportError as e:
        print(f"kincal export: error: {e}", file=sys.stderr)
        return 1
    total = sum(counts.values())
    print(f"wrote {a.out}: {total} messages on {len(counts)} topics")
    for topic in sorted(counts):
        print(f"  {topic}: {counts[topic]}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
