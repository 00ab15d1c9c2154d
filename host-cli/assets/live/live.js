// propid's live page: the last seconds of the drive's feedback, the running estimate with its
// ±2σ band, readiness and bus counters, from the server's event stream (Server-Sent Events); and
// a STOP button that does what Ctrl-C does. The page never sends a setpoint.
//
// The run's token is in the page's own address (/?token=…): every request carries it, STOP in a
// header a cross-site form cannot set. For the browser test, document.body.dataset.samples counts
// the samples received and dataset.finished says whether the drive has stopped.
"use strict";
const TOKEN = new URLSearchParams(window.location.search).get("token") || "";
const WINDOW_S = 10;
const pts = {t: [], sp: [], f: [], v: [], a: []};
const est = {t: [], j: [], jlo: [], jhi: [], c2: [], clo: [], chi: []};
function mk(id, series) {
  const el = document.getElementById(id);
  const width = Math.max(400, Math.min(1200, document.body.clientWidth - 40));
  return new uPlot({width, height: 200, series: [{label: "t [s]"}].concat(series),
    scales: {x: {time: false}},
    axes: [{}, {size: 80, values: (u, vals) => vals.map(v => (v !== 0 && Math.abs(v) < 1e-2) ? v.toExponential(2) : v)}]}, [[]].concat(series.map(() => [])), el);
}
const band = (label, colour) => [{label, stroke: colour, width: 1.5},
  {label: "−2σ", stroke: colour, dash: [4, 4], width: 1}, {label: "+2σ", stroke: colour, dash: [4, 4], width: 1}];
const charts = {
  force: mk("c-force", [{label: "setpoint ×0.1", stroke: "#888", width: 1}, {label: "torque [N·m]", stroke: "#1f77b4", width: 1.5}]),
  vel: mk("c-vel", [{label: "velocity", stroke: "#2ca02c", width: 1.5}]),
  acc: mk("c-acc", [{label: "acceleration", stroke: "#d62728", width: 1}]),
  j: mk("c-j", band("J", "#9467bd")),
  c2: mk("c-c2", band("c2", "#ff7f0e")),
};
const fmt = (x) => (x === null || x === undefined || !isFinite(x)) ? "–" : x.toExponential(4);
function redraw() {
  const n = pts.t.length;
  if (n > 0) {
    const t0 = pts.t[n - 1] - WINDOW_S;
    let i = 0; while (i < n && pts.t[i] < t0) i++;
    for (const k in pts) pts[k].splice(0, i);
  }
  charts.force.setData([pts.t, pts.sp.map(x => x * 0.1), pts.f]);
  charts.vel.setData([pts.t, pts.v]);
  charts.acc.setData([pts.t, pts.a]);
  charts.j.setData([est.t, est.j, est.jlo, est.jhi]);
  charts.c2.setData([est.t, est.c2, est.clo, est.chi]);
}
let last = 0;
const source = new EventSource("/events?token=" + encodeURIComponent(TOKEN));
// Once STOP is acknowledged, an update still in flight from before it (status "running") must
// not take the acknowledgement off the page; the drive's final status replaces it.
let stopping = false;
source.onmessage = (ev) => {
  const u = JSON.parse(ev.data);
  for (const p of u.points) {
    pts.t.push(p.t); pts.sp.push(p.setpoint); pts.f.push(p.force); pts.v.push(p.velocity); pts.a.push(p.acceleration);
  }
  for (const e of u.estimates) {
    est.t.push(e.t); est.j.push(e.j); est.jlo.push(e.j - 2 * e.j_stderr); est.jhi.push(e.j + 2 * e.j_stderr);
    est.c2.push(e.c2); est.clo.push(e.c2 - 2 * e.c2_stderr); est.chi.push(e.c2 + 2 * e.c2_stderr);
  }
  last = u.seq;
  if (!stopping || u.finished) document.getElementById("status").textContent = u.status || "running";
  document.getElementById("readiness").textContent = u.readiness || "–";
  const e = est.j.length ? est.j.length - 1 : -1;
  document.getElementById("j").textContent = e >= 0 ? fmt(est.j[e]) + " ± " + fmt((est.jhi[e] - est.j[e]) / 2) : "–";
  document.getElementById("c2").textContent = e >= 0 ? fmt(est.c2[e]) + " ± " + fmt((est.chi[e] - est.c2[e]) / 2) : "–";
  const num = (x) => (x === null || x === undefined || !isFinite(x)) ? "–" : x.toFixed(0);
  document.getElementById("rx").textContent = num(u.bus.frames_rx_per_s);
  document.getElementById("tx").textContent = num(u.bus.frames_tx_per_s);
  document.getElementById("drop").textContent = u.bus.tx_dropped;
  document.getElementById("rej").textContent = u.bus.rx_rejected;
  document.getElementById("aerr").textContent = u.bus.adapter_errors;
  document.body.dataset.samples = String(last);
  document.body.dataset.finished = String(u.finished);
  redraw();
};
document.getElementById("stop").onclick = async () => {
  const r = await fetch("/stop", {method: "POST", headers: {"X-Propid-Token": TOKEN}});
  stopping = r.ok;
  document.getElementById("status").textContent = await r.text();
};
