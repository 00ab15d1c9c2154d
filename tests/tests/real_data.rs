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
    let cq = 4.0 * std::f64::consts::PI.powi(2) * mean / (1.225 * 0.1778f64.powi(5));
    printed("C_Q", cq, 0.011, 3);
    // "load-cell torque every 150–163 ms, electrical rpm changing at 41–142 Hz".
    let (tlo, thi) = torque_dt
        .iter()
        .fold((f64::MAX, f64::MIN), |(l, h), &c| (l.min(c), h.max(c)));
    printed("torque interval min [ms]", tlo * 1e3, 150.0, 0);
    printed("torque interval max [ms]", thi * 1e3, 163.0, 0);
    printed("torque rate min [Hz]", 1.0 / thi, 6.1, 1);
    printed("torque rate max [Hz]", 1.0 / tlo, 6.7, 1);
    let (rlo, rhi) = rpm_rate
        .iter()
        .fold((f64::MAX, f64::MIN), |(l, h), &c| (l.min(c), h.max(c)));
    eprintln!("rpm change rate {rlo} .. {rhi} Hz");
    printed("rpm rate min [Hz]", rlo, RPM_RATE.0, 0);
    printed("rpm rate max [Hz]", rhi, RPM_RATE.1, 0);
}

/// The electrical rpm's change rates across the six runs as docs/REAL_DATA.md prints them.
const RPM_RATE: (f64, f64) = (41.0, 142.0);

/// The ESC32 F40 log, as the selection over combinations reads it (docs/REAL_DATA.md §2). At full
/// duty the ESC32's speed stops updating (1662.2 rad/s repeated for a second) and then jumps: the
/// held-out error concentrates there, and the diagnosis leaves the 0.4 s where it sits
/// (t = 100.4–100.8 s, 41 samples) out of every fit and score. Then a 3.63 mN·m constant torque
/// (Coulomb friction or an offset: the rotor never reverses) and a 37.2 ms lag of the reported
/// force are named together, and J = 2.35·10⁻⁵ (the seed's model on the same samples: 3.78·10⁻⁵).
/// Before the span was left out, the same selection could not separate the constant from an 80 ms
/// lag (J 1.80 or 3.75·10⁻⁵); before the selection over combinations, one effect at a time named a
/// 57.1 ms lag and 6.09 mN·m of braking.
#[test]
fn esc32_f40_a_constant_torque_and_a_telemetry_lag() {
    use propid_science::diagnose::{EffectKind, Verdict};
    let (imported, r) = autoquad("f40_steps_5-2", 1600.0);
    assert!(imported.assumptions.iter().any(|a| a.contains("Kt")));
    // The held speed at full duty: the longest run of one repeated velocity with the duty at 1.
    let command = imported.stand(propid_io::tsv::StandColumn::Command);
    let (mut held, mut run) = ((0usize, f64::NAN, 0usize), 0usize);
    for (k, w) in imported.rows.windows(2).enumerate() {
        let same = w[1].sample.velocity == w[0].sample.velocity && command[k + 1] == 1.0;
        run = if same { run + 1 } else { 0 };
        if run > held.0 {
            held = (run, w[1].sample.velocity, k + 1);
        }
    }
    assert!(held.0 >= 90, "{held:?}");
    printed("held speed at full duty [rad/s]", held.1, 1662.2, 1);
    // "repeats 1662.2 rad/s for a second (t = 99.7–100.7 s)".
    let t = |row: usize| imported.rows[row].sample.t;
    printed("held from [s]", t(held.2 - held.0), 99.7, 1);
    printed("held until [s]", t(held.2), 100.7, 1);
    assert_eq!(r.verdict, Verdict::Ambiguous);
    let names: Vec<EffectKind> = r.effects.iter().map(|e| e.effect).collect();
    assert_eq!(
        names,
        [EffectKind::CoulombFriction, EffectKind::ForceSensorLag],
        "{names:?}"
    );
    let left = r
        .left_out
        .as_ref()
        .expect("the frozen speed's end is left out");
    printed("left out from [s]", left.from_s, 100.4, 1);
    printed("left out to [s]", left.to_s, 100.8, 1);
    assert_eq!(left.samples, 41);
    printed(
        "J with those samples [%]",
        100.0 * (left.inertia_with / r.extended.inertia - 1.0),
        -4.4,
        1,
    );
    // The seed's model and the extended one, as docs/REAL_DATA.md §2 states them.
    printed("seed J [1e-5]", r.base.inertia * 1e5, 3.78, 2);
    printed("seed c2 [1e-8]", r.base.c2 * 1e8, 5.53, 2);
    printed(
        "seed simulation RMS [rad/s]",
        r.simulation_rms.base,
        58.2,
        1,
    );
    printed(
        "extended simulation RMS [rad/s]",
        r.simulation_rms.extended,
        26.1,
        1,
    );
    printed("extended J [1e-5]", r.extended.inertia * 1e5, 2.35, 2);
    printed("extended c2 [1e-8]", r.extended.c2 * 1e8, 5.34, 2);
    // "11 % and 13 % below the load cell's (§1) on the same motor and ESC": 11-05, F40, ESC32v3.
    printed(
        "below the load cell [%]",
        100.0 * (1.0 - r.extended.c2 / 5.97e-8),
        11.0,
        0,
    );
    printed("constant torque [mN·m]", r.effects[0].value * 1e3, 3.63, 2);
    printed("the lag [ms]", r.effects[1].value * 1e3, 37.2, 1);
    printed(
        "simulation gain [%]",
        r.simulation_rms.gain_percent,
        55.2,
        1,
    );
    // The one tie left: Coulomb friction or an offset, the same column on a rotor that never
    // reverses, and J the same with either.
    assert_eq!(r.ambiguities.len(), 1);
    assert_eq!(
        r.ambiguities[0].between,
        [EffectKind::CoulombFriction, EffectKind::ForceOffset]
    );
    assert!(r.ambiguities[0].agreed.is_some());
}

/// The ESC32 F60 log (docs/REAL_DATA.md §2, §4). Before the selection over combinations diagnose
/// named a 64.5 ms force-sensor lag alone (8.3 % better simulated velocity). Now the held-out error
/// concentrates in t = 94.1–97.0 s, the drop from the log's one step at full duty (15.1 times the
/// rest's), and the 3.2 s where it sits (t = 93.7–96.9 s) are left out of every fit and score (with
/// them J reads 20.5 % higher). Then a 2.55 mN·m constant torque is named, tied with its offset twin,
/// with a viscous friction and a drag exponent of 1.91 (J 2.36 and 2.45·10⁻⁵, agreed with the
/// constant's 2.43) and with a 42.3 ms force-sensor lag (J 3.35·10⁻⁵: not agreed); the model fitted
/// on the first 70 % still simulates the last 30 %, which holds that step, worse than the seed's
/// (−57.4 %).
#[test]
fn esc32_f60_remaining_error_is_localized() {
    use propid_science::diagnose::{EffectKind, Verdict};
    let (_, r) = autoquad("esc32v3_f60-1", 1750.0);
    let names: Vec<EffectKind> = r.effects.iter().map(|e| e.effect).collect();
    assert_eq!(names, [EffectKind::CoulombFriction], "{names:?}");
    printed("seed J [1e-5]", r.base.inertia * 1e5, 3.09, 2);
    printed(
        "seed simulation RMS [rad/s]",
        r.simulation_rms.base,
        58.6,
        1,
    );
    printed(
        "extended simulation RMS [rad/s]",
        r.simulation_rms.extended,
        92.3,
        1,
    );
    printed("extended J [1e-5]", r.extended.inertia * 1e5, 2.43, 2);
    printed("extended c2 [1e-8]", r.extended.c2 * 1e8, 5.12, 2);
    // "... and 13 % below the load cell's": 11-07 18:43, F60, ESC32v3.
    printed(
        "below the load cell [%]",
        100.0 * (1.0 - r.extended.c2 / 5.90e-8),
        13.0,
        0,
    );
    printed("constant torque [mN·m]", r.effects[0].value * 1e3, 2.55, 2);
    printed(
        "simulation gain [%]",
        r.simulation_rms.gain_percent,
        -57.4,
        1,
    );
    assert_eq!(r.verdict, Verdict::Ambiguous);
    let lag = r
        .ambiguities
        .iter()
        .find(|a| a.between[1] == EffectKind::ForceSensorLag)
        .expect("ambiguous with a force-sensor lag");
    printed("the lag [ms]", lag.values[1] * 1e3, 42.3, 1);
    printed(
        "J with the lag [1e-5]",
        lag.alternative.inertia * 1e5,
        3.35,
        2,
    );
    assert!(lag.agreed.is_none(), "{lag:?}");
    for (kind, inertia) in [
        (EffectKind::ViscousFriction, 2.36),
        (EffectKind::DragExponent, 2.45),
    ] {
        let a = r
            .ambiguities
            .iter()
            .find(|a| a.between[1] == kind)
            .unwrap_or_else(|| panic!("ambiguous with {kind}"));
        printed("J with it [1e-5]", a.alternative.inertia * 1e5, inertia, 2);
        assert!(a.agreed.is_some(), "{a:?}");
        if kind == EffectKind::DragExponent {
            printed("the exponent", a.values[1], 1.91, 2);
        }
    }
    let c = r.concentration.as_ref().expect("the error is localized");
    assert_eq!(c.condition, Condition::TimeWindow);
    printed("window from [s]", c.from_s, 94.1, 1);
    printed("window to [s]", c.to_s, 97.0, 1);
    printed("ratio", c.ratio, 15.1, 1);
    let left = r.left_out.as_ref().expect("the drop is left out");
    printed("left out from [s]", left.from_s, 93.7, 1);
    printed("left out to [s]", left.to_s, 96.9, 1);
    printed(
        "J with those samples [%]",
        100.0 * (left.inertia_with / r.extended.inertia - 1.0),
        20.5,
        1,
    );
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
    printed(
        "full duty below the 95 % step [%]",
        100.0 * (1.0 - full.3 / below[6].3),
        5.0,
        0,
    );
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

// ---------------------------------------------------------------------------------------------
// docs/REAL_DATA.md §2: what the ESC32 telemetry's lag is, tested against its duty column.

use propid_core::estimate::NormalEquations;

/// The named numeric columns of a plain comma-separated log with one header line.
fn csv_columns(path: &std::path::Path, names: &[&str]) -> Vec<Vec<f64>> {
    let text = std::fs::read_to_string(path).unwrap();
    let mut lines = text.lines();
    let header: Vec<&str> = lines.next().unwrap().split(',').collect();
    let index: Vec<usize> = names
        .iter()
        .map(|n| header.iter().position(|h| h == n).expect(n))
        .collect();
    let mut columns = vec![Vec::new(); names.len()];
    for line in lines {
        let fields: Vec<&str> = line.split(',').collect();
        for (column, &k) in columns.iter_mut().zip(&index) {
            column.push(fields[k].parse().unwrap());
        }
    }
    columns
}

/// Central difference over the two neighbouring rows (±10 ms, as diagnose's slopes).
fn central_slope(t: &[f64], x: &[f64]) -> Vec<f64> {
    let mut s = vec![f64::NAN; x.len()];
    for i in 1..x.len() - 1 {
        s[i] = (x[i + 1] - x[i - 1]) / (t[i + 1] - t[i - 1]);
    }
    s
}

/// `x` read `delay` seconds later, linear between rows (NaN past the end).
fn later(t: &[f64], x: &[f64], i: usize, delay: f64) -> f64 {
    let target = t[i] + delay;
    let k = t.partition_point(|&s| s <= target);
    if k == 0 || k >= t.len() {
        return f64::NAN;
    }
    let f = (target - t[k - 1]) / (t[k] - t[k - 1]);
    x[k - 1] + f * (x[k] - x[k - 1])
}

/// `x` through a first-order lag of time constant `tau` at row `i`, started at its value 0.3 s
/// earlier (ten time constants of the longest lag tried) and exact for `x` linear between rows.
fn lowpass(t: &[f64], x: &[f64], tau: f64, i: usize) -> f64 {
    let from = t.partition_point(|&s| s < t[i] - 0.3).min(i);
    let mut y = x[from];
    for k in from + 1..=i {
        let h = t[k] - t[k - 1];
        let e = (-h / tau).exp();
        // y' = (x − y)/τ with x linear from x[k−1] to x[k] over h.
        let slope = (x[k] - x[k - 1]) / h;
        y = x[k] - tau * slope + (y - x[k - 1] + tau * slope) * e;
    }
    y
}

/// One ESC32 log as the mechanism analysis reads it.
struct Esc32 {
    t: Vec<f64>,
    /// Velocity [rad/s] and its central difference [rad/s²], as the importer writes them.
    w: Vec<f64>,
    a: Vec<f64>,
    /// The importer's torque Kt·I_bus/duty [N·m] and its slope.
    force: Vec<f64>,
    force_rate: Vec<f64>,
    /// The applied duty [fraction of the PWM period].
    duty: Vec<f64>,
    /// Kt·I_bus [N·m] (the logged bus current times the nominal torque constant) and its slope.
    g: Vec<f64>,
    g_rate: Vec<f64>,
    /// Bus current [A] and voltage [V] as logged, and the current's slope.
    amps: Vec<f64>,
    amps_rate: Vec<f64>,
    volts: Vec<f64>,
    /// Rows the models are compared on: duty above 5 %, faster than 100 rad/s, every column
    /// defined, 80 ms clear of both ends (room for the delays tried).
    rows: Vec<usize>,
}

fn esc32(name: &str, kv: f64) -> Esc32 {
    let imported = import_autoquad(&data(&format!("autoquad/{name}.csv")), kv).unwrap();
    let [amps, volts]: [Vec<f64>; 2] = csv_columns(
        &data(&format!("autoquad/{name}.csv")),
        &["Amps", "Batt. Volts"],
    )
    .try_into()
    .unwrap();
    let kt = 60.0 / (std::f64::consts::TAU * kv);
    let s: Vec<Sample> = samples(&imported.rows);
    let t: Vec<f64> = s.iter().map(|s| s.t).collect();
    // The duty as a ratio (the TSV's `command`).
    let duty: Vec<f64> = imported.stand(propid_io::tsv::StandColumn::Command);
    let force: Vec<f64> = s.iter().map(|s| s.force).collect();
    let g: Vec<f64> = amps.iter().map(|i| kt * i).collect();
    let (force_rate, g_rate, amps_rate) = (
        central_slope(&t, &force),
        central_slope(&t, &g),
        central_slope(&t, &amps),
    );
    let n = t.len();
    let rows = (8..n - 8)
        .filter(|&i| {
            duty[i] > 0.05
                && s[i].velocity > 100.0
                && s[i].acceleration.is_finite()
                && force_rate[i].is_finite()
                && g_rate[i].is_finite()
        })
        .collect();
    Esc32 {
        w: s.iter().map(|s| s.velocity).collect(),
        a: s.iter().map(|s| s.acceleration).collect(),
        t,
        force,
        force_rate,
        duty,
        g,
        g_rate,
        amps,
        amps_rate,
        volts,
        rows,
    }
}

/// Blocked 5-fold cross-validation of a linear model of `y` (fit on four contiguous fifths of
/// `rows`, judged on the fifth): the pooled held-out mean squared error and each fold's held-out
/// sum of squares; infinite where a training set cannot identify the model (a column that is
/// zero throughout it).
fn held_out<const N: usize>(
    rows: &[usize],
    y: impl Fn(usize) -> f64,
    phi: impl Fn(usize) -> [f64; N],
) -> (f64, [f64; 5]) {
    let k = rows.len();
    let sums: Vec<NormalEquations<f64, N>> = (0..5)
        .map(|f| {
            let mut ne = NormalEquations::new();
            for &i in &rows[f * k / 5..(f + 1) * k / 5] {
                ne.update(&phi(i), y(i));
            }
            ne
        })
        .collect();
    let mut per_fold = [0.0; 5];
    for (f, fold) in per_fold.iter_mut().enumerate() {
        let mut train = NormalEquations::new();
        for (_, s) in sums.iter().enumerate().filter(|(g, _)| *g != f) {
            train.merge(s);
        }
        *fold = match train.solve() {
            Ok(fit) => sums[f].residual_sum_of_squares(&fit.theta),
            Err(_) => f64::INFINITY,
        };
    }
    (per_fold.iter().sum::<f64>() / k as f64, per_fold)
}

/// A model's held-out evidence against a reference: gain in % and folds won.
struct Evidence {
    /// The tuned parameter (s, or the parameter's own unit), NaN for none.
    value: f64,
    gain_percent: f64,
    folds_won: usize,
    /// The parameter each fold's held-out error prefers on its own (grid points).
    fold_values: (f64, f64),
}

/// Tunes a model's one parameter on [lo, hi] by its pooled held-out error (a grid of `step`,
/// then golden-section refinement within a step of the best point) and states its evidence
/// against `reference` (pooled error, per-fold errors).
fn tuned<const N: usize>(
    rows: &[usize],
    y: &impl Fn(usize) -> f64,
    reference: (f64, [f64; 5]),
    (lo, hi, step): (f64, f64, f64),
    phi: impl Fn(f64, usize) -> [f64; N],
) -> Evidence {
    let score = |p: f64| held_out(rows, y, |i| phi(p, i));
    let grid: Vec<(f64, (f64, [f64; 5]))> = (0..=((hi - lo) / step).round() as usize)
        .map(|k| lo + k as f64 * step)
        .map(|p| (p, score(p)))
        .collect();
    let best = grid
        .iter()
        .min_by(|a, b| a.1 .0.total_cmp(&b.1 .0))
        .unwrap()
        .0;
    let (mut a, mut b) = ((best - step).max(lo), (best + step).min(hi));
    let r = (5f64.sqrt() - 1.0) / 2.0;
    for _ in 0..30 {
        let (c, d) = (b - r * (b - a), a + r * (b - a));
        if score(c).0 < score(d).0 {
            b = d;
        } else {
            a = c;
        }
    }
    let value = 0.5 * (a + b);
    let (mse, per_fold) = score(value);
    let fold_best: Vec<f64> = (0..5)
        .map(|f| {
            grid.iter()
                .min_by(|x, y| x.1 .1[f].total_cmp(&y.1 .1[f]))
                .unwrap()
                .0
        })
        .collect();
    Evidence {
        value,
        gain_percent: 100.0 * (1.0 - mse / reference.0),
        folds_won: (0..5).filter(|&f| per_fold[f] < reference.1[f]).count(),
        fold_values: fold_best
            .iter()
            .fold((f64::MAX, f64::MIN), |(l, h), &v| (l.min(v), h.max(v))),
    }
}

/// The lag models of docs/REAL_DATA.md §2 on one log, against the seed's regressors.
struct LagModels {
    /// The seed's regressors and a constant torque.
    constant: Evidence,
    /// A first-order lag of the torque Kt·I_bus/duty (what `force_sensor_lag` models).
    force_lag: Evidence,
    /// A first-order lag of the bus current, before it is divided by the duty.
    current_lag: Evidence,
    /// A pure delay of the bus current.
    current_delay: Evidence,
    /// A first-order lag of the applied duty (a slew the duty column does not show): the torque
    /// Kt·I_bus over the lagged duty.
    duty_lag: Evidence,
    /// The current lag and a braking torque ∝ max(0, k·ω − duty): regeneration the current
    /// would not show (gain over the current-lag model).
    braking_on_top: Evidence,
    /// The current-lag model fitted to every row: J [kg·m²], c2 [N·m·s²/rad²] and the constant
    /// torque [N·m].
    current_lag_fit: [f64; 3],
    /// No current at all: a torque driven by the duty against the back-EMF (k₁·duty − k₂·ω).
    duty_driven: Evidence,
}

fn lag_models(e: &Esc32) -> LagModels {
    let y = |i: usize| e.a[i];
    let rows = &e.rows;
    let seed = held_out(rows, y, |i| [e.force[i], -e.w[i] * e.w[i]]);
    let fixed = |f: (f64, [f64; 5])| Evidence {
        value: f64::NAN,
        gain_percent: 100.0 * (1.0 - f.0 / seed.0),
        folds_won: (0..5).filter(|&k| f.1[k] < seed.1[k]).count(),
        fold_values: (f64::NAN, f64::NAN),
    };
    let w2 = |i: usize| -e.w[i] * e.w[i];
    let current = |tau: f64, i: usize| (e.g[i] + tau * e.g_rate[i]) / e.duty[i];
    let current_lag = tuned(rows, &y, seed, (0.0, 0.1, 0.0005), |tau, i| {
        [current(tau, i), w2(i), -1.0]
    });
    let with_lag = held_out(rows, y, |i| [current(current_lag.value, i), w2(i), -1.0]);
    let braking_on_top = tuned(rows, &y, with_lag, (1e-4, 1e-3, 2e-5), |k, i| {
        [
            current(current_lag.value, i),
            w2(i),
            -1.0,
            -(k * e.w[i] - e.duty[i]).max(0.0),
        ]
    });
    let duty_lag = tuned(rows, &y, seed, (0.001, 0.1, 0.001), |tau, i| {
        [e.g[i] / lowpass(&e.t, &e.duty, tau, i), w2(i), -1.0]
    });
    let mut all = NormalEquations::new();
    for &i in rows {
        all.update(&[current(current_lag.value, i), w2(i), -1.0], y(i));
    }
    let theta = all.solve().unwrap().theta;
    LagModels {
        current_lag_fit: [1.0 / theta[0], theta[1] / theta[0], theta[2] / theta[0]],
        duty_lag,
        constant: fixed(held_out(rows, y, |i| [e.force[i], w2(i), -1.0])),
        force_lag: tuned(rows, &y, seed, (0.0, 0.1, 0.0005), |l, i| {
            [e.force[i] + l * e.force_rate[i], w2(i), -1.0]
        }),
        current_lag,
        current_delay: tuned(rows, &y, seed, (0.0, 0.06, 0.0005), |d, i| {
            [later(&e.t, &e.g, i, d) / e.duty[i], w2(i), -1.0]
        }),
        braking_on_top,
        duty_driven: fixed(held_out(rows, y, |i| [e.duty[i], -e.w[i], w2(i), -1.0])),
    }
}

/// The duty's up-steps from at least 10 % after which the speed rises: for each, the rows from
/// the last row before the step to the bus current's peak (within 0.2 s) and to 63 % of the
/// speed's rise (from the median speed over the 0.3 s before the step to the median over 0.2 to
/// 0.5 s after it).
fn up_step_responses(e: &Esc32) -> Vec<(usize, usize)> {
    let median_of = |r: std::ops::Range<usize>| median(e.w[r].to_vec());
    (31..e.t.len() - 50)
        .filter(|&i| e.duty[i] > e.duty[i - 1] + 0.04 && e.duty[i - 1] >= 0.1 - 1e-9)
        .filter_map(|i| {
            let (before, after) = (median_of(i - 30..i), median_of(i + 20..i + 50));
            (after > before + 10.0).then(|| {
                let peak = (i - 1..i + 20)
                    .max_by(|&x, &y| e.amps[x].total_cmp(&e.amps[y]))
                    .unwrap();
                let rise = (i - 1..)
                    .find(|&k| e.w[k] - before >= 0.632 * (after - before))
                    .unwrap();
                (peak - (i - 1), rise - (i - 1))
            })
        })
        .collect()
}

/// What docs/REAL_DATA.md §2 prints for one ESC32 log (lags in ms, gains in %).
struct Mechanisms {
    name: &'static str,
    kv: f64,
    current_lag_ms: f64,
    current_lag_gain: f64,
    current_lag_folds: usize,
    fold_lags_ms: (f64, f64),
    force_lag_ms: f64,
    force_lag_gain: f64,
    delay_ms: f64,
    delay_gain: f64,
    duty_lag_ms: f64,
    duty_lag_gain: f64,
    duty_driven_gain: f64,
    constant_gain: f64,
    braking_gain: f64,
    braking_folds: usize,
    up_steps: usize,
    /// The bus current's lowest reading after the drop from 100 % to 50 %, and after the drop
    /// from 50 % to 25 % [A].
    drop_amps: (f64, f64),
    /// Its lowest value at the drop from 100 % to 50 % with the lag undone [A].
    drop_amps_rebuilt: f64,
    /// The current lag on the rows before the first drop of the duty (up-steps only): lag [ms]
    /// and gain [%].
    up_steps_only: (f64, f64),
    /// The current-lag model's J [1e-5 kg·m²], c2 [1e-8 N·m·s²/rad²], constant torque [mN·m].
    fit: (f64, f64, f64),
    /// The voltage's lag behind the current [ms] and what modelling it gains [%].
    volts_lag_ms: f64,
    volts_lag_gain: f64,
}

/// docs/REAL_DATA.md §2: the tables and figures of one log.
fn check_mechanisms(p: Mechanisms) {
    let name = p.name;
    let e = esc32(name, p.kv);
    let m = lag_models(&e);
    let ms = |x: f64| x * 1e3;
    printed(
        &format!("{name}: current lag [ms]"),
        ms(m.current_lag.value),
        p.current_lag_ms,
        1,
    );
    printed(
        &format!("{name}: current lag gain"),
        m.current_lag.gain_percent,
        p.current_lag_gain,
        1,
    );
    assert_eq!(
        m.current_lag.folds_won, p.current_lag_folds,
        "{name}: folds"
    );
    printed(
        &format!("{name}: fold lags from"),
        ms(m.current_lag.fold_values.0),
        p.fold_lags_ms.0,
        1,
    );
    printed(
        &format!("{name}: fold lags to"),
        ms(m.current_lag.fold_values.1),
        p.fold_lags_ms.1,
        1,
    );
    printed(
        &format!("{name}: force lag [ms]"),
        ms(m.force_lag.value),
        p.force_lag_ms,
        1,
    );
    printed(
        &format!("{name}: force lag gain"),
        m.force_lag.gain_percent,
        p.force_lag_gain,
        1,
    );
    printed(
        &format!("{name}: delay [ms]"),
        ms(m.current_delay.value),
        p.delay_ms,
        1,
    );
    printed(
        &format!("{name}: delay gain"),
        m.current_delay.gain_percent,
        p.delay_gain,
        1,
    );
    printed(
        &format!("{name}: duty lag [ms]"),
        ms(m.duty_lag.value),
        p.duty_lag_ms,
        0,
    );
    printed(
        &format!("{name}: duty lag gain"),
        m.duty_lag.gain_percent,
        p.duty_lag_gain,
        1,
    );
    printed(
        &format!("{name}: duty-driven gain"),
        m.duty_driven.gain_percent,
        p.duty_driven_gain,
        1,
    );
    printed(
        &format!("{name}: constant gain"),
        m.constant.gain_percent,
        p.constant_gain,
        1,
    );
    printed(
        &format!("{name}: braking on top"),
        m.braking_on_top.gain_percent,
        p.braking_gain,
        1,
    );
    assert_eq!(
        m.braking_on_top.folds_won, p.braking_folds,
        "{name}: braking folds"
    );
    printed(
        &format!("{name}: J [1e-5]"),
        m.current_lag_fit[0] * 1e5,
        p.fit.0,
        2,
    );
    printed(
        &format!("{name}: c2 [1e-8]"),
        m.current_lag_fit[1] * 1e8,
        p.fit.1,
        2,
    );
    printed(
        &format!("{name}: constant [mN·m]"),
        m.current_lag_fit[2] * 1e3,
        p.fit.2,
        1,
    );
    // The up-steps alone prefer about the same lag (their transients are small: little gain).
    let first_drop = (1..e.t.len())
        .find(|&i| e.duty[i] < e.duty[i - 1] - 0.1)
        .unwrap();
    let early: Vec<usize> = e.rows.iter().copied().filter(|&i| i < first_drop).collect();
    let y = |i: usize| e.a[i];
    let seed = held_out(&early, y, |i| [e.force[i], -e.w[i] * e.w[i]]);
    let up = tuned(&early, &y, seed, (0.0, 0.1, 0.0005), |tau, i| {
        [
            (e.g[i] + tau * e.g_rate[i]) / e.duty[i],
            -e.w[i] * e.w[i],
            -1.0,
        ]
    });
    printed(
        &format!("{name}: up-steps only, lag"),
        ms(up.value),
        p.up_steps_only.0,
        1,
    );
    printed(
        &format!("{name}: up-steps only, gain"),
        up.gain_percent,
        p.up_steps_only.1,
        1,
    );
    // The current lag explains more than every other structure tried.
    for other in [&m.force_lag, &m.current_delay, &m.duty_lag, &m.duty_driven] {
        assert!(other.gain_percent < m.current_lag.gain_percent);
    }

    // Model-free: after an up-step the current peaks 4 rows (40 ms) after the last row before
    // the step, and the speed has covered 63 % of its rise after 5 rows.
    let steps = up_step_responses(&e);
    assert_eq!(steps.len(), p.up_steps, "{name}: up-steps");
    assert_eq!(
        median(steps.iter().map(|s| s.0 as f64).collect()),
        4.0,
        "{steps:?}"
    );
    assert_eq!(
        median(steps.iter().map(|s| s.1 as f64).collect()),
        5.0,
        "{steps:?}"
    );
    let row_ms = 1e3 * (e.t[e.t.len() - 1] - e.t[0]) / (e.t.len() - 1) as f64;
    printed(&format!("{name}: row interval [ms]"), row_ms, 10.0, 1);

    // The drops: the logged current stays positive from 100 % to 50 % and goes negative from
    // 50 % to 25 %; with the lag undone it goes negative at the first drop too.
    let drop_at = |from: f64, to: f64| {
        (1..e.t.len())
            .find(|&i| (e.duty[i - 1] - from).abs() < 1e-9 && (e.duty[i] - to).abs() < 1e-9)
            .unwrap()
    };
    let lowest = |r: std::ops::Range<usize>, x: &dyn Fn(usize) -> f64| {
        r.map(x).fold(f64::INFINITY, f64::min)
    };
    let (full, half) = (drop_at(1.0, 0.5), drop_at(0.5, 0.25));
    printed(
        &format!("{name}: drop from 100 %"),
        lowest(full..full + 30, &|k| e.amps[k]),
        p.drop_amps.0,
        1,
    );
    printed(
        &format!("{name}: drop from 50 %"),
        lowest(half..half + 30, &|k| e.amps[k]),
        p.drop_amps.1,
        2,
    );
    let tau = m.current_lag.value;
    printed(
        &format!("{name}: drop from 100 %, lag undone"),
        lowest(full..full + 10, &|k| e.amps[k] + tau * e.amps_rate[k]),
        p.drop_amps_rebuilt,
        1,
    );

    // The reported voltage moves with the reported current: a lag between them gains little.
    let all: Vec<usize> = (8..e.t.len() - 8)
        .filter(|&i| e.duty[i] > 0.05 && e.amps_rate[i].is_finite())
        .collect();
    let volts = |i: usize| e.volts[i];
    let plain = held_out(&all, volts, |i| [1.0, e.amps[i]]);
    let lag = tuned(&all, &volts, plain, (-0.03, 0.03, 0.0005), |tau, i| {
        [1.0, e.amps[i] + tau * e.amps_rate[i]]
    });
    printed(
        &format!("{name}: voltage lag [ms]"),
        ms(lag.value),
        p.volts_lag_ms,
        1,
    );
    printed(
        &format!("{name}: voltage lag gain"),
        lag.gain_percent,
        p.volts_lag_gain,
        1,
    );
}

#[test]
fn esc32_f40_lag_sits_on_the_bus_current() {
    check_mechanisms(Mechanisms {
        name: "f40_steps_5-2",
        kv: 1600.0,
        current_lag_ms: 28.1,
        current_lag_gain: 30.4,
        current_lag_folds: 4,
        fold_lags_ms: (23.0, 61.5),
        force_lag_ms: 32.2,
        force_lag_gain: 21.7,
        delay_ms: 15.3,
        delay_gain: 20.1,
        duty_lag_ms: 84.0,
        duty_lag_gain: 17.7,
        duty_driven_gain: -56.4,
        constant_gain: 6.3,
        braking_gain: 4.0,
        braking_folds: 4,
        up_steps: 18,
        drop_amps: (2.8, -0.34),
        drop_amps_rebuilt: -8.9,
        up_steps_only: (28.5, 6.7),
        fit: (2.10, 5.35, 3.6),
        volts_lag_ms: -5.4,
        volts_lag_gain: 0.3,
    });
}

#[test]
fn esc32_f60_lag_sits_on_the_bus_current() {
    check_mechanisms(Mechanisms {
        name: "esc32v3_f60-1",
        kv: 1750.0,
        current_lag_ms: 27.8,
        current_lag_gain: 31.6,
        current_lag_folds: 5,
        fold_lags_ms: (15.0, 78.5),
        force_lag_ms: 20.9,
        force_lag_gain: 11.4,
        delay_ms: 17.3,
        delay_gain: 24.0,
        duty_lag_ms: 100.0,
        duty_lag_gain: 20.0,
        duty_driven_gain: -39.5,
        constant_gain: -5.3,
        braking_gain: 1.6,
        braking_folds: 3,
        up_steps: 16,
        drop_amps: (4.1, -0.29),
        drop_amps_rebuilt: -6.0,
        up_steps_only: (21.8, 6.3),
        fit: (2.17, 5.13, 2.6),
        volts_lag_ms: -4.2,
        volts_lag_gain: 0.2,
    });
}

/// docs/REAL_DATA.md §2: the open ESC32 firmware (v2, bn999/esc32) reports its ADC window
/// (`histSize`, at least 2), its phase averages (ADC sums, non-zero while the motor turns) and
/// its commutation period in µs; these logs carry 0 for the first two in every row and a small
/// count for the third, so they do not show that code's values, nor its 0.85 ms current filter.
/// Every logged duty after the start-up rows sits on a 5 % level, so every step of the duty
/// completed within one 10 ms row.
#[test]
fn esc32_logs_do_not_carry_the_open_firmwares_values_and_the_duty_steps_at_once() {
    // The open firmware's current filter: one update per ADC buffer of 8 conversions of
    // 7.5 + 12.5 cycles at 12 MHz, each moving 1/64 of the way (adc.h, adc.c line 267); its duty
    // ramp: 1 % of the PWM period per 0.5 ms tick, so 2.5 ms per 5 % step (run.c line 488).
    let buffer = 8.0 * (7.5 + 12.5) / 12e6;
    printed(
        "open firmware filter [ms]",
        -buffer / (1.0 - 1.0 / 64.0f64).ln() * 1e3,
        0.85,
        2,
    );
    printed("open firmware ramp per 5 % [ms]", 5.0 * 0.5, 2.5, 1);
    for (name, startup_rows, up_steps) in [("f40_steps_5-2", 1, 18), ("esc32v3_f60-1", 2, 17)] {
        let [window, a, b, c, composite, period, rpm, duty]: [Vec<f64>; 8] = csv_columns(
            &data(&format!("autoquad/{name}.csv")),
            &[
                "ADC Window",
                "Phase A Avg.",
                "Phase B Avg.",
                "Phase C Avg.",
                "Composite Avg.",
                "Comm. Period",
                "RPM",
                "Duty",
            ],
        )
        .try_into()
        .unwrap();
        for column in [&window, &a, &b, &c, &composite] {
            assert!(column.iter().all(|&x| x == 0.0), "{name}");
        }
        assert!(
            period
                .iter()
                .zip(&rpm)
                .all(|(&p, &r)| p <= 35.0 && (r < 5000.0 || p == 0.0 || p == 2.0)),
            "{name}: commutation period"
        );
        let off_level = duty
            .iter()
            .filter(|&&d| (d / 5.0 - (d / 5.0).round()).abs() > 1e-9)
            .count();
        assert_eq!(off_level, startup_rows, "{name}: rows between 5 % levels");
        let steps = duty
            .windows(2)
            .filter(|w| w[1] > w[0] && w[0] >= 10.0)
            .count();
        assert_eq!(steps, up_steps, "{name}: up-steps from 10 % or more");
        assert!(duty
            .windows(2)
            .filter(|w| w[1] > w[0] && w[0] >= 10.0)
            .all(|w| (w[1] - w[0] - 5.0).abs() < 1e-9));
    }
}

/// docs/REAL_DATA.md §3, "What is open": the constant torque diagnose names beside the lag, or a
/// braking torque the bus current hides, asked about with `--compare braking_torque,force_sensor_lag`
/// (fitted as the search fits a model, scored on the same folds). On neither log do the held-out
/// data tell the two apart, and J differs between them by 18–29 %.
#[test]
fn esc32_braking_or_a_constant_torque_is_not_decided_by_these_logs() {
    use propid_science::diagnose::{EffectSet, Preference};
    let compare: EffectSet = "braking_torque,force_sensor_lag".parse().unwrap();
    let options = Options {
        compare,
        ..Options::default()
    };
    // (log, kv, braking [mN·m], lag [ms], J with them [1e-5], gain over the model named,
    // J with them over the J named, % above)
    for (name, kv, braking, lag, inertia, gain, apart) in [
        ("f40_steps_5-2", 1600.0, 6.40, 46.3, 3.03, 0.00, 29.0),
        ("esc32v3_f60-1", 1750.0, 5.26, 33.3, 2.87, 0.42, 18.0),
    ] {
        let imported = import_autoquad(&data(&format!("autoquad/{name}.csv")), kv).unwrap();
        let r = diagnose(&samples(&imported.rows), options).unwrap();
        let c = r
            .compared
            .as_ref()
            .expect("the model asked about is fitted");
        assert_eq!(c.preferred, Preference::Neither, "{name}: {c:?}");
        let run = c.separating_run.as_ref().expect("a run separates them");
        assert_eq!(run.flags(), "--pattern steps", "{name}: {run:?}");
        printed("braking [mN·m]", c.effects[0].value * 1e3, braking, 2);
        printed("lag [ms]", c.effects[1].value * 1e3, lag, 1);
        printed("J with them [1e-5]", c.model.inertia * 1e5, inertia, 2);
        printed("gain over the model named", c.gain.mean, gain, 2);
        // "J differs between them by 18–29 %".
        printed(
            "J with them over the J named [%]",
            100.0 * (c.model.inertia / r.extended.inertia - 1.0),
            apart,
            0,
        );
    }
}
