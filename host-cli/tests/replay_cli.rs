//! `propid replay` on candump logs made from the PyCyphal frame vectors: the DoF3rdTs values
//! come back out as TSV rows; malformed lines are reported with their line number.

mod common;

use common::{propid, repo};
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
        let out = propid(
            &[
                "replay",
                path.to_str().unwrap(),
                "--feedback-id",
                &subject.to_string(),
            ],
            None,
        );
        assert!(
            out.status.success(),
            "{}",
            String::from_utf8_lossy(&out.stderr)
        );
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

#[test]
fn malformed_lines_name_their_number() {
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("bad.log");
    std::fs::write(
        &path,
        "(1.000001) can0 1060642A#03E0\n(1.000002) can0 1060642A#0\n",
    )
    .unwrap();
    let out = propid(
        &["replay", path.to_str().unwrap(), "--feedback-id", "100"],
        None,
    );
    assert_eq!(out.status.code(), Some(2));
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(
        err.contains("bad.log: line 2") && err.contains("whole bytes"),
        "{err}"
    );
}
