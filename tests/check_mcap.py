"""kincal export --format mcap, end to end (issue 35): kincald records 6 s of the simulated
robot with its preview; the export is read back with the `mcap` package (not the writer's
SDK), and for every LCM channel of the recording the MCAP has a channel of the same name
with Foxglove's schema for it, as many messages, with the same log times; the derived
topics (/tf, the preview's annotations, the simulator's true pose) hold one message per
valid pose, per preview and per truth on the floor, the truth's JSON carries the
scenario's parameters,
and the annotations' circles sit on the published markers (pixels, Foxglove's pixel-corner
origin: u + 0.5). A recording that is not one, or one cut short, is a named error with
nothing written.

    check_mcap.py KINCALD KINCAL WORKDIR
"""
import os
import shutil
import subprocess
import sys

HERE = os.path.dirname(os.path.abspath(__file__))
sys.path.insert(0, os.path.join(HERE, "..", "scripts"))

EXPECTED_SCHEMA = {
    "KINCAL_PREVIEW": "foxglove.CompressedImage",
    "KINCAL_FRAME": "foxglove.RawImage",  # the default recording: raw GREY frames
    "KINCAL_MARKERS": "foxglove.ImageAnnotations",
    "KINCAL_POSE": "foxglove.PoseInFrame",
    "KINCAL_PARAMS": "kincal.params_t",
    "KINCAL_HEALTH": "kincal.health_t",
    "KINCAL_MODEL_CHECK": "kincal.model_check_t",
    "KINCAL_CONTROLS": "kincal.controls_t",
    "KINCAL_TRUTH": "kincal.truth_t",
}


def lcm_events(path):
    from kincal_mcap import read_events
    return list(read_events(path))


def check_truth_json(out, failures):
    """The truth's JSON messages carry the parameters of the shipped simulation's scenario
    (config/kincald_sim.yaml -> sim_daemon.yaml), read here from the YAML itself."""
    import json
    import yaml
    from mcap.reader import make_reader
    with open(os.path.join(HERE, "..", "config", "sim_daemon.yaml")) as f:
        want = yaml.safe_load(f)["truth"]
    with open(out, "rb") as f:
        for _, _, message in make_reader(f).iter_messages(topics=["/KINCAL_TRUTH"]):
            m = json.loads(message.data)
            got = dict(zip(m["names"], m["values"]))
            if any(got.get(k) != v for k, v in want.items()):
                failures.append(f"/KINCAL_TRUTH: parameters {got}, the scenario's {want}")
            return
    failures.append("/KINCAL_TRUTH: no message")


def main():
    kincald, kincal, work = sys.argv[1:4]
    shutil.rmtree(work, ignore_errors=True)
    os.makedirs(work)
    log = os.path.join(work, "run.lcm")
    out = os.path.join(work, "run.mcap")
    subprocess.run([kincald, "--fast", "--duration", "6", "--preview", "--record", log, "-q"], check=True)
    subprocess.run([kincal, "export", "--format", "mcap", "--log", log, "--out", out], check=True)

    from kincal_lcm_types import use_lcm_types
    use_lcm_types()
    from kincal import markers_t, pose_t, preview_t, truth_t
    events = lcm_events(log)
    by_channel = {}
    markers, valid_poses, previews, preview_axes, truths_on_floor = {}, 0, 0, {}, 0
    for ch, data, t in events:
        by_channel.setdefault(ch, []).append(t)
        if ch == "KINCAL_MARKERS":
            m = markers_t.decode(data)
            markers[m.utime] = m
        elif ch == "KINCAL_POSE":
            valid_poses += pose_t.decode(data).valid
        elif ch == "KINCAL_TRUTH":
            truths_on_floor += truth_t.decode(data).on_floor
        elif ch == "KINCAL_PREVIEW":
            previews += 1
            p = preview_t.decode(data)
            if p.num_axes == 3:
                preview_axes[(p.utime, p.frame_sequence)] = (p.scale, list(zip(p.axes_u, p.axes_v)))
    assert previews >= 25, f"{previews} previews in 6 s at 5 Hz"

    from mcap.reader import make_reader
    got, schemas, annotations = {}, {}, []
    with open(out, "rb") as f:
        for schema, channel, message in make_reader(f).iter_messages():
            got.setdefault(channel.topic, []).append(message.log_time)
            schemas[channel.topic] = schema.name
            if channel.topic == "/KINCAL_MARKERS":
                annotations.append(message)
    failures = []
    for ch, times in by_channel.items():
        topic = "/" + ch
        if got.get(topic) != times:
            failures.append(f"{topic}: {len(got.get(topic, []))} messages, the log has {len(times)} "
                            "(or their log times differ)")
        want = EXPECTED_SCHEMA.get(ch)
        if want and schemas.get(topic) != want:
            failures.append(f"{topic}: schema {schemas.get(topic)}, expected {want}")
    if len(got.get("/tf", [])) != valid_poses:
        failures.append(f"/tf: {len(got.get('/tf', []))} transforms, {valid_poses} valid poses")
    if not truths_on_floor or len(got.get("/KINCAL_TRUTH/pose", [])) != truths_on_floor:
        failures.append(f"/KINCAL_TRUTH/pose: {len(got.get('/KINCAL_TRUTH/pose', []))} poses, "
                        f"{truths_on_floor} truths on the floor")
    check_truth_json(out, failures)
    if len(got.get("/KINCAL_MARKERS/preview", [])) != previews:
        failures.append(f"preview annotations: {len(got.get('/KINCAL_MARKERS/preview', []))}, {previews} previews")

    # The circles where the markers are: decoded with the protobuf schema the file carries
    # (mcap-protobuf-support), not with the SDK that wrote it.
    from mcap_protobuf.decoder import DecoderFactory
    checked = 0
    with open(out, "rb") as f:
        reader = make_reader(f, decoder_factories=[DecoderFactory()])
        for _, channel, _, a in reader.iter_decoded_messages(topics=["/KINCAL_MARKERS"]):
            if not a.circles:
                continue
            ts = a.circles[0].timestamp
            m = markers.get(ts.seconds * 1_000_000 + ts.nanos // 1000)
            if m is None or m.num_markers != len(a.circles):
                failures.append(f"annotations at {ts.seconds}.{ts.nanos:09d} s: no markers_t with as many markers")
                continue
            for i, c in enumerate(a.circles):
                if abs(c.position.x - (m.u[i] + 0.5)) > 1e-9 or abs(c.position.y - (m.v[i] + 0.5)) > 1e-9:
                    failures.append(f"circle {i} at ({c.position.x}, {c.position.y}), marker at ({m.u[i]}, {m.v[i]})")
            checked += 1
    if checked < 100:
        failures.append(f"only {checked} annotation messages with markers")
    # The target's axes on the previews: two lines from the projected origin, x red, y green.
    with_axes = 0
    with open(out, "rb") as f:
        reader = make_reader(f, decoder_factories=[DecoderFactory()])
        for _, _, _, a in reader.iter_decoded_messages(topics=["/KINCAL_MARKERS/preview"]):
            lines = [p for p in a.points if len(p.points) == 2]
            if not lines:
                continue
            with_axes += 1
            o = lines[0].points[0]
            if not (lines[0].outline_color.r > 0.8 and lines[1].outline_color.g > 0.8):
                failures.append("preview axes: x not red or y not green")
            if not any(abs(o.x - (ax[0][0] + 0.5) / s) < 1e-9 and abs(o.y - (ax[0][1] + 0.5) / s) < 1e-9
                       for s, ax in preview_axes.values()):
                failures.append(f"preview axes' origin at ({o.x}, {o.y}): no preview_t projects it there")
    if with_axes < len(preview_axes) * 0.8 or with_axes == 0:
        failures.append(f"{with_axes} preview annotations with axes, {len(preview_axes)} previews carry them")
    print(f"annotations checked against the markers: {checked}")

    # Bad input: named, nothing written.
    bad = os.path.join(work, "cut.lcm")
    with open(log, "rb") as f, open(bad, "wb") as g:
        g.write(f.read(os.path.getsize(log) // 2))
    for src, pattern in ((bad, "damaged or cut short at byte"), (__file__, "not an LCM log")):
        target = os.path.join(work, "bad.mcap")
        run = subprocess.run([kincal, "export", "--format", "mcap", "--log", src, "--out", target],
                             capture_output=True, text=True)
        if run.returncode == 0 or pattern not in run.stderr or os.path.exists(target):
            failures.append(f"{src}: exit {run.returncode}, {run.stderr.strip()!r}, output left: "
                            f"{os.path.exists(target)}")
    leftovers = [n for n in os.listdir(work) if n.startswith(".kincal_mcap_")]
    if leftovers:
        failures.append(f"temporaries left: {leftovers}")
    for f in failures:
        print("FAIL:", f)
    print(f"{sum(len(v) for v in got.values())} MCAP messages on {len(got)} topics checked")
    return 1 if failures else 0


if __name__ == "__main__":
    sys.exit(main())
