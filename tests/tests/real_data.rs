//! The importers on real test-stand logs (tests/data/esc_test_alspitz, MIT) and what diagnose
//! finds there. Every figure docs/REAL_DATA.md and README.md state about these logs is asserted
//! here to the precision it is printed with (a figure printed as 1.964 must be 1.964 ± 0.0005).

use propid_io::import::{import_autoquad, import_rcbench, Imported, RcbenchOptions};
use propid_io::tsv::Sample;
use propid_science::diagnose::{diagnose, Condition, Decision, Options, Report};

fn data(path: &str) -> std::path::PathBuf {
    std::path::Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("data/esc_test_alspitz")
        .join(path)
}

fn samples(rows: &[propid_io::tsv::Row]) -> Vec<Sample> {
    rows.iter().map(|r| r.sample).collect()
}

/// `value` printed with `decimals` decimals reads `printed`.
#[track_caller]
fn printed(what: &str, value: f64, printed: f64, decimals: i32) {
    let half = 0.5 * 10f64.powi(-decimals) * (1.0 + 1e-9);
    assert!(
        (value - printed).abs() <= half,
        "{what}: measured {value}, the docs print {printed}"
    );
}

fn median(mut x: Vec<f64>) -> f64 {
    x.sort_by(f64::total_cmp);
    x[x.len() / 2]
}

fn rcbench(name: &str) -> (Imported, Report) {
    let imported = import_rcbench(
        &data(&format!("rcbench/Log_{name}.csv")),
        &RcbenchOptions::default(),
    )
    .unwrap();
    let r = diagnose(&samples(&imported.rows), Options::default()).unwrap();
    (imported, r)
}

fn autoquad(name: &str, kv: f64) -> (Imported, Report) {
    let imported = import_autoquad(&data(&format!("autoquad/{name}.csv")), kv).unwrap();
    let r = diagnose(&samples(&imported.rows), Options::default()).unwrap();
    (imported, r)
}

/// docs/REAL_DATA.md §1: the table, the verdict and the figures under it.
#[test]
fn rcbench_drag_law_table() {
    // (run, samples, p, p s.e., held-out gain %, c2 / 1e-8) as printed.
    let table = [
        ("2019-11-05_171350", 670, 1.964, 0.025, 0.3, 5.97),
        ("2019-11-07_174807", 633, 2.071, 0.026, 1.2, 5.92),
        ("2019-11-07_175456", 817, 2.051, 0.023, 0.6, 5.91),
        ("2019-11-07_184325", 585, 1.956, 0.028, 0.4, 5.90),
        ("2019-11-07_211050", 559, 1.976, 0.020, 0.3, 5.97),
        ("2019-11-09_181347", 605, 1.994, 0.023, 0.0, 5.79),
    ];
    // README.md: "exponent 1.96–2.07, standard errors 0.020–0.028".
    let ps: Vec<f64> = table.iter().map(|r| r.2).collect();
    let ses: Vec<f64> = table.iter().map(|r| r.3).collect();
    let span = |x: &[f64]| {
        x.iter()
            .fold((f64::MAX, f64::MIN), |(l, h), &c| (l.min(c), h.max(c)))
    };
    assert_eq!(span(&ps), (1.956, 2.071));
    assert_eq!(span(&ses), (0.020, 0.028));
    let (mut c2s, mut zs) = (Vec::new(), Vec::new());
    let (mut torque_dt, mut rpm_rate) = (Vec::new(), Vec::new());
    for (run, n, p, se, gain, c2) in table {
        let (imported, r) = rcbench(run);
        let law = r.steady_state.as_ref().expect("steady-state drag law");
        assert_eq!(law.samples, n, "{run}: samples");
        printed(&format!("{run}: p"), law.exponent, p, 3);
        printed(&format!("{run}: p s.e."), law.exponent_stderr, se, 3);
        printed(
            &format!("{run}: held-out gain"),
            law.cv_gain_percent,
            gain,
            1,
        );
        printed(&format!("{run}: c2"), law.c2 * 1e8, c2, 2);
        // The verdict: p = 2 within three standard errors, no gain reaching the 3 % it takes to
        // be named, nothing named.
        assert!(
            (law.exponent - 2.0).abs() < 3.0 * law.exponent_stderr,
            "{run}: p = {} ± {}",
            law.exponent,
            law.exponent_stderr
        );
        assert!(
            law.cv_gain_percent < 3.0 && law.decision != Decision::Named && r.effects.is_empty()
        );
        c2s.push(law.c2);
        zs.push((law.exponent - 2.0).abs() / law.exponent_stderr);
        // The rates: the torque's median sample interval, the rpm's median change interval.
        let q: Vec<f64> = imported
            .rows
            .iter()
            .filter(|r| r.sample.force.is_finite())
            .map(|r| r.sample.t)
            .collect();
        torque_dt.push(median(q.windows(2).map(|w| w[1] - w[0]).collect()));
        let mut changes = Vec::new();
        let mut last = (imported.rows[0].sample.t, imported.rows[0].sample.velocity);
        for r in &imported.rows[1..] {
            if r.sample.velocity != last.1 {
                changes.push(r.sample.t - last.0);
                last = (r.sample.t, r.sample.velocity);
            }
        }
        rpm_rate.push(1.0 / median(changes));
    }
    // "The exponent is 2 within three standard errors in every run (0.3 to 2.7 of them)".
    let (zlo, zhi) = span(&zs);
    eprintln!("exponent - 2 in standard errors: {zlo} .. {zhi}");
    printed("fewest standard errors from 2", zlo, 0.3, 1);
    printed("most standard errors from 2", zhi, 2.7, 1);
    // "c2 agrees across three motors and four ESCs within ±1.6 %: c2 = 5.9·10⁻⁸, C_Q ≈ 0.011".
    let (lo, hi) = c2s
        .iter()
        .fold((f64::MAX, f64::MIN), |(l, h), &c| (l.min(c), h.max(c)));
    let mean = c2s.iter().sum::<f64>() / c2s.len() as f64;
    printed("c2 half-spread %", 100.0 * (hi - lo) / (hi + lo), 1.6, 1);
    printed("mean c2", mean * 1e8, 5.9, 1);
    let cq = 4.0 * std::f64::consts::PI.powi(2) * mean / (1.2 * 0.1778f64.powi(5));
    printed("C_Q", cq, 0.011, 3);
    // "load-cell torque every 150–163 ms, electrical rpm changing at 41–142 Hz".
    let (tlo, thi) = torque_dt
        .iter()
        .fold((f64::MAX, f64::MIN), |(l, h), &c| (l.min(c), h.max(c)));
    printed("torque interval min [ms]", tlo * 1e3, 150.0, 0);
    printed("torque interval max [ms]", thi * 1e3, 163.0, 0);
    let (rlo, rhi) = rpm_rate
        .iter()
        .fold((f64::MAX, f64::MIN), |(l, h), &c| (l.min(c), h.max(c)));
    eprintln!("rpm change rate {rlo} .. {rhi} Hz");
    printed("rpm rate min [Hz]", rlo, RPM_RATE.0, 0);
    printed("rpm rate max [Hz]", rhi, RPM_RATE.1, 0);
}

/// The electrical rpm's change rates across the six runs as docs/REAL_DATA.md prints them.
const RPM_RATE: (f64, f64) = (41.0, 142.0);

/// The ESC32 F40 log, as the selection over combinations reads it (docs/REAL_DATA.md §3). Before
/// it (one effect at a time, a 3 % threshold on the acceleration equation, a veto from the
/// simulation) diagnose named a 57.1 ms force-sensor lag and 6.09 mN·m of braking (simulated
/// velocity 38.1 % better). Scored by both held-out errors fold by fold, a 3.57 mN·m constant
/// torque explains the held-out simulation far better (76.9 % against 20.1 %) and the data cannot
/// separate it from an 80 ms force-sensor lag; braking is no better than the constant, which is
/// simpler. J depends on the choice (1.80·10⁻⁵ with the constant, 3.75·10⁻⁵ with the lag): the
/// report says so, with the run that would separate them.
#[test]
fn esc32_f40_a_constant_torque_or_a_telemetry_lag() {
    use propid_science::diagnose::{EffectKind, Verdict};
    let (imported, r) = autoquad("f40_steps_5-2", 1600.0);
    assert!(imported.assumptions.iter().any(|a| a.contains("Kt")));
    assert_eq!(r.verdict, Verdict::Ambiguous);
    let names: Vec<EffectKind> = r.effects.iter().map(|e| e.effect).collect();
    assert_eq!(names, [EffectKind::CoulombFriction], "{names:?}");
    printed("constant torque [mN·m]", r.effects[0].value * 1e3, 3.57, 2);
    let lag = r
        .ambiguities
        .iter()
        .find(|a| a.between[1] == EffectKind::ForceSensorLag)
        .expect("ambiguous with a force-sensor lag");
    printed("the lag [ms]", lag.values[1] * 1e3, 79.9, 1);
    assert!(lag.agreed.is_none(), "{lag:?}");
    printed(
        "J with the constant [1e-5]",
        r.extended.inertia * 1e5,
        1.80,
        2,
    );
    printed(
        "J with the lag [1e-5]",
        lag.alternative.inertia * 1e5,
        3.75,
        2,
    );
    printed(
        "simulation gain [%]",
        r.simulation_rms.gain_percent,
        49.6,
        1,
    );
    assert!(r
        .ambiguities
        .iter()
        .any(|a| a.between == [EffectKind::CoulombFriction, EffectKind::ForceOffset]));
    // The inertia of a 7-inch propeller and an outrunner rotor: 1e-5 .. 1e-4 kg·m², either way.
    assert!(
        (1e-5..1e-4).contains(&r.extended.inertia)
            && (1e-5..1e-4).contains(&lag.alternative.inertia),
        "J {} or {}",
        r.extended.inertia,
        lag.alternative.inertia
    );
}

/// The ESC32 F60 log (docs/REAL_DATA.md §3). Before the selection over combinations diagnose
/// named a 64.5 ms force-sensor lag alone (8.3 % better simulated velocity) and put half of the
/// remaining held-out error in t = 92.5–95.1 s. Now: a 2.68 mN·m constant torque and a 24.1 ms
/// force-sensor delay, both better on held-out folds, yet the model fitted on the first 70 %
/// simulates the last 30 % worse than the seed's (−53 %): that stretch holds the log's one step
/// to full duty and the drop from it, which no other stretch resembles; the remaining error sits
/// in t = 94.1–97.0 s, the drop (6.2 times the rest's), unexplained.
#[test]
fn esc32_f60_remaining_error_is_localized() {
    use propid_science::diagnose::{EffectKind, Verdict};
    let (_, r) = autoquad("esc32v3_f60-1", 1750.0);
    let names: Vec<EffectKind> = r.effects.iter().map(|e| e.effect).collect();
    assert_eq!(
        names,
        [EffectKind::CoulombFriction, EffectKind::ForceSensorLag],
        "{names:?}"
    );
    printed("constant torque [mN·m]", r.effects[0].value * 1e3, 2.68, 2);
    printed("delay [ms]", r.effects[1].value * 1e3, 24.1, 1);
    printed(
        "simulation gain [%]",
        r.simulation_rms.gain_percent,
        -53.0,
        1,
    );
    assert_eq!(r.verdict, Verdict::Ambiguous);
    let c = r.concentration.as_ref().expect("the error is localized");
    assert_eq!(c.condition, Condition::TimeWindow);
    printed("window from [s]", c.from_s, 94.1, 1);
    printed("window to [s]", c.to_s, 97.0, 1);
    printed("error share [%]", c.error_percent, 17.5, 1);
    printed("ratio", c.ratio, 6.2, 1);
}

/// docs/REAL_DATA.md §3, F60: what the localized error holds. The window holds the end of the
/// log's one step at 100 % duty and the drop to 50 %: there the rotor slows at over 8,000
/// rad/s² while the reported force stays positive (braking Kt·I_bus/duty does not show). At full
/// duty the force per ω² also reads 5 % low; corrected, the error still sits in the drop.
#[test]
fn esc32_f60_error_sits_in_the_drop_from_full_duty() {
    let (imported, r) = autoquad("esc32v3_f60-1", 1750.0);
    // The duty in % (the TSV's `command` is the ratio).
    let duty: Vec<f64> = imported
        .stand(propid_io::tsv::StandColumn::Command)
        .iter()
        .map(|d| d * 100.0)
        .collect();
    // Per duty step: its time span, mean speed and Σ F / Σ ω² (the drag law's c2 at that step).
    let step = |d: f64| {
        let rows: Vec<(f64, f64, f64)> = imported
            .rows
            .iter()
            .zip(&duty)
            .filter(|(row, &c)| {
                (c - d).abs() < 1e-6 && row.sample.force.is_finite() && row.sample.velocity > 100.0
            })
            .map(|(row, _)| (row.sample.t, row.sample.force, row.sample.velocity))
            .collect();
        let c2 =
            rows.iter().map(|r| r.1).sum::<f64>() / rows.iter().map(|r| r.2 * r.2).sum::<f64>();
        let speed = rows.iter().map(|r| r.2).sum::<f64>() / rows.len() as f64;
        (rows[0].0, rows[rows.len() - 1].0, speed, c2)
    };
    let full = step(100.0);
    let below: Vec<(f64, f64, f64, f64)> = [65.0, 70.0, 75.0, 80.0, 85.0, 90.0, 95.0]
        .map(step)
        .to_vec();
    printed("full duty from", full.0, 91.8, 1);
    printed("full duty to", full.1, 94.1, 1);
    printed("speed at 95 %", below[6].2, 1683.0, 0);
    printed("speed at 100 %", full.2, 1611.0, 0);
    printed("c2 at 100 % [1e-8]", full.3 * 1e8, 5.01, 2);
    let (lo, hi) = below.iter().fold((f64::INFINITY, 0.0f64), |(lo, hi), s| {
        (lo.min(s.3), hi.max(s.3))
    });
    printed("c2 at 65-95 %, lowest [1e-8]", lo * 1e8, 5.24, 2);
    printed("c2 at 65-95 %, highest [1e-8]", hi * 1e8, 5.29, 2);
    // The window starts within the full-duty step and holds the drop that ends it.
    let c = r.concentration.as_ref().expect("the error is localized");
    // The window (a thirtieth of the record, slid by half of one) holds the drop.
    assert!(
        c.from_s <= full.1 && c.to_s > full.1 + 0.5,
        "{c:?} against {full:?}"
    );
    // The drop: within 0.15 s of the last full-duty sample the rotor slows at over 8,000 rad/s²
    // while every reported force is positive.
    let drop: Vec<&propid_io::tsv::Row> = imported
        .rows
        .iter()
        .filter(|row| row.sample.t > full.1 && row.sample.t < full.1 + 0.15)
        .collect();
    let fastest = drop
        .iter()
        .map(|row| row.sample.acceleration)
        .fold(f64::INFINITY, f64::min);
    printed(
        "deceleration in the drop [1e3 rad/s²]",
        fastest / 1e3,
        -8.7,
        1,
    );
    assert!(
        drop.iter()
            .all(|row| !row.sample.force.is_finite() || row.sample.force > 0.0),
        "the reported force stays positive"
    );
    // The 5 % misreading at full duty, corrected, is not what the window holds: the error
    // still sits in the drop.
    let mut corrected = imported.rows.clone();
    for (row, &d) in corrected.iter_mut().zip(&duty) {
        if (d - 100.0).abs() < 1e-6 {
            row.sample.force *= below[6].3 / full.3;
        }
    }
    let fixed = diagnose(&samples(&corrected), Options::default()).unwrap();
    let c = fixed.concentration.as_ref().expect("still localized");
    assert!(c.from_s <= full.1 && c.to_s > full.1 + 0.5, "{c:?}");
}
