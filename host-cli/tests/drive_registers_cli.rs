//! `propid drive`'s registers come from the defaults, then the `--registers` file, then the
//! environment (the register names as PyCyphal maps them), then the flags; a bad value from any
//! of them is refused before the bus is opened, naming its origin and the register.

use std::path::Path;
use std::process::{Command, Output};

const VARS: [&str; 14] = [
    "MAX_SPEED",
    "SOFT_START_SETPOINT",
    "SOFT_START_DURATION",
    "RAMP_DURATION",
    "SPEED_WATCHDOG",
    "UAVCAN__NODE__ID",
    "UAVCAN__PUB__SP_RAT__ID",
    "UAVCAN__SUB__FB_DYN__ID",
    "UAVCAN__PUB__READINESS__ID",
    "SETPOINT_RAT_LO_HI",
    "PERIOD",
    "PATTERN_DURATION",
    "INIT_DURATION",
    "SETPOINT_PERIOD",
];

fn drive(dir: &Path, args: &[&str], env: &[(&str, &str)]) -> Output {
    let mut cmd = Command::new(env!("CARGO_BIN_EXE_propid"));
    cmd.arg("drive")
        .args(["--iface", "slcan:/dev/null-not-opened"])
        .args(args)
        .current_dir(dir);
    for v in VARS {
        cmd.env_remove(v);
    }
    cmd.envs(env.iter().copied());
    cmd.output().unwrap()
}

fn shown(out: &Output) -> String {
    assert_eq!(
        out.status.code(),
        Some(0),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    String::from_utf8_lossy(&out.stdout).into_owned()
}

fn value<'a>(text: &'a str, name: &str) -> &'a str {
    text.lines()
        .find_map(|l| l.strip_prefix(&format!("{name}: ")))
        .unwrap_or_else(|| panic!("{name} not in {text}"))
}

#[test]
fn file_then_environment_then_flags() {
    let dir = tempfile::tempdir().unwrap();
    let file = dir.path().join("drive.reg");
    std::fs::write(
        &file,
        "# the seed's example\nuavcan.node.id: 10\nuavcan.pub.sp_rat.id = 24\nuavcan.sub.fb_dyn.id: 110\nperiod: 3\nsetpoint_rat_lo_hi: 0.2 0.7\n",
    )
    .unwrap();
    let f = file.to_str().unwrap();
    let base = ["--registers", f, "--show-registers"];
    let only_file = shown(&drive(dir.path(), &base, &[]));
    assert_eq!(value(&only_file, "period"), "3");
    assert_eq!(value(&only_file, "setpoint_rat_lo_hi"), "0.2 0.7");
    assert_eq!(value(&only_file, "pattern_duration"), "200");
    assert_eq!(value(&only_file, "uavcan.pub.readiness.id"), "65535");
    let env = shown(&drive(
        dir.path(),
        &base,
        &[("PERIOD", "2.5"), ("UAVCAN__PUB__READINESS__ID", "10")],
    ));
    assert_eq!(value(&env, "period"), "2.5");
    assert_eq!(value(&env, "uavcan.pub.readiness.id"), "10");
    let mut with_flag = base.to_vec();
    with_flag.extend(["--period", "4", "--setpoint-rat-lo-hi", "0.1 0.5"]);
    let flags = shown(&drive(dir.path(), &with_flag, &[("PERIOD", "2.5")]));
    assert_eq!(value(&flags, "period"), "4");
    assert_eq!(value(&flags, "setpoint_rat_lo_hi"), "0.1 0.5");
    // Without a file: the seed's defaults, the environment for the IDs.
    let defaults = shown(&drive(
        dir.path(),
        &["--show-registers"],
        &[
            ("UAVCAN__NODE__ID", "10"),
            ("UAVCAN__PUB__SP_RAT__ID", "24"),
            ("UAVCAN__SUB__FB_DYN__ID", "110"),
        ],
    ));
    assert_eq!(value(&defaults, "setpoint_rat_lo_hi"), "0.1 0.9");
    assert_eq!(value(&defaults, "setpoint_period"), "0.005");
    assert_eq!(value(&defaults, "init_duration"), "5");
}

#[test]
fn bad_values_are_refused_naming_origin_and_register() {
    let dir = tempfile::tempdir().unwrap();
    let file = dir.path().join("drive.reg");
    let f = file.to_str().unwrap().to_string();
    let (line1, line3) = (format!("{f}:1"), format!("{f}:3"));
    let ids = [
        ("UAVCAN__NODE__ID", "10"),
        ("UAVCAN__PUB__SP_RAT__ID", "24"),
        ("UAVCAN__SUB__FB_DYN__ID", "110"),
    ];
    // (register file, environment, what the error must say)
    type Case<'a> = (&'a str, Vec<(&'a str, &'a str)>, Vec<&'a str>);
    let cases: Vec<Case> = vec![
        (
            "uavcan.node.id: 10\n\nperiod: fast\n",
            vec![],
            vec![
                &line3,
                "register period: `fast` is not a valid real64[1] (flag --period, environment variable PERIOD)",
            ],
        ),
        (
            "no_such_register: 1\n",
            vec![],
            vec![&line1, "no_such_register is not a register of this command"],
        ),
        (
            "just text\n",
            vec![],
            vec![&line1, "expected `name: value`"],
        ),
        (
            "pattern_duration: 0\n",
            ids.to_vec(),
            vec![
                &line1,
                "register pattern_duration: must be a finite number above 0",
                "(flag --pattern-duration, environment variable PATTERN_DURATION)",
            ],
        ),
        (
            "uavcan.sub.fb_dyn.id: 9000\n",
            vec![
                ("UAVCAN__NODE__ID", "10"),
                ("UAVCAN__PUB__SP_RAT__ID", "24"),
            ],
            vec![
                "register uavcan.sub.fb_dyn.id",
                "subject-ID 9000 is out of range",
            ],
        ),
        (
            "",
            vec![("PERIOD", "fast")],
            vec!["environment variable PERIOD", "register period"],
        ),
        (
            "",
            vec![("SETPOINT_RAT_LO_HI", "0.9 0.1"), ids[0], ids[1], ids[2]],
            vec![
                "environment variable SETPOINT_RAT_LO_HI: the setpoint range must satisfy -1 ≤ lo < hi ≤ 1 (got lo = 0.9, hi = 0.1)",
                "(flag --setpoint-rat-lo-hi, register setpoint_rat_lo_hi)",
            ],
        ),
        (
            "",
            vec![("UAVCAN__NODE__ID", "200"), ids[1], ids[2]],
            vec!["register uavcan.node.id", "node-ID 200 is out of range"],
        ),
        (
            "",
            vec![ids[1], ids[2]],
            vec!["--node-id is not set (nor its register uavcan.node.id in a --registers file, nor its environment variable UAVCAN__NODE__ID)"],
        ),
    ];
    for (contents, env, wants) in cases {
        std::fs::write(&file, contents).unwrap();
        let out = drive(dir.path(), &["--registers", &f], &env);
        let err = String::from_utf8_lossy(&out.stderr);
        assert_eq!(out.status.code(), Some(2), "{contents:?} {env:?}: {err}");
        for want in wants {
            assert!(
                err.contains(want),
                "{contents:?} {env:?}: want {want:?} in {err}"
            );
        }
        assert!(
            !err.contains("null-not-opened"),
            "refused before the bus: {err}"
        );
        assert!(!err.contains("panicked") && !err.contains("Some("), "{err}");
    }
    let out = drive(dir.path(), &["--registers", "/nonexistent/drive.reg"], &[]);
    let err = String::from_utf8_lossy(&out.stderr);
    assert_eq!(out.status.code(), Some(2), "{err}");
    assert!(
        err.contains("cannot read the register file /nonexistent/drive.reg"),
        "{err}"
    );
}

#[test]
fn telega_refuses_bad_arguments_before_the_bus() {
    for (args, want) in [
        (
            &["--set", "mns.pub_interval_min"][..],
            "--set `mns.pub_interval_min`: expected NAME=VALUE",
        ),
        (
            &["--listen", "0"],
            "--listen: must be a finite number above 0 and at most 60 s (got 0)",
        ),
        (&["--drive", "200"], "node-ID 200 is out of range"),
    ] {
        let out = Command::new(env!("CARGO_BIN_EXE_propid"))
            .args(["telega", "--iface", "slcan:/dev/null-not-opened"])
            .args(args)
            .output()
            .unwrap();
        let err = String::from_utf8_lossy(&out.stderr);
        assert_eq!(out.status.code(), Some(2), "{args:?}: {err}");
        assert!(err.contains(want), "{args:?}: {err}");
        assert!(!err.contains("null-not-opened"), "{err}");
    }
}

/// The limits are registers like the seed's: the defaults (a 1 s soft start at 0.1, the watchdog
/// at 50 rad/s, no maximum speed, no ramp), a speed in rpm from the file, the environment or the
/// flag (held in rad/s), 0 turning a limit off; a speed that is not one is refused naming where it
/// came from.
#[test]
fn the_limits_are_registers_and_speeds_take_rpm() {
    let dir = tempfile::tempdir().unwrap();
    let ids = [
        ("UAVCAN__NODE__ID", "10"),
        ("UAVCAN__PUB__SP_RAT__ID", "24"),
        ("UAVCAN__SUB__FB_DYN__ID", "110"),
    ];
    let defaults = shown(&drive(dir.path(), &["--show-registers"], &ids));
    for (name, want) in [
        ("max_speed", "0"),
        ("soft_start_setpoint", "0.1"),
        ("soft_start_duration", "1"),
        ("ramp_duration", "0"),
        ("speed_watchdog", "50"),
    ] {
        assert_eq!(value(&defaults, name), want, "{name}");
    }
    let file = dir.path().join("drive.reg");
    std::fs::write(&file, "max_speed: 12000rpm\nspeed_watchdog: 0\n").unwrap();
    let f = file.to_str().unwrap();
    let from_file = shown(&drive(
        dir.path(),
        &["--registers", f, "--show-registers"],
        &ids,
    ));
    let rad_s = |text: &str| text.parse::<f64>().unwrap();
    assert!((rad_s(value(&from_file, "max_speed")) - 1256.637).abs() < 1e-3);
    assert_eq!(value(&from_file, "speed_watchdog"), "0");
    let mut env = ids.to_vec();
    env.push(("MAX_SPEED", "10000 rpm"));
    let from_env = shown(&drive(
        dir.path(),
        &["--registers", f, "--show-registers"],
        &env,
    ));
    assert!((rad_s(value(&from_env, "max_speed")) - 1047.198).abs() < 1e-3);
    let flag = shown(&drive(
        dir.path(),
        &[
            "--show-registers",
            "--max-speed",
            "900",
            "--soft-start-duration",
            "0",
        ],
        &env,
    ));
    assert_eq!(value(&flag, "max_speed"), "900");
    assert_eq!(value(&flag, "soft_start_duration"), "0");
    let mut bad = ids.to_vec();
    bad.push(("MAX_SPEED", "fast"));
    let out = drive(dir.path(), &["--show-registers"], &bad);
    let err = String::from_utf8_lossy(&out.stderr);
    assert_eq!(out.status.code(), Some(2), "{err}");
    assert!(
        err.contains("environment variable MAX_SPEED: `fast` is not a valid speed in rad/s, or rpm (12000rpm) (flag --max-speed, register max_speed)"),
        "{err}"
    );
}

/// The runs `propid diagnose` advises (`propid drive --pattern … --setpoint-rat-lo-hi="LO HI"`)
/// are commands `drive` takes as printed (exit 0), the range (a negative low end too) reaching its
/// register.
#[test]
fn the_runs_diagnose_advises_are_flags_drive_takes() {
    use propid_science::diagnose::SeparatingRun;
    use propid_science::excitation::Pattern;
    let dir = tempfile::tempdir().unwrap();
    let ids = [
        ("UAVCAN__NODE__ID", "10"),
        ("UAVCAN__PUB__SP_RAT__ID", "24"),
        ("UAVCAN__SUB__FB_DYN__ID", "110"),
    ];
    for (pattern, lo, hi, range) in [
        (Pattern::Chirp, Some(-0.5), Some(0.9), "-0.5 0.9"),
        (Pattern::Steps, Some(0.02), None, "0.02 0.9"),
        (Pattern::Chirp, None, None, "0.1 0.9"),
    ] {
        let run = SeparatingRun {
            pattern,
            lo,
            hi,
            why: "",
        };
        // The flags as a shell splits them: the quoted range is one argument.
        let flags = run.flags();
        let mut args: Vec<String> = Vec::new();
        for (k, part) in flags.split('"').enumerate() {
            if k % 2 == 1 {
                let last = args.pop().unwrap();
                args.push(format!("{last}{part}"));
            } else {
                args.extend(part.split_whitespace().map(str::to_owned));
            }
        }
        args.push("--show-registers".into());
        let args: Vec<&str> = args.iter().map(String::as_str).collect();
        let text = shown(&drive(dir.path(), &args, &ids));
        assert_eq!(value(&text, "setpoint_rat_lo_hi"), range, "{flags}");
    }
}
