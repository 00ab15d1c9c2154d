//! `propid size`: the drivetrain for a thrust (torque, speed) — speed, shaft torque and power,
//! and with the motor the current, voltage, efficiency, DC link and battery, and which Kv —
//! around [`propid_science::propulsion::size::size`].
//!
//! The propeller comes from a `propid propulsion` result file (`--propeller`, JSON or YAML) or from
//! its coefficients (`--c-t`, `--c-q`, `--diameter`); the motor from flags, or the result file
//! where it identified the motor. Settings are self-contained: each flag is parsed with its unit
//! once and a bad one is refused by name.

use std::path::PathBuf;

use propid_science::propulsion::size::{
    size, Battery, MotorConstants, Propeller, Question, Supply, Target,
};
use propid_science::propulsion::text::size_text;
use propid_science::propulsion::units::{Dimension, Parsed, G0};
use propid_science::propulsion::{Air, Kind, PowerLaw, Propulsion};

use super::propulsion::{quantity, unit_notes, AirArgs};
use crate::InputError;

/// Output format.
#[derive(Clone, Copy, Debug, PartialEq, Eq, clap::ValueEnum)]
pub enum Format {
    /// A readable answer.
    Text,
    /// JSON.
    Json,
}

/// Arguments of `propid size`.
#[derive(clap::Args, Debug)]
#[command(
    after_help = "Units: thrust 6N, 600g (gram-force), 1.2kgf, 1.3lbf (a bare number is N); \
torque 0.1Nm, 100mNm; speed 12000rpm; mass 1.5kg; voltage 16V or 4S (3.7 V per LiPo cell); \
capacity 5000mAh; resistance 60mohm. Exit status: 0 answered; 2 bad input (a flag, an unreadable \
or foreign result file)."
)]
pub struct Args {
    /// A `propid propulsion` result file (.json, .yaml).
    #[arg(long, conflicts_with_all = ["c_t", "c_q"])]
    pub propeller: Option<PathBuf>,
    /// Also write the answer as JSON to this file (what the Python package's `size` reads).
    #[arg(short, long)]
    pub output: Option<PathBuf>,
    /// A propeller's thrust coefficient (with --c-q and --diameter, instead of --propeller).
    #[arg(long, requires_all = ["c_q", "diameter"])]
    pub c_t: Option<f64>,
    /// Its torque coefficient.
    #[arg(long, requires_all = ["c_t", "diameter"])]
    pub c_q: Option<f64>,
    /// Its diameter (7in, 0.1778m).
    #[arg(long, value_parser = quantity(Dimension::Length))]
    pub diameter: Option<Parsed>,
    /// Thrust per rotor (6N, 600g, 1.2kgf); repeat for several targets.
    #[arg(long, value_parser = quantity(Dimension::Force))]
    pub thrust: Vec<Parsed>,
    /// The vehicle's mass to hover (1.5kg): a thrust of m·g/rotors per rotor.
    #[arg(long, value_parser = quantity(Dimension::Mass))]
    pub hover_mass: Option<Parsed>,
    /// Shaft torque target (0.1Nm); repeatable.
    #[arg(long, value_parser = quantity(Dimension::Torque))]
    pub torque: Vec<Parsed>,
    /// Speed target (12000rpm); repeatable.
    #[arg(long, value_parser = quantity(Dimension::Speed))]
    pub speed: Vec<Parsed>,
    /// Rotors on the vehicle.
    #[arg(long, default_value_t = 1)]
    pub rotors: u32,
    /// The air for the sizing (default: the identification's density).
    #[command(flatten)]
    pub air: AirArgs,
    /// Motor Kv [rpm/V] (default: the result file's, where it identified the motor).
    #[arg(long, value_parser = quantity(Dimension::Kv))]
    pub kv: Option<Parsed>,
    /// Motor resistance (60mohm, 0.06): windings, wiring and switches.
    #[arg(long, value_parser = quantity(Dimension::Resistance))]
    pub resistance: Option<Parsed>,
    /// Motor no-load current (0.8A).
    #[arg(long, value_parser = quantity(Dimension::Current))]
    pub no_load_current: Option<Parsed>,
    /// DC-link (battery) voltage (16V, 4S): duty, DC current, and which Kv.
    #[arg(long, value_parser = quantity(Dimension::Voltage))]
    pub voltage: Option<Parsed>,
    /// Highest duty the controller may use (headroom for control).
    #[arg(long, default_value_t = 1.0)]
    pub max_duty: f64,
    /// Battery capacity (5000mAh): C-rate and endurance.
    #[arg(long, value_parser = quantity(Dimension::Capacity))]
    pub battery: Option<Parsed>,
    /// Usable fraction of the battery's capacity.
    #[arg(long, default_value_t = 0.8)]
    pub usable: f64,
    /// Output format.
    #[arg(long, value_enum, default_value_t = Format::Text)]
    pub format: Format,
}

/// Reads a `propid propulsion` result (JSON or YAML by extension; JSON also from any other name).
fn read_result(path: &std::path::Path) -> Result<Propulsion, InputError> {
    let name = path.display().to_string();
    let text = std::fs::read_to_string(path)
        .map_err(|e| InputError::invalid(format!("--propeller {name}: cannot read: {e}")))?;
    let yaml = matches!(
        path.extension().and_then(|e| e.to_str()),
        Some("yaml" | "yml")
    );
    let parsed: Result<Propulsion, String> = if yaml {
        serde_norway::from_str(&text).map_err(|e| e.to_string())
    } else {
        serde_json::from_str(&text).map_err(|e| e.to_string())
    };
    parsed.map_err(|e| {
        InputError::invalid(format!(
            "--propeller {name}: not a `propid propulsion` result ({e}); write one with `propid propulsion LOG --diameter D -o {}`",
            if yaml { "prop.yaml" } else { "prop.json" }
        ))
    })
}

impl Args {
    fn question(&self) -> Result<Question, InputError> {
        let (propeller, result) = match (&self.propeller, self.c_t, self.c_q) {
            (Some(path), _, _) => {
                let r = read_result(path)?;
                let (rho, d) = (r.air.density, r.diameter);
                let law = |c: &Option<propid_science::propulsion::Coefficient>| {
                    c.as_ref().and_then(|c| c.sizing_law(rho, d))
                };
                (
                    Propeller {
                        diameter: d,
                        density: rho,
                        thrust: law(&r.thrust),
                        torque: law(&r.torque),
                    },
                    Some(r),
                )
            }
            (None, Some(ct), Some(cq)) => {
                let d = self.diameter.ok_or_else(|| InputError::invalid("--c-t and --c-q need --diameter".into()))?;
                if let Some(note) = unit_notes("--diameter", &d, Dimension::Length, 0.02..=3.0) {
                    return Err(InputError::invalid(note));
                }
                for (flag, c, kind) in [("--c-t", ct, Kind::Thrust), ("--c-q", cq, Kind::Torque)] {
                    if !(c > 0.0 && c.is_finite()) {
                        return Err(InputError::invalid(format!("{flag} must be positive (got {c})")));
                    }
                    if let Some(why) = propid_science::propulsion::plausibility(kind, c, d.si) {
                        eprintln!("warning: {flag}: {why}");
                    }
                }
                let rho = Air::isa().density;
                // A constant coefficient: X = C·ρ·n²·D^m about 100 rev/s, no uncertainty given.
                let law = |c: f64, kind: Kind| PowerLaw {
                    reference_speed: 100.0,
                    at_reference: c * kind.scale(rho, 100.0, d.si),
                    exponent: 2.0,
                    covariance: [[0.0; 2]; 2],
                    speed_range: [0.0, f64::INFINITY],
                };
                (
                    Propeller {
                        diameter: d.si,
                        density: rho,
                        thrust: Some(law(ct, Kind::Thrust)),
                        torque: Some(law(cq, Kind::Torque)),
                    },
                    None,
                )
            }
            _ => {
                return Err(InputError::invalid(
                    "give the propeller: --propeller RESULT.json (from `propid propulsion`), or --c-t, --c-q and --diameter".into(),
                ))
            }
        };
        let identified = Air::with_density(propeller.density, None)
            .map_err(|e| InputError::invalid(format!("--propeller: {e}")))?;
        let density = self.air.air(identified)?.density;
        if self.rotors == 0 {
            return Err(InputError::invalid("--rotors must be at least 1".into()));
        }
        let mut targets: Vec<Target> = Vec::new();
        if let Some(m) = self.hover_mass {
            targets.push(Target::Thrust(m.si * G0 / f64::from(self.rotors)));
        }
        targets.extend(self.thrust.iter().map(|t| Target::Thrust(t.si)));
        targets.extend(self.torque.iter().map(|t| Target::Torque(t.si)));
        targets.extend(self.speed.iter().map(|t| Target::Speed(t.si)));
        if targets.is_empty() {
            return Err(InputError::invalid(
                "give at least one target: --thrust 6N, --hover-mass 1.5kg, --torque 0.1Nm or --speed 12000rpm".into(),
            ));
        }
        // The motor: flags first, then what the result identified.
        let identified = result.as_ref().and_then(|r| r.motor.as_ref());
        let from_result =
            |f: fn(&propid_science::propulsion::Motor) -> &propid_science::propulsion::Quantity| {
                identified.and_then(|m| f(m).identified())
            };
        let kv = self.kv.map(|p| p.si).or_else(|| from_result(|m| &m.kv));
        let motor = match kv {
            Some(kv) => {
                let r = self
                    .resistance
                    .map(|p| p.si)
                    .or_else(|| from_result(|m| &m.resistance))
                    .ok_or_else(|| InputError::invalid("a motor needs --resistance too (its Kv is known, its resistance is not)".into()))?;
                let i0 = self
                    .no_load_current
                    .map(|p| p.si)
                    .or_else(|| from_result(|m| &m.no_load_current))
                    .unwrap_or(0.0);
                Some(MotorConstants {
                    kv,
                    resistance: r,
                    no_load_current: i0,
                })
            }
            None if self.resistance.is_some() || self.no_load_current.is_some() => {
                return Err(InputError::invalid(
                    "--resistance and --no-load-current describe a motor: give its --kv too".into(),
                ))
            }
            None => None,
        };
        let losses = identified.and_then(|m| m.losses.clone());
        let supply = self.voltage.map(|v| Supply {
            voltage: v.si,
            max_duty: self.max_duty,
        });
        let battery = self.battery.map(|b| Battery {
            capacity: b.si,
            usable: self.usable,
        });
        let q = Question {
            propeller,
            density,
            motor,
            losses,
            supply,
            rotors: self.rotors,
            battery,
            targets,
        };
        propid_science::propulsion::size::check(&q).map_err(InputError::invalid)?;
        Ok(q)
    }
}

/// Runs `propid size`.
pub fn run(args: Args) -> anyhow::Result<()> {
    let q = args.question()?;
    let answer = size(&q).map_err(InputError::invalid)?;
    if let Some(out) = &args.output {
        let inputs: Vec<&std::path::Path> = args.propeller.iter().map(|p| p.as_path()).collect();
        let mut file = propid_io::output::AtomicOutput::create(out, &inputs)?;
        use std::io::Write as _;
        file.write_all((serde_json::to_string_pretty(&answer)? + "\n").as_bytes())
            .and_then(|()| file.commit())
            .map_err(|e| InputError::invalid(format!("{}: cannot write: {e}", out.display())))?;
    }
    let text = match args.format {
        Format::Text => size_text(&answer),
        Format::Json => serde_json::to_string_pretty(&answer)? + "\n",
    };
    use std::io::Write;
    std::io::stdout().write_all(text.as_bytes())?;
    Ok(())
}
