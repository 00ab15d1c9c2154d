//! `propid sim`: the formula-level stand simulator as a command, writing the TSV `propid drive`
//! would have recorded.

use std::io::Write;
use std::path::PathBuf;

use anyhow::Context;
use propid_io::tsv::TsvWriter;
use propid_science::excitation::{Excitation, Pattern};
use propid_science::stand::{Stand, StandConfig};

use crate::InputError;

/// The simulated stand's parameters as command-line options (shared by `sim`, `sim-drive` and
/// `demo`).
#[derive(clap::Args, Debug, Clone)]
pub struct StandArgs {
    /// Random seed for the noise.
    #[arg(long, default_value_t = 1)]
    pub seed: u64,
    /// Inertia J [kg·m²].
    #[arg(long, default_value_t = StandConfig::default().inertia)]
    pub inertia: f64,
    /// Viscous friction c1 [N·m·s/rad] (hidden effect `viscous_friction`).
    #[arg(long, default_value_t = 0.0)]
    pub c1: f64,
    /// Drag coefficient c2 [N·m·s²/rad²].
    #[arg(long, default_value_t = StandConfig::default().c2)]
    pub c2: f64,
    /// Drag exponent p (hidden effect `drag_exponent` when ≠ 2).
    #[arg(long, default_value_t = 2.0)]
    pub drag_exponent: f64,
    /// Coulomb friction [N·m] (hidden effect `coulomb_friction`).
    #[arg(long, default_value_t = 0.0)]
    pub coulomb: f64,
    /// Torque ripple amplitude [N·m] (hidden effect `torque_ripple`).
    #[arg(long, default_value_t = 0.0)]
    pub ripple: f64,
    /// Ripple periods per revolution.
    #[arg(long, default_value_t = 6.0)]
    pub ripple_harmonic: f64,
    /// Torque at setpoint 1 [N·m].
    #[arg(long, default_value_t = StandConfig::default().max_torque)]
    pub max_torque: f64,
    /// Lag of the felt torque behind the reported one [s] (hidden effect `torque_lag`).
    #[arg(long, default_value_t = 0.0)]
    pub torque_lag: f64,
    /// Lag of the reported torque behind the felt one [s] (hidden effect `force_sensor_lag`).
    #[arg(long, default_value_t = 0.0)]
    pub force_sensor_lag: f64,
    /// Lag of the reported acceleration [s] (hidden effect `acceleration_lag`).
    #[arg(long, default_value_t = 0.0)]
    pub acceleration_lag: f64,
    /// Amplitude of a periodic external torque [N·m] (not a modelled effect: "unexplained").
    #[arg(long, default_value_t = 0.0)]
    pub disturbance: f64,
    /// Frequency of the disturbance [Hz].
    #[arg(long, default_value_t = 7.0)]
    pub disturbance_hz: f64,
    /// Feedback rate [Hz].
    #[arg(long, default_value_t = 500.0)]
    pub rate: f64,
    /// Torque noise [N·m].
    #[arg(long, default_value_t = StandConfig::default().noise_force)]
    pub noise_force: f64,
    /// Velocity noise [rad/s].
    #[arg(long, default_value_t = StandConfig::default().noise_velocity)]
    pub noise_velocity: f64,
    /// Acceleration noise [rad/s²].
    #[arg(long, default_value_t = StandConfig::default().noise_acceleration)]
    pub noise_acceleration: f64,
    /// Sampling-time jitter [s].
    #[arg(long, default_value_t = StandConfig::default().jitter)]
    pub jitter: f64,
}

/// Arguments of `propid sim`.
#[derive(clap::Args, Debug)]
pub struct Args {
    /// Output TSV (standard output if omitted).
    #[arg(short, long)]
    pub output: Option<PathBuf>,
    /// The stand.
    #[command(flatten)]
    pub stand: StandArgs,
    /// Low setpoint.
    #[arg(long, default_value_t = 0.1)]
    pub lo: f64,
    /// High setpoint.
    #[arg(long, default_value_t = 0.9)]
    pub hi: f64,
    /// Period of the sinusoid [s].
    #[arg(long, default_value_t = 2.0)]
    pub period: f64,
    /// Duration of the pattern [s].
    #[arg(long, default_value_t = 60.0)]
    pub duration: f64,
    /// Init phase at the high setpoint [s].
    #[arg(long, default_value_t = 5.0)]
    pub init_duration: f64,
    /// Pattern after the init phase: sine, steps, chirp, square, prbs, multisine.
    #[arg(long, default_value_t = Pattern::Sine)]
    pub pattern: Pattern,
    /// Play a pattern file from `propid plan` instead (its range, period and durations).
    #[arg(long, conflicts_with_all = ["pattern", "lo", "hi", "period", "duration", "init_duration"])]
    pub pattern_file: Option<PathBuf>,
}

impl StandArgs {
    /// The stand configuration these arguments describe (validated).
    pub fn config(&self) -> Result<StandConfig, InputError> {
        let config = self.config_unchecked();
        config.validate()?;
        Ok(config)
    }

    fn config_unchecked(&self) -> StandConfig {
        StandConfig {
            inertia: self.inertia,
            c1: self.c1,
            c2: self.c2,
            drag_exponent: self.drag_exponent,
            coulomb: self.coulomb,
            ripple: self.ripple,
            ripple_harmonic: self.ripple_harmonic,
            max_torque: self.max_torque,
            torque_lag: self.torque_lag,
            force_sensor_lag: self.force_sensor_lag,
            acceleration_lag: self.acceleration_lag,
            disturbance: self.disturbance,
            disturbance_hz: self.disturbance_hz,
            rate: self.rate,
            noise_force: self.noise_force,
            noise_velocity: self.noise_velocity,
            noise_acceleration: self.noise_acceleration,
            jitter: self.jitter,
        }
    }
}

impl Args {
    /// The excitation these arguments describe (a pattern file's, when given).
    pub fn excitation(&self) -> Result<Excitation, InputError> {
        if let Some(path) = &self.pattern_file {
            return read_pattern_file(path);
        }
        Ok(Excitation {
            lo: self.lo,
            hi: self.hi,
            period: self.period,
            duration: self.duration,
            init_duration: self.init_duration,
            pattern: self.pattern,
        })
    }
}

/// Reads a pattern file written by `propid plan`.
pub fn read_pattern_file(path: &std::path::Path) -> Result<Excitation, InputError> {
    let name = path.display().to_string();
    let text = std::fs::read_to_string(path)
        .map_err(|e| InputError(format!("{name}: cannot read: {e}")))?;
    propid_science::plan::excitation_from_file(&text, &name)
}

/// Runs `propid sim`.
pub fn run(args: Args) -> anyhow::Result<()> {
    let config = args.stand.config()?;
    let excitation = args.excitation()?;
    excitation.validate()?;
    let out: Box<dyn Write> = match &args.output {
        Some(p) => Box::new(std::io::BufWriter::new(
            std::fs::File::create(p).with_context(|| format!("cannot create {}", p.display()))?,
        )),
        None => Box::new(std::io::BufWriter::new(std::io::stdout().lock())),
    };
    let mut writer = TsvWriter::new(out, false)?;
    let mut stand = Stand::new(config, args.stand.seed);
    let rows = stand.run(&excitation, |row| writer.write(&row))?;
    writer.into_inner()?;
    eprintln!(
        "simulated {rows} rows ({} s at {} Hz)",
        excitation.duration, config.rate
    );
    Ok(())
}
