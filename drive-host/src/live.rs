//! The live view's model: what the page shows of a drive while it runs, fed from the drive's
//! events by the control loop without ever waiting, and read by a server as JSON.
//!
//! ```text
//!  control loop ─► DriveView::on_event(&DriveEvent) ─► LiveFeed (owned by the loop; batches
//!                  samples, never waits)
//!                     │ try_lock only: if the reader holds the lock, the batch waits for the
//!                     ▼ next call — the control loop is never blocked by a viewer
//!                  LiveState (a ring of the last seconds, estimate, readiness, bus counters)
//!                     ▲
//!  server thread ─── LiveState::update_since(cursor) ─► JSON of what is new
//! ```
//! The HTTP server and the page itself are the command's (`propid`'s `live` module).

use std::sync::{Arc, Mutex};
use std::time::Duration;

use propid_drive_proto::drive::DriveEvent;
use serde::Serialize;

use crate::stand::Played;

/// How many samples the page's ring keeps (about 20 s at 500 Hz).
const RING: usize = 10_000;

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
    pub fn update_since(&self, after: u64, estimates_after: usize) -> (String, u64, usize) {
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

/// Feeds the live page from a drive's events (rows, progress, the stop).
pub struct DriveView {
    feed: LiveFeed,
    played: Played,
    first_t: Option<f64>,
    last_progress: Option<std::time::Instant>,
}

impl DriveView {
    /// A view of a drive playing `played`, published into `state`.
    pub fn new(state: Arc<LiveState>, played: Played) -> Self {
        let mut feed = LiveFeed::new(state);
        feed.readiness("ENGAGED");
        feed.status(
            "soft start and init phase: feedback checked, not recorded",
            false,
        );
        DriveView {
            feed,
            played,
            first_t: None,
            last_progress: None,
        }
    }

    /// Takes one event of the drive (never blocks).
    pub fn on_event(&mut self, event: &DriveEvent) {
        let excitation = self.played.excitation();
        match event {
            DriveEvent::SoftStartPassed(p) => self.feed.status(
                format!(
                    "soft start passed ({:.0} → {:.0} rad/s); init phase at the high setpoint",
                    p.from, p.to
                ),
                false,
            ),
            DriveEvent::PatternStarted => self.feed.status(
                format!(
                    "running: {} pattern, {} s",
                    excitation.pattern, excitation.duration
                ),
                false,
            ),
            DriveEvent::Row(row) => {
                let s = row.sample;
                // The device clock's time since the first row stands for the pattern's time.
                let t0 = *self.first_t.get_or_insert(s.t);
                self.feed.sample(LivePoint {
                    t: s.t,
                    setpoint: excitation.setpoint(s.t - t0),
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

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn updates_start_after_the_cursor_and_the_ring_keeps_the_newest() {
        let state = Arc::new(LiveState::default());
        let mut feed = LiveFeed::new(Arc::clone(&state));
        let n = RING + 3;
        (0..n).for_each(|k| {
            feed.sample(LivePoint {
                t: k as f64,
                setpoint: 0.0,
                force: 0.0,
                velocity: 0.0,
                acceleration: 0.0,
            })
        });
        feed.status("stopped", true);
        feed.flush();
        let parse = |json: String| serde_json::from_str::<serde_json::Value>(&json).unwrap();
        let (json, seq, _) = state.update_since(0, 0);
        let all = parse(json);
        assert_eq!(seq, n as u64);
        let points = all["points"].as_array().unwrap();
        assert_eq!(points.len(), RING);
        assert_eq!(points[0]["t"], 3.0);
        assert_eq!(
            (&all["status"], &all["finished"]),
            (&"stopped".into(), &true.into())
        );
        let (json, _, _) = state.update_since(seq - 2, 0);
        assert_eq!(parse(json)["points"].as_array().unwrap().len(), 2);
    }
}
