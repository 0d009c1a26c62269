#!/usr/bin/env python3
"""kincal view: what kincald sees, on a page in the browser.

`kincal view` runs this program with the venv's Python. It serves one page on a local port
(aiohttp, from PyPI; the charts are plotly.js, shipped inside the plotly package: nothing
comes from the internet), fed either live by kincald's LCM (`--lcm-url`, LCM's default
otherwise) or by a recording (`--log FILE`, with play/pause and a time slider):

  * the latest camera picture (KINCAL_PREVIEW: `kincald --preview`, or a recording's
    frames) with every detected marker (identified: green, unassigned blobs: red), the
    identified target's outline and id, and its recent track in the picture;
  * a map of the floor: the part the camera sees (preview_t's polygon, from kincald's
    camera and floor calibration), the target's track and its pose with its axes, and
    in a simulation the true track (KINCAL_TRUTH, which kincald's simulator publishes);
  * the parameters against time with +-2 sigma and, in a simulation, the truth (from
    KINCAL_TRUTH, or a scenario's `truth:` map with `--truth`), the status,
    the model check's verdict with its suspected effect and evidence, health (frame rate,
    drops, gated poses, latency, resets) and the guidance's advice;
  * "no frames yet" / "daemon not heard for N s" instead of a stale picture.

With `--foxglove [PORT]` (live only) it also serves kincald's channels to the Foxglove app
(or Lichtblick) over Foxglove's WebSocket protocol, through foxglove-sdk's server, with the
topics and schemas `kincal export --format mcap` writes (the picture as CompressedImage,
markers and target as ImageAnnotations, the pose as PoseInFrame and /tf, the rest as JSON):
"Open connection" in the app, ws://127.0.0.1:8766 by default. A recording opens in
Foxglove as the MCAP file that command writes.

Read-only: nothing on the page reaches kincald (the playback controls move this page's
own cursor in a recording). It binds 127.0.0.1 unless `--bind` says otherwise. Every
browser gets the newest state at up to `--rate` updates a second; a slow one misses
updates, it never holds up the LCM thread or kincald. Memory is bounded: live, by the
history kept (`--history-s`); a recording's pictures are read from the file when shown.

Errors are named and exit 1: a port in use, a file that is not a kincal recording, an
LCM URL that cannot be opened. A message on a kincal channel that does not decode is
counted and shown on the page with its channel.
"""

import argparse
import asyncio
import base64
import bisect
import collections
import json
import math
import os
import socket
import sys
import threading
import time

from kincal_lcm_types import message_types, use_lcm_types
from kincal_markers import target_outline

HERE = os.path.dirname(os.path.abspath(__file__))
STATIC = os.path.join(HERE, "view")
DEFAULT_PORT = 8765
# `--foxglove`'s default: beside the page (8765 is also the Foxglove app's own default; the
# app's "Open connection" takes any ws:// address).
FOXGLOVE_PORT = DEFAULT_PORT + 1
MAX_RATE = 30.0         # updates a second to one page at most (new pictures come at once)
ACK_TIMEOUT_S = 5.0     # a page that has not taken a state for this long gets the next anyway
HISTORY_EVERY_S = 0.5   # the charts' history goes to a page this often (the rest: the newest)
TRACK_LEN = 90          # the target's recent track in the picture, in frames
MARKERS_KEPT = 64       # markers kept by frame sequence, for the picture that names them
POSES_KEPT = 3000       # the target's track on the floor map (live: the newest)
FLOOR_POINTS = 600      # points of that track sent to a page
STATUS_NAMES = ["initializing", "converging", "converged", "diverged", "model inadequate"]


class ViewError(Exception):
    pass


def markers_view(m):
    """markers_t as the page draws it: camera pixels, identified or not, the outline."""
    ident = [(m.u[i], m.v[i]) for i in range(m.num_markers) if m.id[i] >= 0]
    outline, target = target_outline(m)
    centre = [sum(p[0] for p in ident) / len(ident), sum(p[1] for p in ident) / len(ident)] if ident else None
    return {"utime": m.utime, "frame_sequence": m.frame_sequence,
            "u": list(m.u), "v": list(m.v), "id": list(m.id), "target_id": target,
            "outline": [list(p) for p in outline], "centre": centre}


class Timeline:
    """Everything the page shows, by time. Live: bounded by `history_s` of data time;
    a recording: all of it (pictures as file offsets). Thread-safe."""

    def __init__(self, history_s=None):
        self.lock = threading.Lock()
        self.history_us = None if history_s is None else int(history_s * 1e6)
        self.previews = collections.deque()   # (utime, preview dict) or (utime, ("offset", ...))
        self.markers = collections.OrderedDict()
        self.track = collections.deque()      # (utime, [u, v]) target centres in the picture
        self.poses = collections.deque()      # (utime, [x, y, theta]) valid poses on the floor
        self.floor_seen = None                # the floor polygon the camera sees (preview_t)
        self.truth = collections.deque()      # (utime, [x, y]) the simulator's true stand (truth_t)
        self.truth_params = {}                # name -> true value (the simulator's truth_t)
        self.params = collections.deque()     # (utime, {names, values, sigmas, status, source})
        self.latest = {}                      # kind -> deque of (utime, dict)
        self.errors = {}                      # channel -> "what", count
        self.channels = collections.Counter()
        self.last_heard = None                # monotonic seconds
        self.first_utime = None
        self.last_utime = None
        self.version = 0
        self.on_change = None  # called (any thread) after a change: wakes the pages' loops

    def _trim(self, q, now_us):
        if self.history_us is None:
            return
        while q and q[0][0] < now_us - self.history_us:
            q.popleft()

    def _append_pose(self, q, utime, pose):
        """A pose on the floor into q: live, the last POSES_KEPT within the history kept."""
        q.append((utime, pose))
        self._trim(q, utime)
        if self.history_us is not None:
            while len(q) > POSES_KEPT:
                q.popleft()

    def _keep(self, kind, utime, item, keep=4):
        q = self.latest.setdefault(kind, collections.deque())
        q.append((utime, item))
        if self.history_us is not None:
            while len(q) > keep:
                q.popleft()

    def add(self, channel, msg, utime, image_ref=None):
        name = type(msg).__name__
        with self.lock:
            self.channels[channel] += 1
            self.last_heard = time.monotonic()
            if self.first_utime is None or utime < self.first_utime:
                self.first_utime = utime
            self.last_utime = max(self.last_utime or utime, utime)
            getattr(self, "_on_" + name, self._on_other)(msg, utime, image_ref)
            self.version += 1
        if self.on_change is not None and name == "preview_t" and image_ref is None:
            self.on_change()

    def error(self, channel, what):
        with self.lock:
            count = self.errors.get(channel, (what, 0))[1] + 1
            self.errors[channel] = (what, count)
            self.last_heard = time.monotonic()
            self.version += 1

    def _on_preview_t(self, m, utime, ref):
        item = ref or {"jpeg": base64.b64encode(bytes(m.data)).decode("ascii"),
                       "received_utime": int(time.time() * 1e6)}
        item.update({"utime": m.utime, "frame_sequence": m.frame_sequence, "scale": max(m.scale, 1), "width": m.width,
                     "height": m.height, "source_width": m.source_width, "source_height": m.source_height})
        if m.num_floor:
            self.floor_seen = [[x, y] for x, y in zip(m.floor_x, m.floor_y)]
        # The target's origin and axis ends in camera pixels (none: the frame gave no pose).
        item["axes"] = [[u, v] for u, v in zip(m.axes_u, m.axes_v)] if m.num_axes == 3 else None
        self.previews.append((utime, item))
        self._trim(self.previews, utime)
        if self.history_us is not None:
            while len(self.previews) > 2:
                self.previews.popleft()

    def _on_frame_t(self, m, utime, ref):
        if ref is None:
            return  # live frames (--publish-frames) are not what the page shows: previews are
        ref.update({"utime": m.utime, "frame_sequence": m.sequence, "scale": 1, "width": m.width, "height": m.height,
                    "source_width": m.width, "source_height": m.height, "pixel_format": m.pixel_format,
                    "stride": m.stride})
        self.previews.append((utime, ref))

    def _on_markers_t(self, m, utime, _):
        v = markers_view(m)
        self.markers[m.frame_sequence] = (utime, v)
        while len(self.markers) > MARKERS_KEPT and self.history_us is not None:
            self.markers.popitem(last=False)
        if v["centre"] is not None:
            self.track.append((utime, v["centre"]))
            if self.history_us is not None:
                while len(self.track) > TRACK_LEN:
                    self.track.popleft()

    def _on_pose_t(self, m, utime, _):
        if not m.valid:
            return
        self._append_pose(self.poses, utime, [m.x, m.y, m.theta])

    def _on_truth_t(self, m, utime, _):
        self.truth_params = {str(n): float(v) for n, v in zip(m.names, m.values)}
        if not m.on_floor:
            return
        self._append_pose(self.truth, utime, [m.x, m.y])

    def _on_params_t(self, m, utime, _):
        self.params.append((utime, {"names": list(m.names), "units": list(m.units), "values": list(m.values),
                                    "sigmas": list(m.sigmas), "status": int(m.status), "source": int(m.source),
                                    "model": m.model, "updates": m.update_count}))
        self._trim(self.params, utime)

    def _on_model_check_t(self, m, utime, _):
        self._keep("model_check", utime, {
            "model": m.model, "consistent": bool(m.consistent), "nis_mean": m.nis_mean,
            "nis_expected": m.nis_expected, "window": m.window, "window_capacity": m.window_capacity,
            "suspected_effect": m.suspected_effect, "candidates": list(m.candidates),
            "confidence": m.confidence, "evidence": m.evidence, "effects_added": list(m.effects_added)})

    def _on_health_t(self, m, utime, _):
        self._keep("health", utime, {s: getattr(m, s) for s in m.__slots__})

    def _on_guidance_t(self, m, utime, _):
        self._keep("guidance", utime, {"parameter": m.parameter, "sigma": m.sigma, "target": m.target,
                                       "motion": m.motion, "duration_s": m.duration_s,
                                       "time_to_target_s": m.time_to_target_s, "utime": utime,
                                       "path": list(zip(getattr(m, "path_x", []), getattr(m, "path_y", [])))})

    def _on_calibration_t(self, m, utime, _):
        self._keep("calibration", utime, {s: getattr(m, s) for s in ("sequence", "ok", "error")
                                          if hasattr(m, s)})

    def _on_other(self, m, utime, _):
        pass  # poses, controls, runs: counted

    # -- what a page gets --------------------------------------------------------------
    @staticmethod
    def _at(q, t):
        """The last item of q (sorted by time) at or before t (None: the newest)."""
        if not q:
            return None
        if t is None:
            return q[-1][1]
        i = bisect.bisect_right([u for u, _ in q], t)
        return q[i - 1][1] if i > 0 else None

    def _advised_path(self, guidance):
        """The guidance's path on the floor: from the target's pose at the estimate it
        advised on (its path is in that pose's frame); None without one."""
        if not guidance or not guidance.get("path"):
            return None
        pose = self._at(self.poses, guidance["utime"])
        if pose is None:
            return None
        x0, y0, th = pose
        c, s = math.cos(th), math.sin(th)
        return [[x0 + c * x - s * y, y0 + s * x + c * y] for x, y in guidance["path"]]

    def snapshot(self, t=None, max_points=600):
        with self.lock:
            preview = self._at(self.previews, t)
            markers = None
            if preview is not None:
                found = self.markers.get(preview["frame_sequence"])
                markers = found[1] if found else None
            track = [c for u, c in self.track if t is None or u <= t][-TRACK_LEN:]
            poses = [c for u, c in self.poses if t is None or u <= t][-POSES_KEPT:]
            floor_track = thinned(poses, FLOOR_POINTS)
            truth_track = thinned([c for u, c in self.truth if t is None or u <= t][-POSES_KEPT:], FLOOR_POINTS)
            params = [(u, p) for u, p in self.params if t is None or u <= t]
            step = max(1, len(params) // max_points)
            history = params[::step]
            if params and (not history or history[-1][0] != params[-1][0]):
                history.append(params[-1])
            guidance = self._at(self.latest.get("guidance"), t)
            return {
                "preview": preview, "markers": markers, "track": track,
                "floor": {"seen": self.floor_seen, "track": floor_track, "pose": poses[-1] if poses else None,
                          "path": self._advised_path(guidance), "truth": truth_track},
                "truth_params": dict(self.truth_params),
                "params": [{"t": (u - (self.first_utime or u)) * 1e-6, **p} for u, p in history],
                "latest_params": params[-1][1] if params else None,
                "model_check": self._at(self.latest.get("model_check"), t),
                "health": self._at(self.latest.get("health"), t),
                "guidance": guidance,
                "calibration": self._at(self.latest.get("calibration"), t),
                "errors": {ch: {"what": w, "count": n} for ch, (w, n) in self.errors.items()},
                "channels": dict(self.channels),
                "heard_s_ago": None if self.last_heard is None else time.monotonic() - self.last_heard,
                "span": [0.0, ((self.last_utime or 0) - (self.first_utime or 0)) * 1e-6],
            }


def thinned(points, n):
    """About n of the points, evenly, always with the last."""
    out = points[::max(1, len(points) // n)]
    if points and (not out or out[-1] is not points[-1]):
        out.append(points[-1])
    return out


class FoxgloveLive:
    """kincald's channels to the Foxglove app as they arrive: kincal_mcap's Exporter (the
    topics and schemas of `kincal export --format mcap`) on foxglove-sdk's WebSocket server.
    Logging to a client is the SDK's (bounded per client): a slow app never holds up LCM."""

    def __init__(self, bind, port):
        import foxglove
        from kincal_mcap import Exporter
        check_port(bind, port)
        self.context = foxglove.Context()
        try:
            self.server = foxglove.start_server(name="kincal view", host=bind, port=port, context=self.context)
        except Exception as e:  # the SDK raises its own error types
            raise ViewError(f"cannot serve Foxglove on {bind}:{port}: {e}") from e
        self.exporter = Exporter(self.context)

    def message(self, channel, m):
        """Logs one decoded message; returns an error's text (a frame Foxglove cannot show)."""
        from kincal_mcap import ExportError
        try:
            self.exporter.message(channel, m, time.time_ns())
        except ExportError as e:
            return str(e)
        return None


class LiveSource:
    """kincald's LCM, on a thread of its own: decoded into the timeline (and to Foxglove with
    --foxglove) as it arrives."""

    def __init__(self, url, timeline, foxglove=None):
        import lcm
        self.types = message_types()
        self.foxglove = foxglove
        try:
            self.lcm = lcm.LCM(url) if url else lcm.LCM()
        except (IOError, OSError, RuntimeError) as e:
            raise ViewError(f"cannot open LCM at {url or 'its default URL'}: {e}") from e
        self.timeline = timeline
        self.stop = threading.Event()
        self.lcm.subscribe("KINCAL_.*", self.on_message)  # kincald's channels (lcm.*_channel)
        self.thread = threading.Thread(target=self.loop, name="lcm", daemon=True)

    def on_message(self, channel, data):
        cls = self.types.get(bytes(data[:8]))
        if cls is None:
            self.timeline.error(channel, "not a kincal message (unknown LCM type)")
            return
        try:
            m = cls.decode(data)
        except Exception as e:  # the generated decoders raise ValueError or struct.error
            self.timeline.error(channel, f"a {cls.__name__} that does not decode: {e}")
            return
        self.timeline.add(channel, m, getattr(m, "utime", 0))
        if self.foxglove is not None:
            error = self.foxglove.message(channel, m)
            if error:
                self.timeline.error(channel, error)

    def loop(self):
        while not self.stop.is_set():
            self.lcm.handle_timeout(100)

    def start(self):
        self.thread.start()


def load_log(path, timeline):
    """A recording into the timeline; pictures stay in the file (offsets). A file that is
    not a kincal recording is a ViewError naming it."""
    from kincal_lcm_log import LogError, read_events_at
    types = message_types()
    n = 0
    try:
        for channel, data, utime, offset in read_events_at(path):
            cls = types.get(bytes(data[:8]))
            if cls is None:
                if channel.startswith("KINCAL_"):
                    timeline.error(channel, "not a kincal message (unknown LCM type)")
                continue
            try:
                m = cls.decode(data)
            except Exception as e:
                timeline.error(channel, f"a {cls.__name__} that does not decode: {e}")
                continue
            ref = None
            if cls.__name__ in ("preview_t", "frame_t"):
                ref = {"offset": offset, "kind": cls.__name__}
            timeline.add(channel, m, getattr(m, "utime", 0) or utime, ref)
            n += 1
    except LogError as e:
        raise ViewError(str(e)) from e
    if n == 0:
        raise ViewError(f"{path}: not a kincal recording: no kincal message in it")
    # Recordings made without --preview: the frames are the pictures.
    if not any(p[1].get("kind") == "preview_t" for p in timeline.previews):
        timeline.previews = collections.deque(p for p in timeline.previews if p[1].get("kind") == "frame_t")
    else:
        timeline.previews = collections.deque(p for p in timeline.previews if p[1].get("kind") == "preview_t")
    return n


def picture_from_file(path, ref, max_width=640):
    """A recorded preview's JPEG, or a recorded frame as a JPEG no wider than max_width."""
    import io
    from kincal_lcm_log import read_event_at
    import kincal as k
    data = read_event_at(path, ref["offset"])
    if ref["kind"] == "preview_t":
        return bytes(k.preview_t.decode(data).data), 1
    f = k.frame_t.decode(data)
    from PIL import Image
    if f.pixel_format in ("MJPG", "PNG"):
        img = Image.open(io.BytesIO(bytes(f.data))).convert("L")
    elif f.pixel_format == "GREY":
        img = Image.frombytes("L", (f.width, f.height), bytes(f.data), "raw", "L", f.stride or f.width)
    elif f.pixel_format == "YUYV":
        img = Image.frombytes("L", (f.width, f.height), bytes(f.data)[0::2], "raw", "L", (f.stride or 2 * f.width) // 2)
    else:
        raise ViewError(f"frame format {f.pixel_format!r} cannot be shown")
    scale = max(1, -(-f.width // max_width))
    if scale > 1:
        img = img.crop((0, 0, f.width - f.width % scale, f.height - f.height % scale))
        img = img.resize((img.width // scale, img.height // scale), Image.BOX)
    out = io.BytesIO()
    img.save(out, format="JPEG", quality=80)
    return out.getvalue(), scale


def load_truth(path):
    """A scenario's `truth:` map (the simulated robot's parameters), or {}."""
    if not path:
        return {}
    import yaml
    try:
        with open(path, encoding="utf-8-sig") as f:
            doc = yaml.safe_load(f) or {}
    except (OSError, yaml.YAMLError) as e:
        raise ViewError(f"{path}: {e}") from e
    truth = doc.get("truth") if isinstance(doc, dict) else None
    if not isinstance(truth, dict) or not all(isinstance(v, (int, float)) for v in truth.values()):
        raise ViewError(f"{path}: no 'truth:' map of parameter values")
    return {str(k): float(v) for k, v in truth.items()}


class Server:
    def __init__(self, args, timeline, log_path=None, truth=None):
        self.args = args
        self.timeline = timeline
        self.log_path = log_path
        self.truth = truth or {}
        self.clients = 0
        self.picture_cache = {}  # offset -> (jpeg base64, scale): the last few shown
        self.wakers = set()      # each page's asyncio.Event: a new picture arrived
        self.loop = None

    def wake_all(self):
        """From the LCM thread: every page loop sends now rather than at its next tick."""
        if self.loop is not None:
            self.loop.call_soon_threadsafe(lambda: [w.set() for w in self.wakers])

    def app(self):
        from aiohttp import web
        import plotly
        app = web.Application()
        plotly_js = os.path.join(os.path.dirname(plotly.__file__), "package_data", "plotly.min.js")
        app.router.add_get("/", self.index)
        app.router.add_get("/ws", self.websocket)
        app.router.add_get("/state", self.state_json)
        app.router.add_get("/plotly.min.js", lambda r: web.FileResponse(plotly_js))
        app.router.add_static("/static/", STATIC)
        return app

    async def index(self, request):
        from aiohttp import web
        return web.FileResponse(os.path.join(STATIC, "index.html"))

    def state(self, cursor):
        s = self.timeline.snapshot(cursor)
        p = s["preview"]
        if p is not None and "offset" in p:
            key = p["offset"]
            if key not in self.picture_cache:
                jpeg, scale = picture_from_file(self.log_path, p)
                if len(self.picture_cache) > 16:
                    self.picture_cache.pop(next(iter(self.picture_cache)))
                self.picture_cache[key] = (base64.b64encode(jpeg).decode("ascii"), scale)
            jpeg, scale = self.picture_cache[key]
            p = dict(p, jpeg=jpeg, scale=p["scale"] * scale, width=p["width"] // scale,
                     height=p["height"] // scale)
            p.pop("offset", None)
            s["preview"] = p
        s["mode"] = "log" if self.log_path else "live"
        # The truth: --truth's scenario when given, else what the simulator publishes.
        learned = s.pop("truth_params")
        s["truth"] = self.truth or learned
        s["clients"] = self.clients
        return s

    async def state_json(self, request):
        from aiohttp import web
        return web.json_response(self.state(None), dumps=lambda o: json.dumps(o, allow_nan=False, default=str))

    async def websocket(self, request):
        from aiohttp import web, WSMsgType
        ws = web.WebSocketResponse(heartbeat=10)
        await ws.prepare(request)
        self.loop = asyncio.get_running_loop()
        wake = asyncio.Event()
        self.wakers.add(wake)
        self.clients += 1
        log_mode = self.log_path is not None
        span = self.timeline.snapshot(None)["span"]
        first = self.timeline.first_utime or 0
        cursor = {"t": span[1] if log_mode else None, "playing": False, "speed": 1.0}
        period = 1.0 / self.args.rate

        acked = asyncio.Event()
        acked.set()

        async def reader():
            async for msg in ws:
                if msg.type != WSMsgType.TEXT:
                    continue
                try:
                    cmd = json.loads(msg.data)
                except ValueError:
                    continue
                if cmd.get("cmd") == "ack":  # the page has taken the last state
                    acked.set()
                if not log_mode:
                    continue  # read-only: live, nothing a page sends does anything else
                if cmd.get("cmd") == "seek" and isinstance(cmd.get("t"), (int, float)):
                    cursor["t"] = min(max(float(cmd["t"]), 0.0), span[1])
                elif cmd.get("cmd") in ("play", "pause"):
                    cursor["playing"] = cmd["cmd"] == "play"
                    if cursor["playing"] and cursor["t"] >= span[1]:
                        cursor["t"] = 0.0

        task = asyncio.ensure_future(reader())
        try:
            last = time.monotonic()
            last_history = 0.0
            while not ws.closed:
                # One state in flight: the next goes once the page has taken the last, so a
                # slow browser misses states instead of queueing them (and nothing waits for it
                # but this loop).
                try:
                    await asyncio.wait_for(acked.wait(), timeout=ACK_TIMEOUT_S)
                except asyncio.TimeoutError:
                    pass
                acked.clear()
                now = time.monotonic()
                if log_mode and cursor["playing"]:
                    cursor["t"] = min(cursor["t"] + (now - last) * cursor["speed"], span[1])
                    if cursor["t"] >= span[1]:
                        cursor["playing"] = False
                last = now
                at = None if cursor["t"] is None else first + int(cursor["t"] * 1e6)
                s = self.state(at)
                s["cursor"] = {"t": cursor["t"], "playing": cursor["playing"]}
                if now - last_history < HISTORY_EVERY_S and not (log_mode and not cursor["playing"]):
                    s.pop("params")  # the charts' history twice a second; the page keeps the last
                else:
                    last_history = now
                await ws.send_str(json.dumps(s, default=str).replace("NaN", "null"))
                # At most MAX_RATE a second; otherwise at --rate, or at once on a new picture.
                await asyncio.sleep(1.0 / MAX_RATE)
                try:
                    await asyncio.wait_for(wake.wait(), timeout=max(period - 1.0 / MAX_RATE, 0.0))
                except asyncio.TimeoutError:
                    pass
                wake.clear()
        except (ConnectionResetError, asyncio.CancelledError):
            pass
        finally:
            task.cancel()
            self.wakers.discard(wake)
            self.clients -= 1
        return ws


def check_port(bind, port):
    """A port in use is named before anything starts."""
    s = socket.socket(socket.AF_INET6 if ":" in bind else socket.AF_INET, socket.SOCK_STREAM)
    try:
        s.bind((bind, port))
    except OSError as e:
        raise ViewError(f"cannot listen on {bind}:{port}: {e.strerror} (another kincal view? --port N)") from e
    finally:
        s.close()


def main(argv=None):
    ap = argparse.ArgumentParser(prog="kincal view", description=__doc__.split("\n\n")[0])
    ap.add_argument("--port", type=int, default=DEFAULT_PORT, help=f"port (default {DEFAULT_PORT})")
    ap.add_argument("--bind", default="127.0.0.1", help="address to listen on (default 127.0.0.1: this machine only)")
    src = ap.add_mutually_exclusive_group()
    src.add_argument("--lcm-url", default="", help="kincald's LCM URL (default: LCM's default, as kincald's)")
    src.add_argument("--log", help="a kincald recording to play instead of live LCM")
    ap.add_argument("--truth", help="a scenario YAML whose truth: map is drawn on the charts "
                    "(default: what kincald's simulator publishes on KINCAL_TRUTH)")
    ap.add_argument("--rate", type=float, default=10.0, help="updates a second to each browser (default 10)")
    ap.add_argument("--history-s", type=float, default=3600.0, help="live: data time kept for the charts (default 3600)")
    ap.add_argument("--foxglove", type=int, nargs="?", const=FOXGLOVE_PORT, metavar="PORT",
                    help=f"live: also serve kincald's channels to the Foxglove app on PORT (default {FOXGLOVE_PORT})")
    ap.add_argument("--lcm-types", help="folder holding the kincal LCM Python package")
    a = ap.parse_args(argv)
    try:
        if not (0 < a.port < 65536) or not (0 < a.rate <= 30):
            raise ViewError("--port must be 1..65535 and --rate in (0, 30]")
        if a.foxglove is not None:
            if a.log:
                raise ViewError("--foxglove serves live LCM; open a recording in Foxglove as MCAP: "
                                "kincal export --format mcap --log RUN.lcm --out RUN.mcap")
            if not (0 < a.foxglove < 65536) or a.foxglove == a.port:
                raise ViewError(f"--foxglove {a.foxglove}: a port 1..65535 other than the page's ({a.port})")
        if not use_lcm_types(a.lcm_types):
            raise ViewError("kincal's LCM Python types were not found (set KINCAL_LCM_TYPES)")
        truth = load_truth(a.truth)
        check_port(a.bind, a.port)
        if a.log:
            timeline = Timeline(None)
            n = load_log(a.log, timeline)
            print(f"kincal view: {a.log}: {n} messages, {timeline.snapshot()['span'][1]:.1f} s", flush=True)
        else:
            timeline = Timeline(a.history_s)
            foxglove = None
            if a.foxglove is not None:
                foxglove = FoxgloveLive(a.bind, a.foxglove)
                fox_host = f"[{a.bind}]" if ":" in a.bind else a.bind
                print(f"kincal view: Foxglove: ws://{fox_host}:{a.foxglove} (the app's Open connection)", flush=True)
            live = LiveSource(a.lcm_url, timeline, foxglove)
            live.start()
        server = Server(a, timeline, a.log, truth)
        timeline.on_change = server.wake_all
    except ViewError as e:
        print(f"kincal view: error: {e}", file=sys.stderr)
        return 1
    from aiohttp import web
    host = f"[{a.bind}]" if ":" in a.bind else a.bind
    print(f"kincal view: http://{host}:{a.port}/ ({'recording ' + a.log if a.log else 'live LCM'}; "
          "Ctrl-C stops)", flush=True)
    try:
        web.run_app(server.app(), host=a.bind, port=a.port, print=None, handle_signals=True)
    except OSError as e:
        print(f"kincal view: error: cannot listen on {a.bind}:{a.port}: {e}", file=sys.stderr)
        return 1
    return 0


if __name__ == "__main__":
    sys.exit(main())
