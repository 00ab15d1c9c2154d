//! `propid replay` on candump logs made from the PyCyphal frame vectors: the DoF3rdTs values
//! come back out as TSV rows; what cannot be used is skipped, counted and named by line.

mod common;

use common::{propid, propid_ok, repo};
use propid_core::dsdl::{DataType, DoF3rdTs};
use serde_json::Value;

#[test]
fn replays_the_vector_frames() {
    let doc: Value = serde_json::from_str(
        &std::fs::read_to_string(repo().join("core/tests/data/can_frames.json")).unwrap(),
    )
    .unwrap();
    let dir = tempfile::tempdir().unwrap();
    let mut checked = 0;
    for (k, case) in doc["cases"].as_array().unwrap().iter().enumerate() {
        if case["payload_type"] != "zubax.physics.dynamics.DoF3rdTs.1.0"
            || case["subject_id"].is_null()
        {
            continue;
        }
        let subject = case["subject_id"].as_u64().unwrap();
        // A log with unrelated traffic first (a heartbeat), then the transfer's frames.
        let mut log = String::from("(1700000000.000100) can0 107D552A#0000000000000000E0\n");
        for (i, f) in case["frames"].as_array().unwrap().iter().enumerate() {
            let id = f["can_id_hex"].as_str().unwrap().to_uppercase();
            let data = f["data_hex"].as_str().unwrap().to_uppercase();
            let sep = if case["mtu"] == 64 { "##0" } else { "#" };
            log += &format!("(1700000000.{:06}) can0 {id}{sep}{data}\n", 200 + i);
        }
        let path = dir.path().join(format!("case{k}.log"));
        std::fs::write(&path, &log).unwrap();
        let out = propid_ok(&[
            "replay",
            path.to_str().unwrap(),
            "--feedback-id",
            &subject.to_string(),
        ]);
        let text = String::from_utf8(out.stdout).unwrap();
        let rows: Vec<Vec<f64>> = text
            .lines()
            .skip(1)
            .map(|l| l.split('\t').map(|x| x.parse().unwrap()).collect())
            .collect();
        assert_eq!(rows.len(), 1, "{text}");
        let fb =
            DoF3rdTs::deserialize(&hex::decode(case["payload_hex"].as_str().unwrap()).unwrap())
                .unwrap();
        let r = &rows[0];
        assert!(
            (r[0] - 1_700_000_000.000_2).abs() < 1e-6,
            "first-frame time {}",
            r[0]
        );
        assert_eq!(r[1], fb.timestamp.microsecond as f64 * 1e-6);
        assert_eq!(r[2], f64::from(fb.value.force));
        assert_eq!(r[3], f64::from(fb.value.kinematics.base.velocity));
        assert_eq!(r[4], f64::from(fb.value.kinematics.acceleration));
        assert_eq!(r[5], f64::from(fb.value.kinematics.base.position));
        checked += 1;
    }
    assert_eq!(checked, 6, "the DoF3rdTs message cases of the vector file");
}

/// The frames of the first Classic-CAN DoF3rdTs case of the vector file: (subject, source node,
/// "ID#DATA" bodies).
fn vector_transfer() -> (u64, u32, Vec<String>) {
    let doc: Value = serde_json::from_str(
        &std::fs::read_to_string(repo().join("core/tests/data/can_frames.json")).unwrap(),
    )
    .unwrap();
    let case = doc["cases"]
        .as_array()
        .unwrap()
        .iter()
        .find(|c| {
            c["payload_type"] == "zubax.physics.dynamics.DoF3rdTs.1.0"
                && !c["subject_id"].is_null()
                && c["mtu"] != 64
                && c["frames"].as_array().unwrap().len() > 1
        })
        .unwrap();
    let frames: Vec<String> = case["frames"]
        .as_array()
        .unwrap()
        .iter()
        .map(|f| {
            format!(
                "{}#{}",
                f["can_id_hex"].as_str().unwrap().to_uppercase(),
                f["data_hex"].as_str().unwrap().to_uppercase()
            )
        })
        .collect();
    let id = u32::from_str_radix(frames[0].split('#').next().unwrap(), 16).unwrap();
    (case["subject_id"].as_u64().unwrap(), id & 0x7F, frames)
}

/// The transfer's frames at `t` seconds, from `node` instead of the vector's source.
fn lines_at(frames: &[String], t: u64, node: u32) -> String {
    frames
        .iter()
        .enumerate()
        .map(|(i, f)| {
            let (id, data) = f.split_once('#').unwrap();
            let id = (u32::from_str_radix(id, 16).unwrap() & !0x7F) | node;
            format!("({t}.{:06}) can0 {id:08X}#{data}\n", 100 + i)
        })
        .collect()
}

fn replay_file(dir: &std::path::Path, log: &[u8], extra: &[&str]) -> std::process::Output {
    let path = dir.join("in.log");
    std::fs::write(&path, log).unwrap();
    let mut args = vec!["replay", path.to_str().unwrap()];
    args.extend_from_slice(extra);
    propid(&args, None)
}

#[test]
fn malformed_lines_are_skipped_counted_and_named() {
    let (subject, node, frames) = vector_transfer();
    let subject = subject.to_string();
    let dir = tempfile::tempdir().unwrap();
    let out_tsv = dir.path().join("out.tsv");
    // Good transfer, then an error frame, a remote frame, a non-ASCII data field, a timestamp
    // that overflows, a half byte; then another good transfer.
    let mut log = lines_at(&frames, 1, node);
    log += "(2.000000) can0 20000080#0000000000000000\n";
    log += "(2.000001) can0 1060642A#R\n";
    log += "(2.000002) can0 1060642A#€0\n";
    log += "(99999999999999.5) can0 1060642A#E0\n";
    log += "(2.000003) can0 1060642A#0\n";
    log += &lines_at(&frames, 5, node);
    let first_bad = frames.len() + 3;
    let out = replay_file(
        dir.path(),
        log.as_bytes(),
        &["--feedback-id", &subject, "-o", out_tsv.to_str().unwrap()],
    );
    let err = String::from_utf8_lossy(&out.stderr);
    assert_eq!(out.status.code(), Some(0), "{err}");
    assert!(!err.contains("panicked"), "{err}");
    for want in [
        "2 feedback messages",
        "1 error frames",
        "1 remote frames",
        "3 malformed lines",
        &format!("in.log: line {first_bad}: `€0` is not hexadecimal data"),
        &format!(
            "in.log: line {}: timestamp `99999999999999.5` is too large",
            first_bad + 1
        ),
        &format!("in.log: line {}: `0` is not whole bytes", first_bad + 2),
    ] {
        assert!(err.contains(want), "`{want}` not in: {err}");
    }
    let tsv = std::fs::read_to_string(&out_tsv).unwrap();
    assert_eq!(tsv.lines().count(), 3, "{tsv}");
}

#[test]
fn nothing_matched_lists_what_was_seen() {
    let (subject, node, frames) = vector_transfer();
    let dir = tempfile::tempdir().unwrap();
    let log = lines_at(&frames, 1, node);
    let out = replay_file(dir.path(), log.as_bytes(), &["--feedback-id", "4321"]);
    let err = String::from_utf8_lossy(&out.stderr);
    assert_eq!(out.status.code(), Some(2), "{err}");
    assert!(
        err.contains("no feedback transfers on subject 4321")
            && err.contains(&format!(
                "subject {subject} ({} frames from node {node})",
                frames.len()
            )),
        "{err}"
    );
    // A chosen source node that is not there.
    let other = (node + 1) % 128;
    let out = replay_file(
        dir.path(),
        log.as_bytes(),
        &[
            "--feedback-id",
            &subject.to_string(),
            "--source-node",
            &other.to_string(),
        ],
    );
    let err = String::from_utf8_lossy(&out.stderr);
    assert_eq!(out.status.code(), Some(2), "{err}");
    assert!(err.contains(&format!("from node {other}")), "{err}");
    // An empty log.
    let out = replay_file(dir.path(), b"", &["--feedback-id", "100"]);
    assert_eq!(out.status.code(), Some(2));
    assert!(String::from_utf8_lossy(&out.stderr).contains("no Cyphal message frames"));
}

#[test]
fn two_source_nodes_are_refused_unless_one_is_chosen() {
    let (subject, node, frames) = vector_transfer();
    let subject = subject.to_string();
    let other = (node + 1) % 128;
    let dir = tempfile::tempdir().unwrap();
    let log = lines_at(&frames, 1, node) + &lines_at(&frames, 2, other);
    let out = replay_file(dir.path(), log.as_bytes(), &["--feedback-id", &subject]);
    let err = String::from_utf8_lossy(&out.stderr);
    assert_eq!(out.status.code(), Some(2), "{err}");
    assert!(
        err.contains("several nodes")
            && err.contains(&format!("node {node} (written)"))
            && err.contains(&format!("node {other} ("))
            && err.contains("--source-node"),
        "{err}"
    );
    assert_eq!(String::from_utf8_lossy(&out.stdout).lines().count(), 2);
    let out = replay_file(
        dir.path(),
        log.as_bytes(),
        &[
            "--feedback-id",
            &subject,
            "--source-node",
            &other.to_string(),
        ],
    );
    let err = String::from_utf8_lossy(&out.stderr);
    assert_eq!(out.status.code(), Some(0), "{err}");
    assert!(err.contains(&format!("from node {other} written")), "{err}");
    assert_eq!(String::from_utf8_lossy(&out.stdout).lines().count(), 2);
}

#[test]
fn out_of_range_ids_are_refused() {
    let dir = tempfile::tempdir().unwrap();
    for args in [
        &["--feedback-id", "9000"][..],
        &["--feedback-id", "100", "--source-node", "128"],
        &["--feedback-id", "-1"],
    ] {
        let out = replay_file(dir.path(), b"", args);
        let err = String::from_utf8_lossy(&out.stderr);
        assert_eq!(out.status.code(), Some(2), "{args:?}: {err}");
        assert!(err.contains(args[args.len() - 1]), "{err}");
    }
}
