//! `propid sim`: a simulated stand as a command, writing the TSV `propid drive` would have
//! recorded. `--stand formula` (the default) is propid-science's stand, whose effects are the
//! diagnosis's own formulas; `--stand mechanism` is propid-mechsim's, whose effects come from a
//! current loop, an observer, a load cell, bearings, a clock (see that crate).

use std::io::Write;
use std::path::PathBuf;

use anyhow::Context;
use propid_io::output::Output;
use propid_io::tsv::{StandColumn, TsvWriter};
use propid_mechsim::{
    Braking, ConfigError, CurrentLoop, Disturbance, Field, MechConfig, MechStand, ReportNoise, Run,
    TorqueReport, TsvSink, VelocityEstimator,
};
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
    /// Velocity noise [rad/s, or rpm with `rpm`].
    #[arg(long, default_value_t = StandConfig::default().noise_velocity, value_parser = super::speed)]
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
    /// Which simulator: `formula` (effects as the diagnosis's own formulas) or `mechanism`
    /// (effects from a current loop, observer, load cell, bearings, clock: propid-mechsim).
    #[arg(long = "stand", value_enum, default_value_t = StandKind::Formula)]
    pub stand_kind: StandKind,
    /// The mechanism-level stand's own options (boxed: they are many).
    #[command(flatten)]
    pub mech: Box<MechArgs>,
    /// A thrust stand's instruments: thrust cell, bus voltage and current, duty.
    #[command(flatten)]
    pub instruments: Box<super::stand_instruments::InstrumentArgs>,
}

/// The stand simulator `propid sim` runs.
#[derive(Clone, Copy, Debug, PartialEq, Eq, clap::ValueEnum)]
pub enum StandKind {
    /// propid-science's formula-level stand.
    Formula,
    /// propid-mechsim's mechanism-level stand.
    Mechanism,
}

/// What the mechanism-level stand reports as `force`.
#[derive(Clone, Copy, Debug, PartialEq, Eq, clap::ValueEnum)]
pub enum ForceReport {
    /// The torque demand (setpoint × max torque).
    Demand,
    /// Kt_nominal × measured current.
    Current,
    /// A load cell under the stator.
    LoadCell,
}

/// Options of `--stand mechanism` (the shared stand options map onto it: --inertia, --c2,
/// --drag-exponent, --c1 as viscous and --coulomb as bearing friction, --ripple as cogging,
/// --disturbance as a periodic external torque, --rate, the noise options as report noise, and
/// --jitter as timestamp jitter).
#[derive(clap::Args, Debug, Clone, PartialEq)]
#[command(next_help_heading = "Mechanism-level stand (--stand mechanism)")]
pub struct MechArgs {
    /// Control rate of the drive: the internal step [Hz].
    #[arg(long, default_value_t = MechConfig::default().drive.control_rate)]
    pub control_rate: f64,
    /// Bandwidth of the PI current loop [rad/s] (0: ideal).
    #[arg(long, default_value_t = 0.0)]
    pub current_loop_bandwidth: f64,
    /// Motor torque constant Kt = Ke [N·m/A].
    #[arg(long, default_value_t = MechConfig::default().motor.kt)]
    pub motor_kt: f64,
    /// Phase resistance [Ω].
    #[arg(long, default_value_t = MechConfig::default().motor.resistance)]
    pub motor_resistance: f64,
    /// Phase inductance [H].
    #[arg(long, default_value_t = MechConfig::default().motor.inductance)]
    pub motor_inductance: f64,
    /// Supply voltage [V] (inf: no limit).
    #[arg(long, default_value_t = f64::INFINITY)]
    pub supply_voltage: f64,
    /// Error of the drive's torque constant: Kt_true/Kt_nominal − 1.
    #[arg(long, default_value_t = 0.0)]
    pub kt_error: f64,
    /// Braking torque, while decelerating, that the current sense does not show [N·m] (0: off).
    #[arg(long, default_value_t = 0.0)]
    pub braking_torque: f64,
    /// Counts per revolution of the rotor angle measurement (0: exact).
    #[arg(long, default_value_t = 0)]
    pub counts_per_rev: u32,
    /// Natural frequency of the drive's velocity observer (PLL) [Hz] (0: exact velocity).
    #[arg(long, default_value_t = 0.0)]
    pub observer_hz: f64,
    /// Damping of the velocity observer.
    #[arg(long, default_value_t = std::f64::consts::FRAC_1_SQRT_2)]
    pub observer_damping: f64,
    /// Time constant of the low-pass filter on the acceleration estimate [s] (0: none).
    #[arg(long, default_value_t = 0.0)]
    pub acceleration_filter: f64,
    /// What `force` reports.
    #[arg(long, value_enum, default_value_t = ForceReport::Current)]
    pub report: ForceReport,
    /// Time constant of the current-sense filter [s] (--report current).
    #[arg(long, default_value_t = 0.0)]
    pub current_filter: f64,
    /// Zero offset of the reported torque [N·m] (--report current or load-cell).
    #[arg(long, default_value_t = 0.0)]
    pub force_offset: f64,
    /// Noise of the current sense [A] (--report current).
    #[arg(long, default_value_t = 0.0)]
    pub current_noise: f64,
    /// Natural frequency of the load cell [Hz] (--report load-cell).
    #[arg(long, default_value_t = 100.0)]
    pub load_cell_hz: f64,
    /// Damping ratio of the load cell.
    #[arg(long, default_value_t = 0.2)]
    pub load_cell_damping: f64,
    /// Sample rate of the load cell [Hz].
    #[arg(long, default_value_t = 80.0)]
    pub load_cell_rate: f64,
    /// Noise per load-cell sample [N·m].
    #[arg(long, default_value_t = 0.0)]
    pub load_cell_noise: f64,
    /// Break-away friction of a Stribeck curve [N·m] (0: Coulomb only).
    #[arg(long, default_value_t = 0.0)]
    pub breakaway: f64,
    /// Stribeck speed [rad/s, or rpm with `rpm`].
    #[arg(long, default_value_t = 10.0, value_parser = super::speed)]
    pub stribeck_speed: f64,
    /// Relative change of the torque coefficient per unit of |ω|/ω_ref.
    #[arg(long, default_value_t = 0.0)]
    pub cq_slope: f64,
    /// ω_ref of --cq-slope [rad/s, or rpm with `rpm`].
    #[arg(long, default_value_t = 1500.0, value_parser = super::speed)]
    pub cq_reference_speed: f64,
    /// Peak of an external torque bump (a gust) [N·m] (0: none).
    #[arg(long, default_value_t = 0.0)]
    pub bump: f64,
    /// Start of the bump, seconds into the pattern.
    #[arg(long, default_value_t = 0.0)]
    pub bump_start: f64,
    /// Width of the bump [s].
    #[arg(long, default_value_t = 1.0)]
    pub bump_width: f64,
    /// Rate error of the device clock against the host's (0.01: 1 % fast).
    #[arg(long, default_value_t = 0.0)]
    pub clock_rate_error: f64,
    /// Drift of that rate error [1/s].
    #[arg(long, default_value_t = 0.0)]
    pub clock_drift: f64,
    /// Probability of losing a feedback message.
    #[arg(long, default_value_t = 0.0)]
    pub drop_probability: f64,
    /// Device-to-host latency [s].
    #[arg(long, default_value_t = 0.0)]
    pub latency: f64,
    /// Mean of an exponentially distributed extra latency [s].
    #[arg(long, default_value_t = 0.0)]
    pub latency_jitter: f64,
    /// Add a `setpoint` column after `position` (propid's reader ignores it).
    #[arg(long)]
    pub write_setpoint: bool,
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
            ..StandConfig::default()
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
        .map_err(|e| InputError::invalid(format!("{name}: cannot read: {e}")))?;
    propid_science::plan::excitation_from_file(&text, &name)
}

/// The defaults of [`MechArgs`], as clap gives them.
fn mech_defaults() -> MechArgs {
    #[derive(clap::Parser)]
    struct Wrap {
        #[command(flatten)]
        mech: MechArgs,
    }
    <Wrap as clap::Parser>::parse_from(["propid"]).mech
}

impl MechArgs {
    /// The mechanism options given a value other than their default, as flags.
    fn changed(&self) -> Vec<&'static str> {
        let d = mech_defaults();
        let mut out = Vec::new();
        macro_rules! cmp {
            ($($field:ident => $flag:literal),* $(,)?) => {
                $(if self.$field != d.$field { out.push($flag); })*
            };
        }
        cmp!(
            control_rate => "--control-rate",
            current_loop_bandwidth => "--current-loop-bandwidth",
            motor_kt => "--motor-kt",
            motor_resistance => "--motor-resistance",
            motor_inductance => "--motor-inductance",
            supply_voltage => "--supply-voltage",
            kt_error => "--kt-error",
            braking_torque => "--braking-torque",
            counts_per_rev => "--counts-per-rev",
            observer_hz => "--observer-hz",
            observer_damping => "--observer-damping",
            acceleration_filter => "--acceleration-filter",
            report => "--report",
            current_filter => "--current-filter",
            force_offset => "--force-offset",
            current_noise => "--current-noise",
            load_cell_hz => "--load-cell-hz",
            load_cell_damping => "--load-cell-damping",
            load_cell_rate => "--load-cell-rate",
            load_cell_noise => "--load-cell-noise",
            breakaway => "--breakaway",
            stribeck_speed => "--stribeck-speed",
            cq_slope => "--cq-slope",
            cq_reference_speed => "--cq-reference-speed",
            bump => "--bump",
            bump_start => "--bump-start",
            bump_width => "--bump-width",
            clock_rate_error => "--clock-rate-error",
            clock_drift => "--clock-drift",
            drop_probability => "--drop-probability",
            latency => "--latency",
            latency_jitter => "--latency-jitter",
            write_setpoint => "--write-setpoint",
        );
        out
    }
}

/// The flag that sets a field of the mechanism-level stand (`None`: propid sets it itself).
/// Every field is listed: a field added to the stand does not compile here until it has its
/// answer.
fn flag(field: Field) -> Option<&'static str> {
    match field {
        Field::DisturbanceAmplitude => Some("--disturbance or --bump"),
        Field::DisturbanceHz => Some("--disturbance-hz"),
        Field::DisturbanceStart => Some("--bump-start"),
        Field::DisturbanceWidth => Some("--bump-width"),
        // Set by propid itself, never from a flag.
        Field::DriveBrakingOffThreshold => None,
        // Set by propid itself, never from a flag.
        Field::DriveBrakingOnThreshold => None,
        Field::DriveBrakingTorque => Some("--braking-torque"),
        Field::DriveControlRate => Some("--control-rate"),
        Field::DriveCurrentLoopBandwidth => Some("--current-loop-bandwidth"),
        Field::DriveKtError => Some("--kt-error"),
        Field::DriveMaxTorque => Some("--max-torque"),
        Field::InstrumentsBusCurrentFilter => Some("--esc-current-filter"),
        Field::InstrumentsBusNoiseCurrent => Some("--noise-bus-current"),
        Field::InstrumentsBusNoiseVoltage => Some("--noise-bus-voltage"),
        Field::InstrumentsBusSourceResistance => Some("--source-resistance"),
        Field::InstrumentsBusSourceVoltage => Some("--bus-voltage"),
        // Set by propid itself, never from a flag.
        Field::InstrumentsThrustCtReferenceSpeed => None,
        // Set by propid itself, never from a flag.
        Field::InstrumentsThrustCtSlope => None,
        Field::InstrumentsThrustExponent => Some("--thrust-exponent"),
        Field::InstrumentsThrustK => Some("--thrust-k"),
        Field::InstrumentsThrustCellDamping => Some("--thrust-cell-damping"),
        Field::InstrumentsThrustCellNaturalHz => Some("--thrust-cell-hz"),
        Field::InstrumentsThrustCellNoise => Some("--noise-thrust"),
        Field::InstrumentsThrustCellOffset => Some("--thrust-offset"),
        Field::InstrumentsThrustCellRate => Some("--thrust-rate"),
        Field::LinkClockDrift => Some("--clock-drift"),
        // Set by propid itself, never from a flag.
        Field::LinkClockOffset => None,
        Field::LinkClockRateError => Some("--clock-rate-error"),
        Field::LinkClockStampJitter => Some("--jitter"),
        Field::LinkDropProbability => Some("--drop-probability"),
        // Set by propid itself, never from a flag.
        Field::LinkHostOffset => None,
        Field::LinkLatency => Some("--latency"),
        Field::LinkLatencyJitter => Some("--latency-jitter"),
        Field::LinkRate => Some("--rate"),
        Field::MotorInductance => Some("--motor-inductance"),
        Field::MotorKt => Some("--motor-kt"),
        Field::MotorResistance => Some("--motor-resistance"),
        Field::MotorSupplyVoltage => Some("--supply-voltage"),
        Field::RotorBearingBreakaway => Some("--breakaway"),
        Field::RotorBearingCoulomb => Some("--coulomb"),
        Field::RotorBearingStribeckSpeed => Some("--stribeck-speed"),
        Field::RotorBearingViscous => Some("--c1"),
        Field::RotorCoggingAmplitude => Some("--ripple"),
        Field::RotorCoggingHarmonic => Some("--ripple-harmonic"),
        // Set by propid itself, never from a flag.
        Field::RotorCoggingPhase => None,
        Field::RotorDragCqReferenceSpeed => Some("--cq-reference-speed"),
        Field::RotorDragCqSlope => Some("--cq-slope"),
        Field::RotorDragExponent => Some("--drag-exponent"),
        Field::RotorDragK => Some("--c2"),
        Field::RotorInertia => Some("--inertia"),
        Field::RunDuration => Some("--duration"),
        Field::RunInitDuration => Some("--init-duration"),
        Field::RunInitSetpoint => Some("--hi"),
        Field::SensingKinematicsAccelerationFilter => Some("--acceleration-filter"),
        Field::SensingKinematicsCountsPerRev => Some("--counts-per-rev"),
        Field::SensingKinematicsVelocityDamping => Some("--observer-damping"),
        Field::SensingKinematicsVelocityNaturalHz => Some("--observer-hz"),
        Field::SensingNoiseAcceleration => Some("--noise-acceleration"),
        Field::SensingNoiseForce => Some("--noise-force"),
        Field::SensingNoiseVelocity => Some("--noise-velocity"),
        Field::SensingTorqueDamping => Some("--load-cell-damping"),
        Field::SensingTorqueFilter => Some("--current-filter"),
        Field::SensingTorqueNaturalHz => Some("--load-cell-hz"),
        Field::SensingTorqueNoise => Some("--current-noise or --load-cell-noise"),
        Field::SensingTorqueOffset => Some("--force-offset"),
        Field::SensingTorqueRate => Some("--load-cell-rate"),
    }
}

/// A mechsim configuration error in terms of the command line.
fn input_error(e: ConfigError) -> InputError {
    let name = |field: Field| flag(field).map_or_else(|| field.path().to_string(), String::from);
    match e {
        ConfigError::OutOfRange {
            field,
            requirement,
            value,
        } => InputError::invalid(format!(
            "{} must be {requirement} (got {value})",
            name(field)
        )),
        ConfigError::Inconsistent {
            fields: [a, b],
            why,
        } => InputError::invalid(format!("{} and {}: {why}", name(a), name(b))),
    }
}

/// The mechanism-level stand these arguments describe.
pub fn mech_config(stand: &StandArgs, m: &MechArgs) -> Result<MechConfig, InputError> {
    for (flag, v) in [
        ("--torque-lag", stand.torque_lag),
        ("--force-sensor-lag", stand.force_sensor_lag),
        ("--acceleration-lag", stand.acceleration_lag),
    ] {
        if v != 0.0 {
            return Err(InputError::invalid(format!(
                "{flag} is a formula-stand effect; with --stand mechanism a lag comes from a mechanism \
                 (--current-loop-bandwidth with --report demand, --current-filter, --observer-hz, \
                 --acceleration-filter, --report load-cell)"
            )));
        }
    }
    let mut c = MechConfig::default();
    c.rotor.inertia = stand.inertia;
    c.rotor.drag.k = stand.c2;
    c.rotor.drag.exponent = stand.drag_exponent;
    c.rotor.drag.cq_slope = m.cq_slope;
    c.rotor.drag.cq_reference_speed = m.cq_reference_speed;
    c.rotor.bearing.coulomb = stand.coulomb;
    c.rotor.bearing.breakaway = m.breakaway;
    c.rotor.bearing.stribeck_speed = m.stribeck_speed;
    c.rotor.bearing.viscous = stand.c1;
    c.rotor.cogging.amplitude = stand.ripple;
    c.rotor.cogging.harmonic = stand.ripple_harmonic;
    c.rotor.cogging.phase = 0.3;
    c.motor.kt = m.motor_kt;
    c.motor.resistance = m.motor_resistance;
    c.motor.inductance = m.motor_inductance;
    c.motor.supply_voltage = m.supply_voltage;
    c.drive.max_torque = stand.max_torque;
    c.drive.control_rate = m.control_rate;
    c.drive.current_loop = (m.current_loop_bandwidth != 0.0).then_some(CurrentLoop {
        bandwidth: m.current_loop_bandwidth,
    });
    c.drive.kt_error = m.kt_error;
    c.drive.braking = (m.braking_torque != 0.0).then_some(Braking {
        torque: m.braking_torque,
        on_threshold: 50.0,
        off_threshold: 20.0,
    });
    c.sensing.kinematics.counts_per_rev = (m.counts_per_rev != 0).then_some(m.counts_per_rev);
    if m.observer_hz != 0.0 {
        c.sensing.kinematics.velocity = VelocityEstimator::Pll {
            natural_hz: m.observer_hz,
            damping: m.observer_damping,
        };
    }
    c.sensing.kinematics.acceleration_filter = m.acceleration_filter;
    c.sensing.torque = match m.report {
        ForceReport::Demand => TorqueReport::Setpoint,
        ForceReport::Current => {
            // The offset is given as torque; the current sense's is in amperes.
            let kt_nominal = m.motor_kt / (1.0 + m.kt_error);
            TorqueReport::Current {
                filter: m.current_filter,
                offset: m.force_offset / kt_nominal,
                noise: m.current_noise,
            }
        }
        ForceReport::LoadCell => TorqueReport::LoadCell {
            natural_hz: m.load_cell_hz,
            damping: m.load_cell_damping,
            rate: m.load_cell_rate,
            offset: m.force_offset,
            noise: m.load_cell_noise,
        },
    };
    c.sensing.noise = ReportNoise {
        force: stand.noise_force,
        velocity: stand.noise_velocity,
        acceleration: stand.noise_acceleration,
    };
    c.disturbance = match (stand.disturbance != 0.0, m.bump != 0.0) {
        (true, true) => {
            return Err(InputError::invalid(
                "--disturbance and --bump cannot be combined (one external torque at a time)"
                    .into(),
            ))
        }
        (true, false) => Disturbance::Periodic {
            amplitude: stand.disturbance,
            hz: stand.disturbance_hz,
        },
        (false, true) => Disturbance::Bump {
            amplitude: m.bump,
            start: m.bump_start,
            width: m.bump_width,
        },
        (false, false) => Disturbance::None,
    };
    c.link.rate = stand.rate;
    c.link.clock.rate_error = m.clock_rate_error;
    c.link.clock.drift = m.clock_drift;
    c.link.clock.stamp_jitter = stand.jitter;
    c.link.drop_probability = m.drop_probability;
    c.link.latency = m.latency;
    c.link.latency_jitter = m.latency_jitter;
    c.validate().map_err(input_error)?;
    Ok(c)
}

fn run_mechanism(args: &Args, out: Box<dyn Write + '_>) -> anyhow::Result<()> {
    let config = mech_config(&args.stand, &args.mech)?;
    let excitation = args.excitation()?;
    excitation.validate()?;
    let run = Run {
        init_setpoint: excitation.hi,
        init_duration: excitation.init_duration,
        duration: excitation.duration,
    };
    run.validate().map_err(input_error)?;
    let mut config = config;
    args.instruments.mechanism(&mut config)?;
    config.validate().map_err(input_error)?;
    let mut sink = TsvSink::with_stand(out, args.mech.write_setpoint, args.instruments.any())?;
    let mut failure = None;
    let stand = MechStand::new(config, args.stand.seed).map_err(input_error)?;
    let rows = stand
        .run(
            &run,
            |t| excitation.setpoint(t),
            |r| {
                if failure.is_none() {
                    failure = sink.write(r).err();
                }
            },
        )
        .map_err(input_error)?;
    if let Some(e) = failure {
        return Err(e.into());
    }
    sink.finish()?;
    eprintln!(
        "simulated {rows} rows ({} s at {} Hz, mechanism-level stand)",
        excitation.duration, config.link.rate
    );
    Ok(())
}

/// Runs `propid sim`.
pub fn run(args: Args) -> anyhow::Result<()> {
    if args.stand_kind == StandKind::Formula {
        let changed = args.mech.changed();
        if !changed.is_empty() {
            return Err(InputError::invalid(format!(
                "{} {} only to --stand mechanism",
                changed.join(", "),
                if changed.len() == 1 {
                    "applies"
                } else {
                    "apply"
                }
            ))
            .into());
        }
    }
    // Standard output, or a file written whole (never over the pattern file read).
    let inputs: Vec<&std::path::Path> = args.pattern_file.iter().map(|p| p.as_path()).collect();
    let mut out = Output::create(args.output.as_deref(), &inputs)?;
    let out_name = out.name();
    let writing = || format!("writing {out_name}");
    if args.stand_kind != StandKind::Formula {
        run_mechanism(&args, Box::new(std::io::BufWriter::new(&mut out)))?;
        return out.finish().with_context(writing);
    }
    let config = args.stand.config()?;
    let excitation = args.excitation()?;
    excitation.validate()?;
    let drivetrain = args.instruments.formula()?;
    let columns: &[StandColumn] = if drivetrain.is_some() {
        &StandColumn::ALL
    } else {
        &[]
    };
    let mut writer =
        TsvWriter::with_columns(std::io::BufWriter::new(&mut out), false, columns, &[])
            .with_context(writing)?;
    let mut stand = Stand::new(config, args.stand.seed);
    if let Some(d) = drivetrain {
        stand = stand.with_drivetrain(d, args.stand.seed);
    }
    let rows = stand
        .run(&excitation, |row| writer.write(&row))
        .with_context(writing)?;
    writer.into_inner().with_context(writing)?;
    out.finish().with_context(writing)?;
    eprintln!(
        "simulated {rows} rows ({} s at {} Hz)",
        excitation.duration, config.rate
    );
    Ok(())
}
