//! Congestion against the reference stack: `propid drive` at the seed's 5 ms setpoint period
//! (a Readiness frame and a 10-frame Vector31 every 5 ms, 2200 frames/s) and PyCyphal 1.27.1
//! (python-can's slcan interface) with a slow CAN bus between them: `tests/pycyphal/slowbus.py`
//! releases propid's SLCAN frame lines to PyCyphal at the pace of a 125 kbit/s bus (at most 954
//! frames/s, fewer than half of what propid offers), holding at most one line itself, so the
//! backlog fills the kernel's pty buffer and propid's writes fail with EAGAIN. One second into the
//! pattern the bus stops for a second altogether (nothing leaves; the buffer stays full).
//!
//! What is shown, against what PyCyphal itself decoded:
//! - the run completes: rows keep being recorded while the bus is stopped, the summary counts the
//!   frames dropped, the setpoints superseded and the times the link was busy (a write that would
//!   block), no write aborts the run, and PyCyphal's last readiness is STANDBY, its last setpoint
//!   zero, decoded within [`STANDBY_BOUND`] of the stop;
//! - SIGINT while the bus is stopped: the same, exit status 130;
//! - the relay killed mid-run (the port vanishes): a clear error, a non-zero exit, every row
//!   counted is whole on disk.
//!
//! Needs python3 with `pycyphal[transport-can-pythoncan]`: `#[ignore]`d, run explicitly by
//! ci/steps/30-pycyphal.sh (`cargo test -p propid --test pycyphal_congestion -- --ignored`).

mod common;

use std::io::{BufRead, BufReader, Read};
use std::path::{Path, PathBuf};
use std::process::{Child, Command, ExitStatus, Stdio};
use std::sync::mpsc::{channel, Receiver};
use std::sync::{Mutex, OnceLock};
use std::time::{Duration, Instant, SystemTime, UNIX_EPOCH};

use common::{assert_seed_setpoints, compile_pycyphal_dsdl, repo, require_python};

/// The slow bus [bit/s].
const BUS_BITRATE: &str = "125000";
/// When the bus stops, after the first frame propid sends [s] (propid's soft start lasts 1 s and
/// its init phase [`INIT`] s, so this is one second into the pattern), and for how long.
const STALL_AT: f64 = 3.0;
const STALL_FOR: f64 = 1.0;
const INIT: &str = "1";
const PATTERN: &str = "5";
/// How long PyCyphal publishes feedback and listens [s] (it then listens one second more).
const PEER_SECONDS: &str = "10";
/// From the stop (propid's "stopping" line) to PyCyphal decoding the first STANDBY, at most:
/// what the bus still had to carry when the stop began (the kernel's pty buffer, 16 KiB on this
/// machine's kernel, at the bus's ~25.8 kB/s of SLCAN text: 0.62 s) plus what is left of a stall
/// (up to 1 s), plus PyCyphal's own scheduling. The stop sequence itself gives up after 2 s.
const STANDBY_BOUND: f64 = 2.5;

/// One scenario at a time: each is a real-time run on a 2-core machine.
static SERIAL: Mutex<()> = Mutex::new(());

fn wall() -> f64 {
    SystemTime::now()
        .duration_since(UNIX_EPOCH)
        .unwrap()
        .as_secs_f64()
}

/// The DSDL compiled for PyCyphal once per test binary.
fn compiled_dsdl() -> &'static Path {
    static DIR: OnceLock<PathBuf> = OnceLock::new();
    DIR.get_or_init(|| {
        let dir = tempfile::tempdir().unwrap().keep();
        compile_pycyphal_dsdl(&dir);
        dir
    })
}

/// What to do to the run while it goes.
#[derive(Clone, Copy, PartialEq)]
enum Action {
    /// Nothing: the pattern completes.
    None,
    /// SIGINT to propid this long after the bus stopped.
    SigintIntoStall(f64),
    /// SIGKILL to the relay this long after propid's first frame.
    KillRelay(f64),
}

/// What one run produced.
struct Run {
    status: ExitStatus,
    /// propid's stderr, each line with the wall time it was read.
    stderr: Vec<(f64, String)>,
    /// The TSV as written.
    tsv: String,
    /// PyCyphal's report (absent when the relay was killed).
    peer: Option<serde_json::Value>,
    /// The relay's events (`first`, `stall`, `resume`, `end`), each with the wall time read.
    relay: Vec<serde_json::Value>,
}

impl Run {
    fn stderr_text(&self) -> String {
        self.stderr
            .iter()
            .map(|(_, l)| l.as_str())
            .collect::<Vec<_>>()
            .join("\n")
    }

    fn relay_event(&self, name: &str) -> &serde_json::Value {
        self.relay
            .iter()
            .find(|e| e["event"] == name)
            .unwrap_or_else(|| panic!("no relay event {name}: {:?}", self.relay))
    }

    /// The wall time of propid's "stopping" line.
    fn stop_time(&self) -> f64 {
        self.stderr
            .iter()
            .find(|(_, l)| l.starts_with("drive: stopping ("))
            .unwrap_or_else(|| panic!("no stopping line in {}", self.stderr_text()))
            .0
    }

    /// The final summary line.
    fn summary(&self) -> &str {
        &self
            .stderr
            .iter()
            .find(|(_, l)| l.starts_with("drive: stopped ("))
            .unwrap_or_else(|| panic!("no summary in {}", self.stderr_text()))
            .1
    }
}

/// A number in the summary after `key`.
fn count(summary: &str, key: &str) -> u64 {
    summary
        .split(key)
        .nth(1)
        .and_then(|s| s.split([' ', ',', ')']).next())
        .and_then(|n| n.parse().ok())
        .unwrap_or_else(|| panic!("no `{key}` count in {summary}"))
}

/// The number before " rows written" in the summary.
fn rows_written(summary: &str) -> u64 {
    summary
        .split(" rows written")
        .next()
        .and_then(|s| s.rsplit(' ').next())
        .and_then(|n| n.parse().ok())
        .unwrap_or_else(|| panic!("no row count in {summary}"))
}

fn lines_to_channel<R: Read + Send + 'static>(r: R) -> Receiver<(f64, String)> {
    let (tx, rx) = channel();
    std::thread::spawn(move || {
        for line in BufReader::new(r).lines() {
            let Ok(line) = line else { break };
            if tx.send((wall(), line)).is_err() {
                break;
            }
        }
    });
    rx
}

fn signal(child: &Child, sig: &str) {
    let ok = Command::new("kill")
        .args([sig, &child.id().to_string()])
        .status()
        .unwrap();
    assert!(ok.success(), "kill {sig}");
}

fn wait_with_timeout(child: &mut Child, limit: Duration, what: &str) -> ExitStatus {
    let t0 = Instant::now();
    loop {
        if let Some(s) = child.try_wait().unwrap() {
            return s;
        }
        if t0.elapsed() > limit {
            let _ = child.kill();
            panic!("{what} did not end within {limit:?}");
        }
        std::thread::sleep(Duration::from_millis(20));
    }
}

fn run(action: Action) -> Run {
    let _one = SERIAL.lock().unwrap_or_else(|e| e.into_inner());
    require_python("pycyphal, can, serial");
    let compiled = compiled_dsdl();
    let dir = tempfile::tempdir().unwrap();

    // The slow bus.
    let mut relay = Command::new("python3")
        .arg(repo().join("tests/pycyphal/slowbus.py"))
        .arg(BUS_BITRATE)
        .args(["--stall-at", &STALL_AT.to_string()])
        .args(["--stall-for", &STALL_FOR.to_string()])
        .stdout(Stdio::piped())
        .spawn()
        .unwrap();
    let relay_lines = lines_to_channel(relay.stdout.take().unwrap());
    let (_, first) = relay_lines
        .recv_timeout(Duration::from_secs(20))
        .expect("the relay starts");
    let paths: serde_json::Value = serde_json::from_str(&first).unwrap();
    let (a, b) = (
        paths["a"].as_str().unwrap().to_string(),
        paths["b"].as_str().unwrap().to_string(),
    );

    // PyCyphal on side B, listening before propid starts.
    let mut py = Command::new("python3")
        .arg(repo().join("tests/pycyphal/interop.py"))
        .arg(compiled)
        .arg(format!("slcan:{b}@115200"))
        .arg(PEER_SECONDS)
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .spawn()
        .unwrap();
    let py_err = lines_to_channel(py.stderr.take().unwrap());
    loop {
        let (_, line) = py_err
            .recv_timeout(Duration::from_secs(60))
            .expect("PyCyphal did not start");
        if line.trim() == "ready" {
            break;
        }
    }
    let mut py_out = py.stdout.take().unwrap();
    let py_report = std::thread::spawn(move || {
        let mut out = Vec::new();
        let _ = py_out.read_to_end(&mut out);
        out
    });

    // propid on side A at the seed's 5 ms setpoint period.
    let tsv_path = dir.path().join("run.tsv");
    let mut drive = Command::new(env!("CARGO_BIN_EXE_propid"))
        .args([
            "drive",
            "--iface",
            &format!("slcan:{a}@115200"),
            "--init-duration",
            INIT,
            "--pattern-duration",
            PATTERN,
            "--deadman",
            "2",
            "-o",
        ])
        .arg(&tsv_path)
        .env("UAVCAN__NODE__ID", "10")
        .env("UAVCAN__PUB__READINESS__ID", "10")
        .env("UAVCAN__PUB__SP_RAT__ID", "24")
        .env("UAVCAN__SUB__FB_DYN__ID", "110")
        .env("SETPOINT_PERIOD", "0.005")
        .stderr(Stdio::piped())
        .spawn()
        .unwrap();
    let stderr_lines = lines_to_channel(drive.stderr.take().unwrap());

    let mut relay_events: Vec<serde_json::Value> = Vec::new();
    let next_relay_event = |name: &str, events: &mut Vec<serde_json::Value>| {
        let (t, line) = relay_lines
            .recv_timeout(Duration::from_secs(30))
            .unwrap_or_else(|_| panic!("no relay event {name}"));
        let mut v: serde_json::Value = serde_json::from_str(&line).unwrap();
        v["read_at"] = t.into();
        assert_eq!(v["event"], name, "{v}");
        events.push(v);
    };
    next_relay_event("first", &mut relay_events);
    match action {
        Action::None => {}
        Action::SigintIntoStall(after) => {
            next_relay_event("stall", &mut relay_events);
            std::thread::sleep(Duration::from_secs_f64(after));
            signal(&drive, "-INT");
        }
        Action::KillRelay(after) => {
            std::thread::sleep(Duration::from_secs_f64(after));
            relay.kill().unwrap();
            relay.wait().unwrap();
        }
    }
    let status = wait_with_timeout(&mut drive, Duration::from_secs(30), "propid drive");
    let stderr: Vec<(f64, String)> = stderr_lines.iter().collect();

    let peer = if matches!(action, Action::KillRelay(_)) {
        let _ = py.kill();
        let _ = py.wait();
        None
    } else {
        let py_status = wait_with_timeout(&mut py, Duration::from_secs(30), "PyCyphal");
        let err: Vec<String> = py_err.try_iter().map(|(_, l)| l).collect();
        assert!(py_status.success(), "PyCyphal failed: {}", err.join("\n"));
        let out = py_report.join().unwrap();
        signal(&relay, "-TERM");
        wait_with_timeout(&mut relay, Duration::from_secs(10), "the relay");
        Some(serde_json::from_slice(&out).expect("PyCyphal's report"))
    };
    for (t, line) in relay_lines.iter() {
        let mut v: serde_json::Value = serde_json::from_str(&line).unwrap();
        v["read_at"] = t.into();
        relay_events.push(v);
    }
    let tsv = std::fs::read_to_string(&tsv_path).unwrap_or_default();
    let run = Run {
        status,
        stderr,
        tsv,
        peer,
        relay: relay_events,
    };
    eprintln!("{}", run.stderr_text());
    eprintln!("relay: {:?}", run.relay);
    run
}

/// Every row is whole (six numbers, the file ends with a newline); the data rows.
fn whole_rows(tsv: &str) -> Vec<Vec<f64>> {
    assert!(
        tsv.ends_with('\n'),
        "the last row is cut: {:?}",
        tsv.lines().last()
    );
    tsv.lines()
        .skip(1)
        .map(|l| {
            let v: Vec<f64> = l
                .split('\t')
                .map(|x| x.parse().unwrap_or_else(|_| panic!("row {l:?}")))
                .collect();
            assert_eq!(v.len(), 6, "row {l:?}");
            v
        })
        .collect()
}

/// PyCyphal decoded nothing torn: every setpoint is 31 equal values, zero or in the pattern's
/// range; its last readiness is STANDBY and its last setpoint zero, and it took every STANDBY and
/// zero setpoint the summary says were sent, discarding none as a repeat. Returns the wall time at
/// which it decoded the first STANDBY.
fn standby_last(peer: &serde_json::Value, summary: &str) -> f64 {
    let readiness: Vec<u64> = peer["readiness"]
        .as_array()
        .unwrap()
        .iter()
        .map(|v| v.as_u64().unwrap())
        .collect();
    assert_eq!(readiness.first(), Some(&3), "ENGAGED first: {readiness:?}");
    assert_eq!(readiness.last(), Some(&2), "STANDBY last: {readiness:?}");
    let setpoints = peer["setpoints"].as_array().unwrap();
    assert!(
        setpoints.len() > 20,
        "{} setpoints decoded",
        setpoints.len()
    );
    assert_seed_setpoints(setpoints);
    assert_eq!(
        setpoints.last().unwrap()[0].as_f64().unwrap(),
        0.0,
        "zero setpoint last"
    );
    // The repeats leave one after another, and a transfer takes its transfer-ID only as it
    // leaves, so the IDs PyCyphal sees follow on from the last transfer that crossed, however
    // many were superseded or purged meanwhile: it takes every one. (When IDs were given at
    // publication, a stop's first zero setpoint could carry the ID of the last setpoint that
    // crossed before the stall, 32 or 64 IDs earlier, and PyCyphal discarded it as a repeat.)
    // "… sent (N and M times) …": N STANDBY, M zero setpoints.
    let (standby_sent, zeros_sent) = summary
        .split_once("sent (")
        .and_then(|(_, rest)| rest.split_once(" times)"))
        .and_then(|(counts, _)| counts.split_once(" and "))
        .and_then(|(n, m)| Some((n.parse::<u64>().ok()?, m.parse::<u64>().ok()?)))
        .unwrap_or_else(|| panic!("no `sent (N and M times)` in {summary}"));
    let trailing_zeros = setpoints
        .iter()
        .rev()
        .take_while(|sp| sp[0].as_f64() == Some(0.0))
        .count() as u64;
    let trailing_standby = readiness.iter().rev().take_while(|&&r| r == 2).count() as u64;
    let tail = |key: &str| -> Vec<serde_json::Value> {
        let v = peer[key].as_array().cloned().unwrap_or_default();
        v[v.len().saturating_sub(8)..].to_vec()
    };
    let last = format!(
        "the peer's last setpoints {:?} at {:?} (transfer-IDs {:?}), readiness {:?} at {:?} (transfer-IDs {:?}); reassembly errors {}",
        tail("setpoints").iter().map(|v| v[0].clone()).collect::<Vec<_>>(),
        tail("setpoints_t"),
        tail("setpoints_tid"),
        tail("readiness"),
        tail("readiness_t"),
        tail("readiness_tid"),
        peer["reassembly_errors"]
    );
    assert_eq!(
        (trailing_standby, trailing_zeros),
        (standby_sent, zeros_sent),
        "STANDBY and zero setpoints at the end, against those sent ({summary}); {last}"
    );
    for sub in ["setpoints", "readiness"] {
        assert_eq!(
            peer["reassembly_errors"][sub]["UNEXPECTED_TRANSFER_ID"].as_u64(),
            Some(0),
            "PyCyphal discarded {sub} frames for their transfer-ID; {last}"
        );
    }
    let first_standby = readiness.iter().position(|&r| r == 2).unwrap();
    assert!(
        readiness[first_standby..].iter().all(|&r| r == 2),
        "nothing but STANDBY after the first: {readiness:?}"
    );
    peer["readiness_t"][first_standby].as_f64().unwrap()
}

#[test]
#[ignore = "needs python3 with pycyphal"]
fn a_congested_bus_loses_setpoints_not_the_run_and_standby_arrives_last() {
    let run = run(Action::None);
    let err = run.stderr_text();
    assert!(run.status.success(), "propid drive failed: {err}");
    assert!(!err.contains("panicked"), "{err}");
    let summary = run.summary();
    assert!(
        summary.starts_with(
            "drive: stopped (the pattern is complete); STANDBY and a zero setpoint sent"
        ),
        "{summary}"
    );
    let (dropped, busy, superseded) = (
        count(summary, "frames dropped "),
        count(summary, "link busy "),
        count(summary, "times, "),
    );
    eprintln!(
        "congested: {dropped} frames dropped, link busy {busy} times, {superseded} superseded"
    );
    // The bus carries fewer than half the frames offered, and nothing for a second.
    assert!(busy > 100, "{summary}");
    assert!(dropped + superseded > 1000, "{summary}");

    // Rows were recorded all through, the stall included, each the value PyCyphal sent.
    let peer = run.peer.as_ref().unwrap();
    let rows = whole_rows(&run.tsv);
    assert_eq!(rows.len() as u64, rows_written(summary), "{summary}");
    let sent = peer["sent"].as_array().unwrap();
    let sent_at = |k: f64| sent[k as usize - 1]["wall"].as_f64().unwrap();
    for r in &rows {
        let k = r[3];
        assert_eq!(k.fract(), 0.0, "velocity is the sequence number: {r:?}");
        assert_eq!(r[2], f64::from((k / 1000.0) as f32), "force {r:?}");
        assert_eq!(r[4], -k, "acceleration {r:?}");
    }
    let (stall, resume) = (
        run.relay_event("stall")["t"].as_f64().unwrap(),
        run.relay_event("resume")["t"].as_f64().unwrap(),
    );
    let in_stall = rows
        .iter()
        .filter(|r| (stall..resume).contains(&sent_at(r[3])))
        .count();
    let sent_in_stall = sent
        .iter()
        .filter(|s| (stall..resume).contains(&s["wall"].as_f64().unwrap()))
        .count();
    eprintln!(
        "rows recorded while the bus was stopped ({:.2} s): {in_stall} of the {sent_in_stall} PyCyphal sent",
        resume - stall
    );
    assert!(in_stall >= 50, "{in_stall} rows while the bus was stopped");
    assert_eq!(
        in_stall, sent_in_stall,
        "every feedback message sent meanwhile is a row"
    );
    // The progress lines during the stall show the drops growing, the run going on.
    let during: Vec<&String> = run
        .stderr
        .iter()
        .filter(|(t, l)| (stall..resume + 0.5).contains(t) && l.starts_with("drive: pattern "))
        .map(|(_, l)| l)
        .collect();
    assert!(
        !during.is_empty(),
        "no progress while the bus was stopped: {err}"
    );

    let standby_at = standby_last(peer, summary);
    let latency = standby_at - run.stop_time();
    eprintln!("STANDBY decoded by PyCyphal {latency:.3} s after the stop began");
    assert!(
        (0.0..=STANDBY_BOUND).contains(&latency),
        "STANDBY {latency:.3} s after the stop"
    );
}

#[test]
#[ignore = "needs python3 with pycyphal"]
fn sigint_while_the_bus_is_stopped_still_ends_with_standby_at_the_peer() {
    let run = run(Action::SigintIntoStall(0.3));
    let err = run.stderr_text();
    assert_eq!(run.status.code(), Some(130), "{err}");
    assert!(!err.contains("panicked"), "{err}");
    let summary = run.summary();
    assert!(
        summary.starts_with(
            "drive: stopped (interrupted by a signal); STANDBY and a zero setpoint sent"
        ),
        "{summary}"
    );
    let stop = run.stop_time();
    let (stall, resume) = (
        run.relay_event("stall")["t"].as_f64().unwrap(),
        run.relay_event("resume")["t"].as_f64().unwrap(),
    );
    assert!(
        (stall..resume).contains(&stop),
        "the stop began while the bus was stopped"
    );
    whole_rows(&run.tsv);
    let standby_at = standby_last(run.peer.as_ref().unwrap(), summary);
    let latency = standby_at - stop;
    eprintln!(
        "SIGINT {:.3} s into the stall: STANDBY decoded by PyCyphal {latency:.3} s after the stop began ({:.3} s after the bus resumed)",
        stop - stall,
        standby_at - resume
    );
    assert!(
        standby_at >= resume,
        "nothing crosses a stopped bus: {standby_at} < {resume}"
    );
    assert!(
        (0.0..=STANDBY_BOUND).contains(&latency),
        "STANDBY {latency:.3} s after the stop"
    );
}

#[test]
#[ignore = "needs python3 with pycyphal"]
fn the_relay_killed_mid_run_stops_the_drive_with_a_clear_error_and_whole_rows() {
    // 3.5 s after propid's first frame: 1.5 s into the pattern, in the middle of the stall (3 s
    // to 4 s), with propid's writes refused.
    let run = run(Action::KillRelay(3.5));
    let err = run.stderr_text();
    assert_ne!(run.status.code(), Some(0), "{err}");
    assert_ne!(run.status.code(), Some(101), "a panic: {err}");
    assert!(!err.contains("panicked") && !err.contains("Os {"), "{err}");
    assert!(err.contains("device vanished"), "{err}");
    let summary = run.summary();
    assert!(summary.contains("NOT confirmed sent"), "{summary}");
    let rows = whole_rows(&run.tsv);
    assert!(rows.len() > 50, "{} rows", rows.len());
    assert_eq!(rows.len() as u64, rows_written(summary), "{summary}");
}
