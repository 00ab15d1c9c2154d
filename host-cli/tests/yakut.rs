//! The register API against the reference tools, over a socat pseudo-terminal pair and SLCAN:
//! Yakut 0.14.2 (`register-list`, `register-access`, `subscribe`) against `propid drive` and
//! `propid sim-drive`, and `propid telega` configuring a register server written with PyCyphal.
//! Run by ci/steps/80-yakut.sh (`cargo test -p propid --test yakut -- --ignored`).

mod common;

use std::path::{Path, PathBuf};
use std::process::{Child, Command, Output, Stdio};
use std::time::Duration;

use common::repo;

/// A socat pty pair; killed on drop.
struct Ptys {
    socat: Child,
    a: PathBuf,
    b: PathBuf,
    _dir: tempfile::TempDir,
}

impl Ptys {
    fn new() -> Ptys {
        let dir = tempfile::tempdir().unwrap();
        let (a, b) = (dir.path().join("ttyA"), dir.path().join("ttyB"));
        let socat = Command::new("socat")
            .arg(format!("pty,raw,echo=0,link={}", a.display()))
            .arg(format!("pty,raw,echo=0,link={}", b.display()))
            .stderr(Stdio::null())
            .spawn()
            .expect("socat runs");
        for _ in 0..100 {
            if a.exists() && b.exists() {
                break;
            }
            std::thread::sleep(Duration::from_millis(20));
        }
        Ptys {
            socat,
            a,
            b,
            _dir: dir,
        }
    }

    fn iface(p: &Path) -> String {
        format!("slcan:{}@115200", p.display())
    }
}

impl Drop for Ptys {
    fn drop(&mut self) {
        let _ = self.socat.kill();
        let _ = self.socat.wait();
    }
}

/// Stops a child with SIGINT (propid then sends STANDBY) and collects its output.
fn interrupt(child: Child) -> Output {
    let _ = Command::new("kill")
        .args(["-INT", &child.id().to_string()])
        .status();
    child.wait_with_output().unwrap()
}

/// Runs yakut (node 100) on `iface`; stdout.
fn yakut(iface: &str, args: &[&str], timeout_s: u32) -> String {
    let out = Command::new("timeout")
        .arg(timeout_s.to_string())
        .arg("yakut")
        .args(args)
        .env("CYPHAL_PATH", repo().join("dsdl"))
        .env("UAVCAN__CAN__IFACE", iface)
        .env("UAVCAN__CAN__MTU", "8")
        .env("UAVCAN__CAN__BITRATE", "1000000 1000000")
        .env("UAVCAN__NODE__ID", "100")
        .env(
            "YAKUT_COMPILE_OUTPUT",
            std::env::temp_dir().join("propid-yakut-dsdl"),
        )
        .output()
        .expect("yakut runs");
    let stdout = String::from_utf8_lossy(&out.stdout).into_owned();
    eprintln!(
        "yakut {args:?}: {stdout}{}",
        String::from_utf8_lossy(&out.stderr)
            .lines()
            .filter(|l| !l.contains(" INF ") && !l.contains(" WAR "))
            .collect::<Vec<_>>()
            .join("\n")
    );
    stdout
}

#[test]
#[ignore = "needs yakut, pycyphal and socat"]
fn yakut_lists_reads_and_writes_propid_drive_registers() {
    let p = Ptys::new();
    let dir = tempfile::tempdir().unwrap();
    let regfile = dir.path().join("drive.reg");
    // The file gives the period and the node-ID; the environment overrides the node-ID.
    std::fs::write(&regfile, "period: 2.5\nuavcan.node.id: 11\n").unwrap();
    let drive = Command::new(env!("CARGO_BIN_EXE_propid"))
        .args([
            "drive",
            "--iface",
            &Ptys::iface(&p.b),
            "--registers",
            regfile.to_str().unwrap(),
        ])
        // No motor at the other end: no soft start (which would stop for want of feedback),
        // only the init phase while Yakut talks to it.
        .args([
            "--init-duration",
            "120",
            "--soft-start-duration",
            "0",
            "--progress=false",
            "-o",
            "/dev/null",
        ])
        .env("UAVCAN__NODE__ID", "10")
        .env("UAVCAN__PUB__SP_RAT__ID", "24")
        .env("UAVCAN__SUB__FB_DYN__ID", "110")
        .env("SETPOINT_RAT_LO_HI", "0.2 0.8")
        // python-can's slcan reader under Yakut drains the pty slowly: with a setpoint every
        // 5 ms (10 frames each) the service responses would be dropped as congestion.
        .env("SETPOINT_PERIOD", "0.5")
        .stderr(Stdio::piped())
        .spawn()
        .unwrap();
    let iface = Ptys::iface(&p.a);
    let list = yakut(&iface, &["register-list", "10"], 120);
    for name in [
        "setpoint_rat_lo_hi",
        "period",
        "pattern_duration",
        "init_duration",
        "setpoint_period",
        "uavcan.node.id",
        "uavcan.pub.readiness.id",
        "uavcan.pub.sp_rat.id",
        "uavcan.sub.fb_dyn.id",
        "max_speed",
        "soft_start_setpoint",
        "soft_start_duration",
        "ramp_duration",
        "speed_watchdog",
    ] {
        assert!(list.contains(&format!("\"{name}\"")), "{name} in {list}");
    }
    // A limit set over the bus, as any register: 12,000 rpm in rad/s.
    let max = yakut(
        &iface,
        &["register-access", "10", "max_speed", "1256.6"],
        60,
    );
    assert_eq!(max.trim(), "1256.6");
    let lohi = yakut(&iface, &["register-access", "10", "setpoint_rat_lo_hi"], 60);
    assert_eq!(lohi.trim().replace(' ', ""), "[0.2,0.8]");
    let period = yakut(&iface, &["register-access", "10", "period", "3"], 60);
    assert_eq!(period.trim(), "3.0");
    let ro = yakut(
        &iface,
        &["register-access", "10", "uavcan.sub.fb_dyn.type", "x"],
        60,
    );
    assert!(ro.contains("zubax.physics.dynamics.DoF3rdTs.1.0"), "{ro}");
    let out = interrupt(drive);
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(err.contains("STANDBY"), "{err}");
    // The write went to the register file, for the next run.
    let saved = std::fs::read_to_string(&regfile).unwrap();
    assert!(saved.contains("\nperiod: 3\n"), "{saved}");
    assert!(saved.contains("\nmax_speed: 1256.6\n"), "{saved}");
    assert!(saved.contains("\nuavcan.node.id: 10\n"), "{saved}");
}

#[test]
#[ignore = "needs yakut, pycyphal and socat"]
fn yakut_configures_the_simulated_telega_and_the_rate_follows() {
    let p = Ptys::new();
    let start = std::time::Instant::now();
    let sim = Command::new(env!("CARGO_BIN_EXE_propid"))
        .args(["sim-drive", "--iface", &Ptys::iface(&p.b)])
        .args(["--interval", "0.1"])
        .stderr(Stdio::piped())
        .spawn()
        .unwrap();
    let iface = Ptys::iface(&p.a);
    let list = yakut(&iface, &["register-list", "42"], 120);
    for name in [
        "mns.pub_interval_min",
        "mns.local_timestamp",
        "uavcan.pub.dynamics.id",
    ] {
        assert!(list.contains(&format!("\"{name}\"")), "{name} in {list}");
    }
    let w = yakut(
        &iface,
        &["register-access", "42", "mns.pub_interval_min", "0.02"],
        60,
    );
    assert!(w.trim().starts_with("0.0199"), "{w}");
    let written = start.elapsed().as_secs_f64();
    std::thread::sleep(Duration::from_secs(5));
    let out = interrupt(sim);
    let total = start.elapsed().as_secs_f64();
    let err = String::from_utf8_lossy(&out.stderr);
    // "sim-drive: … N feedback published …"
    let published: f64 = err
        .split(" feedback published")
        .next()
        .and_then(|s| s.rsplit(' ').next())
        .and_then(|n| n.parse().ok())
        .unwrap_or_else(|| panic!("{err}"));
    // At 10 Hz until the write at most, then 50 Hz: at least 80 % of the 50 Hz part must show.
    let after = published - 10.0 * written;
    eprintln!(
        "sim-drive published {published} in {total:.1} s; {after:.0} beyond 10 Hz after the write at {written:.1} s"
    );
    assert!(
        after >= 0.8 * 50.0 * (total - written - 1.0),
        "{after} of {published}"
    );
}

const PYCYPHAL_SERVER: &str = r#"
import os, sys, time, asyncio, json
import pycyphal, pycyphal.application
from pycyphal.application.register import Real32, Bit, Natural16
import uavcan.node
async def main():
    node = pycyphal.application.make_node(uavcan.node.GetInfo_1_0.Response(name="com.example.pycyphal_drive"))
    node.registry.setdefault("mns.pub_interval_min", Real32([0.05]))
    node.registry.setdefault("mns.local_timestamp", Bit([False]))
    node.registry.setdefault("uavcan.pub.dynamics.id", Natural16([110]))
    node.start()
    print("ready", flush=True)
    await asyncio.sleep(float(sys.argv[1]))
    print(json.dumps({n: list(map(float, pycyphal.application.register.ValueProxy(node.registry[n]).floats))
                      for n in ("mns.pub_interval_min", "mns.local_timestamp", "uavcan.pub.dynamics.id")}))
    node.close()
asyncio.run(main())
"#;

#[test]
#[ignore = "needs yakut, pycyphal and socat"]
fn propid_telega_configures_a_pycyphal_register_server() {
    let p = Ptys::new();
    let dir = tempfile::tempdir().unwrap();
    let compiled = dir.path().join("compiled");
    let dsdl = repo().join("dsdl");
    let status = Command::new("python3")
        .arg("-c")
        .arg(format!(
            "import pycyphal.dsdl as d; d.compile('{u}', output_directory='{o}')",
            u = dsdl.join("uavcan").display(),
            o = compiled.display()
        ))
        .status()
        .unwrap();
    assert!(status.success());
    let mut server = Command::new("python3")
        .args(["-c", PYCYPHAL_SERVER, "25"])
        .env("PYTHONPATH", &compiled)
        .env("UAVCAN__CAN__IFACE", Ptys::iface(&p.a))
        .env("UAVCAN__CAN__MTU", "8")
        .env("UAVCAN__CAN__BITRATE", "1000000 1000000")
        .env("UAVCAN__NODE__ID", "42")
        .stdout(Stdio::piped())
        .spawn()
        .unwrap();
    // PyCyphal is up once it says so (its node started), however long its imports took.
    let mut stdout = std::io::BufReader::new(server.stdout.take().unwrap());
    let mut first = String::new();
    std::io::BufRead::read_line(&mut stdout, &mut first).unwrap();
    assert_eq!(first.trim(), "ready", "the PyCyphal server did not start");
    let telega = |extra: &[&str]| {
        let out = Command::new(env!("CARGO_BIN_EXE_propid"))
            .args(["telega", "--iface", &Ptys::iface(&p.b), "--listen", "2.5"])
            .args(extra)
            .output()
            .unwrap();
        let text = format!(
            "{}{}",
            String::from_utf8_lossy(&out.stdout),
            String::from_utf8_lossy(&out.stderr)
        );
        eprintln!("propid telega {extra:?}:\n{text}");
        (out.status.code(), text)
    };
    let (code, text) = telega(&[]);
    assert_eq!(code, Some(1), "{text}");
    assert!(text.contains("com.example.pycyphal_drive"), "{text}");
    assert!(text.contains("mns.local_timestamp is false"), "{text}");
    assert!(text.contains("mns.pub_interval_min is 0.05"), "{text}");
    let (code, text) = telega(&["--fix", "--feedback-id", "110"]);
    assert_eq!(code, Some(0), "{text}");
    assert!(text.contains("ready"), "{text}");
    let mut held = String::new();
    std::io::Read::read_to_string(&mut stdout, &mut held).unwrap();
    assert!(server.wait().unwrap().success());
    // What PyCyphal's registry holds after propid's writes.
    assert!(held.contains("\"mns.local_timestamp\": [1.0]"), "{held}");
    assert!(
        held.contains("\"mns.pub_interval_min\": [0.004999"),
        "{held}"
    );
}

#[test]
#[ignore = "needs yakut, pycyphal and socat"]
fn telega_fixes_the_simulated_drive_then_drive_runs_on_its_port_ids() {
    // Discover, check, configure, drive, STANDBY: the simulated Telega starts at 20 Hz without
    // local timestamps, on feedback subject 111.
    let p = Ptys::new();
    let sim = Command::new(env!("CARGO_BIN_EXE_propid"))
        .args(["sim-drive", "--iface", &Ptys::iface(&p.b)])
        .args(["--interval", "0.05", "--local-timestamp", "false"])
        .args(["--feedback-id", "111", "--readiness-id", "10"])
        .stderr(Stdio::piped())
        .spawn()
        .unwrap();
    let iface = Ptys::iface(&p.a);
    let propid = |args: &[&str]| {
        let out = Command::new(env!("CARGO_BIN_EXE_propid"))
            .args(args)
            .args(["--iface", &iface])
            .env_remove("UAVCAN__NODE__ID")
            .output()
            .unwrap();
        let text = format!(
            "{}{}",
            String::from_utf8_lossy(&out.stdout),
            String::from_utf8_lossy(&out.stderr)
        );
        eprintln!("propid {args:?}:\n{text}");
        (out.status.code(), text)
    };
    // Refused before engaging: the drive's configuration would spoil the data.
    let (code, text) = propid(&[
        "drive",
        "--node-id",
        "10",
        "--from-telega",
        "42",
        "-o",
        "/dev/null",
    ]);
    assert_ne!(code, Some(0), "{text}");
    assert!(text.contains("not engaging it"), "{text}");
    assert!(text.contains("mns.pub_interval_min is 0.05"), "{text}");
    let (code, text) = propid(&["telega"]);
    assert_eq!(code, Some(1), "{text}");
    let (code, text) = propid(&["telega", "--fix", "--store"]);
    assert_eq!(code, Some(0), "{text}");
    assert!(text.contains("stored"), "{text}");
    let dir = tempfile::tempdir().unwrap();
    let tsv = dir.path().join("run.tsv");
    let (code, text) = propid(&[
        "drive",
        "--node-id",
        "10",
        "--from-telega",
        "42",
        "--init-duration",
        "0.5",
        "--pattern-duration",
        "3",
        "--setpoint-period",
        "0.02",
        "--progress=false",
        "-o",
        tsv.to_str().unwrap(),
    ]);
    assert_eq!(code, Some(0), "{text}");
    assert!(text.contains("publishes feedback on 111"), "{text}");
    assert!(text.contains("STANDBY and a zero setpoint sent"), "{text}");
    let rows = std::fs::read_to_string(&tsv).unwrap().lines().count() - 1;
    // 3 s at 200 Hz after the fix (at 20 Hz it would be 60).
    assert!(rows >= 500, "{rows} rows");
    let out = interrupt(sim);
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(
        err.contains("last readiness STANDBY, last setpoint 0"),
        "{err}"
    );
}
