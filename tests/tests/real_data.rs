//! The importers on real test-stand logs (tests/data/esc_test_alspitz, MIT) and what diagnose
//! finds there: facts computed from the data, checked against physical expectations.

use propid_io::import::{import_autoquad, import_rcbench};
use propid_io::tsv::Sample;
use propid_science::diagnose::{diagnose, Options};

fn data(path: &str) -> std::path::PathBuf {
    std::path::Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("data/esc_test_alspitz")
        .join(path)
}

fn samples(rows: &[propid_io::tsv::Row]) -> Vec<Sample> {
    rows.iter().map(|r| r.sample).collect()
}

#[test]
fn rcbench_plateaus_confirm_the_quadratic_drag_law() {
    let imported = import_rcbench(&data("rcbench/Log_2019-11-07_184325.csv")).unwrap();
    assert!(imported
        .assumptions
        .iter()
        .any(|a| a.contains("load-cell torque")));
    // The torque is sparse (~6.7 Hz) and never interpolated.
    let with_torque = imported
        .rows
        .iter()
        .filter(|r| r.sample.force.is_finite())
        .count();
    assert!(
        with_torque > 500 && with_torque < imported.rows.len() / 10,
        "{with_torque}"
    );
    let r = diagnose(&samples(&imported.rows), Options::default()).unwrap();
    let law = r.steady_state.expect("steady-state drag law");
    // p = 2 within three standard errors, no significant held-out gain: the seed's law holds.
    assert!(
        (law.exponent - 2.0).abs() < 3.0 * law.exponent_stderr + 0.02,
        "p = {} ± {}",
        law.exponent,
        law.exponent_stderr
    );
    assert!(!law.selected && r.effects.is_empty());
    // c2 of a 7-inch propeller: C_Q = 4π²c2/(ρD⁵) in the usual 0.005–0.02.
    let cq = 4.0 * std::f64::consts::PI.powi(2) * law.c2 / (1.2 * 0.1778f64.powi(5));
    assert!((0.005..0.02).contains(&cq), "C_Q {cq}");
}

#[test]
fn esc_telemetry_shows_its_lag_and_the_motor_friction() {
    let imported = import_autoquad(&data("autoquad/f40_steps_5-2.csv"), 1600.0).unwrap();
    assert!(imported.assumptions.iter().any(|a| a.contains("Kt")));
    let r = diagnose(&samples(&imported.rows), Options::default()).unwrap();
    let names: Vec<&str> = r.effects.iter().map(|e| e.name).collect();
    assert!(names.contains(&"force_sensor_lag"), "{names:?}");
    let lag = r
        .effects
        .iter()
        .find(|e| e.name == "force_sensor_lag")
        .unwrap()
        .value;
    assert!((0.01..0.1).contains(&lag), "telemetry lag {lag} s");
    // The inertia of a 7-inch propeller and an outrunner rotor: 1e-5 .. 1e-4 kg·m².
    assert!(
        (1e-5..1e-4).contains(&r.extended.mass),
        "J {}",
        r.extended.mass
    );
    assert!(
        r.simulation_rms.gain_percent > 10.0,
        "{:?}",
        r.simulation_rms
    );
}

#[test]
fn importers_reject_bad_files_with_the_place() {
    let dir = tempfile::tempdir().unwrap();
    let p = dir.path().join("aq.csv");
    std::fs::write(&p, "Timestamp,Amps,RPM,Duty\nx,1.0,fast,50\n").unwrap();
    let e = import_autoquad(&p, 1600.0).err().unwrap().to_string();
    assert!(e.contains("aq.csv: line 2, column `RPM`: `fast`"), "{e}");
    std::fs::write(&p, "Time (s),Current (A)\n0,1\n").unwrap();
    let e = import_rcbench(&p).err().unwrap().to_string();
    assert!(e.contains("line 1: no column `Torque (N·m)`"), "{e}");
    assert!(import_autoquad(&p, -3.0).is_err());
}
