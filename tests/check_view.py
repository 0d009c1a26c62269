"""kincal view in a real browser (issue 35): Debian's chromium, driven by selenium.

live:  kincald on the simulated camera with guidance (--preview, paced, on an LCM URL of
       this test's own) and `kincal view` on it. After the first update the page must draw
       every published marker of the picture it shows where preview_t's mapping puts it (in
       the page's own record and in the canvas's pixels; in a screenshot too, on the paused
       recording below), the floor the camera sees with the track, the pose and the
       guidance's advised path (as the last KINCAL_GUIDANCE has it), one chart per
       parameter named after it with the truth kincald's simulator publishes (KINCAL_TRUTH,
       equal to the scenario's truth: map) and the true track on the floor, >= 5 updates a
       second, frames on the page <= 250 ms after their capture, a second browser served
       at the same time, and once kincald has ended the health the
       last KINCAL_HEALTH says (the preview's counts too) and "daemon not heard for N s"
       over the picture.
log:   `kincal view --log` on the recording kincald made: play, pause and the slider move
       the picture and the charts through the run; the truth is the recording's.
errors: garbage on a kincal channel is named on the page; a port in use and a file that
       is not a recording are named and exit 1.

    check_view.py KINCALD KINCAL WORKDIR [--no-timing]

--no-timing (the sanitizer build, where kincald runs many times slower): the update rate
and the latency are printed, not judged.
"""
import json
import math
import os
import shutil
import socket
import subprocess
import sys
import threading
import time

HERE = os.path.dirname(os.path.abspath(__file__))
sys.path.insert(0, os.path.join(HERE, "..", "scripts"))


def free_port():
    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        return s.getsockname()[1]


def browser():
    from selenium import webdriver
    from selenium.webdriver.chrome.service import Service
    o = webdriver.ChromeOptions()
    o.binary_location = "/usr/bin/chromium"
    for a in ("--headless=new", "--no-sandbox", "--disable-gpu", "--disable-dev-shm-usage",
              "--window-size=1400,1100"):
        o.add_argument(a)
    return webdriver.Chrome(service=Service("/usr/bin/chromedriver"), options=o)


def wait_for(driver, script, timeout, what):
    t0 = time.time()
    while time.time() - t0 < timeout:
        v = driver.execute_script(script)
        if v:
            return v
        time.sleep(0.1)
    raise AssertionError(f"timed out after {timeout} s waiting for {what}")


def start_view(kincal, args, port):
    p = subprocess.Popen([kincal, "view", "--port", str(port)] + args, stdout=subprocess.PIPE,
                         stderr=subprocess.STDOUT, text=True)
    line = p.stdout.readline()
    deadline = time.time() + 30
    while "http://" not in line and time.time() < deadline:
        if p.poll() is not None:
            raise AssertionError(f"kincal view ended: {line}{p.stdout.read()}")
        line = p.stdout.readline()
    return p


class Health(threading.Thread):
    """The last KINCAL_HEALTH and KINCAL_GUIDANCE, heard beside the page."""

    def __init__(self, url):
        super().__init__(daemon=True)
        import lcm
        from kincal_lcm_types import use_lcm_types
        use_lcm_types()
        from kincal import guidance_t, health_t
        self.lcm, self.type, self.last, self.stop = lcm.LCM(url), health_t, None, False
        self.guidance = None
        self.lcm.subscribe("KINCAL_HEALTH", lambda ch, data: setattr(self, "last", self.type.decode(data)))
        self.lcm.subscribe("KINCAL_GUIDANCE", lambda ch, data: setattr(self, "guidance", guidance_t.decode(data)))

    def run(self):
        while not self.stop:
            self.lcm.handle_timeout(50)


def ring_colour(rgb, identified):
    """The page's ring colours (green: identified, red: unassigned), blended with the grey
    picture at the ring's edge; the picture itself is grey (r = g = b)."""
    r, g, b = rgb[:3]
    return g > r + 50 and g > b + 40 if identified else r > g + 50 and r > b + 40


def check_overlay(driver, failures):
    """The markers drawn where the state's markers_t puts them, and seen in the pixels."""
    got = driver.execute_script("""
      const s = window.kincalView.lastState();
      const d = window.kincalView.drawnMarkers, f = window.kincalView.drawnFrame;
      const c = document.getElementById('picture'), x = c.getContext('2d');
      // Eight points on each ring (radius 5): the target's outline may cross two of them.
      const px = d.map(([u, v]) => [0, 1, 2, 3, 4, 5, 6, 7].map((k) => Array.from(x.getImageData(
          Math.round(u + 5 * Math.cos(k * Math.PI / 4)), Math.round(v + 5 * Math.sin(k * Math.PI / 4)), 1, 1).data)));
      const a = window.kincalView.drawnAxes;
      const mid = a ? [1, 2].map((k) => Array.from(x.getImageData(Math.round((a[0][0] + a[k][0]) / 2),
          Math.round((a[0][1] + a[k][1]) / 2), 1, 1).data)) : null;
      return {s: s, d: d, f: f, px: px, w: c.width, h: c.height, axes: a, mid: mid};""")
    s = got["s"]
    p, m = s["preview"], s["markers"]
    if m is None or p is None:
        failures.append("no markers for the picture shown")
        return
    if got["f"] != p["frame_sequence"] or m["frame_sequence"] != p["frame_sequence"]:
        return  # a newer state arrived between drawing and reading: not a failure
    want = [((u + 0.5) / p["scale"], (v + 0.5) / p["scale"], i) for u, v, i in zip(m["u"], m["v"], m["id"])]
    if len(want) != len(got["d"]) or any(abs(a[0] - b[0]) > 1e-6 or abs(a[1] - b[1]) > 1e-6 or a[2] != b[2]
                                         for a, b in zip(want, got["d"])):
        failures.append(f"markers drawn at {got['d']}, published at {want}")
    for (u, v, i), ring in zip(want, got["px"]):
        if sum(ring_colour(rgba[:3], i >= 0) for rgba in ring) < 5:
            failures.append(f"canvas pixels on the ring of marker ({u:.1f}, {v:.1f}): {ring}")
    check_axes(p, want, got, failures)
    return want


def check_axes(p, want, got, failures):
    """The target's axes drawn from the preview's projection of the pose: the origin among
    the identified markers, the x axis red and the y axis green at their middles."""
    identified = [(u, v) for u, v, i in want if i >= 0]
    if len(identified) < 3:
        return
    if not p.get("axes") or not got["axes"]:
        failures.append("a frame with an identified target but no axes drawn")
        return
    drawn = [((u + 0.5) / p["scale"], (v + 0.5) / p["scale"]) for u, v in p["axes"]]
    if any(abs(a[0] - b[0]) > 1e-6 or abs(a[1] - b[1]) > 1e-6 for a, b in zip(drawn, got["axes"])):
        failures.append(f"axes drawn at {got['axes']}, published at {drawn}")
    us, vs = [u for u, _ in identified], [v for _, v in identified]
    ox, oy = drawn[0]
    if not (min(us) - 3 <= ox <= max(us) + 3 and min(vs) - 3 <= oy <= max(vs) + 3):
        failures.append(f"the target's origin drawn at ({ox:.1f}, {oy:.1f}), outside its markers {identified}")
    (xr, xg, xb, _), (yr, yg, yb, _) = got["mid"]
    if not (xr > xg + 50 and xr > xb + 40) or not (yg > yr + 50 and yg > yb + 40):
        failures.append(f"axis colours at their middles: x {got['mid'][0]}, y {got['mid'][1]}")


def check_screenshot(driver, want, failures, path):
    """The same rings in a screenshot of the page (what a user sees)."""
    from PIL import Image
    el = driver.find_element("id", "picture")
    el.screenshot(path)
    img = Image.open(path).convert("RGB")
    w, h = driver.execute_script("const c = document.getElementById('picture'); return [c.width, c.height];")
    sx, sy = img.width / w, img.height / h
    hits = 0
    for u, v, i in want or []:
        # Any ring colour within the ring's radius (5 px of canvas) around the marker.
        found = False
        for dx in range(-7, 8):
            for dy in range(-7, 8):
                x, y = int((u + dx) * sx), int((v + dy) * sy)
                if 0 <= x < img.width and 0 <= y < img.height:
                    if ring_colour(img.getpixel((x, y)), i >= 0):
                        found = True
        hits += found
    if want and hits < len(want):
        failures.append(f"screenshot: {hits} of {len(want)} markers' rings seen")


def load_truth_map(path):
    """A scenario's truth: map, read as kincal view reads it."""
    sys.path.insert(0, os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "scripts"))
    from kincal_view import load_truth
    return load_truth(path)


def check_truth(driver, scenario, failures, where):
    """The simulated robot's truth, as kincald's simulator published it (no --truth given):
    on every chart the scenario's value, and the true track on the floor map."""
    truth = load_truth_map(scenario)
    drawn = driver.execute_script(
        "return Object.fromEntries(Array.from(document.querySelectorAll('#charts .chart')).map("
        "d => [d.dataset.param, (d.data.find(t => t.name === 'truth') || {y: [null]}).y[0]]))")
    if not drawn or any(drawn.get(n) != truth.get(n) for n in drawn):
        failures.append(f"{where}: truth on the charts {drawn}, the scenario's {truth}")
    floor = driver.execute_script("return window.kincalView.floorDrawn")
    if not floor or floor.get("truth", 0) < 10:
        failures.append(f"{where}: the true track on the floor map: {floor}")


def check_advised_path(driver, health, failures):
    """The guidance's path on the floor map: as many points as the last KINCAL_GUIDANCE
    carries, as far from its start to its end (the message's path is in the target's frame,
    the page's on the floor: a rotation and a shift keep that distance)."""
    wait_for(driver, "const f = window.kincalView.floorDrawn; return f && f.path && f.path.length > 1", 20,
             "the guidance's path on the floor map")
    for _ in range(20):  # a newer advice may land between reading the page and the message
        path = driver.execute_script("return window.kincalView.floorDrawn.path")
        g = health.guidance
        if g is not None and len(path) == g.num_path:
            drawn = math.dist(path[0], path[-1])
            sent = math.hypot(g.path_x[-1], g.path_y[-1])
            if abs(drawn - sent) < 1e-9 + 1e-9 * sent:
                return
        time.sleep(0.1)
    failures.append(f"the advised path on the page {path[:2]}...{path[-1:]} ({len(path)} points) does not "
                    f"match the last KINCAL_GUIDANCE ({g.num_path if g else None} points)")


def live(kincald, kincal, work, failures, timing=True):
    url = f"udpm://239.255.76.67:{free_port()}?ttl=0"
    port = free_port()
    log = os.path.join(work, "live.lcm")
    health = Health(url)
    health.start()
    config = os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "config", "kincald_sim_guidance.yaml")
    daemon = subprocess.Popen([kincald, "-c", config, "--duration", "25", "--preview", "--lcm-url", url,
                               "--record", log, "-q"],
                              stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
    scenario = os.path.join(os.path.dirname(config), "sim_daemon.yaml")  # the config's sim.scenario
    view = start_view(kincal, ["--lcm-url", url], port)
    driver = browser()
    second = browser()
    try:
        driver.get(f"http://127.0.0.1:{port}/")
        second.get(f"http://127.0.0.1:{port}/")
        wait_for(driver, "return window.kincalView.drawnMarkers.length > 0 && window.kincalView.lastState().latest_params", 20,
                 "the first picture with markers and an estimate")
        wait_for(driver, "return document.querySelectorAll('#charts .chart').length > 0", 5, "the charts")
        # Latency: a frame's capture (preview utime, host realtime) to the page.
        driver.execute_script("""
          window.lat = []; window.lastSeq = -1;
          const old = window.kincalView.lastState;
          window.latServer = [];
          setInterval(() => { const s = old(); if (s && s.preview && s.preview.frame_sequence !== window.lastSeq) {
            window.lastSeq = s.preview.frame_sequence; window.lat.push(Date.now() - s.preview.utime / 1000);
            window.latServer.push((s.preview.received_utime - s.preview.utime) / 1000); } }, 5);""")
        u0 = driver.execute_script("return window.kincalView.updates")
        time.sleep(3.0)
        rate = (driver.execute_script("return window.kincalView.updates") - u0) / 3.0
        if rate < 5 and timing:
            failures.append(f"{rate:.1f} updates a second (>= 5 wanted)")
        lat = sorted(driver.execute_script("return window.lat"))
        if not lat or (lat[len(lat) // 2] > 250 and timing):
            failures.append(f"capture to page: median {lat[len(lat) // 2] if lat else None} ms of {len(lat)} (<= 250 wanted)")
        ls = sorted(driver.execute_script("return window.latServer"))
        print(f"live: {rate:.1f} updates/s; capture to page median {lat[len(lat) // 2]:.0f} ms, max {lat[-1]:.0f} ms; "
              f"capture to kincal view's LCM thread median {ls[len(ls) // 2]:.0f} ms")
        if second.execute_script("return window.kincalView.updates") < 5:
            failures.append("the second browser got no updates")
        for _ in range(10):  # a newer picture may land between drawing and reading: again
            if check_overlay(driver, failures):
                break
            time.sleep(0.1)
        else:
            failures.append("live: no picture with markers could be checked")
        floor = driver.execute_script("return window.kincalView.floorDrawn")
        if not floor or floor["seen"] != 32 or floor["track"] < 10 or not floor["pose"]:
            failures.append(f"floor map drawn: {floor} (want the 32-point polygon, a track and a pose)")
        check_advised_path(driver, health, failures)
        n_params = len(driver.execute_script("return window.kincalView.lastState().latest_params.names"))
        names = driver.execute_script(
            "return Array.from(document.querySelectorAll('#charts .chart')).map(d => [d.dataset.param, d.data[0].name])")
        if len(names) != n_params or any(a != b for a, b in names):
            failures.append(f"charts {names} for {n_params} parameters")
        check_truth(driver, scenario, failures, "live")
        # Garbage on a kincal channel: named on the page, with its channel.
        import lcm
        lcm.LCM(url).publish("KINCAL_HEALTH_X", b"\x00garbage, not a kincal message")
        wait_for(driver, "return !document.getElementById('errors-panel').hidden && "
                 "document.getElementById('errors').textContent.includes('KINCAL_HEALTH_X')", 5,
                 "the garbage to be named on the page")
        daemon.wait(timeout=120)
        time.sleep(3.5)  # the final health, then silence
        text = driver.execute_script("return document.getElementById('no-picture').hidden ? '' : "
                                     "document.getElementById('no-picture').textContent")
        if "daemon not heard for" not in text:
            failures.append(f"after kincald ended the picture says {text!r}")
        h = health.last
        shown = driver.execute_script("return document.querySelector('[data-key=\"frames\"]').textContent")
        if h is None or not shown.startswith(f"{h.frames_captured} "):
            failures.append(f"health on the page {shown!r}, last KINCAL_HEALTH frames_captured "
                            f"{h.frames_captured if h else None}")
        preview = driver.execute_script(
            "return document.querySelector('[data-key=\"preview\"]').textContent")
        if h is None or h.preview_published <= 0 or not preview.startswith(
                f"{h.preview_published} published, {h.preview_skipped} skipped"):
            failures.append(f"preview on the page {preview!r}, last KINCAL_HEALTH "
                            f"{(h.preview_published, h.preview_skipped) if h else None}")
        driver.save_screenshot(os.path.join(work, "view_live.png"))
    finally:
        health.stop = True
        driver.quit()
        second.quit()
        view.terminate()
        view.wait(timeout=10)
        if daemon.poll() is None:
            daemon.kill()
    return log


def recording(kincal, log, scenario, work, failures):
    port = free_port()
    view = start_view(kincal, ["--log", log], port)
    driver = browser()
    try:
        driver.get(f"http://127.0.0.1:{port}/")
        wait_for(driver, "return window.kincalView.updates > 0 && !document.getElementById('playback').hidden", 20,
                 "the recording's page")
        end = driver.execute_script("return window.kincalView.lastState().span[1]")
        seq_end = driver.execute_script("return window.kincalView.lastState().preview.frame_sequence")
        driver.execute_script("const s = document.getElementById('slider'); s.value = s.max * 0.25;"
                              "s.dispatchEvent(new Event('input'));")
        wait_for(driver, f"return Math.abs(window.kincalView.lastState().cursor.t - {end * 0.25}) < 0.05", 5,
                 "the slider to move the cursor")
        s = driver.execute_script("return window.kincalView.lastState()")
        if not s["preview"] or s["preview"]["frame_sequence"] >= seq_end or not s["params"] \
                or s["params"][-1]["t"] > s["cursor"]["t"] + 1e-6:
            failures.append(f"at a quarter of the run the page shows frame "
                            f"{s['preview'] and s['preview']['frame_sequence']} (end {seq_end}) and params to "
                            f"{s['params'][-1]['t'] if s['params'] else None} s")
        # Paused, so the picture stays once drawn (its image decodes asynchronously: slower
        # under the sanitizers' load than any fixed wait): the screenshot matches the state.
        wait_for(driver, "const s = window.kincalView.lastState(); "
                 "return s.preview && window.kincalView.drawnFrame === s.preview.frame_sequence", 20,
                 "the paused picture to be drawn")
        want = check_overlay(driver, failures)
        if not want:
            failures.append("log: no markers drawn on the paused picture")
        check_truth(driver, scenario, failures, "log")
        check_screenshot(driver, want, failures, os.path.join(work, "log_picture.png"))
        driver.find_element("id", "play").click()
        time.sleep(1.5)
        t_play = driver.execute_script("return window.kincalView.lastState().cursor.t")
        if not (end * 0.25 + 0.8 < t_play < end * 0.25 + 3.0):
            failures.append(f"playing from {end * 0.25:.2f} s for 1.5 s reached {t_play:.2f} s")
        driver.find_element("id", "play").click()
        time.sleep(0.5)
        t1 = driver.execute_script("return window.kincalView.lastState().cursor.t")
        time.sleep(1.0)
        t2 = driver.execute_script("return window.kincalView.lastState().cursor.t")
        if abs(t2 - t1) > 1e-9:
            failures.append(f"paused, the cursor moved from {t1} to {t2}")
        driver.save_screenshot(os.path.join(work, "view_log.png"))
        print(f"log: {end:.1f} s; slider to {end * 0.25:.2f} s, played to {t_play:.2f} s, paused")
    finally:
        driver.quit()
        view.terminate()
        view.wait(timeout=10)


def errors(kincal, log, failures):
    """A port in use and a file that is not a recording: named, exit 1."""
    with socket.socket() as held:
        held.bind(("127.0.0.1", 0))
        held.listen(1)
        port = held.getsockname()[1]
        for args, pattern in ((["--port", str(port), "--log", log], f"cannot listen on 127.0.0.1:{port}"),
                              (["--port", str(free_port()), "--log", __file__], "not an LCM log")):
            run = subprocess.run([kincal, "view"] + args, capture_output=True, text=True, timeout=60)
            if run.returncode != 1 or pattern not in run.stderr:
                failures.append(f"kincal view {' '.join(args)}: exit {run.returncode}, {run.stderr.strip()!r}")


def main():
    kincald, kincal, work = sys.argv[1:4]
    timing = "--no-timing" not in sys.argv[4:]
    shutil.rmtree(work, ignore_errors=True)
    os.makedirs(work)
    failures = []
    log = live(kincald, kincal, work, failures, timing)
    scenario = os.path.join(HERE, "..", "config", "sim_daemon.yaml")  # kincald_sim_guidance.yaml's
    recording(kincal, log, scenario, work, failures)
    errors(kincal, log, failures)
    for f in failures:
        print("FAIL:", f)
    return 1 if failures else 0


if __name__ == "__main__":
    sys.exit(main())
