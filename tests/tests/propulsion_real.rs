//! Propulsion on the six measured RCbenchmark logs of one DALPROP T7056 (7 in) and the two ESC32
//! logs (tests/data/esc_test_alspitz, MIT). Every figure docs/PROPULSION.md states about them is
//! asserted here at the precision it is printed with.

use propid_io::import::{import_autoquad, import_rcbench, write_tsv, RcbenchOptions};
use propid_science::propulsion::read::{read, ReadOptions};
use propid_science::propulsion::{
    identify, Air, MethodChoice, Options, PlateauOptions, Propulsion, Quantity,
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

/// `value` printed with `decimals` decimals reads `printed`.
#[track_caller]
fn printed(what: &str, value: f64, printed: f64, decimals: i32) {
    let half = 0.5 * 10f64.powi(-decimals) * (1.0 + 1e-9);
    assert!(
        (value - printed).abs() <= half,
        "{what}: measured {value}, the docs print {printed}"
    );
}

fn q(x: &Quantity) -> (f64, f64) {
    (
        x.identified()
            .unwrap_or_else(|| panic!("not identified: {}", x.describe())),
        x.stderr().unwrap(),
    )
}

/// (log, motor, C_T ± s.e., C_Q ± s.e., T·D/Q ± s.e.) at 12 000 rpm, as docs/PROPULSION.md §3 prints them.
/// A value and its standard error.
type Pm = [f64; 2];

/// A row of the table: log, motor, C_T, C_Q, T·D/Q.
type LogRow = (&'static str, &'static str, Pm, Pm, Pm);

const TABLE: [LogRow; 6] = [
    (
        "2019-11-05_171350",
        "F40",
        [0.1402, 0.0022],
        [0.010868, 0.000023],
        [12.90, 0.21],
    ),
    (
        "2019-11-07_174807",
        "F60",
        [0.14191, 0.00046],
        [0.010799, 0.000046],
        [13.142, 0.070],
    ),
    (
        "2019-11-07_175456",
        "F60",
        [0.14210, 0.00056],
        [0.010817, 0.000042],
        [13.137, 0.073],
    ),
    (
        "2019-11-07_184325",
        "F60",
        [0.14259, 0.00066],
        [0.010734, 0.000028],
        [13.284, 0.070],
    ),
    (
        "2019-11-07_211050",
        "F60",
        [0.14144, 0.00082],
        [0.010872, 0.000082],
        [13.01, 0.12],
    ),
    (
        "2019-11-09_181347",
        "F80",
        [0.1349, 0.0017],
        [0.01026, 0.00011],
        [13.15, 0.22],
    ),
];

/// Decimals of a figure printed with two significant digits of its standard error.
fn decimals(stderr: f64) -> i32 {
    1 - stderr.log10().floor() as i32
}

#[test]
fn c_t_and_c_q_of_the_six_logs_at_12000_rpm() {
    let mut got = Vec::new();
    let mut exponents = Vec::new();
    let air = Air::isa();
    printed(
        "Re_D at 12000 rpm [1e5]",
        air.reynolds_rotational(200.0, D) / 1e5,
        4.33,
        2,
    );
    printed("tip Mach at 12000 rpm", air.tip_mach(200.0, D), 0.33, 2);
    for (name, _, ct, cq, ratio) in TABLE {
        let p = rcbench(name);
        assert!(
            p.warnings
                .iter()
                .all(|w| !w.contains("outside what propellers have")),
            "{:?}",
            p.warnings
        );
        let t = q(&p.thrust.as_ref().unwrap().at_reference);
        let c = q(&p.torque.as_ref().unwrap().at_reference);
        let r = q(&p.performance.as_ref().unwrap().thrust_torque_ratio);
        for (what, v, doc) in [("C_T", t, ct), ("C_Q", c, cq), ("T·D/Q", r, ratio)] {
            printed(&format!("{name} {what}"), v.0, doc[0], decimals(doc[1]));
            printed(
                &format!("{name} {what} s.e."),
                v.1,
                doc[1],
                decimals(doc[1]),
            );
        }
        got.push([t, c, r]);
        exponents.push((
            q(&p.thrust.as_ref().unwrap().exponent).0,
            q(&p.torque.as_ref().unwrap().exponent).0,
        ));
    }
    // Agreement. The four F60 runs of one day (one motor and propeller, four ESCs) differ by more
    // than their standard errors: their standard deviation is the run-to-run reproducibility,
    // added to each run's own error. Against the F60 runs' mean, the F40 run agrees within two
    // standard errors in C_T, C_Q and T·D/Q; the F80 run of 11-09 is lower in C_T and C_Q by more
    // than three, by the same factor in both, and its density-free T·D/Q agrees.
    let pick = |g: &[(f64, f64); 3], k: usize| g[k];
    let stats = |k: usize| {
        let v: Vec<f64> = got[1..5].iter().map(|g| pick(g, k).0).collect();
        let m = v.iter().sum::<f64>() / 4.0;
        let sd = (v.iter().map(|x| (x - m).powi(2)).sum::<f64>() / 3.0).sqrt();
        (m, sd)
    };
    let z = |i: usize, k: usize| {
        let (m, sd) = stats(k);
        let (v, e) = pick(&got[i], k);
        (v - m).abs() / (e * e + sd * sd + sd * sd / 4.0).sqrt()
    };
    for k in 0..3 {
        assert!(
            z(0, k) < 2.0,
            "F40, quantity {k}: {:.1} σ from the F60 runs",
            z(0, k)
        );
    }
    assert!(
        z(5, 0) > 3.0 && z(5, 1) > 3.0,
        "the F80's C_T, C_Q: {:.1}, {:.1} σ",
        z(5, 0),
        z(5, 1)
    );
    assert!(z(5, 2) < 2.0, "the F80's T·D/Q: {:.1} σ", z(5, 2));
    printed(
        "F60 reproducibility of C_T [%]",
        100.0 * stats(0).1 / stats(0).0,
        0.34,
        2,
    );
    printed(
        "F60 reproducibility of C_Q [%]",
        100.0 * stats(1).1 / stats(1).0,
        0.53,
        2,
    );
    let (ct60, _) = stats(0);
    let (cq60, _) = stats(1);
    let (ct80, cq80) = (got[5][0].0, got[5][1].0);
    printed("F80/F60 C_T", ct80 / ct60, 0.950, 3);
    printed("F80/F60 C_Q", cq80 / cq60, 0.950, 3);
    // "5 % thinner air (a room about 15 °C warmer, or 51 hPa lower pressure), or an rpm reading
    // 2.6 % high": the density ratio at 20 °C and 1013.25 hPa, and the speed scale that lowers
    // C_T (∝ 1/n²) by the same factor.
    let ratio = ct80 / ct60;
    printed("warmer [K]", 293.15 * (1.0 / ratio - 1.0), 15.0, 0);
    printed("lower pressure [hPa]", 1013.25 * (1.0 - ratio), 51.0, 0);
    printed(
        "rpm reading high [%]",
        100.0 * (1.0 / ratio.sqrt() - 1.0),
        2.6,
        1,
    );
    // "thrust ∝ n^p with p = 2.21–2.26 on the six runs, torque with p = 2.03–2.07".
    let range = |k: usize| {
        exponents
            .iter()
            .fold((f64::MAX, f64::MIN), |(l, h), e: &(f64, f64)| {
                let v = if k == 0 { e.0 } else { e.1 };
                (l.min(v), h.max(v))
            })
    };
    assert_eq!(exponents.len(), 6);
    printed("lowest thrust exponent", range(0).0, 2.21, 2);
    printed("highest thrust exponent", range(0).1, 2.26, 2);
    printed("lowest torque exponent", range(1).0, 2.03, 2);
    printed("highest torque exponent", range(1).1, 2.07, 2);
}

/// Published static coefficients, UIUC Propeller Database (J. B. Brandt, R. W. Deters,
/// G. K. Ananda, O. D. Dantsker and M. S. Selig, University of Illinois at Urbana-Champaign,
/// https://m-selig.ae.illinois.edu/props/propDB.html), as compiled in the CSV files
/// `volume1_exp.csv` and `volume2_exp.csv` of github.com/Piotrek2133/Drone-Propellers-Optimizer
/// (commit 77bd2293f675f9e2483ed68dcdb80fa280f0e01a), rows with J = 0:
/// (name, blades, diameter [in], rpm, C_T, C_P).
const UIUC: [(&str, u32, f64, f64, f64, f64); 2] = [
    // Vol. 1, APC Sport 7×6, static, its fastest row.
    ("APC Sport 7x6", 2, 7.0, 7002.0, 0.0953, 0.0723),
    // Vol. 2, DA4052 9×6.75, three blades, static, its fastest row.
    (
        "DA4052 9x6.75 (3 blades)",
        3,
        9.0,
        5700.0,
        0.145621,
        0.081547,
    ),
];

#[test]
fn the_t7056_against_published_static_coefficients() {
    use propid_science::propulsion::{figure_of_merit, Kind, TAU};
    // The 18:43 run (F60, ESC32v3): the widest speed range of the six.
    let p = rcbench("2019-11-07_184325");
    let at = |rpm: f64| {
        let n = rpm / 60.0;
        let t = p.thrust.as_ref().unwrap().law.unwrap();
        let q = p.torque.as_ref().unwrap().law.unwrap();
        let ct = t.value(n) / Kind::Thrust.scale(1.225, n, D);
        let cp = TAU * q.value(n) / Kind::Torque.scale(1.225, n, D);
        (ct, cp, figure_of_merit(ct, cp / TAU))
    };
    // At the APC's speed on the same diameter: the same Reynolds and tip Mach numbers.
    let (name, blades, _, rpm, ct_apc, cp_apc) = UIUC[0];
    let (ct, cp, fm) = at(rpm);
    printed("T7056 C_T at 7002 rpm", ct, 0.1262, 4);
    printed("T7056 C_P at 7002 rpm", cp, 0.0655, 4);
    printed("T7056 FM at 7002 rpm", fm, 0.546, 3);
    printed(
        &format!("{name} FM"),
        figure_of_merit(ct_apc, cp_apc / TAU),
        0.325,
        3,
    );
    // Per blade: C_T within 12 %, C_P 40 % lower.
    printed(
        "C_T per blade, T7056/APC",
        (ct / 3.0) / (ct_apc / f64::from(blades)),
        0.883,
        3,
    );
    printed(
        "C_P per blade, T7056/APC",
        (cp / 3.0) / (cp_apc / f64::from(blades)),
        0.604,
        3,
    );
    // At the DA4052's rotational Reynolds number ρ·n·D²/μ: n·D² equal.
    let (_, _, d_in, rpm, ct_da, cp_da) = UIUC[1];
    let rpm_same_re = rpm * (d_in / 7.0).powi(2);
    printed("speed of equal Re_D [rpm]", rpm_same_re, 9422.0, 0);
    let (ct, cp, fm) = at(rpm_same_re);
    printed("T7056 C_T there", ct, 0.1350, 4);
    printed("T7056 C_P there", cp, 0.0666, 4);
    printed("T7056 FM there", fm, 0.594, 3);
    printed("DA4052 FM", figure_of_merit(ct_da, cp_da / TAU), 0.544, 3);
    printed("C_T, T7056/DA4052 at equal Re_D", ct / ct_da, 0.93, 2);
    printed("C_P, T7056/DA4052 at equal Re_D", cp / cp_da, 0.82, 2);
    // Electrical rpm with 7 pole pairs would give C_T 49 times smaller: no propeller has that.
    assert!(
        propid_science::propulsion::plausibility(Kind::Thrust, ct / 49.0, D)
            .is_some_and(|w| w.contains("electrical") && w.contains("has 7, which gives 0.1350"))
    );
}

#[test]
fn esc32_kv_from_back_emf_against_the_importers_kv() {
    for (file, kv_given, kv, kv_se, r, r_se, rms, sigmas) in [
        (
            "f40_steps_5-2.csv",
            1600.0,
            2083.0,
            58.0,
            0.2474,
            0.0098,
            0.122,
            8.4,
        ),
        (
            "esc32v3_f60-1.csv",
            1750.0,
            2084.0,
            112.0,
            0.230,
            0.018,
            0.219,
            3.0,
        ),
    ] {
        let imported = import_autoquad(&data(&format!("autoquad/{file}")), kv_given).unwrap();
        let p = identify(&through_tsv(&imported, true), &options(None)).unwrap();
        let m = p.motor.as_ref().unwrap();
        let (k, ks) = q(&m.kv);
        let (res, rs) = q(&m.resistance);
        printed(&format!("{file} Kv"), k, kv, 0);
        printed(&format!("{file} Kv s.e."), ks, kv_se, 0);
        printed(&format!("{file} R"), res, r, decimals(r_se));
        printed(&format!("{file} R s.e."), rs, r_se, decimals(r_se));
        printed(&format!("{file} residual"), m.back_emf_rms.unwrap(), rms, 3);
        // How many standard errors the --kv given lies below the back-EMF's.
        printed(
            &format!("{file} (Kv − --kv)/s.e."),
            (k - kv_given) / ks,
            sigmas,
            1,
        );
        printed(
            &format!("{file} Kv/--kv"),
            k / kv_given,
            if kv_given == 1600.0 { 1.30 } else { 1.19 },
            2,
        );
        // The importer's torque (K_t·I/duty from --kv) is recognised as computed from the current.
        assert!(m.kt.identified().is_none() && m.losses.is_none());
    }
}
