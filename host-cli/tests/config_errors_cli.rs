//! Configuration errors all at once, and operating-system errors once with what fixes them
//! (issue 29: "--node-id is not set", fix, run again, "--setpoint-id is not set", …; and
//! "slcan:/dev/ttyNOPE: No such file or directory: No such file or directory").

use std::process::{Command, Output};

/// Every variable a `propid drive` or `sim-drive` setting reads.
const VARS: [&str; 17] = [
    "UAVCAN__NODE__ID",
    "UAVCAN__NODE__DESCRIPTION",
    "UAVCAN__CAN__IFACE",
    "UAVCAN__CAN__MTU",
    "UAVCAN__CAN__BITRATE",
    "UAVCAN__PUB__READINESS__ID",
    "UAVCAN__PUB__SP_RAT__ID",
    "UAVCAN__SUB__FB_DYN__ID",
    "SETPOINT_RAT_LO_HI",
    "PERIOD",
    "PATTERN_DURATION",
    "INIT_DURATION",
    "SETPOINT_PERIOD",
    "UAVCAN__SUB__READINESS__ID",
    "UAVCAN__SUB__SETPOINT_R_TORQ__ID",
    "UAVCAN__PUB__DYNAMICS__ID",
    "MNS__PUB_INTERVAL_MIN",
];

fn propid(args: &[&str], env: &[(&str, &str)]) -> Output {
    let mut cmd = Command::new(env!("CARGO_BIN_EXE_propid"));
    cmd.args(args);
    for v in VARS {
        cmd.env_remove(v);
    }
    cmd.envs(env.iter().copied());
    cmd.output().unwrap()
}

fn stderr(out: &Output) -> String {
    String::from_utf8_lossy(&out.stderr).into_owned()
}

#[test]
fn three_missing_settings_are_named_in_one_message() {
    let out = propid(&["drive", "--iface", "slcan:/dev/null-not-opened"], &[]);
    let err = stderr(&out);
    assert_eq!(out.status.code(), Some(2), "{err}");
    assert!(err.starts_with("error: 3 settings are wrong:\n"), "{err}");
    let lines: Vec<&str> = err.lines().skip(1).collect();
    assert_eq!(lines.len(), 3, "{err}");
    for (line, (flag, register, env)) in lines.iter().zip([
        ("--node-id", "uavcan.node.id", "UAVCAN__NODE__ID"),
        (
            "--setpoint-id",
            "uavcan.pub.sp_rat.id",
            "UAVCAN__PUB__SP_RAT__ID",
        ),
        (
            "--feedback-id",
            "uavcan.sub.fb_dyn.id",
            "UAVCAN__SUB__FB_DYN__ID",
        ),
    ]) {
        assert_eq!(
            line.trim(),
            format!(
                "{flag} is not set (nor its register {register} in a --registers file, nor its environment variable {env})"
            )
        );
    }
    assert!(
        !err.contains("null-not-opened"),
        "refused before the bus: {err}"
    );
    assert!(out.stdout.is_empty());
}

#[test]
fn wrong_values_from_a_flag_a_variable_and_a_file_are_said_in_their_own_words() {
    let dir = tempfile::tempdir().unwrap();
    let file = dir.path().join("drive.reg");
    std::fs::write(
        &file,
        "uavcan.node.id: 10\nperiod: 0\nuavcan.pub.sp_rat.type: x\n",
    )
    .unwrap();
    let f = file.to_str().unwrap();
    let out = propid(
        &[
            "drive",
            "--registers",
            f,
            "--iface",
            "slcan:/dev/null-not-opened",
            "--mtu",
            "64",
            "--setpoint-id",
            "9000",
        ],
        &[
            ("UAVCAN__SUB__FB_DYN__ID", "65535"),
            ("SETPOINT_PERIOD", "fast"),
        ],
    );
    let err = stderr(&out);
    assert_eq!(out.status.code(), Some(2), "{err}");
    for want in [
        "error: 6 settings are wrong:",
        &format!("{f}:3: uavcan.pub.sp_rat.type is read-only"),
        "--mtu: SLCAN carries Classic CAN only: set it to 8 (register uavcan.can.mtu, environment variable UAVCAN__CAN__MTU)",
        "--setpoint-id: subject-ID 9000 is out of range: it must be from 0 to 8191 (register uavcan.pub.sp_rat.id, environment variable UAVCAN__PUB__SP_RAT__ID)",
        "environment variable UAVCAN__SUB__FB_DYN__ID: 65535 leaves it unset, and it is needed (flag --feedback-id, register uavcan.sub.fb_dyn.id)",
        &format!("{f}:2: register period: must be a finite number above 0 and at most 86400 s (got 0) (flag --period, environment variable PERIOD)"),
        "environment variable SETPOINT_PERIOD: `fast` is not a valid real64[1] (flag --setpoint-period, register setpoint_period)",
    ] {
        assert_eq!(err.matches(want).count(), 1, "want {want:?} once in {err}");
    }
    assert!(!err.contains("null-not-opened"), "{err}");
}

/// `propid drive` on `iface` with every setting right: it fails opening the bus.
fn open(iface: &str, as_nobody: bool) -> Output {
    let ids = [
        ("UAVCAN__NODE__ID", "10"),
        ("UAVCAN__PUB__SP_RAT__ID", "24"),
        ("UAVCAN__SUB__FB_DYN__ID", "110"),
    ];
    if !as_nobody {
        return propid(&["drive", "--iface", iface], &ids);
    }
    // Root may open anything: drop to nobody to meet a port it may not open.
    let mut cmd = Command::new("setpriv");
    cmd.args(["--reuid=65534", "--regid=65534", "--clear-groups"])
        .arg(env!("CARGO_BIN_EXE_propid"))
        .args(["drive", "--iface", iface]);
    for v in VARS {
        cmd.env_remove(v);
    }
    cmd.envs(ids).output().expect("setpriv (util-linux) runs")
}

/// The error is one line naming the device, with the operating system's reason once and the hint.
#[track_caller]
fn said_once(out: &Output, device: &str, reason: &str, hints: &[&str]) {
    let err = stderr(out);
    assert_eq!(out.status.code(), Some(1), "{err}");
    assert_eq!(err.lines().count(), 1, "{err}");
    assert!(
        err.starts_with(&format!("error: {device}: {reason}")),
        "{err}"
    );
    assert_eq!(err.matches(reason).count(), 1, "the reason once: {err}");
    for hint in hints {
        assert_eq!(err.matches(hint).count(), 1, "{hint:?} once in {err}");
    }
    for debug in [
        "os error",
        "Os {",
        "Some(",
        "kind:",
        "No such file or directory",
        "..=",
    ] {
        assert!(!err.contains(debug), "{debug:?} in {err}");
    }
}

#[test]
fn a_missing_serial_device_is_said_once_with_where_to_look() {
    let out = open("slcan:/dev/ttyNOPE", false);
    said_once(
        &out,
        "slcan:/dev/ttyNOPE",
        "no such device.",
        &[
            "Is the adapter plugged in?",
            "ls /dev/ttyACM* /dev/serial/by-id/",
        ],
    );
}

#[test]
fn a_regular_file_is_not_a_serial_port() {
    let dir = tempfile::tempdir().unwrap();
    let file = dir.path().join("port");
    std::fs::write(&file, "").unwrap();
    let iface = format!("slcan:{}", file.display());
    said_once(
        &open(&iface, false),
        &iface,
        "not a serial port",
        &["give the adapter's device"],
    );
    let err = stderr(&open(&iface, false));
    assert!(
        !err.contains("typewriter") && !err.contains("ioctl"),
        "{err}"
    );
}

#[cfg(unix)]
#[test]
fn a_port_without_permission_says_which_group_or_udev_rule() {
    use std::os::unix::fs::PermissionsExt;
    let dir = tempfile::tempdir().unwrap();
    std::fs::set_permissions(dir.path(), std::fs::Permissions::from_mode(0o755)).unwrap();
    let port = dir.path().join("ttyACM9");
    std::fs::write(&port, "").unwrap();
    std::fs::set_permissions(&port, std::fs::Permissions::from_mode(0o600)).unwrap();
    let iface = format!("slcan:{}", port.display());
    said_once(
        &open(&iface, is_root()),
        &iface,
        "permission denied.",
        &[
            &format!("ls -l {}", port.display()),
            "sudo usermod -aG dialout $USER",
            "uucp",
            "udev rule",
        ],
    );
}

/// Whether this test runs as root (who may open any file).
#[cfg(unix)]
fn is_root() -> bool {
    std::fs::read_to_string("/proc/self/status")
        .ok()
        .and_then(|s| {
            s.lines()
                .find_map(|l| l.strip_prefix("Uid:"))
                .and_then(|l| l.split_whitespace().nth(1).map(|e| e == "0"))
        })
        .unwrap_or(false)
}

#[cfg(target_os = "linux")]
#[test]
fn a_missing_socketcan_interface_is_said_once_with_the_command_that_lists_them() {
    let out = open("socketcan:can9", false);
    let err = stderr(&out);
    // This machine's kernel may have no CAN at all: that has its own words.
    let reason = if err.contains("this kernel has no SocketCAN") {
        "this kernel has no SocketCAN"
    } else {
        "no such CAN interface."
    };
    let hints: &[&str] = if reason.starts_with("no such") {
        &[
            "`ip link show`",
            "`sudo ip link set can9 up type can bitrate 1000000`",
        ]
    } else {
        &["modprobe can_raw"]
    };
    said_once(&out, "socketcan:can9", reason, hints);
}
