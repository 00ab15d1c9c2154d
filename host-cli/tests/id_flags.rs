//! Node-, subject- and service-IDs are parsed into the core's types where they enter: an
//! out-of-range value is refused with the range named and exit code 2, before any device is
//! opened (issue 13: `sim-drive --node-id 200` and `--feedback-id 9000` used to run forever
//! publishing nothing; `replay --feedback-id 9000` was accepted).

use std::process::Command;

#[test]
fn out_of_range_ids_are_refused_naming_the_range() {
    let cases: [(&[&str], &str); 5] = [
        (
            &[
                "sim-drive",
                "--iface",
                "slcan:/dev/null-not-opened",
                "--node-id",
                "200",
            ],
            "node-ID 200 is out of range: it must be from 0 to 127",
        ),
        (
            &[
                "sim-drive",
                "--iface",
                "slcan:/dev/null-not-opened",
                "--feedback-id",
                "9000",
            ],
            "subject-ID 9000 is out of range: it must be from 0 to 8191",
        ),
        (
            &["replay", "/dev/null-not-opened", "--feedback-id", "9000"],
            "subject-ID 9000 is out of range: it must be from 0 to 8191",
        ),
        (
            &[
                "drive",
                "--iface",
                "slcan:/dev/null-not-opened",
                "--node-id=-1",
            ],
            "node-ID -1 is out of range: it must be from 0 to 127",
        ),
        (
            &[
                "drive",
                "--iface",
                "slcan:/dev/null-not-opened",
                "--readiness-id",
                "ten",
            ],
            "a subject-ID must be an integer from 0 to 8191",
        ),
    ];
    for (args, want) in cases {
        let out = Command::new(env!("CARGO_BIN_EXE_propid"))
            .args(args)
            .env_remove("UAVCAN__NODE__ID")
            .env_remove("UAVCAN__SUB__FB_DYN__ID")
            .env_remove("UAVCAN__PUB__FB_DYN__ID")
            .env_remove("UAVCAN__PUB__READINESS__ID")
            .output()
            .unwrap();
        let err = String::from_utf8_lossy(&out.stderr);
        assert_eq!(out.status.code(), Some(2), "{args:?}: {err}");
        assert!(err.contains(want), "{args:?}: {err}");
        assert!(!err.contains("panicked"), "{err}");
    }
}
