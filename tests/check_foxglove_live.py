#!/usr/bin/env python3
"""`kincal view --foxglove` as the Foxglove app sees it (ctest cli.view_foxglove).

kincald runs on the simulated camera with the preview on; kincal view listens to its LCM
with --foxglove. A WebSocket client speaking the protocol of foxglove-sdk's server
(foxglove.sdk.v1, as the Foxglove app does) connects and checks:
  * the advertised channels: the picture as foxglove.CompressedImage, the markers as
    foxglove.ImageAnnotations, the pose as foxglove.PoseInFrame and /tf as
    foxglove.FrameTransform, the estimate as JSON: the topics `kincal export --format mcap`
    writes;
  * a subscription to the estimate delivers messages whose JSON holds the parameters
    kincald publishes (as many values as the model has parameters, finite);
  * the page still serves beside it;
and the errors: --foxglove with --log, and a Foxglove port in use, are named, exit 1.

usage: check_foxglove_live.py KINCALD KINCAL
"""

import asyncio
import json
import math
import socket
import struct
import subprocess
import sys
import time
import urllib.request

WANT = {
    "/KINCAL_PREVIEW": "foxglove.CompressedImage",
    "/KINCAL_MARKERS": "foxglove.ImageAnnotations",
    "/KINCAL_POSE": "foxglove.PoseInFrame",
    "/tf": "foxglove.FrameTransform",
    "/KINCAL_PARAMS": "kincal.params_t",
}


def free_port():
    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        return s.getsockname()[1]


def start_view(kincal, args):
    p = subprocess.Popen([kincal, "view"] + args, stdout=subprocess.PIPE, stderr=subprocess.STDOUT, text=True)
    lines, deadline = [], time.time() + 30
    while time.time() < deadline:
        line = p.stdout.readline()
        if not line and p.poll() is not None:
            raise AssertionError("kincal view ended: " + "".join(lines))
        lines.append(line)
        if "http://" in line:
            return p, "".join(lines)
    raise AssertionError("kincal view did not start in 30 s: " + "".join(lines))


async def as_the_app(port, failures):
    """Connects as Foxglove does; returns (advertised {topic: schemaName}, params messages)."""
    import aiohttp
    channels, params = {}, []
    async with aiohttp.ClientSession() as session:
        async with session.ws_connect(f"ws://127.0.0.1:{port}", protocols=("foxglove.sdk.v1",)) as ws:
            deadline = time.time() + 30
            subscribed = False
            while time.time() < deadline and len(params) < 3:
                try:
                    msg = await ws.receive(timeout=max(0.1, deadline - time.time()))
                except asyncio.TimeoutError:
                    break
                if msg.type == aiohttp.WSMsgType.TEXT:
                    m = json.loads(msg.data)
                    if m.get("op") == "advertise":
                        for c in m["channels"]:
                            channels[c["topic"]] = (c["id"], c["schemaName"], c["encoding"])
                    if not subscribed and "/KINCAL_PARAMS" in channels:
                        await ws.send_str(json.dumps({"op": "subscribe", "subscriptions": [
                            {"id": 7, "channelId": channels["/KINCAL_PARAMS"][0]}]}))
                        subscribed = True
                elif msg.type == aiohttp.WSMsgType.BINARY:
                    op, sub = struct.unpack_from("<BI", msg.data)
                    if op == 1 and sub == 7:  # message data: subscription, log time, payload
                        params.append(json.loads(msg.data[13:]))
                elif msg.type in (aiohttp.WSMsgType.CLOSED, aiohttp.WSMsgType.ERROR):
                    failures.append(f"the server closed the connection: {msg}")
                    break
    return channels, params


def live(kincald, kincal, failures):
    url = f"udpm://239.255.76.67:{free_port()}?ttl=0"
    page, fox = free_port(), free_port()
    daemon = subprocess.Popen([kincald, "--duration", "20", "--preview", "--lcm-url", url, "-q"],
                              stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
    view, said = start_view(kincal, ["--lcm-url", url, "--port", str(page), "--foxglove", str(fox)])
    try:
        if f"ws://127.0.0.1:{fox}" not in said:
            failures.append(f"kincal view did not say where Foxglove connects: {said!r}")
        channels, params = asyncio.run(as_the_app(fox, failures))
        for topic, schema in WANT.items():
            got = channels.get(topic)
            if got is None or got[1] != schema:
                failures.append(f"{topic}: advertised as {got and got[1]!r}, want {schema!r}")
        if channels.get("/KINCAL_PARAMS", (0, 0, ""))[2] != "json":
            failures.append(f"/KINCAL_PARAMS: encoding {channels.get('/KINCAL_PARAMS')}, want json")
        if len(params) < 3:
            failures.append(f"{len(params)} estimate messages through the subscription, want >= 3")
        for p in params:
            values = p.get("values", [])
            if len(values) != p.get("num_params") or not all(math.isfinite(v) for v in values):
                failures.append(f"an estimate message that is not kincald's: {p}")
                break
        with urllib.request.urlopen(f"http://127.0.0.1:{page}/", timeout=10) as r:
            if r.status != 200:
                failures.append(f"the page beside it: HTTP {r.status}")
    finally:
        view.terminate()
        daemon.terminate()
        view.wait(timeout=10)
        daemon.wait(timeout=30)


def errors(kincal, failures):
    with socket.socket() as held:
        held.bind(("127.0.0.1", 0))
        held.listen(1)
        taken = held.getsockname()[1]
        for args, pattern in (
                (["--log", __file__, "--foxglove"], "--foxglove serves live LCM"),
                (["--lcm-url", "udpm://239.255.76.67:7667?ttl=0", "--foxglove", str(taken)],
                 f"cannot listen on 127.0.0.1:{taken}")):
            run = subprocess.run([kincal, "view", "--port", str(free_port())] + args, capture_output=True,
                                 text=True, timeout=60)
            if run.returncode != 1 or pattern not in run.stderr:
                failures.append(f"kincal view {' '.join(args)}: exit {run.returncode}, {run.stderr.strip()!r}")


def main():
    kincald, kincal = sys.argv[1:3]
    failures = []
    live(kincald, kincal, failures)
    errors(kincal, failures)
    for f in failures:
        print("FAIL:", f)
    print("ok" if not failures else f"{len(failures)} failures")
    return 1 if failures else 0


if __name__ == "__main__":
    sys.exit(main())
