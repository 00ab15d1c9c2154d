//! The live page: what the drive is doing, in a browser, while it runs — and a STOP button.
//!
//! ```text
//!  control loop ──► LiveFeed (owned by the loop; batches samples, never waits)
//!                     │ try_lock only: if the page's side holds the lock, the batch waits for
//!                     ▼ the next call — the control loop is never blocked by a viewer
//!                   LiveState (a ring of the last seconds, estimate, readiness, bus counters)
//!                     ▲
//!  HTTP thread (tiny_http) ── GET /?token=…        the page (uPlot embedded, works offline)
//!                          ── GET /events?token=…  Server-Sent Events: new samples + state, 10 /s
//!                          ── POST /stop  + header X-Propid-Token: … ──► the same stop flag as Ctrl-C
//! ```
//! Safety: the server binds to loopback unless told otherwise; every request needs the per-run
//! token printed on the terminal (a page of another site can neither read the data nor press
//! STOP: it does not know the token, and a cross-site form cannot set the header); the page can
//! only stop the drive — it never sends a setpoint.

use std::net::SocketAddr;
use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::{Arc, Mutex};
use std::time::Duration;

use anyhow::Context;
use serde::Serialize;

/// How many samples the page's ring keeps (about 20 s at 500 Hz).
const RING: usize = 10_000;
/// How often the page is sent what is new.
const PUSH_PERIOD: Duration = Duration::from_millis(100);

/// One point of the live plots.
#[derive(Clone, Copy, Debug, PartialEq, Serialize)]
pub struct LivePoint {
    /// Device time [s].
    pub t: f64,
    /// Ratiometric setpoint commanded.
    pub setpoint: f64,
    /// Reported torque [N·m].
    pub force: f64,
    /// Velocity [rad/s].
    pub velocity: f64,
    /// Acceleration [rad/s²].
    pub acceleration: f64,
}

/// The running estimate with its standard errors.
#[derive(Clone, Copy, Debug, PartialEq, Serialize)]
pub struct LiveEstimate {
    /// Device time of the estimate [s].
    pub t: f64,
    /// Inertia [kg·m²].
    pub j: f64,
    /// Its standard error.
    pub j_stderr: f64,
    /// Quadratic drag [N·m·s²/rad²].
    pub c2: f64,
    /// Its standard error.
    pub c2_stderr: f64,
}

/// Bus health as the drive loop counts it.
#[derive(Clone, Copy, Debug, Default, PartialEq, Serialize)]
pub struct LiveBus {
    /// Frames received per second.
    pub frames_rx_per_s: f64,
    /// Frames sent per second.
    pub frames_tx_per_s: f64,
    /// Frames dropped (deadline passed, superseded, queue full) so far.
    pub tx_dropped: u64,
    /// Transfers the reassembler rejected so far.
    pub rx_rejected: u64,
    /// Errors the adapter reported so far.
    pub adapter_errors: u64,
}

#[derive(Default)]
struct Inner {
    /// Sequence number of the newest point (points are numbered from 1).
    seq: u64,
    points: std::collections::VecDeque<LivePoint>,
    estimates: Vec<LiveEstimate>,
    readiness: &'static str,
    bus: LiveBus,
    status: String,
    finished: bool,
}

/// What the page shows, shared between the control loop's [`LiveFeed`] and the server.
#[derive(Default)]
pub struct LiveState {
    inner: Mutex<Inner>,
}

/// The control loop's handle: collects updates and hands them over without ever waiting.
pub struct LiveFeed {
    state: Arc<LiveState>,
    pending: Vec<LivePoint>,
    estimate: Option<LiveEstimate>,
    readiness: Option<&'static str>,
    bus: Option<LiveBus>,
    status: Option<(String, bool)>,
}

impl LiveFeed {
    /// A feed into `state`.
    pub fn new(state: Arc<LiveState>) -> Self {
        LiveFeed {
            state,
            pending: Vec::new(),
            estimate: None,
            readiness: None,
            bus: None,
            status: None,
        }
    }

    /// A new feedback sample.
    pub fn sample(&mut self, point: LivePoint) {
        if self.pending.len() < RING {
            self.pending.push(point);
        }
        self.publish();
    }

    /// The running estimate changed.
    pub fn estimate(&mut self, estimate: LiveEstimate) {
        self.estimate = Some(estimate);
        self.publish();
    }

    /// The readiness commanded.
    pub fn readiness(&mut self, readiness: &'static str) {
        self.readiness = Some(readiness);
        self.publish();
    }

    /// Bus counters.
    pub fn bus(&mut self, bus: LiveBus) {
        self.bus = Some(bus);
        self.publish();
    }

    /// A status line (phase, stop reason); `finished` once the drive stopped.
    pub fn status(&mut self, status: impl Into<String>, finished: bool) {
        self.status = Some((status.into(), finished));
        self.publish();
    }

    /// Hands what is pending to the page's side if it is not busy; returns at once either way.
    pub fn publish(&mut self) {
        let Ok(mut inner) = self.state.inner.try_lock() else {
            return;
        };
        for p in self.pending.drain(..) {
            inner.seq += 1;
            if inner.points.len() == RING {
                inner.points.pop_front();
            }
            inner.points.push_back(p);
        }
        if let Some(e) = self.estimate.take() {
            if inner.estimates.len() < 100_000 {
                inner.estimates.push(e);
            }
        }
        if let Some(r) = self.readiness.take() {
            inner.readiness = r;
        }
        if let Some(b) = self.bus.take() {
            inner.bus = b;
        }
        if let Some((s, finished)) = self.status.take() {
            inner.status = s;
            inner.finished |= finished;
        }
    }

    /// Publishes what is pending, waiting for the lock (for the end of a run, not the loop).
    pub fn flush(&mut self) {
        for _ in 0..100 {
            self.publish();
            if self.pending.is_empty() && self.status.is_none() {
                return;
            }
            std::thread::sleep(Duration::from_millis(1));
        }
    }
}

/// One Server-Sent Events message: points after `after`, the estimates after index
/// `estimates_after`, and the current state.
#[derive(Serialize)]
struct Update<'a> {
    seq: u64,
    points: Vec<LivePoint>,
    estimates: &'a [LiveEstimate],
    readiness: &'a str,
    bus: LiveBus,
    status: &'a str,
    finished: bool,
}

impl LiveState {
    /// The JSON of what is new since point `after` and estimate index `estimates_after`; returns
    /// the new cursors.
    fn update_since(&self, after: u64, estimates_after: usize) -> (String, u64, usize) {
        let inner = match self.inner.lock() {
            Ok(g) => g,
            Err(poisoned) => poisoned.into_inner(),
        };
        let oldest = inner.seq - inner.points.len() as u64;
        let skip = after.saturating_sub(oldest) as usize;
        let points: Vec<LivePoint> = inner.points.iter().skip(skip).copied().collect();
        let from = estimates_after.min(inner.estimates.len());
        let update = Update {
            seq: inner.seq,
            points,
            estimates: &inner.estimates[from..],
            readiness: inner.readiness,
            bus: inner.bus,
            status: &inner.status,
            finished: inner.finished,
        };
        let json = serde_json::to_string(&update).unwrap_or_else(|_| "{}".into());
        (json, inner.seq, inner.estimates.len())
    }
}

/// Writes a Server-Sent Events response on the raw connection: a header, then what is new every
/// [`PUSH_PERIOD`], each message flushed; ends when the viewer goes or the server shuts down.
fn stream_events(
    w: &mut dyn std::io::Write,
    state: &LiveState,
    shutdown: &AtomicBool,
) -> std::io::Result<()> {
    w.write_all(
        b"HTTP/1.1 200 OK\r\nContent-Type: text/event-stream\r\nCache-Control: no-cache\r\nConnection: close\r\n\r\n",
    )?;
    let (mut after, mut estimates_after) = (0, 0);
    while !shutdown.load(Ordering::Relaxed) {
        let (json, seq, est) = state.update_since(after, estimates_after);
        after = seq;
        estimates_after = est;
        w.write_all(format!("data: {json}\n\n").as_bytes())?;
        w.flush()?;
        std::thread::sleep(PUSH_PERIOD);
    }
    Ok(())
}

/// The running server. Dropping it stops it.
pub struct LiveServer {
    /// The address it listens on.
    pub addr: SocketAddr,
    /// The per-run token every request must carry.
    pub token: String,
    shutdown: Arc<AtomicBool>,
    server: Arc<tiny_http::Server>,
    thread: Option<std::thread::JoinHandle<()>>,
}

impl LiveServer {
    /// The page's address, token included (what the user opens).
    pub fn url(&self) -> String {
        format!("http://{}/?token={}", self.addr, self.token)
    }
}

impl Drop for LiveServer {
    fn drop(&mut self) {
        self.shutdown.store(true, Ordering::Relaxed);
        self.server.unblock();
        if let Some(t) = self.thread.take() {
            let _ = t.join();
        }
    }
}

/// A fresh random token (128 bits, hex).
pub fn new_token() -> String {
    let bytes: [u8; 16] = rand::random();
    bytes.iter().map(|b| format!("{b:02x}")).collect()
}

/// Checks the address the user gave: loopback always; anything else only with `allow_remote`.
pub fn check_addr(addr: &str, allow_remote: bool) -> Result<SocketAddr, crate::InputError> {
    let parsed: SocketAddr = addr.parse().map_err(|_| {
        crate::InputError::invalid(format!(
            "--live `{addr}` is not an address like 127.0.0.1:8080"
        ))
    })?;
    if !parsed.ip().is_loopback() && !allow_remote {
        return Err(crate::InputError::invalid(format!(
            "--live {addr} is not a loopback address: anyone who can reach it and has the token could stop the drive; add --live-allow-remote to serve it anyway"
        )));
    }
    Ok(parsed)
}

/// Starts serving the page for `state`; STOP raises `stop`.
pub fn serve(
    addr: SocketAddr,
    state: Arc<LiveState>,
    stop: Arc<AtomicBool>,
    title: String,
) -> anyhow::Result<LiveServer> {
    let server = Arc::new(
        tiny_http::Server::http(addr)
            .map_err(|e| anyhow::anyhow!("cannot serve the live page on {addr}: {e}"))?,
    );
    let addr = server
        .server_addr()
        .to_ip()
        .context("the live page's listening address")?;
    let token = new_token();
    let shutdown = Arc::new(AtomicBool::new(false));
    let thread = {
        let (server, token, shutdown) = (Arc::clone(&server), token.clone(), Arc::clone(&shutdown));
        std::thread::Builder::new()
            .name("live-page".into())
            .spawn(move || accept_loop(&server, &token, &state, &stop, &shutdown, &title))
            .context("starting the live page's thread")?
    };
    Ok(LiveServer {
        addr,
        token,
        shutdown,
        server,
        thread: Some(thread),
    })
}

fn query_token(url: &str) -> Option<&str> {
    let query = url.split_once('?')?.1;
    query.split('&').find_map(|kv| kv.strip_prefix("token="))
}

fn header<'r>(request: &'r tiny_http::Request, name: &'static str) -> Option<&'r str> {
    request
        .headers()
        .iter()
        .find(|h| h.field.equiv(name))
        .map(|h| h.value.as_str())
}

fn text_response(code: u16, body: &str) -> tiny_http::Response<std::io::Cursor<Vec<u8>>> {
    tiny_http::Response::from_string(body).with_status_code(code)
}

fn content_type(value: &str) -> tiny_http::Header {
    tiny_http::Header::from_bytes("Content-Type", value).expect("a valid header")
}

fn accept_loop(
    server: &tiny_http::Server,
    token: &str,
    state: &Arc<LiveState>,
    stop: &Arc<AtomicBool>,
    shutdown: &Arc<AtomicBool>,
    title: &str,
) {
    let page = live_page(title, token);
    for request in server.incoming_requests() {
        if shutdown.load(Ordering::Relaxed) {
            break;
        }
        let url = request.url().to_string();
        let path = url.split('?').next().unwrap_or("");
        let method = request.method().clone();
        let authorised =
            query_token(&url) == Some(token) || header(&request, "X-Propid-Token") == Some(token);
        let result = match (method, path) {
            (_, _) if !authorised => request.respond(text_response(
                403,
                "forbidden: this page needs the run's token (printed on the terminal)\n",
            )),
            (tiny_http::Method::Get, "/") => request.respond(
                tiny_http::Response::from_string(page.clone())
                    .with_header(content_type("text/html; charset=utf-8")),
            ),
            (tiny_http::Method::Get, "/events") => {
                let (state, shutdown) = (Arc::clone(state), Arc::clone(shutdown));
                // Each viewer gets its own thread: a slow browser never holds up another one.
                // The stream is written by hand on the raw connection so that every message is
                // flushed as it is made (no chunking, no buffering until a chunk fills).
                let _ = std::thread::Builder::new()
                    .name("live-events".into())
                    .spawn(move || {
                        let mut w = request.into_writer();
                        let _ = stream_events(&mut *w, &state, &shutdown);
                    });
                Ok(())
            }
            // STOP must come with the header: a cross-site form or image cannot set it.
            (tiny_http::Method::Post, "/stop")
                if header(&request, "X-Propid-Token") == Some(token) =>
            {
                stop.store(true, Ordering::SeqCst);
                request.respond(text_response(
                    200,
                    "stopping: STANDBY and a zero setpoint\n",
                ))
            }
            (tiny_http::Method::Post, "/stop") => request.respond(text_response(
                403,
                "forbidden: STOP needs the X-Propid-Token header\n",
            )),
            _ => request.respond(text_response(404, "not found\n")),
        };
        let _ = result;
    }
}

/// The page: uPlot charts fed by the event stream, the estimate, readiness, bus health, STOP.
fn live_page(title: &str, token: &str) -> String {
    let body = format!(
        r##"<section>
<div class="verdict" id="status">connecting…</div>
<p><button id="stop" style="font-size:1.4em;padding:0.4em 1.6em;background:#c62828;color:#fff;border:0;border-radius:6px;cursor:pointer">STOP</button>
&nbsp; readiness <b id="readiness">–</b></p>
<table><tr><th>J [kg·m²]</th><th>c2 [N·m·s²/rad²]</th><th>feedback frames/s</th><th>sent frames/s</th><th>tx dropped</th><th>rx rejected</th><th>adapter errors</th></tr>
<tr><td class="num" id="j">–</td><td class="num" id="c2">–</td><td class="num" id="rx">–</td><td class="num" id="tx">–</td><td class="num" id="drop">–</td><td class="num" id="rej">–</td><td class="num" id="aerr">–</td></tr></table>
</section>
<h3>setpoint and torque</h3><div class="chart" id="c-force"></div>
<h3>velocity [rad/s]</h3><div class="chart" id="c-vel"></div>
<h3>acceleration [rad/s²]</h3><div class="chart" id="c-acc"></div>
<h3>running J (±2σ)</h3><div class="chart" id="c-j"></div>
<h3>running c2 (±2σ)</h3><div class="chart" id="c-c2"></div>
<script>
const TOKEN = {token};
const WINDOW_S = 10;
const pts = {{t: [], sp: [], f: [], v: [], a: []}};
const est = {{t: [], j: [], jlo: [], jhi: [], c2: [], clo: [], chi: []}};
function mk(id, series) {{
  const el = document.getElementById(id);
  const width = Math.max(400, Math.min(1200, document.body.clientWidth - 40));
  return new uPlot({{width, height: 200, series: [{{label: "t [s]"}}].concat(series),
    scales: {{x: {{time: false}}}},
    axes: [{{}}, {{size: 80, values: (u, vals) => vals.map(v => (v !== 0 && Math.abs(v) < 1e-2) ? v.toExponential(2) : v)}}]}}, [[]].concat(series.map(() => [])), el);
}}
const band = (label, colour) => [{{label, stroke: colour, width: 1.5}},
  {{label: "−2σ", stroke: colour, dash: [4, 4], width: 1}}, {{label: "+2σ", stroke: colour, dash: [4, 4], width: 1}}];
const charts = {{
  force: mk("c-force", [{{label: "setpoint ×0.1", stroke: "#888", width: 1}}, {{label: "torque [N·m]", stroke: "#1f77b4", width: 1.5}}]),
  vel: mk("c-vel", [{{label: "velocity", stroke: "#2ca02c", width: 1.5}}]),
  acc: mk("c-acc", [{{label: "acceleration", stroke: "#d62728", width: 1}}]),
  j: mk("c-j", band("J", "#9467bd")),
  c2: mk("c-c2", band("c2", "#ff7f0e")),
}};
const fmt = (x) => (x === null || x === undefined || !isFinite(x)) ? "–" : x.toExponential(4);
function redraw() {{
  const n = pts.t.length;
  if (n > 0) {{
    const t0 = pts.t[n - 1] - WINDOW_S;
    let i = 0; while (i < n && pts.t[i] < t0) i++;
    for (const k in pts) pts[k].splice(0, i);
  }}
  charts.force.setData([pts.t, pts.sp.map(x => x * 0.1), pts.f]);
  charts.vel.setData([pts.t, pts.v]);
  charts.acc.setData([pts.t, pts.a]);
  charts.j.setData([est.t, est.j, est.jlo, est.jhi]);
  charts.c2.setData([est.t, est.c2, est.clo, est.chi]);
}}
let last = 0;
const source = new EventSource("/events?token=" + TOKEN);
// Once STOP is acknowledged, an update still in flight from before it (status "running") must
// not take the acknowledgement off the page; the drive's final status replaces it.
let stopping = false;
source.onmessage = (ev) => {{
  const u = JSON.parse(ev.data);
  for (const p of u.points) {{
    pts.t.push(p.t); pts.sp.push(p.setpoint); pts.f.push(p.force); pts.v.push(p.velocity); pts.a.push(p.acceleration);
  }}
  for (const e of u.estimates) {{
    est.t.push(e.t); est.j.push(e.j); est.jlo.push(e.j - 2 * e.j_stderr); est.jhi.push(e.j + 2 * e.j_stderr);
    est.c2.push(e.c2); est.clo.push(e.c2 - 2 * e.c2_stderr); est.chi.push(e.c2 + 2 * e.c2_stderr);
  }}
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
}};
document.getElementById("stop").onclick = async () => {{
  const r = await fetch("/stop", {{method: "POST", headers: {{"X-Propid-Token": TOKEN}}}});
  stopping = r.ok;
  document.getElementById("status").textContent = await r.text();
}};
</script>
"##,
        token = crate::html::json_string(token),
    );
    crate::html::page(title, &[body])
}

/// Feeds the live page from a drive's events (rows, progress, the stop).
pub struct DriveView {
    feed: LiveFeed,
    excitation: propid_science::excitation::Excitation,
    first_t: Option<f64>,
    last_progress: Option<std::time::Instant>,
}

impl DriveView {
    /// A view of a drive playing `excitation`, published into `state`.
    pub fn new(state: Arc<LiveState>, excitation: propid_science::excitation::Excitation) -> Self {
        let mut feed = LiveFeed::new(state);
        feed.readiness("ENGAGED");
        feed.status(
            "init phase: at the high setpoint, feedback not recorded",
            false,
        );
        DriveView {
            feed,
            excitation,
            first_t: None,
            last_progress: None,
        }
    }

    /// Takes one event of the drive (never blocks).
    pub fn on_event(&mut self, event: &propid_drive::drive::DriveEvent) {
        use propid_drive::drive::DriveEvent;
        match event {
            DriveEvent::PatternStarted => self.feed.status(
                format!(
                    "running: {} pattern, {} s",
                    self.excitation.pattern, self.excitation.duration
                ),
                false,
            ),
            DriveEvent::Row(row) => {
                let s = row.sample;
                // The device clock's time since the first row stands for the pattern's time.
                let t0 = *self.first_t.get_or_insert(s.t);
                self.feed.sample(LivePoint {
                    t: s.t,
                    setpoint: self.excitation.setpoint(s.t - t0),
                    force: s.force,
                    velocity: s.velocity,
                    acceleration: s.acceleration,
                });
            }
            DriveEvent::Progress(p) => {
                let now = std::time::Instant::now();
                let dt = self
                    .last_progress
                    .map_or(1.0, |l| now.duration_since(l).as_secs_f64().max(1e-3));
                self.last_progress = Some(now);
                if let Some(e) = p.estimate {
                    self.feed.estimate(LiveEstimate {
                        t: p.elapsed,
                        j: e.j,
                        j_stderr: e.j_stderr,
                        c2: e.c2,
                        c2_stderr: e.c2_stderr,
                    });
                }
                self.feed.bus(LiveBus {
                    frames_rx_per_s: p.feedback_per_s as f64 / dt,
                    frames_tx_per_s: f64::NAN,
                    tx_dropped: p.tx.dropped,
                    rx_rejected: p.dropped_transfers,
                    adapter_errors: p.tx.refused,
                });
            }
            DriveEvent::Stopping(reason) => {
                self.feed.readiness("STANDBY");
                self.feed.status(
                    format!("stopping ({reason}): STANDBY and a zero setpoint"),
                    false,
                );
            }
            DriveEvent::Stopped(report) => {
                self.feed.readiness("STANDBY");
                // The page's last word says what was sent (a STANDBY the drive never handed to
                // the link is not claimed): the final status replaces "stopping …: STANDBY", and
                // once said "stopped (…); N rows" without it, so the safety state left the page.
                let sent = format!(
                    "{}{} zero setpoint{} sent",
                    if report.standby_sent > 0 {
                        "STANDBY and "
                    } else {
                        ""
                    },
                    report.zero_setpoints_sent,
                    if report.zero_setpoints_sent == 1 {
                        ""
                    } else {
                        "s"
                    },
                );
                self.feed.status(
                    format!(
                        "stopped ({}): {sent}; {} rows recorded",
                        report.reason, report.rows
                    ),
                    true,
                );
                self.feed.flush();
            }
            DriveEvent::RegisterWritten { .. } => {}
        }
    }
}

/// Starts the live page for a drive if `addr` is given: prints the URL on stderr.
pub fn start_for_drive(
    addr: Option<&str>,
    allow_remote: bool,
    stop: &Arc<AtomicBool>,
    excitation: propid_science::excitation::Excitation,
    title: &str,
) -> anyhow::Result<Option<(LiveServer, DriveView)>> {
    let Some(addr) = addr else {
        return Ok(None);
    };
    let addr = check_addr(addr, allow_remote)?;
    if !addr.ip().is_loopback() {
        eprintln!(
            "warning: the live page is served on {addr}, beyond this machine; anyone who reaches it with the token can stop the drive"
        );
    }
    let state = Arc::new(LiveState::default());
    let server = serve(
        addr,
        Arc::clone(&state),
        Arc::clone(stop),
        title.to_string(),
    )?;
    eprintln!(
        "live: open {} (STOP there does what Ctrl-C does)",
        server.url()
    );
    Ok(Some((server, DriveView::new(state, excitation))))
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::io::{BufRead, BufReader, Read, Write};
    use std::net::TcpStream;

    fn get(addr: SocketAddr, request: &str) -> (u16, String) {
        let mut s = TcpStream::connect(addr).unwrap();
        s.write_all(request.as_bytes()).unwrap();
        let mut text = String::new();
        let _ = s.set_read_timeout(Some(Duration::from_secs(5)));
        let _ = s.read_to_string(&mut text);
        let code = text
            .split_whitespace()
            .nth(1)
            .and_then(|c| c.parse().ok())
            .unwrap_or(0);
        (code, text)
    }

    #[test]
    fn token_guards_every_route_and_stop_needs_the_header() {
        let state = Arc::new(LiveState::default());
        let stop = Arc::new(AtomicBool::new(false));
        let server = serve(
            "127.0.0.1:0".parse().unwrap(),
            Arc::clone(&state),
            Arc::clone(&stop),
            "test".into(),
        )
        .unwrap();
        let (a, tok) = (server.addr, server.token.clone());
        let close = "Connection: close\r\n\r\n";
        assert_eq!(
            get(a, &format!("GET / HTTP/1.1\r\nHost: x\r\n{close}")).0,
            403
        );
        let (code, page) = get(
            a,
            &format!("GET /?token={tok} HTTP/1.1\r\nHost: x\r\n{close}"),
        );
        assert_eq!(code, 200);
        assert!(page.contains("STOP") && page.contains("uPlot"));
        // A cross-site form post knows neither the token nor how to set the header.
        let form =
            format!("POST /stop?token={tok} HTTP/1.1\r\nHost: x\r\nContent-Length: 0\r\n{close}");
        assert_eq!(get(a, &form).0, 403);
        assert!(!stop.load(Ordering::SeqCst));
        let wrong = format!(
            "POST /stop HTTP/1.1\r\nHost: x\r\nX-Propid-Token: 00\r\nContent-Length: 0\r\n{close}"
        );
        assert_eq!(get(a, &wrong).0, 403);
        assert!(!stop.load(Ordering::SeqCst));
        let right = format!("POST /stop HTTP/1.1\r\nHost: x\r\nX-Propid-Token: {tok}\r\nContent-Length: 0\r\n{close}");
        assert_eq!(get(a, &right).0, 200);
        assert!(stop.load(Ordering::SeqCst));
    }

    #[test]
    fn events_carry_what_the_feed_published() {
        let state = Arc::new(LiveState::default());
        let mut feed = LiveFeed::new(Arc::clone(&state));
        for k in 0..5 {
            feed.sample(LivePoint {
                t: k as f64,
                setpoint: 0.5,
                force: 0.01,
                velocity: 100.0,
                acceleration: 1.0,
            });
        }
        feed.readiness("ENGAGED");
        feed.flush();
        let server = serve(
            "127.0.0.1:0".parse().unwrap(),
            Arc::clone(&state),
            Arc::new(AtomicBool::new(false)),
            "test".into(),
        )
        .unwrap();
        let mut s = TcpStream::connect(server.addr).unwrap();
        write!(
            s,
            "GET /events?token={} HTTP/1.1\r\nHost: x\r\n\r\n",
            server.token
        )
        .unwrap();
        let mut r = BufReader::new(s);
        let mut line = String::new();
        let data = loop {
            line.clear();
            r.read_line(&mut line).unwrap();
            if let Some(d) = line.trim_end().strip_prefix("data: ") {
                break d.to_string();
            }
        };
        let v: serde_json::Value = serde_json::from_str(&data).unwrap();
        assert_eq!(v["seq"], 5);
        assert_eq!(v["points"].as_array().unwrap().len(), 5);
        assert_eq!(v["readiness"], "ENGAGED");
    }

    #[test]
    fn remote_addresses_need_an_explicit_flag() {
        assert!(check_addr("127.0.0.1:8080", false).is_ok());
        assert!(check_addr("0.0.0.0:8080", false).is_err());
        assert!(check_addr("0.0.0.0:8080", true).is_ok());
        assert!(check_addr("localhost", false).is_err());
    }
}
