// vigil-sim live view. Plain JavaScript, no dependencies: receives `init`,
// `frame` and `control` events over Server-Sent Events from /events and
// draws the latest frame on a canvas, at most once per animation frame.
"use strict";

const $ = (id) => document.getElementById(id);
const canvas = $("zone");
const ctx = canvas.getContext("2d");
const MARGIN = 28;
const STATUS_COLOUR = ["#14a02c", "#f08c00", "#8a5cc2", "#555"];
// Obstacles: buildings opaque and dark, screens translucent green and
// hatched (as in vigil-sim --svg).
const BUILDING_FILL = "rgb(90,90,100)";
const BUILDING_EDGE = "rgb(40,40,48)";
const SCREEN_FILL = "rgba(50,160,60,0.5)";
const SCREEN_HATCH = "rgba(20,100,30,0.8)";

let init = null;
let frame = null;
let dirty = false;
let scale = 1;
let heat = null; // offscreen canvas of the d_hat map
let speedNow = 10;

// Zone coordinates → canvas pixels (y up).
const px = (x) => MARGIN + x * scale;
const py = (y) => MARGIN + (init.height - y) * scale;
const cellX = (col) => px((col + 0.5) * init.cell_size);
const cellY = (row) => py((row + 0.5) * init.cell_size);

function priorityColour(p, alpha) {
  const n = init.sensors;
  const hue = p == null ? 200 : (n <= 1 ? 0 : (230 * (p - 1)) / (n - 1));
  const sat = p == null ? 10 : 80;
  return `hsla(${hue.toFixed(0)},${sat}%,42%,${alpha})`;
}

function setup(data) {
  init = data;
  scale = Math.min(700 / init.width, 520 / init.height);
  canvas.width = Math.ceil(init.width * scale + 2 * MARGIN);
  canvas.height = Math.ceil(init.height * scale + 2 * MARGIN);
  $("title").textContent = `· ${init.scenario} · ${init.policy} · ${init.sensors} sensors · seed ${init.seed}`;
  $("run-info").textContent =
    `${init.steps} measured steps after a ${init.warmup}-step warm-up · T = ${init.horizon} · ` +
    `zone ${init.width}×${init.height}, cells of ${init.cell_size}` +
    (init.min_separation > 0 ? ` · sensors ≥ ${init.min_separation} cells apart` : "");
  $("prio-max").textContent = String(init.sensors);
  $("legend-obstacles").hidden = !hasObstacles();
  const sel = $("explain-sensor");
  sel.innerHTML = "";
  for (let i = 0; i < init.sensors; i++) sel.add(new Option(String(i), String(i)));
  const st = $("explain-step");
  st.innerHTML = "";
  for (let t = 1; t <= init.horizon; t++) st.add(new Option(String(t), String(t)));
  // The heat map, once.
  heat = document.createElement("canvas");
  heat.width = canvas.width;
  heat.height = canvas.height;
  const h = heat.getContext("2d");
  h.fillStyle = "#fff";
  h.fillRect(0, 0, heat.width, heat.height);
  const top = Math.max(1e-12, ...init.d_hat);
  const cs = init.cell_size * scale;
  for (let row = 0; row < init.rows; row++) {
    for (let col = 0; col < init.cols; col++) {
      const v = init.d_hat[row * init.cols + col] / top;
      h.fillStyle = `rgb(255,${Math.round(255 - 70 * v)},${Math.round(255 - 170 * v)})`;
      h.fillRect(px(col * init.cell_size), py((row + 1) * init.cell_size), Math.ceil(cs), Math.ceil(cs));
    }
  }
  dirty = true;
}

const hasObstacles = () => Boolean(init && init.obstacles && init.obstacles.length);

// A path through zone points given flat, [x0, y0, x1, y1, …], closed.
function flatPath(xy) {
  ctx.beginPath();
  ctx.moveTo(px(xy[0]), py(xy[1]));
  for (let k = 2; k < xy.length; k += 2) ctx.lineTo(px(xy[k]), py(xy[k + 1]));
  ctx.closePath();
}

// Buildings filled dark; screens translucent green, hatched.
function drawObstacles() {
  let buildings = 0, screens = 0;
  for (const o of init.obstacles || []) {
    flatPath(o.polygon.flat());
    if (o.kind === "screen") {
      ctx.save();
      ctx.fillStyle = SCREEN_FILL;
      ctx.fill();
      ctx.clip();
      const xs = o.polygon.map(([x]) => px(x)), ys = o.polygon.map(([, y]) => py(y));
      const x0 = Math.min(...xs), x1 = Math.max(...xs), y0 = Math.min(...ys), y1 = Math.max(...ys);
      ctx.strokeStyle = SCREEN_HATCH;
      ctx.lineWidth = 1;
      ctx.beginPath();
      for (let d = x0 - (y1 - y0); d < x1; d += 5) { ctx.moveTo(d, y1); ctx.lineTo(d + (y1 - y0), y0); }
      ctx.stroke();
      ctx.restore();
      flatPath(o.polygon.flat());
      ctx.strokeStyle = SCREEN_HATCH;
      ctx.lineWidth = 1;
      ctx.stroke();
      screens++;
    } else {
      ctx.fillStyle = BUILDING_FILL;
      ctx.fill();
      ctx.strokeStyle = BUILDING_EDGE;
      ctx.lineWidth = 1.5;
      ctx.stroke();
      buildings++;
    }
  }
  canvas.dataset.buildingsDrawn = String(buildings);
  canvas.dataset.screensDrawn = String(screens);
}

function drawStatic() {
  ctx.drawImage(heat, 0, 0);
  // No-go zones (none in the model yet), hatched.
  for (const r of init.no_go) {
    const x = px(r.x0), y = py(r.y1), w = (r.x1 - r.x0) * scale, hh = (r.y1 - r.y0) * scale;
    ctx.save();
    ctx.beginPath();
    ctx.rect(x, y, w, hh);
    ctx.clip();
    ctx.fillStyle = "rgba(80,80,80,0.25)";
    ctx.fillRect(x, y, w, hh);
    ctx.strokeStyle = "rgba(60,60,60,0.7)";
    ctx.beginPath();
    for (let d = -hh; d < w; d += 8) { ctx.moveTo(x + d, y + hh); ctx.lineTo(x + d + hh, y); }
    ctx.stroke();
    ctx.restore();
  }
  ctx.strokeStyle = "#222";
  ctx.lineWidth = 2;
  ctx.strokeRect(px(0), py(init.height), init.width * scale, init.height * scale);
  // Sources and their cones.
  const reach = Math.hypot(init.width, init.height) * scale * 1.5;
  for (const s of init.sources) {
    const x = px(s.x), y = py(s.y);
    if (s.cone) {
      ctx.save();
      ctx.beginPath();
      ctx.rect(px(0), py(init.height), init.width * scale, init.height * scale);
      ctx.clip();
      ctx.beginPath();
      ctx.moveTo(x, y);
      // Canvas angles run clockwise (y down): negate.
      ctx.arc(x, y, reach, -s.cone[1], -s.cone[0]);
      ctx.closePath();
      ctx.fillStyle = "rgba(30,60,160,0.07)";
      ctx.fill();
      ctx.strokeStyle = "rgba(30,60,160,0.45)";
      ctx.lineWidth = 1;
      ctx.setLineDash([4, 4]);
      ctx.stroke();
      ctx.setLineDash([]);
      ctx.restore();
    }
    if (!hasObstacles()) sourceMark(x, y);
  }
  // Obstacles over the cones, under the sources' marks.
  drawObstacles();
  if (hasObstacles()) for (const s of init.sources) sourceMark(px(s.x), py(s.y));
}

function sourceMark(x, y) {
  ctx.strokeStyle = "#000";
  ctx.lineWidth = 2;
  ctx.beginPath();
  ctx.moveTo(x - 6, y - 6); ctx.lineTo(x + 6, y + 6);
  ctx.moveTo(x + 6, y - 6); ctx.lineTo(x - 6, y + 6);
  ctx.stroke();
}

function fovPath(col, row, fov) {
  fov = fov || init.fov;
  const cx = (col + 0.5) * init.cell_size, cy = (row + 0.5) * init.cell_size;
  ctx.beginPath();
  if (fov.shape === "circle") {
    ctx.arc(px(cx), py(cy), fov.radius * scale, 0, 2 * Math.PI);
  } else {
    const hw = fov.half_width;
    const x0 = Math.max(0, cx - hw), x1 = Math.min(init.width, cx + hw);
    const y0 = Math.max(0, cy - hw), y1 = Math.min(init.height, cy + hw);
    ctx.rect(px(x0), py(y1), (x1 - x0) * scale, (y1 - y0) * scale);
  }
}

function drawExplain(f) {
  const i = Number($("explain-sensor").value);
  const t = Number($("explain-step").value);
  const e = f.explain && f.explain[i];
  if (!$("explain").checked || !e) {
    $("explain-legend").hidden = true;
    return 0;
  }
  const layer = e.values[t - 1];
  if (!layer) return 0;
  const T = (layer.length - 1) / 2;
  let top = 0;
  for (const r of layer) for (const v of r) if (v != null) top = Math.max(top, v);
  top = Math.max(top, 1e-12);
  const cs = init.cell_size * scale;
  for (let dr = -T; dr <= T; dr++) {
    for (let dc = -T; dc <= T; dc++) {
      const v = layer[dr + T][dc + T];
      if (v == null) continue;
      const col = e.col + dc, row = e.row + dr;
      ctx.fillStyle = `rgba(${Math.round(40 + 80 * v / top)},0,${Math.round(90 + 110 * v / top)},${(0.15 + 0.65 * v / top).toFixed(3)})`;
      ctx.fillRect(px(col * init.cell_size), py((row + 1) * init.cell_size), cs, cs);
    }
  }
  ctx.strokeStyle = "#000";
  ctx.lineWidth = 1;
  ctx.strokeRect(px((e.col - T) * init.cell_size), py((e.row + T + 1) * init.cell_size),
    (2 * T + 1) * cs, (2 * T + 1) * cs);
  $("explain-legend").hidden = false;
  $("explain-max").textContent = top.toFixed(3);
  return 1;
}

function draw() {
  if (!init) return;
  drawStatic();
  const f = frame;
  if (!f) return;
  // Zone clip for everything that moves.
  ctx.save();
  ctx.beginPath();
  ctx.rect(px(0), py(init.height), init.width * scale, init.height * scale);
  ctx.clip();
  const explained = drawExplain(f);
  // Traces.
  f.traces.forEach((tr, i) => {
    if (tr.length < 4) return;
    ctx.strokeStyle = priorityColour(f.sensors[i].priority, 0.35);
    ctx.lineWidth = 1.5;
    ctx.beginPath();
    ctx.moveTo(cellX(tr[0]), cellY(tr[1]));
    for (let k = 2; k < tr.length; k += 2) ctx.lineTo(cellX(tr[k]), cellY(tr[k + 1]));
    ctx.stroke();
  });
  // Fields of view. With obstacles, the part each sensor sees is shaded:
  // a ground sensor's `view` outline (its field of view less what the
  // obstacles hide, its whole field of view drawn dashed), an elevated
  // one's whole field of view.
  let views = 0;
  f.sensors.forEach((s) => {
    if (!hasObstacles()) {
      fovPath(s.col, s.row, s.fov);
      ctx.fillStyle = priorityColour(s.priority, 0.08);
      ctx.fill();
      ctx.strokeStyle = priorityColour(s.priority, 0.75);
      ctx.lineWidth = 1;
      ctx.stroke();
      return;
    }
    if (s.view && s.view.length >= 6) {
      flatPath(s.view);
      ctx.fillStyle = priorityColour(s.priority, 0.3);
      ctx.fill();
      ctx.strokeStyle = priorityColour(s.priority, 0.8);
      ctx.lineWidth = 1;
      ctx.stroke();
      fovPath(s.col, s.row, s.fov);
      ctx.strokeStyle = priorityColour(s.priority, 0.45);
      ctx.setLineDash([3, 3]);
      ctx.stroke();
      ctx.setLineDash([]);
      views++;
    } else {
      fovPath(s.col, s.row, s.fov);
      ctx.fillStyle = priorityColour(s.priority, 0.1);
      ctx.fill();
      ctx.strokeStyle = priorityColour(s.priority, 0.75);
      ctx.lineWidth = 1;
      ctx.stroke();
    }
  });
  canvas.dataset.viewsDrawn = String(views);
  // Plans.
  f.sensors.forEach((s) => {
    const p = s.path;
    if (p.length < 4) return;
    ctx.strokeStyle = priorityColour(s.priority, 0.95);
    ctx.lineWidth = 2.5;
    ctx.setLineDash([5, 3]);
    ctx.beginPath();
    ctx.moveTo(cellX(p[0]), cellY(p[1]));
    for (let k = 2; k < p.length; k += 2) ctx.lineTo(cellX(p[k]), cellY(p[k + 1]));
    ctx.stroke();
    ctx.setLineDash([]);
    for (let k = 2; k < p.length; k += 2) {
      ctx.fillStyle = priorityColour(s.priority, 0.95);
      ctx.beginPath();
      ctx.arc(cellX(p[k]), cellY(p[k + 1]), 2.5, 0, 2 * Math.PI);
      ctx.fill();
    }
  });
  // Targets.
  for (const [x, y, st] of f.targets) {
    ctx.beginPath();
    ctx.arc(px(x), py(y), st <= 1 ? 3.5 : 3, 0, 2 * Math.PI);
    if (st <= 1) {
      ctx.fillStyle = STATUS_COLOUR[st];
      ctx.fill();
    } else {
      ctx.strokeStyle = STATUS_COLOUR[st];
      ctx.lineWidth = st === 2 ? 2 : 1.5;
      ctx.stroke();
    }
  }
  ctx.restore();
  // Sensors, on top.
  let drawn = 0;
  f.sensors.forEach((s, i) => {
    const x = cellX(s.col), y = cellY(s.row);
    ctx.fillStyle = priorityColour(s.priority, 1);
    ctx.strokeStyle = "#fff";
    ctx.lineWidth = 1.5;
    ctx.beginPath();
    ctx.arc(x, y, 8, 0, 2 * Math.PI);
    ctx.fill();
    ctx.stroke();
    ctx.fillStyle = "#fff";
    ctx.font = "bold 10px system-ui, sans-serif";
    ctx.textAlign = "center";
    ctx.textBaseline = "middle";
    ctx.fillText(String(i), x, y + 0.5);
    drawn++;
  });
  canvas.dataset.sensorsDrawn = String(drawn);
  canvas.dataset.explainDrawn = String(explained);
}

function chart(id, values, fixedTop) {
  const c = $(id);
  const g = c.getContext("2d");
  g.clearRect(0, 0, c.width, c.height);
  g.strokeStyle = "#ddd";
  g.strokeRect(0.5, 0.5, c.width - 1, c.height - 1);
  const pts = values.map((v, k) => [k, v]).filter(([, v]) => v != null);
  c.dataset.points = String(pts.length);
  if (pts.length < 2) return;
  const n = Math.max(values.length - 1, 1);
  const top = fixedTop ?? Math.max(1e-9, ...pts.map(([, v]) => v));
  g.strokeStyle = "#1f5fbf";
  g.lineWidth = 1.2;
  g.beginPath();
  pts.forEach(([k, v], j) => {
    const x = 2 + (k / n) * (c.width - 4);
    const y = c.height - 2 - (Math.min(v, top) / top) * (c.height - 4);
    if (j === 0) g.moveTo(x, y); else g.lineTo(x, y);
  });
  g.stroke();
}

const fmt = (v, d) => (v == null ? "–" : Number(v).toFixed(d));
// A fraction as a percentage; "n/a" when the run's plans carry no
// certificate (the paper estimator, local policies).
const gapText = (v) => (!init || !init.certified ? "n/a" : v == null ? "–" : `${(100 * v).toFixed(3)}%`);

function panel(f) {
  const st = $("step");
  st.dataset.step = String(f.step);
  st.textContent = `${f.step} / ${f.steps}`;
  showStatus();
  const m = f.metrics;
  $("metrics").dataset.step = String(f.step);
  $("m-ad").textContent = f.step ? String(m.ad) : "–";
  $("m-ad-mean").textContent = f.step ? fmt(m.ad_mean, 1) : "–";
  $("m-af").textContent = fmt(m.af, 2);
  $("m-af-mean").textContent = f.step ? fmt(m.af_mean, 3) : "–";
  $("m-once").textContent = f.step ? fmt(m.once, 3) : "–";
  // Null until a counted target has been detected (delay) or has left the
  // zone (missed): shown as "–", not as a zero.
  $("m-delay").textContent = fmt(m.delay, 2);
  $("m-missed").textContent = fmt(m.missed, 3);
  $("m-calib").textContent = fmt(m.calibration, 3);
  $("m-plan").textContent = fmt(m.plan_ms, 1);
  $("m-plan-mean").textContent = fmt(m.plan_ms_mean, 1);
  $("m-inzone").textContent = f.step ? String(m.in_zone) : "–";
  $("m-cells").textContent = f.step ? String(m.cells) : "–";
  $("m-cells-mean").textContent = f.step ? fmt(m.cells_mean, 2) : "–";
  $("m-viol").textContent = m.violations == null ? "–" : String(m.violations);
  $("m-viol-mean").textContent = m.violating_plans == null ? "–" : `${fmt(100 * m.violating_plans, 1)}%`;
  $("m-gap").textContent = gapText(m.gap);
  $("m-gap").dataset.gap = m.gap == null ? "" : String(m.gap);
  $("m-gap-mean").textContent = gapText(m.gap_mean);
  $("row-joint").hidden = m.joint_rounds == null;
  $("m-joint").textContent = m.joint_rounds == null ? "–" : String(m.joint_rounds);
  chart("c-ad", f.series.ad);
  chart("c-af", f.series.af, 1);
  chart("c-once", f.series.once, 1);
  chart("c-delay", f.series.delay);
  chart("c-missed", f.series.missed, 1);
  chart("c-calib", f.series.calibration);
  chart("c-plan", f.series.plan_ms);
  chart("c-gap", f.series.gap);
  const body = $("sensor-table").tBodies[0];
  while (body.rows.length > f.sensors.length) body.deleteRow(-1);
  while (body.rows.length < f.sensors.length) {
    const r = body.insertRow();
    r.className = "sensor";
    for (let k = 0; k < 4; k++) r.insertCell();
  }
  f.sensors.forEach((s, i) => {
    const r = body.rows[i];
    r.cells[0].innerHTML = `<span class="sw" style="background:${priorityColour(s.priority, 1)}"></span>${i}`;
    r.cells[1].textContent = s.priority == null ? "–" : String(s.priority);
    r.cells[2].textContent = `(${s.col}, ${s.row})`;
    r.cells[3].textContent = fmt(s.expected, 2);
  });
}

function showStatus() {
  const paused = $("pause").dataset.paused === "true";
  $("status").textContent = frame && frame.finished ? "finished" : (paused ? "paused" : "running");
}

function showControl(paused, speed) {
  $("pause").textContent = paused ? "Resume" : "Pause";
  $("pause").dataset.paused = String(paused);
  speedNow = speed;
  $("speed-value").textContent = `${speed < 10 ? speed.toFixed(1) : speed.toFixed(0)} steps/s`;
  if (document.activeElement !== $("speed")) {
    $("speed").value = String(Math.round((100 * Math.log(speed / 0.2)) / Math.log(1000)));
  }
}

function send(body) {
  return fetch("control", {
    method: "POST",
    headers: { "content-type": "application/json" },
    body: JSON.stringify(body),
  });
}

$("pause").addEventListener("click", () =>
  send({ action: $("pause").dataset.paused === "true" ? "resume" : "pause" }));
$("step-once").addEventListener("click", () => send({ action: "step" }));
$("speed").addEventListener("input", () => {
  const speed = 0.2 * Math.pow(1000, Number($("speed").value) / 100);
  send({ action: "speed", speed });
});
for (const id of ["explain", "explain-sensor", "explain-step"]) {
  $(id).addEventListener("change", () => { dirty = true; });
}

function loop() {
  if (dirty) {
    dirty = false;
    if (frame) panel(frame);
    draw();
  }
  requestAnimationFrame(loop);
}

const events = new EventSource("events");
events.addEventListener("init", (e) => { setup(JSON.parse(e.data)); });
events.addEventListener("frame", (e) => {
  const f = JSON.parse(e.data);
  if (!f) return;
  frame = f;
  dirty = true;
});
events.addEventListener("control", (e) => {
  const c = JSON.parse(e.data);
  showControl(c.paused, c.speed);
  showStatus();
});
events.onopen = () => { $("conn").textContent = "connected"; $("conn").className = ""; };
events.onerror = () => { $("conn").textContent = "disconnected, retrying"; $("conn").className = "bad"; };
requestAnimationFrame(loop);
