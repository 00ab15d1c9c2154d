//! Setpoint publication jitter: `propid drive`'s loop against the seed's asyncio loop, both
//! publishing every 5 ms for the same time in one run. propid's side is the Sans-IO `Drive`
//! machine in the real-time loop (`run_drive`, as `propid drive` runs it) on an in-memory bus whose `send` records when each setpoint frame leaves; the seed's side is its
//! `publish_until` with a publisher that records when it is called
//! (`benches/setpoint_jitter/seed_loop.py`). Reported: percentiles of |interval − 5 ms|.
//! `cargo bench -p propid-benches --bench setpoint_jitter [-- SECONDS]`; with `--test` (CI smoke)
//! it runs for 0.5 s.

use std::sync::atomic::AtomicBool;
use std::time::{Duration, Instant};

use propid_drive_host::drive::run_drive;
use propid_drive_host::live::{DriveView, LiveState};
use propid_drive_host::realtime::SystemClock;
use propid_drive_host::stand::Played;
use propid_drive_proto::drive::DriveConfig;
use propid_science::excitation::{Excitation, Pattern};
use propid_transport::{CanTransport, Frame, MemoryBus, TransportError};

/// Records when setpoint frames (subject 24, first frame) are sent.
struct Recorder {
    inner: MemoryBus,
    sent: Vec<Instant>,
}

impl CanTransport for Recorder {
    fn send(&mut self, frame: &Frame) -> Result<(), TransportError> {
        let subject = (frame.id() >> 8) & 0x1FFF;
        let start_of_transfer = frame.data().last().is_some_and(|t| t & 0x80 != 0);
        if subject == 24 && start_of_transfer {
            self.sent.push(Instant::now());
        }
        self.inner.send(frame)
    }
    fn flush(&mut self, deadline: std::time::Instant) -> Result<bool, TransportError> {
        self.inner.flush(deadline)
    }
    fn receive(&mut self, timeout: Duration) -> Result<Option<Frame>, TransportError> {
        self.inner.receive(timeout)
    }
    fn mtu(&self) -> usize {
        8
    }
    fn name(&self) -> String {
        "recorder".into()
    }
    fn health(&self) -> propid_transport::Health {
        self.inner.health()
    }
}

fn jitter_us(stamps: &[f64]) -> Vec<f64> {
    let mut j: Vec<f64> = stamps
        .windows(2)
        .map(|w| ((w[1] - w[0]) - 0.005).abs() * 1e6)
        .collect();
    j.sort_by(f64::total_cmp);
    j
}

fn pct(sorted: &[f64], p: f64) -> f64 {
    if sorted.is_empty() {
        return f64::NAN;
    }
    sorted[((sorted.len() - 1) as f64 * p).round() as usize]
}

/// Runs the drive loop for `seconds` of init phase (setpoints only) and returns the publication
/// times [s]; with `live`, the live page is served and a viewer reads its event stream.
fn run_loop(seconds: f64, live: bool) -> Vec<f64> {
    use std::io::{Read, Write};
    use std::sync::Arc;
    let (a, _b) = MemoryBus::pair(8);
    let mut rec = Recorder {
        inner: a,
        sent: Vec::new(),
    };
    // The init phase publishes at the setpoint period like the pattern does; no feedback is
    // needed for it, so the measurement is the loop alone.
    let excitation = Excitation {
        lo: 0.1,
        hi: 0.9,
        period: 2.0,
        duration: 0.001,
        init_duration: seconds,
        pattern: Pattern::Sine,
    };
    let played = Played::try_from(excitation).unwrap();
    // No drive answers: no soft start (it would stop for want of feedback), the loop alone.
    let cfg = DriveConfig {
        limits: propid_drive_proto::limits::Limits::OFF,
        ..DriveConfig::example(played)
    };
    let stop = Arc::new(AtomicBool::new(false));
    let mut page = live.then(|| {
        let state = Arc::new(LiveState::default());
        let server = propid::live::serve(
            "127.0.0.1:0".parse().unwrap(),
            Arc::clone(&state),
            Arc::clone(&stop),
            "bench".into(),
        )
        .unwrap();
        let (addr, token) = (server.addr, server.token.clone());
        let viewer = std::thread::spawn(move || {
            let mut s = std::net::TcpStream::connect(addr).unwrap();
            // The stream stays open after the server stops; a quiet second ends the viewer.
            s.set_read_timeout(Some(Duration::from_secs(1))).unwrap();
            write!(s, "GET /events?token={token} HTTP/1.1\r\nHost: x\r\n\r\n").unwrap();
            let mut buf = vec![0u8; 1 << 16];
            let mut total = 0;
            while let Ok(n) = s.read(&mut buf) {
                if n == 0 {
                    break;
                }
                total += n;
            }
            total
        });
        (server, DriveView::new(state, played), viewer)
    });
    let t0 = Instant::now();
    let _ = run_drive(
        cfg,
        &mut rec,
        &SystemClock,
        &stop,
        &mut std::io::sink(),
        &mut |e| {
            if let Some((_, view, _)) = page.as_mut() {
                view.on_event(e);
            }
        },
    );
    if let Some((server, _, viewer)) = page {
        drop(server);
        let _ = viewer.join();
    }
    rec.sent
        .iter()
        .map(|t| t.duration_since(t0).as_secs_f64())
        .filter(|t| *t < seconds)
        .collect()
}

fn main() {
    let smoke = std::env::args().any(|a| a == "--test");
    let seconds: f64 = std::env::args()
        .filter_map(|a| a.parse().ok())
        .next()
        .unwrap_or(if smoke { 0.5 } else { 10.0 });
    let ours = run_loop(seconds, false);
    // The same loop with the live page served and a viewer connected to its event stream, fed
    // from the loop's events (issue 17: the live view must not change the jitter).
    let with_page = run_loop(seconds, true);
    let root = std::path::Path::new(env!("CARGO_MANIFEST_DIR"));
    let seed = std::process::Command::new("python3")
        .arg(root.join("setpoint_jitter/seed_loop.py"))
        .arg(seconds.to_string())
        .output();
    let theirs: Vec<f64> = match seed {
        Ok(o) if o.status.success() => String::from_utf8_lossy(&o.stdout)
            .lines()
            .filter_map(|l| l.parse().ok())
            .collect(),
        _ => Vec::new(),
    };
    let (jo, js) = (jitter_us(&ours), jitter_us(&theirs));
    let jl = jitter_us(&with_page);
    println!("setpoint publication jitter |interval − 5 ms| over {seconds} s [µs]:");
    println!(
        "{:<22} {:>8} {:>8} {:>8} {:>8} {:>8}",
        "loop", "n", "p50", "p90", "p99", "max"
    );
    for (name, j) in [
        ("propid drive", &jo),
        ("  with a live viewer", &jl),
        ("seed asyncio loop", &js),
    ] {
        println!(
            "{name:<22} {:>8} {:>8.1} {:>8.1} {:>8.1} {:>8.1}",
            j.len(),
            pct(j, 0.5),
            pct(j, 0.9),
            pct(j, 0.99),
            j.last().copied().unwrap_or(f64::NAN)
        );
    }
    if !js.is_empty() {
        println!(
            "ratio seed/propid: p50 {:.1}, p99 {:.1}",
            pct(&js, 0.5) / pct(&jo, 0.5),
            pct(&js, 0.99) / pct(&jo, 0.99)
        );
    } else {
        println!("(python3 not available: the seed loop was not measured)");
    }
    assert!(
        jo.len() as f64 > 0.8 * seconds / 0.005,
        "propid published {} times",
        jo.len()
    );
}
