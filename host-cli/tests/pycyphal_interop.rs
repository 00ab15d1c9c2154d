//! Interop with the reference stack: PyCyphal 1.27.1 (python-can's slcan interface) on one end of a
//! socat pseudo-terminal pair, `propid drive` on the other. PyCyphal publishes DoF3rdTs and
//! Heartbeat and propid records the same values; propid publishes Readiness and Vector31 and
//! PyCyphal decodes the same values (ENGAGED and the setpoints, then STANDBY and zero).
//! A second run uses the seed's own 5 ms setpoint period, which python-can's slcan reader may not
//! drain (it reads more slowly than propid writes, above all while it starts): the run completes,
//! the summary reports what was dropped, and PyCyphal's last readiness is STANDBY, its last
//! setpoint zero. (A really congested bus: `pycyphal_congestion.rs`; in virtual time:
//! `drive-host/tests/virtual_run.rs`.)
//! Needs python3 with `pycyphal[transport-can-pythoncan]` and socat: `#[ignore]`d, run explicitly
//! by ci/steps/30-pycyphal.sh (`cargo test -p propid --test pycyphal_interop -- --ignored`).

mod common;

use std::process::{Command, Stdio};
use std::time::Duration;

use common::{assert_seed_setpoints, compile_pycyphal_dsdl, python_has, repo};

/// What one run against PyCyphal produced.
struct Interop {
    /// PyCyphal's JSON report.
    report: serde_json::Value,
    /// propid's TSV rows.
    rows: Vec<Vec<f64>>,
    /// propid's stderr.
    stderr: String,
}

/// Runs `propid drive` (3 s init, 4 s pattern) against PyCyphal for 9 s at `setpoint_period`.
fn run_against_pycyphal(setpoint_period: &str) -> Interop {
    assert!(
        python_has("pycyphal, can, serial"),
        "python3 with pycyphal[transport-can-pythoncan] 1.27.1 is needed"
    );
    let has_socat = Command::new("socat")
        .arg("-V")
        .stdout(Stdio::null())
        .status()
        .is_ok_and(|s| s.success());
    assert!(has_socat, "socat is needed");
    let dir = tempfile::tempdir().unwrap();
    let compiled = dir.path().join("compiled");
    compile_pycyphal_dsdl(&compiled);
    let (a, b) = (dir.path().join("ttyA"), dir.path().join("ttyB"));
    let mut socat = Command::new("socat")
        .arg(format!("pty,raw,echo=0,link={}", a.display()))
        .arg(format!("pty,raw,echo=0,link={}", b.display()))
        .stderr(Stdio::null())
        .spawn()
        .unwrap();
    for _ in 0..50 {
        if a.exists() && b.exists() {
            break;
        }
        std::thread::sleep(Duration::from_millis(20));
    }
    let tsv = dir.path().join("run.tsv");
    // PyCyphal first: propid starts once it is listening (its imports take seconds on a busy
    // machine, longer than the init phase).
    let mut py = Command::new("python3")
        .arg(repo().join("tests/pycyphal/interop.py"))
        .arg(&compiled)
        .arg(format!("slcan:{}@115200", a.display()))
        .arg("9")
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .spawn()
        .unwrap();
    let mut py_err = std::io::BufReader::new(py.stderr.take().unwrap());
    let mut line = String::new();
    while {
        line.clear();
        std::io::BufRead::read_line(&mut py_err, &mut line).unwrap() > 0
    } {
        if line.trim() == "ready" {
            break;
        }
    }
    assert_eq!(line.trim(), "ready", "PyCyphal did not start");
    let py_err = std::thread::spawn(move || {
        let mut rest = String::new();
        std::io::Read::read_to_string(&mut py_err, &mut rest).unwrap();
        rest
    });
    let mut drive = Command::new(env!("CARGO_BIN_EXE_propid"))
        .args([
            "drive",
            "--iface",
            &format!("slcan:{}@115200", b.display()),
            "--init-duration",
            "3",
            "--pattern-duration",
            "4",
            "--deadman",
            "2",
            "-o",
        ])
        .arg(&tsv)
        .env("UAVCAN__NODE__ID", "10")
        .env("UAVCAN__PUB__READINESS__ID", "10")
        .env("UAVCAN__PUB__SP_RAT__ID", "24")
        .env("UAVCAN__SUB__FB_DYN__ID", "110")
        .env("SETPOINT_PERIOD", setpoint_period)
        .stderr(Stdio::piped())
        .spawn()
        .unwrap();
    // Its report can exceed a pipe's buffer: read it all before waiting.
    let py_stdout = {
        let mut out = Vec::new();
        std::io::Read::read_to_end(&mut py.stdout.take().unwrap(), &mut out).unwrap();
        out
    };
    let py_status = py.wait().unwrap();
    let py_stderr = py_err.join().unwrap();
    let drive_out = {
        use std::io::Read;
        let mut err = String::new();
        drive
            .stderr
            .take()
            .unwrap()
            .read_to_string(&mut err)
            .unwrap();
        (drive.wait().unwrap(), err)
    };
    let _ = socat.kill();
    let _ = socat.wait();
    assert!(py_status.success(), "{py_stderr}");
    let (drive_status, stderr) = drive_out;
    assert!(drive_status.success(), "propid drive failed: {stderr}");
    let report: serde_json::Value = serde_json::from_slice(&py_stdout).unwrap();
    let text = std::fs::read_to_string(&tsv).unwrap();
    let rows: Vec<Vec<f64>> = text
        .lines()
        .skip(1)
        .map(|l| l.split('\t').map(|x| x.parse().unwrap()).collect())
        .collect();
    Interop {
        report,
        rows,
        stderr,
    }
}

/// The last readiness and setpoint PyCyphal decoded are STANDBY and zero, and it discarded no
/// frame of either subject for its transfer-ID: propid numbers only the transfers that leave, so
/// none can look like a repeat (frames python-can loses show as other reassembly errors).
fn assert_standby_last(report: &serde_json::Value) {
    for sub in ["setpoints", "readiness"] {
        assert_eq!(
            report["reassembly_errors"][sub]["UNEXPECTED_TRANSFER_ID"].as_u64(),
            Some(0),
            "PyCyphal discarded {sub} frames for their transfer-ID: {}",
            report["reassembly_errors"]
        );
    }
    let readiness = report["readiness"].as_array().unwrap();
    assert_eq!(
        readiness.last().and_then(|v| v.as_u64()),
        Some(2),
        "{readiness:?}"
    );
    let setpoints = report["setpoints"].as_array().unwrap();
    assert_eq!(
        setpoints.last().unwrap()[0].as_f64().unwrap(),
        0.0,
        "zero setpoint last"
    );
}

#[test]
#[ignore = "needs python3 with pycyphal and socat"]
fn propid_and_pycyphal_understand_each_other_over_slcan() {
    // python-can's slcan reader keeps up with a setpoint every 50 ms, not every 5 ms.
    let Interop { report, rows, .. } = run_against_pycyphal("0.05");

    // PyCyphal → propid: every recorded row is a DoF3rdTs PyCyphal sent, value for value.
    assert!(rows.len() > 100, "{} rows", rows.len());
    for r in &rows {
        let k = r[3];
        assert_eq!(k.fract(), 0.0, "velocity is the sequence number: {r:?}");
        assert!((r[1] - k * 0.01).abs() < 1e-9, "timestamp {r:?}");
        assert_eq!(r[2], f64::from((k / 1000.0) as f32), "force {r:?}");
        assert_eq!(r[4], -k, "acceleration {r:?}");
        assert_eq!(r[5], 0.25, "position {r:?}");
    }
    assert!(report["sent"].as_array().unwrap().len() >= rows.len());
    assert_standby_last(&report);

    // propid → PyCyphal: ENGAGED while driving, STANDBY at the end; setpoints decoded the same.
    let readiness: Vec<u64> = report["readiness"]
        .as_array()
        .unwrap()
        .iter()
        .map(|v| v.as_u64().unwrap())
        .collect();
    assert_eq!(readiness.first(), Some(&3), "{readiness:?}");
    assert_eq!(readiness.last(), Some(&2), "{readiness:?}");
    let setpoints = report["setpoints"].as_array().unwrap();
    assert!(setpoints.len() > 50, "{}", setpoints.len());
    assert_seed_setpoints(setpoints);
    let first = setpoints[0][0].as_f64().unwrap();
    assert_eq!(
        first,
        f64::from(half_precision(0.1)),
        "the soft start at 0.1 first"
    );
    let init = setpoints
        .iter()
        .position(|s| s[0].as_f64() != Some(first))
        .expect("the init phase follows");
    assert_eq!(
        setpoints[init][0].as_f64().unwrap(),
        f64::from(half_precision(0.9)),
        "then the init phase at the high setpoint"
    );
    assert_eq!(
        setpoints.last().unwrap()[0].as_f64().unwrap(),
        0.0,
        "zero setpoint last"
    );
}

#[test]
#[ignore = "needs python3 with pycyphal and socat"]
fn at_the_seeds_5_ms_period_the_run_completes_with_standby_last_and_drops_reported() {
    let Interop {
        report,
        rows,
        stderr,
    } = run_against_pycyphal("0.005");
    assert_standby_last(&report);
    assert!(rows.len() > 100, "{} rows", rows.len());
    // Drops are reported: the final summary counts frames dropped and refusals by the link.
    let summary = stderr
        .lines()
        .find(|l| l.starts_with("drive: stopped (the pattern is complete)"))
        .unwrap_or_else(|| panic!("no summary in {stderr}"));
    assert!(summary.contains("frames dropped"), "{summary}");
    assert!(
        summary.contains("STANDBY and a zero setpoint sent"),
        "{summary}"
    );
    // The counts are there as numbers (whether python-can fell behind depends on the machine:
    // it did when it was still starting up, and not once it was listening).
    let count = |key: &str| -> u64 {
        summary
            .split(key)
            .nth(1)
            .and_then(|s| s.split(' ').next())
            .and_then(|n| n.parse().ok())
            .unwrap_or_else(|| panic!("no `{key}` count in {summary}"))
    };
    let (dropped, busy) = (count("frames dropped "), count("link busy "));
    eprintln!(
        "PyCyphal at 5 ms: {dropped} frames dropped, the link busy {busy} times; its reassembly errors {}",
        report["reassembly_errors"]
    );
    eprintln!("{summary}");
}

/// 0.9 through float16, as both stacks send it.
fn half_precision(x: f32) -> f32 {
    let mut buf = [0u8; 62];
    use propid_core::dsdl::{DataType, Vector31};
    Vector31::splat(x).serialize(&mut buf);
    Vector31::deserialize(&buf).unwrap().value[0]
}
