//! # propid-python: the extension module `propid._propid`
//!
//! The Python package `propid` (the pure-Python layer in `propid/`) over the same crates the
//! command uses; nothing here computes anything of its own:
//!
//! ```text
//!  pandas DataFrame / dict of arrays ─► float64 columns (numpy, read in place as &[f64])
//!      ─► fit_columns ─► science::fit::fit_columns ──────────────┐
//!      ─► diagnose_columns ─► science::diagnose::diagnose_rows ───┤  serde JSON (the CLI's
//!  a path ─► fit_path (science::fit::fit_path_with, as `propid fit`) ┤  `--format json`) ─►
//!         ─► diagnose_path (read_rows + diagnose_rows, as `propid   ┤  typed Python classes
//!            diagnose`)                                            ┘  (FitResult, Diagnosis…)
//!  read_tsv / import_* ─► propid-io ─► numpy arrays that own the Rust vectors (no copy)
//!  run_cli (the `propid` command) / call_cli (simulate, plan) ─► propid::cli, in-process
//! ```
//!
//! Results cross as the CLI's JSON, so a field renamed in Rust changes one mapping in the Python
//! layer, not these bindings. Long work releases the GIL. Errors become `propid.InputError`
//! (the CLI's exit status 2), `propid.CannotJudge` (3) or `propid.PropidError` (1), with the
//! CLI's message.
#![deny(missing_docs)]

use std::ffi::OsString;
use std::path::PathBuf;

use numpy::{PyArray1, PyReadonlyArray1};
use pyo3::create_exception;
use pyo3::exceptions::PyException;
use pyo3::prelude::*;
use pyo3::types::PyDict;

use propid_io::import::{Imported, RcbenchOptions};
use propid_io::tsv::{Row, Sample, StandColumn, TsvReader, HEADER};
use propid_science::fit::{fit_columns as fit_in_memory, fit_path_with, Columns, FitOptions};

create_exception!(
    propid,
    PropidError,
    PyException,
    "Any error propid reports (the command's exit status 1)."
);
create_exception!(
    propid,
    InputError,
    PropidError,
    "Bad input: a file, a column or a value (the command's exit status 2). The message names the file, line, column or option."
);
create_exception!(
    propid,
    CannotJudge,
    PropidError,
    "The data cannot support a verdict (the command's exit status 3)."
);

/// The Python exception for an error of the command line, by the exit status it gives.
fn py_error(err: &anyhow::Error) -> PyErr {
    let message = format!("{err:#}");
    match propid::exit_status_for(err) {
        propid::EXIT_CANNOT_JUDGE => CannotJudge::new_err(message),
        2 => InputError::new_err(message),
        _ => PropidError::new_err(message),
    }
}

/// A usage error of the command line: the first paragraph of clap's message, without its
/// "error: " (the usage and the --help tip name the command's flags, not the Python function's
/// arguments).
fn usage_error(e: clap::Error) -> PyErr {
    let text = e.render().to_string();
    let first = text.split("\n\n").next().unwrap_or(&text);
    InputError::new_err(first.trim_start_matches("error: ").trim().to_string())
}

fn input_error(e: impl std::fmt::Display) -> PyErr {
    InputError::new_err(e.to_string())
}

/// The fit's bounds and C_Q geometry, from a dict with every key (`None`: the command's default).
#[derive(FromPyObject)]
#[pyo3(from_item_all)]
struct Bounds {
    mass_min: Option<f64>,
    mass_max: Option<f64>,
    c1_max: Option<f64>,
    c2_max: Option<f64>,
    diameter: Option<f64>,
    density: Option<f64>,
    flip_torque: Option<bool>,
    velocity_unit: Option<String>,
}

impl TryFrom<Bounds> for FitOptions {
    type Error = PyErr;

    /// The fit's options; a velocity unit the command would refuse is refused in its words.
    fn try_from(b: Bounds) -> PyResult<FitOptions> {
        let d = FitOptions::default();
        let velocity_unit = match &b.velocity_unit {
            Some(u) => propid_science::plausibility::SpeedUnit::parse(u)
                .map_err(|e| InputError::new_err(format!("velocity_unit: {e}")))?,
            None => d.reading.velocity_unit,
        };
        Ok(FitOptions {
            mass_min: b.mass_min.unwrap_or(d.mass_min),
            mass_max: b.mass_max.unwrap_or(d.mass_max),
            c1_max: b.c1_max.unwrap_or(d.c1_max),
            c2_max: b.c2_max.unwrap_or(d.c2_max),
            diameter: b.diameter,
            density: b.density.unwrap_or(d.density),
            reading: propid_science::plausibility::Reading {
                flip_torque: b.flip_torque.unwrap_or(d.reading.flip_torque),
                velocity_unit,
            },
        })
    }
}

fn json(value: &impl serde::Serialize) -> PyResult<String> {
    serde_json::to_string(value).map_err(|e| PropidError::new_err(e.to_string()))
}

/// A contiguous column as a slice (the Python layer makes every column contiguous float64).
fn slice<'a>(a: &'a PyReadonlyArray1<'_, f64>, name: &str) -> PyResult<&'a [f64]> {
    a.as_slice()
        .map_err(|_| InputError::new_err(format!("column `{name}` is not contiguous")))
}

/// `propid fit FILE --format json`: the fit's report as JSON.
#[pyfunction]
fn fit_path(py: Python<'_>, path: PathBuf, bounds: Bounds) -> PyResult<String> {
    let options = FitOptions::try_from(bounds)?;
    let result = py.detach(|| fit_path_with(&path, &options, false, &mut |_, _| {}));
    let (report, _) = result.map_err(|e| py_error(&e.into()))?;
    json(&report)
}

/// The fit of columns (t, force, velocity, acceleration), named `name` in messages.
#[pyfunction]
fn fit_columns(
    py: Python<'_>,
    t: PyReadonlyArray1<'_, f64>,
    force: PyReadonlyArray1<'_, f64>,
    velocity: PyReadonlyArray1<'_, f64>,
    acceleration: PyReadonlyArray1<'_, f64>,
    name: &str,
    bounds: Bounds,
) -> PyResult<String> {
    let options = FitOptions::try_from(bounds)?;
    let columns = Columns {
        t: slice(&t, "t")?,
        force: slice(&force, "force")?,
        velocity: slice(&velocity, "velocity")?,
        acceleration: slice(&acceleration, "acceleration")?,
    };
    let result = py.detach(|| fit_in_memory(&columns, &options, name));
    json(&result.map_err(|e| py_error(&e.into()))?)
}

/// `propid diagnose`'s arguments: the Python keyword arguments' flags, parsed by the command's
/// own parser (`file` stands for the data), so every option is checked as the command checks it.
fn diagnose_args(file: &str, flags: Vec<OsString>) -> PyResult<propid::cmd::diagnose::Args> {
    use clap::Parser;
    let argv = [OsString::from("propid"), "diagnose".into(), file.into()]
        .into_iter()
        .chain(flags);
    match propid::cli::Cli::try_parse_from(argv)
        .map_err(usage_error)?
        .command
    {
        propid::cli::Command::Diagnose(args) => Ok(args),
        _ => Err(PropidError::new_err("`diagnose` parsed as another command")),
    }
}

/// The diagnosis of what was read, as `propid diagnose` makes it: (JSON, text, cannot-judge
/// message).
fn diagnose_named(
    py: Python<'_>,
    input: propid::cmd::DiagnosisInput,
    args: &propid::cmd::diagnose::Args,
    name: &str,
) -> PyResult<(String, String, Option<String>)> {
    let air = args.propeller.air().map_err(|e| py_error(&e.into()))?;
    let (report, outcome) = py
        .detach(|| propid::cmd::diagnose::diagnose_input(input, args.options(), air, name, &|_| {}))
        .map_err(|e| py_error(&e))?;
    let cannot_judge = report
        .verdict
        .cannot_judge_reasons()
        .map(|why| format!("{name}: cannot judge: {why}"));
    let value = propid::cmd::diagnose::json(&report, outcome.as_ref())
        .map_err(|e| PropidError::new_err(e.to_string()))?;
    let text = propid::cmd::diagnose::text(&report, outcome.as_ref(), name);
    Ok((json(&value)?, text, cannot_judge))
}

/// `propid diagnose FILE` with the command's `flags`: (JSON, text, cannot-judge message).
#[pyfunction]
#[pyo3(signature = (path, flags))]
fn diagnose_path(
    py: Python<'_>,
    path: PathBuf,
    flags: Vec<OsString>,
) -> PyResult<(String, String, Option<String>)> {
    let name = path.display().to_string();
    let args = diagnose_args(&name, flags)?;
    let input = py
        .detach(|| propid::cmd::DiagnosisInput::read(&path, &args.reading.reading(), args.despike))
        .map_err(|e| py_error(&e.into()))?;
    diagnose_named(py, input, &args, &name)
}

/// The diagnosis of columns (as a file with them would be diagnosed) with the command's
/// `flags`: (JSON, text, cannot-judge message).
#[pyfunction]
#[pyo3(signature = (t, force, velocity, acceleration, ts_local, position, thrust, name, flags))]
#[allow(clippy::too_many_arguments)]
fn diagnose_columns(
    py: Python<'_>,
    t: PyReadonlyArray1<'_, f64>,
    force: PyReadonlyArray1<'_, f64>,
    velocity: PyReadonlyArray1<'_, f64>,
    acceleration: PyReadonlyArray1<'_, f64>,
    ts_local: Option<PyReadonlyArray1<'_, f64>>,
    position: Option<PyReadonlyArray1<'_, f64>>,
    thrust: Option<PyReadonlyArray1<'_, f64>>,
    name: &str,
    flags: Vec<OsString>,
) -> PyResult<(String, String, Option<String>)> {
    let args = diagnose_args(name, flags)?;
    let (t, force) = (slice(&t, "t")?, slice(&force, "force")?);
    let (velocity, acceleration) = (
        slice(&velocity, "velocity")?,
        slice(&acceleration, "acceleration")?,
    );
    let ts_local = ts_local
        .as_ref()
        .map(|a| slice(a, "ts_local"))
        .transpose()?;
    let position = position
        .as_ref()
        .map(|a| slice(a, "position"))
        .transpose()?;
    let thrust = thrust.as_ref().map(|a| slice(a, "thrust")).transpose()?;
    let n = t.len();
    let lengths = [
        ("force", Some(force.len())),
        ("velocity", Some(velocity.len())),
        ("acceleration", Some(acceleration.len())),
        ("ts_local", ts_local.map(<[f64]>::len)),
        ("position", position.map(<[f64]>::len)),
        ("thrust", thrust.map(<[f64]>::len)),
    ];
    if let Some((column, Some(len))) = lengths.iter().find(|(_, l)| l.is_some_and(|l| l != n)) {
        return Err(InputError::new_err(format!(
            "{name}: column `{column}` has {len} values, `t` has {n}: every column needs one value per row"
        )));
    }
    // The rows a file with these columns gives the command's reader: those it keeps, the rest
    // counted.
    let reading = args.reading.reading();
    let input = py.detach(|| {
        let at = |c: Option<&[f64]>, i: usize| c.map_or(f64::NAN, |c| c[i]);
        let mut rows = Vec::with_capacity(n);
        for i in 0..n {
            let mut row = Row::new(
                at(ts_local, i),
                Sample {
                    t: t[i],
                    force: force[i],
                    velocity: velocity[i],
                    acceleration: acceleration[i],
                    position: at(position, i),
                },
            );
            row.stand.thrust = at(thrust, i);
            if propid::cmd::DiagnosisInput::keep(&row) {
                rows.push(row);
            }
        }
        let skipped = n - rows.len();
        let columns: &[StandColumn] = if thrust.is_some() {
            &[StandColumn::Thrust]
        } else {
            &[]
        };
        propid::cmd::DiagnosisInput::from_rows(
            name,
            rows,
            skipped,
            columns,
            Vec::new(),
            &reading,
            args.despike,
        )
    });
    diagnose_named(py, input, &args, name)
}

/// Columns as numpy arrays that own the vectors, in a dict (in `order`).
fn columns_dict<'py>(
    py: Python<'py>,
    columns: Vec<(String, Vec<f64>)>,
) -> PyResult<Bound<'py, PyDict>> {
    let dict = PyDict::new(py);
    for (name, values) in columns {
        dict.set_item(name, PyArray1::from_vec(py, values))?;
    }
    Ok(dict)
}

/// The rows' standard columns (those in `keep`), in the TSV's order.
fn row_columns(rows: &[Row], keep: [bool; 6]) -> Vec<(String, Vec<f64>)> {
    let field = |r: &Row, k: usize| match k {
        0 => r.ts_local,
        1 => r.sample.t,
        2 => r.sample.force,
        3 => r.sample.velocity,
        4 => r.sample.acceleration,
        _ => r.sample.position,
    };
    (0..6)
        .filter(|k| keep[*k])
        .map(|k| {
            (
                HEADER[k].to_string(),
                rows.iter().map(|r| field(r, k)).collect(),
            )
        })
        .collect()
}

/// `read_tsv(path)`: the standard columns the file has (`t`, `force`, `velocity`,
/// `acceleration`, and `ts_local` and `position` when its header names them) and the stand
/// columns it has (`thrust`, `voltage`, `current`, `command`), read by propid's own reader (its
/// messages name file, line and column).
#[pyfunction]
fn read_tsv<'py>(py: Python<'py>, path: PathBuf) -> PyResult<Bound<'py, PyDict>> {
    let columns = py.detach(|| -> Result<_, anyhow::Error> {
        let name = path.display().to_string();
        let file = std::fs::File::open(&path)
            .map_err(|e| propid::InputError::os(name.clone(), "cannot open", &e))?;
        let mut reader = TsvReader::new(std::io::BufReader::with_capacity(1 << 20, file), name)?;
        // The reader keeps the header's positions, not its names: the first line, once more.
        let mut header = String::new();
        std::io::BufRead::read_line(
            &mut std::io::BufReader::new(std::fs::File::open(&path)?),
            &mut header,
        )?;
        let has = |column: &str| {
            header
                .trim_start_matches('\u{feff}')
                .split('\t')
                .any(|c| c.trim() == column)
        };
        let keep = [
            has("ts_local"),
            true,
            true,
            true,
            true,
            reader.has_position(),
        ];
        let stand = reader.stand_columns();
        let mut rows = Vec::new();
        while let Some(row) = reader.next_row()? {
            rows.push(row);
        }
        let mut columns = row_columns(&rows, keep);
        // The stand columns the file has (thrust, voltage, current, command), as `propid
        // propulsion` reads them.
        for column in stand {
            columns.push((
                column.name().into(),
                rows.iter().map(|r| r.stand.get(column)).collect(),
            ));
        }
        Ok(columns)
    });
    columns_dict(py, columns.map_err(|e| py_error(&e))?)
}

/// An imported recording: (columns as `propid import` writes them, the importer's findings).
fn imported<'py>(
    py: Python<'py>,
    imported: Imported,
) -> PyResult<(Bound<'py, PyDict>, Vec<String>)> {
    let mut columns = row_columns(&imported.rows, [true; 6]);
    // The stand columns the importer kept (thrust, voltage, current, command).
    for column in &imported.stand_columns {
        columns.push((column.name().into(), imported.stand(*column)));
    }
    // The other measured columns the command writes after them (electrical power, …).
    for extra in &imported.extra {
        columns.push((extra.name.into(), extra.values.clone()));
    }
    Ok((columns_dict(py, columns)?, imported.assumptions))
}

/// `propid import rcbench FILE`.
#[pyfunction]
#[pyo3(signature = (path, subtract_zero_offset=false))]
fn import_rcbench<'py>(
    py: Python<'py>,
    path: PathBuf,
    subtract_zero_offset: bool,
) -> PyResult<(Bound<'py, PyDict>, Vec<String>)> {
    let options = RcbenchOptions {
        subtract_zero_offset,
        ..RcbenchOptions::default()
    };
    let result = py.detach(|| propid_io::import::import_rcbench(&path, &options));
    imported(py, result.map_err(input_error)?)
}

/// `propid import autoquad FILE --kv KV`.
#[pyfunction]
fn import_autoquad<'py>(
    py: Python<'py>,
    path: PathBuf,
    kv: f64,
) -> PyResult<(Bound<'py, PyDict>, Vec<String>)> {
    let result = py.detach(|| propid_io::import::import_autoquad(&path, kv));
    imported(py, result.map_err(input_error)?)
}

/// The `propid` command, in-process: `args` with the program name first; returns the exit
/// status. Messages go to stderr as from the binary.
#[pyfunction]
fn run_cli(py: Python<'_>, args: Vec<OsString>) -> u8 {
    py.detach(|| propid::exit_status(args))
}

/// A command run for its files (`simulate`, `plan`): a usage error or a failure becomes the
/// Python exception of its exit status, with the command's message.
#[pyfunction]
fn call_cli(py: Python<'_>, args: Vec<OsString>) -> PyResult<()> {
    use clap::Parser;
    let cli = propid::cli::Cli::try_parse_from(args).map_err(usage_error)?;
    py.detach(|| cli.run()).map_err(|e| py_error(&e))
}

/// The extension module.
#[pymodule]
fn _propid(m: &Bound<'_, PyModule>) -> PyResult<()> {
    let py = m.py();
    m.add("PropidError", py.get_type::<PropidError>())?;
    m.add("InputError", py.get_type::<InputError>())?;
    m.add("CannotJudge", py.get_type::<CannotJudge>())?;
    m.add_function(wrap_pyfunction!(fit_path, m)?)?;
    m.add_function(wrap_pyfunction!(fit_columns, m)?)?;
    m.add_function(wrap_pyfunction!(diagnose_path, m)?)?;
    m.add_function(wrap_pyfunction!(diagnose_columns, m)?)?;
    m.add_function(wrap_pyfunction!(read_tsv, m)?)?;
    m.add_function(wrap_pyfunction!(import_rcbench, m)?)?;
    m.add_function(wrap_pyfunction!(import_autoquad, m)?)?;
    m.add_function(wrap_pyfunction!(run_cli, m)?)?;
    m.add_function(wrap_pyfunction!(call_cli, m)?)?;
    Ok(())
}
