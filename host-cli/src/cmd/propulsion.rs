//! `propid propulsion`: C_T and C_Q over speed, thrust per watt, the figure of merit and the
//! motor's constants from a stand's TSV, around [`propid_science::propulsion::identify`].
//!
//! Its settings are self-contained ([`Args`] → [`Args::options`]): every quantity is parsed with
//! its unit once, and a bad one is refused naming its flag.

use std::path::{Path, PathBuf};

use propid_science::propulsion::read::{read_path, ReadOptions};
use propid_science::propulsion::units::{parse, Dimension, Parsed};
use propid_science::propulsion::{
    figure::figure, identify, text::propulsion_text, Air, MethodChoice, Options, Propulsion,
    Quantity,
};

use crate::{CannotJudge, InputError};

/// Output format.
#[derive(Clone, Copy, Debug, PartialEq, Eq, clap::ValueEnum)]
pub enum Format {
    /// A readable report.
    Text,
    /// JSON (the result file `propid size` reads).
    Json,
    /// YAML (the same keys).
    Yaml,
}

/// How coefficients are measured.
#[derive(Clone, Copy, Debug, PartialEq, Eq, clap::ValueEnum)]
pub enum Method {
    /// Steady plateaus where there are three at different speeds, else the dynamic fit.
    Auto,
    /// Steady plateaus only.
    Plateaus,
    /// Row by row through the load cell's lag (a sine, a chirp).
    Dynamic,
}

/// A quantity with its unit, as clap parses it.
pub fn quantity(dimension: Dimension) -> impl Fn(&str) -> Result<Parsed, String> + Clone {
    move |s| parse(s, dimension)
}

/// The air: a density, or a temperature and a pressure (`propid propulsion` and `propid size`).
#[derive(clap::Args, Debug)]
pub struct AirArgs {
    /// Air density [kg/m³].
    #[arg(long, allow_negative_numbers = true, value_parser = quantity(Dimension::Density), conflicts_with_all = ["temperature", "pressure"])]
    pub density: Option<Parsed>,
    /// Air temperature (20C, 293K), with --pressure: the density of dry air.
    #[arg(long, value_parser = quantity(Dimension::Temperature), requires = "pressure")]
    pub temperature: Option<Parsed>,
    /// Air pressure (1013hPa, 101325Pa), with --temperature.
    #[arg(long, value_parser = quantity(Dimension::Pressure), requires = "temperature")]
    pub pressure: Option<Parsed>,
}

impl AirArgs {
    /// The air the flags describe, `default` when none is given.
    pub fn air(&self, default: Air) -> Result<Air, InputError> {
        match (&self.density, &self.temperature, &self.pressure) {
            (Some(d), _, _) => Air::with_density(d.si, None),
            (None, Some(t), Some(p)) => Air::from_temperature_pressure(t.si, p.si),
            _ => Ok(default),
        }
        .map_err(|e| InputError::invalid(format!("--density/--temperature/--pressure: {e}")))
    }
}

/// Arguments of `propid propulsion`.
#[derive(clap::Args, Debug)]
#[command(
    after_help = "Units: --diameter 7in, 0.1778m, 178mm (a bare number is metres); speeds \
12000rpm, 200rev/s, 1257rad/s; temperature 20C, 293K, 68F; pressure 1013hPa, 101325Pa, 29.92inHg. \
Exit status: 0 every coefficient asked for is identified; 2 bad input; 3 cannot judge (a \
coefficient not identified or implausible, no steady plateau and too few samples, --motor without \
voltage, current or duty); the report says why."
)]
pub struct Args {
    /// The recording: propid's TSV with `thrust`, `voltage`, `current`, `command` where the
    /// stand has them (`propid import rcbench|autoquad` writes them); `-` reads standard input.
    pub file: PathBuf,
    /// Propeller diameter (7in, 0.1778m, 178mm).
    #[arg(long, value_parser = quantity(Dimension::Length))]
    pub diameter: Parsed,
    /// The air (default: ISA sea level, 1.225 kg/m³).
    #[command(flatten)]
    pub air: AirArgs,
    /// Blade chord at 75 % radius (15mm): also gives the blade Reynolds number.
    #[arg(long, value_parser = quantity(Dimension::Length))]
    pub chord: Option<Parsed>,
    /// The speed column is electrical: divide it by this many pole pairs (7 for a 14-pole motor).
    #[arg(long)]
    pub pole_pairs: Option<u32>,
    /// Speed the coefficients are quoted at (12000rpm; default: the log-mean of the plateaus).
    #[arg(long, value_parser = quantity(Dimension::Speed))]
    pub reference_speed: Option<Parsed>,
    /// How to measure.
    #[arg(long, value_enum, default_value_t = Method::Auto)]
    pub method: Method,
    /// The `command` column is the ESC's duty (ratio 0–1; an ESC32 log's is): needed for Kv.
    #[arg(long)]
    pub command_is_duty: bool,
    /// Ask for the motor's constants: exit 3 unless Kv and R are identified.
    #[arg(long)]
    pub motor: bool,
    /// Output format on standard output.
    #[arg(long, value_enum, default_value_t = Format::Text)]
    pub format: Format,
    /// Also write the result to this file (.json or .yaml), for `propid size --propeller`.
    #[arg(short, long)]
    pub output: Option<PathBuf>,
    /// Plot thrust and torque over speed with the laws, the coefficients, the efficiency map
    /// (.svg, .png or .html).
    #[arg(long)]
    pub plot: Option<PathBuf>,
}

/// Notes about the flags themselves (a diameter without a unit).
pub fn unit_notes(
    flag: &str,
    p: &Parsed,
    dimension: Dimension,
    plausible: std::ops::RangeInclusive<f64>,
) -> Option<String> {
    (p.unit.is_none() && !plausible.contains(&p.si)).then(|| {
        format!(
            "{flag} {} has no unit and is read as {} {}, outside {}–{} {}: write the unit (for a diameter 7in, 178mm)",
            p.si,
            p.si,
            dimension.si_unit(),
            plausible.start(),
            plausible.end(),
            dimension.si_unit()
        )
    })
}

impl Args {
    /// The identification's options, checked; errors name the flag.
    pub fn options(&self) -> Result<Options, InputError> {
        let air = self.air.air(Air::isa())?;
        if self.pole_pairs == Some(0) {
            return Err(InputError::invalid(
                "--pole-pairs must be at least 1".into(),
            ));
        }
        let options = Options {
            chord: self.chord.map(|c| c.si),
            reference_speed: self.reference_speed.map(|s| s.si / std::f64::consts::TAU),
            method: match self.method {
                Method::Auto => MethodChoice::Auto,
                Method::Plateaus => MethodChoice::Plateaus,
                Method::Dynamic => MethodChoice::Dynamic,
            },
            ..Options::at(self.diameter.si, air)
        };
        options.check().map_err(|e| {
            InputError::invalid(format!("--diameter/--chord/--reference-speed: {e}"))
        })?;
        Ok(options)
    }
}

/// Writes `p` as JSON or YAML by the file's extension.
pub fn write_result(p: &Propulsion, path: &Path) -> anyhow::Result<()> {
    let text = match path.extension().and_then(|e| e.to_str()) {
        Some("yaml" | "yml") => serde_norway::to_string(p)?,
        Some("json") => serde_json::to_string_pretty(p)? + "\n",
        _ => {
            return Err(InputError::invalid(format!(
                "--output {}: the result file must end in .json, .yaml or .yml",
                path.display()
            ))
            .into())
        }
    };
    std::fs::write(path, text)
        .map_err(|e| InputError::invalid(format!("{}: cannot write: {e}", path.display())))?;
    Ok(())
}

/// What was asked and is not identified, in words.
fn unanswered(p: &Propulsion, motor: bool) -> Vec<String> {
    let mut out = Vec::new();
    let mut need = |what: &str, q: &Quantity| {
        if q.identified().is_none() {
            out.push(format!("{what}: {}", q.describe()));
        }
    };
    if let Some(c) = &p.thrust {
        need("C_T", &c.at_reference);
    }
    if let Some(c) = &p.torque {
        need("C_Q", &c.at_reference);
    }
    if motor {
        match &p.motor {
            Some(m) => {
                need("Kv", &m.kv);
                need("R", &m.resistance);
            }
            None => out.push(format!(
                "the motor: {}",
                p.motor_absent.as_deref().unwrap_or("no motor columns")
            )),
        }
    }
    out
}

/// Runs `propid propulsion`.
pub fn run(args: Args) -> anyhow::Result<()> {
    let options = args.options()?;
    // A bare number outside 0.02–3 m is refused, as by fit and diagnose (7 is inches far more
    // often than a 7 m rotor).
    if let Some(note) = unit_notes("--diameter", &args.diameter, Dimension::Length, 0.02..=3.0) {
        return Err(InputError::invalid(note).into());
    }
    if let Some(out) = &args.output {
        if out == &args.file {
            return Err(InputError::invalid(format!(
                "--output {} is the recording itself: it would be overwritten",
                out.display()
            ))
            .into());
        }
    }
    let name = args.file.display().to_string();
    let (rec, report) = read_path(
        &args.file,
        &ReadOptions {
            pole_pairs: args.pole_pairs,
            command_is_duty: args.command_is_duty,
        },
    )?;
    if report.without_speed > 0 || report.time_not_increasing > 0 {
        eprintln!(
            "note: {name}: {} rows without a time or speed and {} whose time does not increase were not used",
            report.without_speed, report.time_not_increasing
        );
    }
    if args.motor && rec.duty.is_none() && report.columns.contains(&"command") {
        eprintln!("note: {name} has a `command` column; if it is the ESC's duty, give --command-is-duty (Kv needs it)");
    }
    let p = identify(&rec, &options).map_err(|e| InputError::invalid(format!("{name}: {e}")))?;
    if let Some(out) = &args.output {
        write_result(&p, out)?;
        eprintln!("result written to {}", out.display());
    }
    if let Some(plot) = &args.plot {
        crate::plot::write(plot, &figure(&p, Some(&rec)))?;
        eprintln!("plot written to {}", plot.display());
    }
    let text = match args.format {
        Format::Text => propulsion_text(&p, &name),
        Format::Json => serde_json::to_string_pretty(&p)? + "\n",
        Format::Yaml => serde_norway::to_string(&p)?,
    };
    use std::io::Write;
    std::io::stdout().write_all(text.as_bytes())?;
    let missing = unanswered(&p, args.motor);
    if missing.is_empty() {
        Ok(())
    } else {
        Err(CannotJudge(format!("{name}: cannot judge {}", missing.join("; "))).into())
    }
}
