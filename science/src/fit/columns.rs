//! The seed regressor on columns already in memory (the arrays of a pandas DataFrame, from the
//! Python package): the same window, the same blocks of sums and the same report as the file
//! scan gives, so a recording fitted from its file and from its columns agrees to the last bit
//! whenever the file is scanned as one piece (files under 1 MiB; larger files are split among
//! threads, whose block borders then differ in the last bits of the sums).
//!
//! Rows are numbered in messages as in the TSV they would be written to: the header is line 1,
//! row `i` (0-based) is line `i + 2`.

use propid_core::estimate::LoadEstimator;
use propid_io::tsv::Sample;
use propid_io::InputError;

use super::scan::{sums_from, Run};
use super::{
    overflow_error, report_of, sums_finite, window_of, FitError, FitOptions, FitReport, Window,
};

/// The columns the fit reads, one value per row, all of the same length.
#[derive(Clone, Copy, Debug)]
pub struct Columns<'a> {
    /// Device time [s].
    pub t: &'a [f64],
    /// Torque [N·m].
    pub force: &'a [f64],
    /// Angular velocity [rad/s].
    pub velocity: &'a [f64],
    /// Angular acceleration [rad/s²].
    pub acceleration: &'a [f64],
}

impl Columns<'_> {
    fn sample(&self, i: usize) -> Sample {
        Sample {
            t: self.t[i],
            force: self.force[i],
            velocity: self.velocity[i],
            acceleration: self.acceleration[i],
            position: f64::NAN,
        }
    }

    /// The line row `i` would have in a TSV (header = line 1).
    fn line(i: usize) -> u64 {
        i as u64 + 2
    }
}

/// Fits columns with the seed's trimming and bounds, as [`super::fit_path`] fits a file;
/// `name` stands for the data in messages.
pub fn fit_columns(
    columns: &Columns<'_>,
    options: &FitOptions,
    name: &str,
) -> Result<FitReport, FitError> {
    options.check()?;
    let n = columns.t.len();
    for (column, len) in [
        ("force", columns.force.len()),
        ("velocity", columns.velocity.len()),
        ("acceleration", columns.acceleration.len()),
    ] {
        if len != n {
            return Err(InputError::invalid(format!(
                "{name}: column `{column}` has {len} values, `t` has {n}: every column needs one value per row"
            ))
            .into());
        }
    }
    let window: Window = window_of(
        (0..n).map(|i| Ok((Columns::line(i), columns.sample(i)))),
        name,
    )?;
    // The run's blocks as the file scan forms them (offset = row index), then the cut.
    let (first, last) = (window.first as usize, window.last as usize);
    let mut run = Run::default();
    for i in window.run_start as usize..=last {
        run.push(
            i,
            Columns::line(i),
            columns.force[i],
            columns.velocity[i],
            columns.acceleration[i],
        );
    }
    let resum = |b: &super::scan::Block, skip: u64| {
        let mut est = LoadEstimator::new();
        for i in b.offset + skip as usize..b.offset + b.rows as usize {
            est.update(
                columns.force[i],
                columns.velocity[i],
                columns.acceleration[i],
            );
        }
        est
    };
    let estimator = sums_from(
        run.blocks.iter().map(|b| (0, b)),
        window.first - window.run_start,
        resum,
    )
    .map(|(sums, _)| sums)
    .unwrap_or_default();
    if !sums_finite(&estimator) {
        let mut est = LoadEstimator::new();
        for i in first..=last {
            est.update(
                columns.force[i],
                columns.velocity[i],
                columns.acceleration[i],
            );
            if !sums_finite(&est) {
                return Err(overflow_error(name, Columns::line(i), &columns.sample(i)).into());
            }
        }
    }
    let gate: Vec<Sample> = (first..=last)
        .take(super::GATE_ROWS as usize)
        .map(|i| columns.sample(i))
        .collect();
    let mut report = report_of(&estimator, options, window, name, &gate)?;
    // The velocity-glitch test the file's fit makes, over every row (lines as the file's).
    let mut found = propid_io::glitch::find(columns.velocity);
    found
        .rows
        .iter_mut()
        .for_each(|r| *r = Columns::line(*r as usize));
    report.warnings.extend(super::glitch_warning(name, &found));
    Ok(report)
}

#[cfg(test)]
mod tests {
    use super::super::{fit_bytes, FitOptions};
    use super::*;

    /// A TSV and its columns, with incomplete rows (a NaN velocity) at the given rows.
    fn recording(rows: usize, holes: &[usize]) -> (String, [Vec<f64>; 4]) {
        let mut text = String::from("t\tforce\tvelocity\tacceleration\n");
        let mut cols: [Vec<f64>; 4] = Default::default();
        let mut w = 3.0f64;
        for i in 0..rows {
            let t = i as f64 * 0.002;
            let q = 1.0 + (i as f64 * 0.01).sin();
            let a = (q - 0.1 * w - 0.02 * w * w.abs()) / 0.5 + (i as f64 * 7.7).sin() * 0.01;
            let v = if holes.contains(&i) { f64::NAN } else { w };
            text += &format!("{t}\t{q}\t{v}\t{a}\n");
            for (c, x) in cols.iter_mut().zip([t, q, v, a]) {
                c.push(x);
            }
            w += a * 0.002;
        }
        (text, cols)
    }

    fn columns(c: &[Vec<f64>; 4]) -> Columns<'_> {
        Columns {
            t: &c[0],
            force: &c[1],
            velocity: &c[2],
            acceleration: &c[3],
        }
    }

    /// The file's report (or error) and the columns', both as text.
    fn both(rows: usize, holes: &[usize], options: &FitOptions) -> (String, String) {
        let (text, cols) = recording(rows, holes);
        let show = |r: Result<FitReport, FitError>| match r {
            Ok(report) => serde_json::to_string(&report).unwrap(),
            Err(e) => e.to_string(),
        };
        let file = fit_bytes(
            text.as_bytes(),
            None,
            "x",
            options,
            false,
            1,
            &mut |_, _| {},
        );
        let mem = fit_columns(&columns(&cols), options, "x");
        (show(file.map(|(report, _)| report)), show(mem))
    }

    /// Columns give the file's report to the last bit (one chunk), wherever incomplete rows
    /// fall and whether the blocks doubled or not; and the same errors.
    #[test]
    fn columns_fit_like_the_file_to_the_last_bit() {
        let holes: [&[usize]; 4] = [&[], &[0, 1, 2], &[700, 1500], &[2999]];
        let options = FitOptions {
            c1_max: f64::INFINITY,
            ..FitOptions::default()
        };
        for hole in holes {
            let (file, mem) = both(3000, hole, &options);
            assert!(file.starts_with("{\"mass\""), "{file}");
            assert_eq!(file, mem, "holes {hole:?}");
        }
        let (file, mem) = both(5, &[], &options);
        assert!(file.contains("usable samples"), "{file}");
        assert_eq!(file, mem);
    }

    /// A velocity glitch (one sample 50 % off and straight back) is announced with its line by
    /// the file's fit, in one piece or three, and by the columns' fit alike.
    #[test]
    fn velocity_glitches_are_announced_alike() {
        let (_, mut cols) = recording(3000, &[]);
        cols[2][1000] *= 1.5;
        let mut text = String::from("t\tforce\tvelocity\tacceleration\n");
        let rows = cols[0].iter().zip(&cols[1]).zip(&cols[2]).zip(&cols[3]);
        for (((t, q), v), a) in rows {
            text += &format!("{t}\t{q}\t{v}\t{a}\n");
        }
        let options = FitOptions::default();
        let file = |chunks| {
            fit_bytes(
                text.as_bytes(),
                None,
                "x",
                &options,
                false,
                chunks,
                &mut |_, _| {},
            )
            .unwrap()
            .0
        };
        let mem = fit_columns(&columns(&cols), &options, "x").unwrap();
        let note = |r: &FitReport| {
            r.warnings
                .iter()
                .find(|w| w.contains("jump away"))
                .cloned()
                .unwrap_or_default()
        };
        let one = note(&file(1));
        assert!(
            one.starts_with("x: `velocity`: 1 samples jump away"),
            "{one}"
        );
        assert!(one.contains("(lines 1002)"), "{one}");
        assert_eq!(one, note(&file(3)));
        assert_eq!(one, note(&mem));
        // Without the glitch: nothing.
        let (_, clean) = recording(3000, &[]);
        assert_eq!(
            note(&fit_columns(&columns(&clean), &options, "x").unwrap()),
            ""
        );
    }

    #[test]
    fn columns_of_different_lengths_are_refused_by_name() {
        let (_, mut cols) = recording(100, &[]);
        cols[2].pop();
        let e = fit_columns(&columns(&cols), &FitOptions::default(), "data").unwrap_err();
        assert_eq!(
            e.to_string(),
            "data: column `velocity` has 99 values, `t` has 100: every column needs one value per row"
        );
    }
}
