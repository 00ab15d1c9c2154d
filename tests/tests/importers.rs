//! The importers on synthetic RCbenchmark/Tyto-style CSVs whose truth is known: a load-cell
//! zero offset, a flipped torque sign, sparse or dense torque, optical or electrical rpm, time in
//! seconds or milliseconds, a command column; and the bad inputs they must refuse.

use propid_io::import::{import_autoquad, import_rcbench, write_tsv, RcbenchOptions};
use propid_io::tsv::StandColumn;

const J: f64 = 2e-5;
const C2: f64 = 6e-8;
const ZERO: f64 = 0.002; // the load cell's zero offset [N·m]

struct Stand {
    /// Write the torque every `torque_every` rows.
    torque_every: usize,
    /// The load cell reads the reaction (−Q) instead of Q.
    reaction: bool,
    /// Time column in milliseconds.
    millis: bool,
    /// The speed goes in the optical column (the electrical one stays zero), or the reverse.
    optical: bool,
}

/// 100 Hz rows: at rest for 1 s, then ESC steps 1100 → 1500 → 1300 µs held 3 s each, the rotor
/// a first-order response (τ = 0.2 s) to 800, 1500, 1200 rad/s. Returns the CSV and, per row,
/// the true drive torque Q = J·dω/dt + c2·ω² (NaN where the torque is not written).
fn tyto_csv(s: &Stand) -> (String, Vec<f64>) {
    let mut csv = format!(
        "\u{feff}{},ESC signal (µs),Torque (N·m),Thrust (kgf),Voltage (V),Current (A),Motor Electrical Speed (RPM),Motor Optical Speed (RPM),App message,\n",
        if s.millis { "Time (ms)" } else { "Time (s)" }
    );
    let mut truth = Vec::new();
    let dt = 0.01;
    let mut w = 0.0f64;
    for k in 0..1000 {
        let t = k as f64 * dt;
        let (cmd, target) = match t {
            t if t < 1.0 => (1000.0, 0.0),
            t if t < 4.0 => (1100.0, 800.0),
            t if t < 7.0 => (1500.0, 1500.0),
            _ => (1300.0, 1200.0),
        };
        let a = (target - w) / 0.2;
        let q = J * a + C2 * w * w;
        let logged = if s.reaction { -q } else { q } + ZERO;
        let rpm = w * 60.0 / std::f64::consts::TAU;
        let (el, op) = if s.optical { (0.0, rpm) } else { (rpm, 0.0) };
        let has_q = k % s.torque_every == 0;
        let time = if s.millis { t * 1e3 } else { t };
        csv += &format!(
            "{time},{cmd},{},0.1,16,2,{el},{op},,\n",
            if has_q {
                logged.to_string()
            } else {
                String::new()
            }
        );
        truth.push(if has_q { q } else { f64::NAN });
        w += a * dt;
    }
    (csv, truth)
}

fn import(csv: &str, subtract: bool) -> propid_io::import::Imported {
    let dir = tempfile::tempdir().unwrap();
    let p = dir.path().join("tyto.csv");
    std::fs::write(&p, csv).unwrap();
    import_rcbench(
        &p,
        &RcbenchOptions {
            subtract_zero_offset: subtract,
            ..RcbenchOptions::default()
        },
    )
    .unwrap()
}

fn said<'a>(imported: &'a propid_io::import::Imported, what: &str) -> &'a str {
    imported
        .assumptions
        .iter()
        .find(|a| a.contains(what))
        .unwrap_or_else(|| panic!("nothing about `{what}` in {:#?}", imported.assumptions))
}

#[test]
fn flipped_sign_and_zero_offset_are_measured_and_reported() {
    let stand = Stand {
        torque_every: 5,
        reaction: true,
        millis: false,
        optical: true,
    };
    let (csv, truth) = tyto_csv(&stand);
    // Reported, not subtracted: force = Q − ZERO after the flip.
    let im = import(&csv, false);
    assert!(
        said(&im, "torque sign").contains("flipped"),
        "{:#?}",
        im.assumptions
    );
    let zero = said(&im, "zero offset");
    assert!(
        zero.contains("-2.00 ± 0.00 mN·m") && zero.contains("not subtracted"),
        "{zero}"
    );
    assert!(
        said(&im, "force =").contains("updates at 20.000 Hz"),
        "{:#?}",
        im.assumptions
    );
    assert!(said(&im, "force =").contains("200 of 1000 rows"));
    assert!(said(&im, "velocity =").contains("Motor Optical Speed (RPM)"));
    assert!(said(&im, "time =").contains("median row interval 10.00 ms"));
    for (r, q) in im.rows.iter().zip(&truth) {
        if q.is_finite() {
            assert!(
                (r.sample.force - (q - ZERO)).abs() < 1e-12,
                "{} vs {q}",
                r.sample.force
            );
        } else {
            assert!(r.sample.force.is_nan(), "never interpolated");
        }
    }
    // Subtracted when asked: the true torque exactly.
    let im = import(&csv, true);
    assert!(said(&im, "zero offset").contains("subtracted from every sample"));
    for (r, q) in im.rows.iter().zip(&truth) {
        if q.is_finite() {
            assert!(
                (r.sample.force - q).abs() < 1e-12,
                "{} vs {q}",
                r.sample.force
            );
        }
    }
    // The command is kept as a ratio (and the logged µs as an extra column), both written to
    // the TSV with the stand's thrust, voltage and current.
    let cmd = im.stand(StandColumn::Command);
    let close = |a: f64, b: f64| (a - b).abs() < 1e-12;
    assert!(
        close(cmd[0], 0.0) && close(cmd[150], 0.1) && close(cmd[500], 0.5) && close(cmd[900], 0.3),
        "{:?}",
        (cmd[0], cmd[150], cmd[500], cmd[900])
    );
    assert!(said(&im, "command =").contains("ESC signal"));
    assert_eq!(
        im.stand_columns,
        [
            StandColumn::Thrust,
            StandColumn::Voltage,
            StandColumn::Current,
            StandColumn::Command
        ]
    );
    let tsv = String::from_utf8(write_tsv(&im, Vec::new()).unwrap()).unwrap();
    assert!(tsv.starts_with(
        "ts_local\tt\tforce\tvelocity\tacceleration\tposition\tthrust\tvoltage\tcurrent\tcommand\tesc_signal_us\n"
    ));
    assert!(
        tsv.lines()
            .nth(151)
            .unwrap()
            .ends_with("\t16\t2\t0.1\t1100"),
        "{}",
        tsv.lines().nth(151).unwrap()
    );
    // …and the TSV reader still reads the file (it ignores the extra column).
    let mut reader = propid_io::tsv::TsvReader::new(tsv.as_bytes(), "x.tsv").unwrap();
    let mut n = 0;
    while reader.next_row().unwrap().is_some() {
        n += 1;
    }
    assert_eq!(n, 1000);
}

#[test]
fn dense_torque_kept_sign_electrical_rpm_and_milliseconds() {
    let stand = Stand {
        torque_every: 1,
        reaction: false,
        millis: true,
        optical: false,
    };
    let (csv, truth) = tyto_csv(&stand);
    let im = import(&csv, false);
    assert!(
        said(&im, "torque sign").contains("kept"),
        "{:#?}",
        im.assumptions
    );
    assert!(said(&im, "zero offset").contains("+2.00 ± 0.00 mN·m"));
    assert!(said(&im, "force =").contains("1000 of 1000 rows (100 %)"));
    assert!(said(&im, "velocity =").contains("Motor Electrical Speed (RPM)"));
    assert!(said(&im, "time =").contains("in milliseconds"));
    assert!((im.rows[999].sample.t - 9.99).abs() < 1e-9);
    assert!((im.rows[500].sample.force - (truth[500] + ZERO)).abs() < 1e-12);
    // No message states a figure the file does not give: nothing of the old fixed texts.
    for a in &im.assumptions {
        assert!(
            !a.contains("6.7 Hz") && !a.contains("positive at speed") && !a.contains("±1.5"),
            "{a}"
        );
    }
}

#[test]
fn bad_files_are_refused_with_the_place() {
    let dir = tempfile::tempdir().unwrap();
    let p = dir.path().join("bad.csv");
    let none = RcbenchOptions::default();
    // A short row: an error naming the line and the column, never a silent NaN.
    std::fs::write(
        &p,
        "Time (s),Torque (N·m),Motor Electrical Speed (RPM)\n0,0.1,100\n0.01,0.1\n",
    )
    .unwrap();
    let e = import_rcbench(&p, &none).err().unwrap().to_string();
    assert!(
        e.contains("bad.csv: line 3, column `Motor Electrical Speed (RPM)`: missing"),
        "{e}"
    );
    std::fs::write(
        &p,
        "Timestamp,Amps,RPM,Duty\n2019-11-05 17:14:08:947,1.0,100\n",
    )
    .unwrap();
    let e = import_autoquad(&p, 1600.0).err().unwrap().to_string();
    assert!(e.contains("bad.csv: line 2, column `Duty`: missing"), "{e}");
    // A non-numeric field, likewise.
    std::fs::write(
        &p,
        "Timestamp,Amps,RPM,Duty\n2019-11-05 17:14:08:947,1.0,fast,50\n",
    )
    .unwrap();
    let e = import_autoquad(&p, 1600.0).err().unwrap().to_string();
    assert!(e.contains("bad.csv: line 2, column `RPM`: `fast`"), "{e}");
    // kv: inf, NaN, zero, negative.
    for kv in [f64::INFINITY, f64::NAN, 0.0, -3.0] {
        let e = import_autoquad(&p, kv).err().unwrap().to_string();
        assert!(e.contains("kv must be a finite positive"), "{kv}: {e}");
    }
    // Seconds that are really milliseconds.
    let (csv, _) = tyto_csv(&Stand {
        torque_every: 1,
        reaction: false,
        millis: true,
        optical: true,
    });
    std::fs::write(&p, csv.replace("Time (ms)", "Time (s)")).unwrap();
    let e = import_rcbench(&p, &none).err().unwrap().to_string();
    assert!(
        e.contains("median interval between rows is 10 s") && e.contains("unit"),
        "{e}"
    );
    // No torque column at all, and one that is always empty.
    std::fs::write(&p, "Time (s),Current (A)\n0,1\n").unwrap();
    let e = import_rcbench(&p, &none).err().unwrap().to_string();
    assert!(e.contains("line 1: no column `Torque (N·m)`"), "{e}");
    std::fs::write(&p, "Time (s),Torque (N·m),RPM\n0,,100\n0.01,,200\n").unwrap();
    let e = import_rcbench(&p, &none).err().unwrap().to_string();
    assert!(e.contains("empty in every row"), "{e}");
}

/// The rest of the stand (issue 27): thrust converted to N from the unit its header names and
/// signed positive at speed, bus voltage and current, the ESC signal as a ratio, the stand's
/// power as extra columns; each column's update rate measured. A thrust in a unit propid does not
/// know is refused by name.
#[test]
fn thrust_voltage_current_command_and_power_are_kept() {
    let k_t = 1.5e-5; // thrust = k_t·ω² [N]
    for (unit, newtons, flip) in [
        ("gf", 9.806_65e-3, false),
        ("kgf", 9.806_65, true),
        ("N", 1.0, false),
        ("lbf", 4.448_221_615_260_5, true),
    ] {
        let mut csv = format!(
            "Time (s),ESC signal (%),Torque (N·m),Thrust ({unit}),Voltage (V),Current (A),Motor Optical Speed (RPM),Electrical Power (W),Mechanical Power (W)\n"
        );
        let mut truth = Vec::new();
        for k in 0..600 {
            let t = k as f64 * 0.01;
            // At rest for 1 s, then 40 % (600 rad/s) and 80 % (1200 rad/s).
            let (pct, w) = match t {
                t if t < 1.0 => (0.0, 0.0),
                t if t < 3.5 => (40.0, 600.0),
                _ => (80.0, 1200.0),
            };
            let thrust = k_t * w * w;
            let logged = if flip { -thrust } else { thrust } / newtons;
            let every_third = k % 3 == 0;
            csv += &format!(
                "{t},{pct},{},{},{},{},{},{},{}\n",
                6e-8 * w * w,
                if every_third {
                    logged.to_string()
                } else {
                    String::new()
                },
                16.0 - 0.001 * w,
                0.01 * w,
                w * 60.0 / std::f64::consts::TAU,
                0.16 * w,
                6e-8 * w * w * w,
            );
            truth.push(if every_third { thrust } else { f64::NAN });
        }
        let im = import(&csv, false);
        let thrust = im.stand(StandColumn::Thrust);
        for (k, (got, want)) in thrust.iter().zip(&truth).enumerate() {
            if want.is_finite() {
                assert!(
                    (got - want).abs() <= 1e-9 * want.max(1.0),
                    "{unit} row {k}: {got} vs {want}"
                );
            } else {
                assert!(got.is_nan(), "{unit} row {k}: never interpolated");
            }
        }
        let said_thrust = said(&im, "thrust =");
        assert!(
            said_thrust.contains(&format!("Thrust ({unit})")),
            "{said_thrust}"
        );
        assert!(
            said_thrust.contains("present in 200 of 600 rows"),
            "{said_thrust}"
        );
        assert_eq!(
            said(&im, "thrust sign").contains("flipped"),
            flip,
            "{unit}: {:#?}",
            im.assumptions
        );
        assert!(said(&im, "thrust zero offset").contains("+0.00 ± 0.00 mN"));
        let v = im.stand(StandColumn::Voltage);
        let i = im.stand(StandColumn::Current);
        let c = im.stand(StandColumn::Command);
        assert_eq!((v[0], i[0], c[0]), (16.0, 0.0, 0.0));
        assert!((v[500] - 14.8).abs() < 1e-12 && (i[500] - 12.0).abs() < 1e-12);
        assert!((c[200] - 0.4).abs() < 1e-12 && (c[500] - 0.8).abs() < 1e-12);
        assert!(said(&im, "voltage =").contains("Voltage (V)"));
        assert!(said(&im, "current =").contains("present in 600 of 600 rows"));
        assert!(said(&im, "command =").contains("`ESC signal (%)` / 100"));
        let names: Vec<&str> = im.extra.iter().map(|c| c.name).collect();
        assert_eq!(names, ["electrical_power", "mechanical_power"]);
        assert!((im.extra[0].values[500] - 192.0).abs() < 1e-9);
        // Written and read back by name.
        let tsv = write_tsv(&im, Vec::new()).unwrap();
        let mut r = propid_io::tsv::TsvReader::new(&tsv[..], "x.tsv").unwrap();
        assert_eq!(r.stand_columns(), StandColumn::ALL);
        let mut k = 0;
        while let Some(row) = r.next_row().unwrap() {
            let same = |a: f64, b: f64| a.to_bits() == b.to_bits() || (a.is_nan() && b.is_nan());
            assert!(
                same(row.stand.thrust, thrust[k]) && same(row.stand.voltage, v[k]),
                "row {k}"
            );
            k += 1;
        }
        assert_eq!(k, 600);
    }
    // A thrust column without a unit, or in one propid does not convert: refused by name.
    for header in ["Thrust", "Thrust (mN·m)"] {
        let dir = tempfile::tempdir().unwrap();
        let p = dir.path().join("bad.csv");
        std::fs::write(
            &p,
            format!("Time (s),Torque (N·m),{header},RPM\n0,0.1,1,100\n0.01,0.1,1,200\n"),
        )
        .unwrap();
        let e = import_rcbench(&p, &RcbenchOptions::default())
            .err()
            .unwrap()
            .to_string();
        assert!(
            e.contains(&format!("line 1, column `{header}`")) && e.contains("gf, kgf, N, lbf"),
            "{e}"
        );
    }
}

/// One bad row costs one row (issue 26, item 5): a stale time in the first data row (the next
/// rows restart near 0), a row whose time goes back, an empty time, a copied line — each is
/// dropped alone and listed with its line and reason; the rest of the log is kept.
#[test]
fn a_bad_row_costs_that_row_only_and_is_listed() {
    let stand = Stand {
        torque_every: 5,
        reaction: false,
        millis: false,
        optical: true,
    };
    let (csv, _) = tyto_csv(&stand);
    let mut lines: Vec<String> = csv.lines().map(str::to_owned).collect();
    // Line 2 (the first data row): a stale time of 7.5 s.
    lines[1] = lines[1].replacen("0,", "7.5,", 1);
    // Line 501: back to the time of line 401; line 601: no time; line 701 copied once.
    let back = lines[400].split(',').next().unwrap().to_owned();
    let (_, rest) = lines[500].split_once(',').unwrap();
    lines[500] = format!("{back},{rest}");
    let (_, rest) = lines[600].split_once(',').unwrap();
    lines[600] = format!(",{rest}");
    lines.insert(701, lines[700].clone());
    let im = import(&(lines.join("\n") + "\n"), false);
    assert_eq!(im.rows.len(), 1000 - 3, "{:#?}", im.dropped);
    use propid_io::import::{DropReason, Dropped};
    assert_eq!(
        im.dropped,
        [
            Dropped {
                line: 2,
                reason: DropReason::TimeAhead
            },
            Dropped {
                line: 501,
                reason: DropReason::TimeGoesBack
            },
            Dropped {
                line: 601,
                reason: DropReason::NoTime
            },
            Dropped {
                line: 702,
                reason: DropReason::Duplicate
            },
        ]
    );
    let said = said(&im, "rows dropped");
    assert!(
        said.starts_with("4 of 1001 rows dropped, each for itself: line 2 (the time is later than the rows after it (stale))"),
        "{said}"
    );
    assert!(im
        .warnings
        .iter()
        .any(|w| w.contains("1 of 1001 lines repeat the line before them")));
    assert!(im.rows.windows(2).all(|w| w[1].sample.t > w[0].sample.t));
}

/// Velocity glitches (a sample jumping away and straight back) are found and reported with
/// their lines; kept unless --despike, which sets their velocity to NaN (nothing interpolated).
/// Real steps are not glitches.
#[test]
fn velocity_glitches_are_reported_and_removed_only_when_asked() {
    let stand = Stand {
        torque_every: 1,
        reaction: false,
        millis: false,
        optical: true,
    };
    let (csv, _) = tyto_csv(&stand);
    let mut lines: Vec<String> = csv.lines().map(str::to_owned).collect();
    // Lines 302 and 802: the optical probe counts a mark twice (+400 rpm) for one sample.
    for k in [301, 801] {
        let mut f: Vec<String> = lines[k].split(',').map(str::to_owned).collect();
        let rpm: f64 = f[7].parse().unwrap();
        f[7] = (rpm + 400.0).to_string();
        lines[k] = f.join(",");
    }
    let text = lines.join("\n") + "\n";
    let clean = import(&csv, false);
    assert!(clean.warnings.is_empty(), "{:?}", clean.warnings);
    let kept = import(&text, false);
    let w = kept
        .warnings
        .iter()
        .find(|w| w.contains("glitches"))
        .unwrap();
    assert!(
        w.contains("2 samples") && w.contains("lines 302, 802") && w.contains("--despike"),
        "{w}"
    );
    assert!(kept.rows[300].sample.velocity.is_finite());
    let dir = tempfile::tempdir().unwrap();
    let p = dir.path().join("g.csv");
    std::fs::write(&p, &text).unwrap();
    let removed = import_rcbench(
        &p,
        &RcbenchOptions {
            despike: true,
            ..RcbenchOptions::default()
        },
    )
    .unwrap();
    for k in 0..1000 {
        assert_eq!(
            removed.rows[k].sample.velocity.is_nan(),
            k == 300 || k == 800,
            "row {k}"
        );
    }
    assert!(removed.warnings[0].contains("NaN in the TSV (--despike)"));
}
