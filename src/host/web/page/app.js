// The live page of `teleop --web` (src/host/web): draws what the server
// sends (src/host/web/model.rs says what each message holds) and sends the
// pilot's commands (src/host/web/command.rs). The box is drawn to scale in
// mm: x north (up), y east (right), as simulate's and replay's SVGs.
// Safety: a held motion is repeated every `refresh_ms` while the button or
// key is down; the server stops the robot when the repeats stop.
"use strict";

const SVG = "http://www.w3.org/2000/svg";
const $ = (id) => document.getElementById(id);
const MARGIN = 30; // mm around the box
const RAYS_KEPT = 24; // recent readings drawn (older ones fade out)

const state = {
  ws: null, hello: null, role: "viewer", held: null, timer: null,
  trail: [], rays: [], messages: [], row: null, truth: null,
};

function el(tag, attrs, parent) {
  const e = document.createElementNS(SVG, tag);
  for (const [k, v] of Object.entries(attrs)) e.setAttribute(k, v);
  if (parent) parent.appendChild(e);
  return e;
}

// (x north, y east) mm -> svg coordinates
function px(x, y) {
  return [y, state.hello.arena.x - x];
}

function fmt(v, d = 1) {
  return v === null || v === undefined ? "-" : Number(v).toFixed(d);
}

// A body outline (and nose line) in the robot's frame, for a group placed at a pose.
function drawBody(g, scale = 1) {
  g.replaceChildren();
  const pts = state.hello.body.map(([f, r]) => `${r * scale},${-f * scale}`).join(" ");
  el("polygon", { class: "body", points: pts }, g);
  for (const [f, r] of state.hello.wheels) {
    el("line", { class: "wheel", x1: r * scale, x2: r * scale, y1: -(f - 20) * scale, y2: -(f + 20) * scale }, g);
  }
  el("circle", { r: 3, cx: 0, cy: 0, class: "nose", fill: "none" }, g);
}

function place(g, pose) {
  const [sx, sy] = px(pose.x, pose.y);
  g.setAttribute("transform", `translate(${sx.toFixed(2)} ${sy.toFixed(2)}) rotate(${pose.heading.toFixed(2)})`);
  g.style.display = "";
}

function onHello(h) {
  state.hello = h;
  const X = h.arena.x, Y = h.arena.y;
  const map = $("map");
  map.setAttribute("viewBox", `${-MARGIN} ${-MARGIN} ${Y + 2 * MARGIN} ${X + 2 * MARGIN}`);
  $("box").setAttribute("width", Y);
  $("box").setAttribute("height", X);
  const grid = $("grid");
  grid.replaceChildren();
  for (let x = 100; x < X; x += 100) el("line", { x1: 0, x2: Y, y1: X - x, y2: X - x }, grid);
  for (let y = 100; y < Y; y += 100) el("line", { x1: y, x2: y, y1: 0, y2: X }, grid);
  $("north").textContent = `N ↑  box ${X} × ${Y} mm, grid 100 mm`;
  drawBody($("robot"));
  drawBody($("truth"));
  setRole(h.role);
}

function setRole(role) {
  state.role = role;
  document.body.className = role;
  $("role").textContent = role === "pilot" ? "you drive" : "watching (read-only)";
  $("take").hidden = role === "pilot";
  if (role !== "pilot") release(false); // the robot is no longer ours to stop

}

function onRow(r) {
  state.row = r;
  const e = r.estimate;
  place($("robot"), e);
  // the trail
  const [sx, sy] = px(e.x, e.y);
  state.trail.push(`${sx.toFixed(1)},${sy.toFixed(1)}`);
  if (state.trail.length > state.hello.trail_points) state.trail.shift();
  $("trail").setAttribute("points", state.trail.join(" "));
  // the fresh lidar readings: from the lidar to where the beam ended
  const rays = $("rays");
  for (const ray of r.rays) {
    const color = ray.color;
    const [x1, y1] = px(ray.from[0], ray.from[1]);
    const [x2, y2] = px(ray.to[0], ray.to[1]);
    const g = el("g", {}, rays);
    el("line", { x1, y1, x2, y2, stroke: color }, g);
    el("circle", { cx: x2, cy: y2, r: 3, fill: color }, g);
    state.rays.push(g);
  }
  while (state.rays.length > RAYS_KEPT) state.rays.shift().remove();
  state.rays.forEach((g, i) => g.setAttribute("opacity", (0.15 + 0.85 * (i + 1) / state.rays.length).toFixed(2)));
  // the uncertainty: 2 sigma of the last fix, where the fix was
  const sig = $("sigma");
  sig.replaceChildren();
  if (e.sigma) {
    const [cx, cy] = px(e.sigma.at.x, e.sigma.at.y);
    el("ellipse", { cx, cy, rx: Math.max(2 * e.sigma.y, 1), ry: Math.max(2 * e.sigma.x, 1) }, sig);
  }
  // other hypotheses, when the robot reports them
  const hy = $("hypotheses");
  hy.replaceChildren();
  for (const h of e.hypotheses || []) {
    const g = el("g", { opacity: Math.max(0.2, h.weight ?? 0.5) }, hy);
    drawBody(g, 0.8);
    place(g, h);
    if (h.sigma) {
      const [cx, cy] = px(h.x, h.y);
      el("ellipse", { cx, cy, rx: 2 * h.sigma.y, ry: 2 * h.sigma.x, fill: "none", stroke: "#9467bd" }, hy);
    }
  }
  const states = { unknown: "not located this session", located: "located", ambiguous: "AMBIGUOUS: more than one place fits", lost: "LOST: pose unknown", set: "set by hand" };
  $("pose").textContent =
    `t ${r.t_ms} ms\nx ${fmt(e.x)} mm  y ${fmt(e.y)} mm  heading ${fmt(e.heading, 2)}°\n` +
    `estimate: ${states[e.state] || e.state}` + (e.sigma ? `  (fix σ ${fmt(e.sigma.x, 0)} × ${fmt(e.sigma.y, 0)} mm)` : "") +
    `\nmotion ${r.motion}  v ${fmt(r.v, 3)} m/s  w ${fmt(r.w, 3)} rad/s\nservos L ${fmt(r.servos[0], 2)}  R ${fmt(r.servos[1], 2)}` +
    (state.truth ? `\ntruth x ${fmt(state.truth.x)}  y ${fmt(state.truth.y)}  heading ${fmt(state.truth.heading, 2)}°` : "");
  const lid = (name, l) => (l ? `${name} raw ${l.raw} mm  dist ${fmt(l.mm)} mm` : `${name} -`);
  if (r.front || r.right || r.compass !== null) {
    state.sensors = state.sensors || {};
    if (r.front) state.sensors.front = lid("front", r.front);
    if (r.right) state.sensors.right = lid("right", r.right);
    if (r.compass !== null) state.sensors.compass = `compass ${fmt(r.compass, 1)}°  mag ${r.mag ? r.mag.join(" ") : "-"}`;
  }
  const s = state.sensors || {};
  $("sensors").textContent = [s.front || "front -", s.right || "right -", s.compass || "compass -"].join("\n");
  const f = r.faults;
  $("faults").textContent = `bus ${f.bus}  timeout ${f.timeout}  missing ${f.missing}\nbad sample ${f.bad_sample}  outliers ${f.outliers}  overruns ${f.overruns}`;
}

function onTruth(t) {
  state.truth = t.pose;
  place($("truth"), t.pose);
}

function onState(s) {
  if (s.role !== state.role) setRole(s.role);
  const l = s.link, d = s.drive;
  const link = l.waiting ? "waiting for telemetry" : l.stale ? "STALE: no telemetry" : "ok";
  $("link").textContent =
    `telemetry ${link}  rows ${l.rows}  err ${l.errors}  bad ${l.bad}\n` +
    `holding ${d.holding}  sent ${d.sent}  last \`${d.last_sent ?? "-"}\`\nspeed ${d.speeds}` +
    (s.pilot_present ? "" : "\nnobody drives: take over to drive");
  $("level").textContent = `speed ${d.level}/${d.levels}`;
}

function onMessage(text) {
  state.messages.push(text);
  if (state.messages.length > 50) state.messages.shift();
  const m = $("messages");
  m.textContent = state.messages.join("\n");
  m.scrollTop = m.scrollHeight;
}

function notice(text) {
  $("notice").textContent = text;
  $("notice").hidden = false;
}

function send(obj) {
  if (state.ws && state.ws.readyState === WebSocket.OPEN) state.ws.send(JSON.stringify(obj));
}

// a motion held down: sent now and every refresh period until released
function hold(motion) {
  if (state.role !== "pilot") return;
  if (state.held === motion) return;
  state.held = motion;
  document.querySelectorAll("#pad button").forEach((b) => b.classList.toggle("held", b.dataset.motion === motion));
  send({ cmd: "hold", motion });
  clearInterval(state.timer);
  state.timer = setInterval(() => send({ cmd: "hold", motion }), state.hello ? state.hello.refresh_ms : 125);
}

// lets go of a held motion (and says stop, unless told not to)
function release(sayStop = true) {
  clearInterval(state.timer);
  state.timer = null;
  document.querySelectorAll("#pad button").forEach((b) => b.classList.remove("held"));
  if (state.held && sayStop) send({ cmd: "stop" });
  state.held = null;
}

function connect() {
  const ws = new WebSocket(`${location.protocol === "https:" ? "wss" : "ws"}://${location.host}/ws`);
  state.ws = ws;
  ws.onopen = () => { $("conn").textContent = "connected"; $("conn").className = "ok"; };
  ws.onmessage = (ev) => {
    const m = JSON.parse(ev.data);
    switch (m.type) {
      case "hello": onHello(m); break;
      case "row": if (state.hello) onRow(m); break;
      case "truth": if (state.hello) onTruth(m); break;
      case "state": onState(m); break;
      case "message": onMessage(m.text); break;
      case "notice": notice(m.text); break;
    }
  };
  ws.onclose = (ev) => {
    release();
    $("conn").textContent = `disconnected${ev.reason ? ": " + ev.reason : ""}`;
    $("conn").className = "bad";
    setRole("viewer");
    $("take").hidden = true;
    setTimeout(connect, 2000); // the tool may come back
  };
}

for (const b of document.querySelectorAll("#pad button[data-motion]")) {
  b.addEventListener("pointerdown", (e) => { e.preventDefault(); b.setPointerCapture?.(e.pointerId); hold(b.dataset.motion); });
  for (const ev of ["pointerup", "pointercancel", "lostpointercapture"]) b.addEventListener(ev, () => release());
  b.addEventListener("contextmenu", (e) => e.preventDefault());
}
// (stop and locate: the server lets go of a held motion itself)
$("btn-stop").addEventListener("pointerdown", () => { release(false); send({ cmd: "stop" }); });
$("faster").addEventListener("click", () => send({ cmd: "faster" }));
$("slower").addEventListener("click", () => send({ cmd: "slower" }));
$("locate").addEventListener("click", () => { release(false); send({ cmd: "locate" }); });
$("take").addEventListener("click", () => { send({ cmd: "take" }); $("notice").hidden = true; });

const KEYS = { ArrowUp: "fwd", w: "fwd", ArrowDown: "back", s: "back", ArrowLeft: "ccw", a: "ccw", ArrowRight: "cw", d: "cw" };
document.addEventListener("keydown", (e) => {
  const k = e.key.length === 1 ? e.key.toLowerCase() : e.key;
  if (KEYS[k]) { e.preventDefault(); if (!e.repeat) hold(KEYS[k]); }
  else if (k === " " || k === "x") { e.preventDefault(); release(false); send({ cmd: "stop" }); }
  else if (k === "+" || k === "=" || k === "e") send({ cmd: "faster" });
  else if (k === "-" || k === "_" || k === "z") send({ cmd: "slower" });
  else if (k === "r") { release(false); send({ cmd: "locate" }); }
});
document.addEventListener("keyup", (e) => {
  const k = e.key.length === 1 ? e.key.toLowerCase() : e.key;
  if (KEYS[k] === state.held) release();
});
// a hidden tab or a lost focus lets go of everything
document.addEventListener("visibilitychange", () => { if (document.hidden) release(); });
window.addEventListener("blur", () => release());
window.addEventListener("pagehide", () => release());

// a bug in this page shows itself instead of freezing the map silently
window.addEventListener("error", (e) => notice(`page error: ${e.message} (${e.lineno})`));

connect();
