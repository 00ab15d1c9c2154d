//! The importers on synthetic RCbenchmark/Tyto-style CSVs whose truth is known: a load-cell
//! zero offset, a flipped torque sign, sparse or dense torque, optical or electrical rpm, time in
//! seconds or milliseconds, a command column; and the bad inputs they must refuse.

use propid_io::import::{import_autoquad, import_rcbench, write_tsv, RcbenchOptions};

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
    // The command column is kept, and written to the TSV.
    let cmd = im.command.as_ref().expect("command column");
    assert_eq!(
        (cmd[0], cmd[150], cmd[500], cmd[900]),
        (1000.0, 1100.0, 1500.0, 1300.0)
    );
    assert!(said(&im, "command =").contains("ESC signal"));
    let tsv = String::from_utf8(write_tsv(&im, Vec::new()).unwrap()).unwrap();
    assert!(tsv.starts_with("ts_local\tt\tforce\tvelocity\tacceleration\tposition\tcommand\n"));
    assert!(
        tsv.lines().nth(151).unwrap().ends_with("\t1100"),
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
