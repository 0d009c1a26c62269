// kincal view's page: draws the newest state the server sends over the WebSocket (the
// camera picture with the markers, the target and its track; the parameters +-2 sigma
// against time; status, model check, health, guidance). Nothing here reaches kincald.
"use strict";

const STALE_S = 2.0;  // "daemon not heard for N s" after this
const STATUS = ["initializing", "converging", "converged", "diverged", "model inadequate"];
const STATUS_CLASS = ["warn", "warn", "ok", "bad", "bad"];
const canvas = document.getElementById("picture");
const ctx = canvas.getContext("2d");
const image = new Image();
let latest = null;        // the last state received
let shownPicture = null;  // the jpeg string drawn
let charts = {};          // parameter name -> div
let socket = null;
let drawPending = false;  // a draw is queued for the next animation frame
let chartsDrawnAt = 0;    // the charts are redrawn twice a second at most

window.kincalView = { updates: 0, drawnMarkers: [], lastState: () => latest };

function connect() {
  socket = new WebSocket((location.protocol === "https:" ? "wss://" : "ws://") + location.host + "/ws");
  socket.onmessage = (ev) => {
    const s = JSON.parse(ev.data);
    if (s.params === undefined && latest) s.params = latest.params;  // sent twice a second
    latest = s;
    window.kincalView.updates += 1;
    socket.send(JSON.stringify({ cmd: "ack" }));  // the server sends the next one after this
    if (!drawPending) {
      drawPending = true;
      requestAnimationFrame(() => { drawPending = false; render(latest); });
    }
  };
  socket.onclose = () => {
    document.getElementById("heard").textContent = "page disconnected from kincal view: retrying";
    document.getElementById("heard").className = "badge bad";
    setTimeout(connect, 1000);
  };
}

function fmt(v, digits = 4) {
  if (v === null || v === undefined || Number.isNaN(v)) return "–";
  if (typeof v !== "number") return String(v);
  return Math.abs(v) >= 1e4 || (Math.abs(v) < 1e-3 && v !== 0) ? v.toExponential(3) : v.toPrecision(digits);
}

function render(s) {
  document.getElementById("mode").textContent =
    s.mode === "log" ? "recording" : "live (LCM)";
  renderHeard(s);
  renderPicture(s);
  renderFloor(s.floor);
  renderEstimate(s);
  renderModelCheck(s.model_check);
  renderHealth(s.health);
  renderGuidance(s.guidance);
  renderErrors(s.errors);
  renderCharts(s);
  renderPlayback(s);
}

function renderHeard(s) {
  const el = document.getElementById("heard");
  if (s.mode === "log") {
    el.textContent = "";
    el.className = "";
  } else if (s.heard_s_ago === null) {
    el.textContent = "daemon not heard yet";
    el.className = "badge warn";
  } else if (s.heard_s_ago > STALE_S) {
    el.textContent = `daemon not heard for ${Math.round(s.heard_s_ago)} s`;
    el.className = "badge bad";
  } else {
    el.textContent = "daemon heard";
    el.className = "badge ok";
  }
}

function stale(s) {
  return s.mode !== "log" && s.heard_s_ago !== null && s.heard_s_ago > STALE_S;
}

function renderPicture(s) {
  const cover = document.getElementById("no-picture");
  const p = s.preview;
  if (!p) {
    cover.textContent = "no frames yet" + (s.mode === "log" ? " in the recording" : " (kincald --preview)");
    cover.hidden = false;
    return;
  }
  if (stale(s)) {
    cover.textContent = `daemon not heard for ${Math.round(s.heard_s_ago)} s`;
    cover.hidden = false;
  } else {
    cover.hidden = true;
  }
  if (p.jpeg !== shownPicture) {
    shownPicture = p.jpeg;
    image.onload = () => drawOverlay(p, s.markers, s.track);
    image.src = "data:image/jpeg;base64," + p.jpeg;
  } else {
    drawOverlay(p, s.markers, s.track);
  }
  const m = s.markers;
  document.getElementById("picture-info").textContent =
    `frame ${p.frame_sequence}, ${p.source_width}x${p.source_height} shown at 1/${p.scale}` +
    (m ? `; ${m.u.length} blobs, ${m.id.filter((i) => i >= 0).length} identified` +
         (m.target_id >= 0 ? `, target ${m.target_id}` : ", no target") : "; no markers for this frame");
}

// Camera pixel (centre of pixel u at u) to the canvas: (u + 0.5) / scale.
function toCanvas(p, u, v) {
  return [(u + 0.5) / p.scale, (v + 0.5) / p.scale];
}

// The target's axes (preview_t: its origin and axis ends, projected from the frame's
// pose): x red, y green.
function drawAxes(p) {
  window.kincalView.drawnAxes = null;
  if (!p.axes) return;
  const [ox, oy] = toCanvas(p, p.axes[0][0], p.axes[0][1]);
  const ends = [];
  [["#f23333", 1], ["#1ad933", 2]].forEach(([colour, k]) => {
    const [x, y] = toCanvas(p, p.axes[k][0], p.axes[k][1]);
    ctx.strokeStyle = colour;
    ctx.lineWidth = 2;
    ctx.beginPath();
    ctx.moveTo(ox, oy);
    ctx.lineTo(x, y);
    ctx.stroke();
    ends.push([x, y]);
  });
  window.kincalView.drawnAxes = [[ox, oy], ...ends];
}

function drawOverlay(p, markers, track) {
  if (canvas.width !== p.width || canvas.height !== p.height) {
    canvas.width = p.width;
    canvas.height = p.height;
  }
  ctx.drawImage(image, 0, 0);
  const drawn = [];
  if (track && track.length > 1) {
    ctx.strokeStyle = "#ffcc00";
    ctx.lineWidth = 1.5;
    ctx.beginPath();
    track.forEach((c, i) => {
      const [x, y] = toCanvas(p, c[0], c[1]);
      if (i === 0) ctx.moveTo(x, y); else ctx.lineTo(x, y);
    });
    ctx.stroke();
  }
  if (markers) {
    if (markers.outline.length >= 3) {
      ctx.strokeStyle = "#3399ff";
      ctx.lineWidth = 2;
      ctx.beginPath();
      markers.outline.forEach((q, i) => {
        const [x, y] = toCanvas(p, q[0], q[1]);
        if (i === 0) ctx.moveTo(x, y); else ctx.lineTo(x, y);
      });
      ctx.closePath();
      ctx.stroke();
      const [cx, cy] = toCanvas(p, markers.centre[0], markers.centre[1]);
      ctx.fillStyle = "#3399ff";
      ctx.font = "12px sans-serif";
      ctx.fillText(`target ${markers.target_id}`, cx + 6, cy - 6);
    }
    drawAxes(p);
    for (let i = 0; i < markers.u.length; i++) {
      const [x, y] = toCanvas(p, markers.u[i], markers.v[i]);
      ctx.strokeStyle = markers.id[i] >= 0 ? "#1ad933" : "#f23333";
      ctx.lineWidth = 2;
      ctx.beginPath();
      ctx.arc(x, y, 5, 0, 2 * Math.PI);
      ctx.stroke();
      drawn.push([x, y, markers.id[i]]);
    }
  }
  window.kincalView.drawnMarkers = drawn;
  window.kincalView.drawnFrame = p.frame_sequence;
}

// The floor map: what the camera sees, the track, the target's pose with its axes. Floor
// x right, y up; fitted to the polygon and the track with a margin.
function renderFloor(f) {
  const c = document.getElementById("floor");
  const g = c.getContext("2d");
  g.clearRect(0, 0, c.width, c.height);
  if (!f) return;
  const pts = (f.seen || []).concat((f.track || []).map((p) => [p[0], p[1]]), f.path || [], f.truth || []);
  if (!pts.length) {
    g.fillStyle = "#888";
    g.fillText("no floor polygon or pose yet", 10, 20);
    return;
  }
  let x0 = Math.min(...pts.map((p) => p[0])), x1 = Math.max(...pts.map((p) => p[0]));
  let y0 = Math.min(...pts.map((p) => p[1])), y1 = Math.max(...pts.map((p) => p[1]));
  const span = Math.max(x1 - x0, y1 - y0, 0.2);
  const k = 0.9 * Math.min(c.width / Math.max(x1 - x0, span * 0.3), c.height / Math.max(y1 - y0, span * 0.3));
  const cx = 0.5 * (x0 + x1), cy = 0.5 * (y0 + y1);
  const px = (x, y) => [c.width / 2 + k * (x - cx), c.height / 2 - k * (y - cy)];
  const line = (list, colour, close) => {
    g.strokeStyle = colour;
    g.beginPath();
    list.forEach((p, i) => { const [u, v] = px(p[0], p[1]); if (i === 0) g.moveTo(u, v); else g.lineTo(u, v); });
    if (close) g.closePath();
    g.stroke();
  };
  g.lineWidth = 1.5;
  if (f.seen && f.seen.length >= 3) line(f.seen, "#7fa7c9", true);
  if (f.truth && f.truth.length > 1) {  // the simulator's true track, under the measured one
    g.setLineDash([2, 3]);
    line(f.truth, "#ffffff", false);
    g.setLineDash([]);
  }
  if (f.track && f.track.length > 1) line(f.track, "#ffcc00", false);
  if (f.path && f.path.length > 1) {  // the guidance's advised motion, from where it was advised
    g.setLineDash([6, 4]);
    line(f.path, "#d070ff", false);
    g.setLineDash([]);
  }
  if (f.pose) {
    const [x, y, th] = f.pose;
    const a = 0.15 * span;
    line([[x, y], [x + a * Math.cos(th), y + a * Math.sin(th)]], "#ff6e6e", false);
    line([[x, y], [x - a * Math.sin(th), y + a * Math.cos(th)]], "#6eff8a", false);
  }
  g.fillStyle = "#888";
  g.fillText(`${fmt(span, 2)} m across`, 6, c.height - 6);
  window.kincalView.floorDrawn = {
    seen: (f.seen || []).length, track: (f.track || []).length, pose: f.pose, path: f.path || null,
    truth: (f.truth || []).length };
}

function renderEstimate(s) {
  const p = s.latest_params;
  const table = document.getElementById("estimate");
  const badge = document.getElementById("status");
  if (!p) {
    table.innerHTML = "<tr><td>no estimate yet</td></tr>";
    badge.textContent = "";
    badge.className = "";
    return;
  }
  badge.textContent = STATUS[p.status] || `status ${p.status}`;
  badge.className = "badge " + (STATUS_CLASS[p.status] || "");
  let rows = `<tr><td colspan="3">${p.model}: ${p.source === 1 ? "the batch calibration" : "the filter's"} ` +
             `(${p.updates} updates)</td></tr>`;
  p.names.forEach((n, i) => {
    const truth = s.truth && s.truth[n] !== undefined ? ` (truth ${fmt(s.truth[n])})` : "";
    rows += `<tr><td>${n}</td><td>${fmt(p.values[i], 6)} ± ${fmt(p.sigmas[i], 2)} ${p.units[i]}</td>` +
            `<td>${truth}</td></tr>`;
  });
  table.innerHTML = rows;
}

function renderModelCheck(m) {
  const el = document.getElementById("model-check");
  if (!m) { el.textContent = "–"; return; }
  const verdict = m.consistent ? "consistent" : (m.window < m.window_capacity ? "filling its window" : "inconsistent");
  el.innerHTML = `<div>${m.model}: <b>${verdict}</b> (NIS ${fmt(m.nis_mean, 3)} / ${fmt(m.nis_expected, 2)}, ` +
    `window ${m.window}/${m.window_capacity})</div>` +
    (m.suspected_effect ? `<div>suspected: <b>${m.suspected_effect}</b> (confidence ${fmt(m.confidence, 2)})</div>` : "") +
    (m.effects_added.length ? `<div>added online: ${m.effects_added.join(", ")}</div>` : "") +
    (m.evidence ? `<div class="evidence">${escapeHtml(m.evidence)}</div>` : "");
}

function renderHealth(h) {
  const table = document.getElementById("health");
  if (!h) { table.innerHTML = "<tr><td>–</td></tr>"; return; }
  const rows = [
    ["frame rate", `${fmt(h.frame_rate_hz, 3)} Hz`],
    ["frames", `${h.frames_captured} (dropped: device ${h.frames_dropped_device}, queue ${h.frames_dropped_queue}; bad ${h.frames_bad})`],
    ["poses", `${h.poses_valid} valid, ${h.poses_invalid} without target, ${h.poses_gated} gated`],
    ["latency", `p50 ${fmt(h.latency_p50_ms, 3)} ms, p99 ${fmt(h.latency_p99_ms, 3)} ms`],
    ["resets", `${h.filter_resets} filter, ${h.run_resets} runs, ${h.time_resets} time, ${h.source_restarts} source`],
    ["controls", `${h.controls_received} (${h.messages_rejected} rejected, ${h.controls_dropped_queue} dropped)`],
    ["batches", `${h.batch_runs} (${h.batch_failed} failed), ${h.filter_recentres} re-centres`],
    ["preview", `${h.preview_published} published, ${h.preview_skipped} skipped (worker busy)`],
    ["health", h.ok ? "ok" : `not ok: ${escapeHtml(h.message)}`],
  ];
  table.innerHTML = rows.map(([k, v]) => `<tr><td>${k}</td><td data-key="${k}">${v}</td></tr>`).join("");
}

function renderGuidance(g) {
  const el = document.getElementById("guidance");
  if (!g) { el.textContent = "no guidance (guidance.enabled)"; return; }
  el.innerHTML = `<div><b>${escapeHtml(g.motion)}</b> for ${fmt(g.duration_s, 2)} s</div>` +
    `<div>${g.parameter}: σ ${fmt(g.sigma, 3)} → target ${fmt(g.target, 3)}` +
    (g.time_to_target_s >= 0 ? `; about ${fmt(g.time_to_target_s, 3)} s of driving to every target` : "") + "</div>";
}

function renderErrors(errors) {
  const keys = Object.keys(errors || {});
  document.getElementById("errors-panel").hidden = keys.length === 0;
  document.getElementById("errors").innerHTML =
    keys.map((k) => `<div>${escapeHtml(k)}: ${escapeHtml(errors[k].what)} (${errors[k].count}×)</div>`).join("");
}

function renderCharts(s) {
  const box = document.getElementById("charts");
  const last = s.latest_params;
  if (!last || !s.params) return;
  if (performance.now() - chartsDrawnAt < 500 && Object.keys(charts).length) return;
  chartsDrawnAt = performance.now();
  last.names.forEach((name, i) => {
    if (!charts[name]) {
      const div = document.createElement("div");
      div.className = "chart";
      div.dataset.param = name;
      box.appendChild(div);
      charts[name] = div;
    }
    const t = s.params.map((p) => p.t);
    const v = s.params.map((p) => p.values[p.names.indexOf(name)]);
    const sg = s.params.map((p) => p.sigmas[p.names.indexOf(name)]);
    const hi = v.map((x, k) => x + 2 * sg[k]);
    const lo = v.map((x, k) => x - 2 * sg[k]);
    const traces = [
      { x: t, y: v, name: name, mode: "lines", line: { color: "#4fc3f7" } },
      { x: t.concat(t.slice().reverse()), y: hi.concat(lo.slice().reverse()), name: "±2σ",
        fill: "toself", mode: "none", fillcolor: "rgba(79,195,247,0.2)", hoverinfo: "skip" },
    ];
    if (s.truth && s.truth[name] !== undefined && t.length) {
      traces.push({ x: [t[0], t[t.length - 1]], y: [s.truth[name], s.truth[name]], name: "truth",
                    mode: "lines", line: { color: "#ffcc00", dash: "dash" } });
    }
    Plotly.react(charts[name], traces, {
      title: { text: `${name} [${last.units[i]}]`, font: { size: 12 } },
      margin: { l: 60, r: 10, t: 28, b: 30 }, showlegend: false,
      paper_bgcolor: "#1d2128", plot_bgcolor: "#1d2128", font: { color: "#ccc", size: 10 },
      xaxis: { title: { text: "s" } },
    }, { displayModeBar: false, staticPlot: false });
  });
}

function renderPlayback(s) {
  const box = document.getElementById("playback");
  if (s.mode !== "log") { box.hidden = true; return; }
  box.hidden = false;
  const slider = document.getElementById("slider");
  slider.max = s.span[1];
  if (!slider.matches(":active")) slider.value = s.cursor.t;
  document.getElementById("play").textContent = s.cursor.playing ? "pause" : "play";
  document.getElementById("clock").textContent = `${fmt(s.cursor.t, 4)} / ${fmt(s.span[1], 4)} s`;
}

function escapeHtml(text) {
  return String(text).replace(/[&<>"']/g, (c) => ({ "&": "&amp;", "<": "&lt;", ">": "&gt;", '"': "&quot;", "'": "&#39;" }[c]));
}

document.getElementById("play").addEventListener("click", () => {
  if (!latest || !socket) return;
  socket.send(JSON.stringify({ cmd: latest.cursor.playing ? "pause" : "play" }));
});
document.getElementById("slider").addEventListener("input", (ev) => {
  if (socket) socket.send(JSON.stringify({ cmd: "seek", t: parseFloat(ev.target.value) }));
});

connect();
