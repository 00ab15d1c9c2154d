//! The stand's description: one struct per physical part, every mechanism off by default.
//!
//! [`MechConfig::default`] is a clean stand: an ideal current loop, exact sensing, no friction, no
//! offset, a perfect clock, no lost messages and no noise. Each field that switches a mechanism on
//! says what it models and in which unit. [`MechConfig::validate`] checks everything once and
//! returns a [`ConfigError`] naming the field.

use std::fmt;

/// A field of the configuration, by its dotted path ([`Field::path`]): what a [`ConfigError`]
/// names, typed, so a caller can say which of its own settings set it (and a new field is one
/// new variant every such caller must handle).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum Field {
    /// `disturbance.amplitude`.
    DisturbanceAmplitude,
    /// `disturbance.hz`.
    DisturbanceHz,
    /// `disturbance.start`.
    DisturbanceStart,
    /// `disturbance.width`.
    DisturbanceWidth,
    /// `drive.braking.off_threshold`.
    DriveBrakingOffThreshold,
    /// `drive.braking.on_threshold`.
    DriveBrakingOnThreshold,
    /// `drive.braking.torque`.
    DriveBrakingTorque,
    /// `drive.control_rate`.
    DriveControlRate,
    /// `drive.current_loop.bandwidth`.
    DriveCurrentLoopBandwidth,
    /// `drive.kt_error`.
    DriveKtError,
    /// `drive.max_torque`.
    DriveMaxTorque,
    /// `instruments.bus.current_filter`.
    InstrumentsBusCurrentFilter,
    /// `instruments.bus.noise_current`.
    InstrumentsBusNoiseCurrent,
    /// `instruments.bus.noise_voltage`.
    InstrumentsBusNoiseVoltage,
    /// `instruments.bus.source_resistance`.
    InstrumentsBusSourceResistance,
    /// `instruments.bus.source_voltage`.
    InstrumentsBusSourceVoltage,
    /// `instruments.thrust.ct_reference_speed`.
    InstrumentsThrustCtReferenceSpeed,
    /// `instruments.thrust.ct_slope`.
    InstrumentsThrustCtSlope,
    /// `instruments.thrust.exponent`.
    InstrumentsThrustExponent,
    /// `instruments.thrust.k`.
    InstrumentsThrustK,
    /// `instruments.thrust_cell.damping`.
    InstrumentsThrustCellDamping,
    /// `instruments.thrust_cell.natural_hz`.
    InstrumentsThrustCellNaturalHz,
    /// `instruments.thrust_cell.noise`.
    InstrumentsThrustCellNoise,
    /// `instruments.thrust_cell.offset`.
    InstrumentsThrustCellOffset,
    /// `instruments.thrust_cell.rate`.
    InstrumentsThrustCellRate,
    /// `link.clock.drift`.
    LinkClockDrift,
    /// `link.clock.offset`.
    LinkClockOffset,
    /// `link.clock.rate_error`.
    LinkClockRateError,
    /// `link.clock.stamp_jitter`.
    LinkClockStampJitter,
    /// `link.drop_probability`.
    LinkDropProbability,
    /// `link.host_offset`.
    LinkHostOffset,
    /// `link.latency`.
    LinkLatency,
    /// `link.latency_jitter`.
    LinkLatencyJitter,
    /// `link.rate`.
    LinkRate,
    /// `motor.inductance`.
    MotorInductance,
    /// `motor.kt`.
    MotorKt,
    /// `motor.resistance`.
    MotorResistance,
    /// `motor.supply_voltage`.
    MotorSupplyVoltage,
    /// `rotor.bearing.breakaway`.
    RotorBearingBreakaway,
    /// `rotor.bearing.coulomb`.
    RotorBearingCoulomb,
    /// `rotor.bearing.stribeck_speed`.
    RotorBearingStribeckSpeed,
    /// `rotor.bearing.viscous`.
    RotorBearingViscous,
    /// `rotor.cogging.amplitude`.
    RotorCoggingAmplitude,
    /// `rotor.cogging.harmonic`.
    RotorCoggingHarmonic,
    /// `rotor.cogging.phase`.
    RotorCoggingPhase,
    /// `rotor.drag.cq_reference_speed`.
    RotorDragCqReferenceSpeed,
    /// `rotor.drag.cq_slope`.
    RotorDragCqSlope,
    /// `rotor.drag.exponent`.
    RotorDragExponent,
    /// `rotor.drag.k`.
    RotorDragK,
    /// `rotor.inertia`.
    RotorInertia,
    /// `run.duration`.
    RunDuration,
    /// `run.init_duration`.
    RunInitDuration,
    /// `run.init_setpoint`.
    RunInitSetpoint,
    /// `sensing.kinematics.acceleration_filter`.
    SensingKinematicsAccelerationFilter,
    /// `sensing.kinematics.counts_per_rev`.
    SensingKinematicsCountsPerRev,
    /// `sensing.kinematics.velocity.damping`.
    SensingKinematicsVelocityDamping,
    /// `sensing.kinematics.velocity.natural_hz`.
    SensingKinematicsVelocityNaturalHz,
    /// `sensing.noise.acceleration`.
    SensingNoiseAcceleration,
    /// `sensing.noise.force`.
    SensingNoiseForce,
    /// `sensing.noise.velocity`.
    SensingNoiseVelocity,
    /// `sensing.torque.damping`.
    SensingTorqueDamping,
    /// `sensing.torque.filter`.
    SensingTorqueFilter,
    /// `sensing.torque.natural_hz`.
    SensingTorqueNaturalHz,
    /// `sensing.torque.noise`.
    SensingTorqueNoise,
    /// `sensing.torque.offset`.
    SensingTorqueOffset,
    /// `sensing.torque.rate`.
    SensingTorqueRate,
}

impl Field {
    /// The field's dotted path, e.g. `link.rate`.
    pub const fn path(self) -> &'static str {
        match self {
            Field::DisturbanceAmplitude => "disturbance.amplitude",
            Field::DisturbanceHz => "disturbance.hz",
            Field::DisturbanceStart => "disturbance.start",
            Field::DisturbanceWidth => "disturbance.width",
            Field::DriveBrakingOffThreshold => "drive.braking.off_threshold",
            Field::DriveBrakingOnThreshold => "drive.braking.on_threshold",
            Field::DriveBrakingTorque => "drive.braking.torque",
            Field::DriveControlRate => "drive.control_rate",
            Field::DriveCurrentLoopBandwidth => "drive.current_loop.bandwidth",
            Field::DriveKtError => "drive.kt_error",
            Field::DriveMaxTorque => "drive.max_torque",
            Field::InstrumentsBusCurrentFilter => "instruments.bus.current_filter",
            Field::InstrumentsBusNoiseCurrent => "instruments.bus.noise_current",
            Field::InstrumentsBusNoiseVoltage => "instruments.bus.noise_voltage",
            Field::InstrumentsBusSourceResistance => "instruments.bus.source_resistance",
            Field::InstrumentsBusSourceVoltage => "instruments.bus.source_voltage",
            Field::InstrumentsThrustCtReferenceSpeed => "instruments.thrust.ct_reference_speed",
            Field::InstrumentsThrustCtSlope => "instruments.thrust.ct_slope",
            Field::InstrumentsThrustExponent => "instruments.thrust.exponent",
            Field::InstrumentsThrustK => "instruments.thrust.k",
            Field::InstrumentsThrustCellDamping => "instruments.thrust_cell.damping",
            Field::InstrumentsThrustCellNaturalHz => "instruments.thrust_cell.natural_hz",
            Field::InstrumentsThrustCellNoise => "instruments.thrust_cell.noise",
            Field::InstrumentsThrustCellOffset => "instruments.thrust_cell.offset",
            Field::InstrumentsThrustCellRate => "instruments.thrust_cell.rate",
            Field::LinkClockDrift => "link.clock.drift",
            Field::LinkClockOffset => "link.clock.offset",
            Field::LinkClockRateError => "link.clock.rate_error",
            Field::LinkClockStampJitter => "link.clock.stamp_jitter",
            Field::LinkDropProbability => "link.drop_probability",
            Field::LinkHostOffset => "link.host_offset",
            Field::LinkLatency => "link.latency",
            Field::LinkLatencyJitter => "link.latency_jitter",
            Field::LinkRate => "link.rate",
            Field::MotorInductance => "motor.inductance",
            Field::MotorKt => "motor.kt",
            Field::MotorResistance => "motor.resistance",
            Field::MotorSupplyVoltage => "motor.supply_voltage",
            Field::RotorBearingBreakaway => "rotor.bearing.breakaway",
            Field::RotorBearingCoulomb => "rotor.bearing.coulomb",
            Field::RotorBearingStribeckSpeed => "rotor.bearing.stribeck_speed",
            Field::RotorBearingViscous => "rotor.bearing.viscous",
            Field::RotorCoggingAmplitude => "rotor.cogging.amplitude",
            Field::RotorCoggingHarmonic => "rotor.cogging.harmonic",
            Field::RotorCoggingPhase => "rotor.cogging.phase",
            Field::RotorDragCqReferenceSpeed => "rotor.drag.cq_reference_speed",
            Field::RotorDragCqSlope => "rotor.drag.cq_slope",
            Field::RotorDragExponent => "rotor.drag.exponent",
            Field::RotorDragK => "rotor.drag.k",
            Field::RotorInertia => "rotor.inertia",
            Field::RunDuration => "run.duration",
            Field::RunInitDuration => "run.init_duration",
            Field::RunInitSetpoint => "run.init_setpoint",
            Field::SensingKinematicsAccelerationFilter => "sensing.kinematics.acceleration_filter",
            Field::SensingKinematicsCountsPerRev => "sensing.kinematics.counts_per_rev",
            Field::SensingKinematicsVelocityDamping => "sensing.kinematics.velocity.damping",
            Field::SensingKinematicsVelocityNaturalHz => "sensing.kinematics.velocity.natural_hz",
            Field::SensingNoiseAcceleration => "sensing.noise.acceleration",
            Field::SensingNoiseForce => "sensing.noise.force",
            Field::SensingNoiseVelocity => "sensing.noise.velocity",
            Field::SensingTorqueDamping => "sensing.torque.damping",
            Field::SensingTorqueFilter => "sensing.torque.filter",
            Field::SensingTorqueNaturalHz => "sensing.torque.natural_hz",
            Field::SensingTorqueNoise => "sensing.torque.noise",
            Field::SensingTorqueOffset => "sensing.torque.offset",
            Field::SensingTorqueRate => "sensing.torque.rate",
        }
    }
}

impl fmt::Display for Field {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(self.path())
    }
}

/// Why a configuration does not describe a stand. Every variant names the field (a dotted path
/// such as `motor.resistance`).
#[derive(Clone, Debug, PartialEq)]
pub enum ConfigError {
    /// A value is outside the range it must lie in.
    OutOfRange {
        /// The field, e.g. `link.rate`.
        field: Field,
        /// What the value must satisfy, e.g. `> 0 and finite`.
        requirement: &'static str,
        /// The value found.
        value: f64,
    },
    /// Two fields contradict each other.
    Inconsistent {
        /// The fields involved.
        fields: [Field; 2],
        /// Why they do not go together.
        why: &'static str,
    },
}

impl fmt::Display for ConfigError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            ConfigError::OutOfRange {
                field,
                requirement,
                value,
            } => write!(f, "{field} must be {requirement} (got {value})"),
            ConfigError::Inconsistent { fields, why } => {
                write!(f, "{} and {}: {why}", fields[0], fields[1])
            }
        }
    }
}

impl std::error::Error for ConfigError {}

fn check(field: Field, value: f64, requirement: &'static str, ok: bool) -> Result<(), ConfigError> {
    if ok && !value.is_nan() {
        Ok(())
    } else {
        Err(ConfigError::OutOfRange {
            field,
            requirement,
            value,
        })
    }
}

fn positive(field: Field, v: f64) -> Result<(), ConfigError> {
    check(field, v, "> 0 and finite", v > 0.0 && v.is_finite())
}

fn non_negative(field: Field, v: f64) -> Result<(), ConfigError> {
    check(field, v, "≥ 0 and finite", v >= 0.0 && v.is_finite())
}

fn finite(field: Field, v: f64) -> Result<(), ConfigError> {
    check(field, v, "finite", v.is_finite())
}

/// The aerodynamic load: drag torque `k·|ω|^p·(1 + α·(|ω|/ω_ref − 1))·sgn ω`.
///
/// The last factor is a torque coefficient that varies with speed (Reynolds number, blade flex,
/// tip effects): `C_Q(ω) = C_Q(ω_ref)·(1 + α·(|ω|/ω_ref − 1))`. With α = 0 (the default) the law is
/// the plain power law, and with p = 2 the seed's `c2·ω|ω|`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Drag {
    /// k [N·m·(s/rad)^p]; with p = 2 this is the seed's c2.
    pub k: f64,
    /// p: the exponent of the speed [–].
    pub exponent: f64,
    /// α: relative change of the torque coefficient per unit of |ω|/ω_ref [–] (0: constant C_Q).
    pub cq_slope: f64,
    /// ω_ref: the speed at which C_Q has its nominal value [rad/s].
    pub cq_reference_speed: f64,
}

/// Bearing friction: `(F_c + (F_s − F_c)·exp(−(ω/ω_s)²))·sgn ω + b·ω` (Coulomb + Stribeck +
/// viscous). It acts between rotor and stator, so a load cell under the stator does not see it.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Bearing {
    /// F_c: Coulomb (kinetic) friction [N·m].
    pub coulomb: f64,
    /// F_s: break-away (static) friction, ≥ F_c when a Stribeck dip is wanted; 0 means F_s = F_c.
    pub breakaway: f64,
    /// ω_s: the Stribeck speed, below which friction rises towards F_s [rad/s].
    pub stribeck_speed: f64,
    /// b: viscous friction [N·m·s/rad].
    pub viscous: f64,
}

/// Cogging torque of the motor's magnets against its slots: `A·sin(n·θ + φ)`. It acts between
/// rotor and stator (a load cell sees it; the phase current does not carry it).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Cogging {
    /// A: amplitude [N·m] (0: none).
    pub amplitude: f64,
    /// n: periods per revolution (a whole number).
    pub harmonic: f64,
    /// φ: phase [rad].
    pub phase: f64,
}

/// The rotor with its propeller.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Rotor {
    /// J: inertia of rotor and propeller [kg·m²].
    pub inertia: f64,
    /// The aerodynamic drag.
    pub drag: Drag,
    /// The bearing friction.
    pub bearing: Bearing,
    /// The cogging torque.
    pub cogging: Cogging,
}

/// The motor's electrical side (SI units, so the back-EMF constant equals the torque constant).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Motor {
    /// Kt = Ke: torque per ampere of q-axis current [N·m/A], equal to the back-EMF constant
    /// [V·s/rad].
    pub kt: f64,
    /// R: phase resistance [Ω].
    pub resistance: f64,
    /// L: phase inductance [H].
    pub inductance: f64,
    /// Supply (DC-link) voltage available to the q axis [V]; infinity means no limit.
    pub supply_voltage: f64,
}

/// A PI current loop of finite bandwidth.
///
/// Gains by pole-zero cancellation, `Kp = L·ω_c`, `Ki = R·ω_c`, with back-EMF feed-forward `Kt·ω`
/// (the drive's own Kt, see [`Drive::kt_error`]): the closed loop is then exactly `ω_c/(s + ω_c)`
/// from current reference to current, as long as the supply voltage does not limit it. The
/// controller is modelled in continuous time; a digital loop at 10–20 kHz adds half a period
/// (25–50 µs), under 1 % of the lags it is used for. Anti-windup: the integrator holds while the
/// voltage is limited and the error pushes further into the limit.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct CurrentLoop {
    /// ω_c: closed-loop bandwidth [rad/s].
    pub bandwidth: f64,
}

/// Active braking that the drive's current measurement does not show.
///
/// While the drive's own acceleration estimate is below `−on_threshold`, it adds a braking torque
/// opposing rotation (e.g. it shorts the phases in a path its shunt does not see, or regenerates
/// through a one-way current sense); it stops when the estimate rises above `−off_threshold`
/// (hysteresis, so the decision does not chatter). The brake is held between control ticks.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Braking {
    /// B: braking torque magnitude [N·m].
    pub torque: f64,
    /// Deceleration above which the brake engages [rad/s²] (positive number).
    pub on_threshold: f64,
    /// Deceleration below which it releases [rad/s²] (positive, ≤ `on_threshold`).
    pub off_threshold: f64,
}

/// The drive (motor controller) in ratiometric torque mode.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Drive {
    /// Torque at setpoint 1 [N·m]: torque command = setpoint × this.
    pub max_torque: f64,
    /// Control rate: the internal integration step is one control period; the rotor angle is
    /// sampled, the setpoint read and the brake decided once per period [Hz].
    pub control_rate: f64,
    /// The current loop; `None` is an ideal one (the current equals its reference at once, limited
    /// only quasi-statically by the supply voltage: |R·i + Kt·ω| ≤ V).
    pub current_loop: Option<CurrentLoop>,
    /// Relative error of the drive's torque constant: `Kt_true/Kt_nominal − 1` [–]. The drive
    /// converts torque to current and current to reported torque with Kt_nominal.
    pub kt_error: f64,
    /// Active braking not shown by the reported current (`None`: off).
    pub braking: Option<Braking>,
}

/// How the drive estimates velocity from the rotor angle.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum VelocityEstimator {
    /// The true velocity at the control tick.
    Ideal,
    /// A type-2 tracking observer (PLL) on the sampled, held angle:
    /// `θ̂' = ω̂ + k1·e`, `ω̂' = k2·e`, `e = θ_meas − θ̂`, `k1 = 2ζω_n`, `k2 = ω_n²`.
    /// Then `ω̂/ω = ω_n²/(s² + 2ζω_n s + ω_n²)` exactly: the velocity (and the acceleration taken
    /// from it) lags by `2ζ/ω_n` at low frequency.
    Pll {
        /// f_n = ω_n/2π: natural frequency of the observer [Hz].
        natural_hz: f64,
        /// ζ: damping (1/√2 makes the magnitude maximally flat).
        damping: f64,
    },
}

/// The drive's sensing of the rotor.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Kinematics {
    /// Counts per revolution of the angle measurement (encoder, Hall sensors, or the resolution of
    /// a sensorless estimate); `None`: exact.
    pub counts_per_rev: Option<u32>,
    /// The velocity estimator.
    pub velocity: VelocityEstimator,
    /// Time constant of a first-order low-pass filter on the derivative of the velocity estimate,
    /// which is the reported acceleration [s]; 0: unfiltered.
    pub acceleration_filter: f64,
}

/// What the `force` field of the feedback carries.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum TorqueReport {
    /// The torque command (setpoint × max torque), as a drive reports its demand.
    Setpoint,
    /// `Kt_nominal × measured current`: the current through a first-order current-sense filter,
    /// plus a zero offset and white noise.
    Current {
        /// Time constant of the current-sense filter [s] (0: none).
        filter: f64,
        /// Zero offset of the current sense [A].
        offset: f64,
        /// White noise on each reported current (standard deviation) [A].
        noise: f64,
    },
    /// A load cell under the stator: a mass-spring-damper driven by the rotor–stator torque
    /// (electromagnetic + cogging + brake − bearing friction), sampled at its own rate and held
    /// (zero-order hold) between samples, with a zero offset and white noise per sample.
    LoadCell {
        /// Natural frequency of the cell with the motor on it [Hz].
        natural_hz: f64,
        /// Damping ratio [–].
        damping: f64,
        /// Sample rate of the cell's ADC [Hz].
        rate: f64,
        /// Zero offset [N·m].
        offset: f64,
        /// White noise per sample (standard deviation) [N·m].
        noise: f64,
    },
}

/// White noise added to the reported values (a stand-in for noise sources the mechanisms here do
/// not produce themselves; zero by default).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ReportNoise {
    /// On force [N·m].
    pub force: f64,
    /// On velocity [rad/s].
    pub velocity: f64,
    /// On acceleration [rad/s²].
    pub acceleration: f64,
}

/// The drive's sensing and reporting.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Sensing {
    /// Angle, velocity and acceleration estimation.
    pub kinematics: Kinematics,
    /// The source of the reported force.
    pub torque: TorqueReport,
    /// Extra white noise on the reported values.
    pub noise: ReportNoise,
}

/// An external torque on the rotor that is none of the modelled mechanisms.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Disturbance {
    /// None.
    None,
    /// `A·sin(2π f t)` (e.g. a vibrating fixture, a wake).
    Periodic {
        /// A [N·m].
        amplitude: f64,
        /// f [Hz].
        hz: f64,
    },
    /// A raised-cosine bump `A·(1 − cos(2π(t − t0)/w))/2` on `[t0, t0 + w]` (a gust, a hand on the
    /// fixture), `t` in seconds since the pattern began.
    Bump {
        /// A: peak torque [N·m] (positive drives the rotor).
        amplitude: f64,
        /// t0 [s].
        start: f64,
        /// w [s].
        width: f64,
    },
}

/// The device clock: device time `τ = offset + (1 + ε)·t + ε̇·t²/2`, t the true time since the
/// pattern began.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct DeviceClock {
    /// ε: rate error of the device clock against the host's [–] (0.01: 1 % fast).
    pub rate_error: f64,
    /// ε̇: drift of the rate error [1/s].
    pub drift: f64,
    /// Device time at the start of the pattern [s].
    pub offset: f64,
    /// Jitter of the timestamp against the instant the message was built (standard deviation) [s].
    pub stamp_jitter: f64,
}

/// The feedback link: message rate, loss, and the host's receive time.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Link {
    /// Feedback message rate, on the device clock [Hz].
    pub rate: f64,
    /// The device clock.
    pub clock: DeviceClock,
    /// Probability that a message is lost [–].
    pub drop_probability: f64,
    /// Fixed latency from device to host [s].
    pub latency: f64,
    /// Mean of an exponentially distributed extra latency [s] (0: none).
    pub latency_jitter: f64,
    /// Host time (`ts_local`) at the start of the pattern [s].
    pub host_offset: f64,
}

/// The propeller's thrust: `T = k·|ω|^p·(1 + α·(|ω|/ω_ref − 1))` along the thrust axis. Like
/// [`Drag`], the last factor lets the thrust coefficient change with speed.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Thrust {
    /// k [N·(s/rad)^p]; 0: no thrust.
    pub k: f64,
    /// p.
    pub exponent: f64,
    /// α: relative change of C_T per unit of |ω|/ω_ref.
    pub ct_slope: f64,
    /// ω_ref [rad/s].
    pub ct_reference_speed: f64,
}

/// A thrust load cell: a mass-spring-damper driven by the thrust, read by its own ADC at its
/// own rate and held between readings, with a zero offset and noise per reading.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ThrustCell {
    /// Natural frequency with the motor and propeller on it [Hz].
    pub natural_hz: f64,
    /// Damping ratio.
    pub damping: f64,
    /// ADC rate [Hz].
    pub rate: f64,
    /// Zero offset [N].
    pub offset: f64,
    /// Noise per reading [N].
    pub noise: f64,
}

/// The controller's DC side: a source with internal resistance feeding an ESC without losses
/// (`V_bus·I_bus = v·i`, `d = v/V_bus`), whose reported bus current passes a first-order filter.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Bus {
    /// Source voltage with no load [V].
    pub source_voltage: f64,
    /// Source (battery, wiring) resistance [Ω].
    pub source_resistance: f64,
    /// Time constant of the ESC's bus-current filter [s] (0: none).
    pub current_filter: f64,
    /// Noise on the reported bus voltage [V].
    pub noise_voltage: f64,
    /// Noise on the reported bus current [A].
    pub noise_current: f64,
}

/// What a thrust stand measures besides the drive's feedback. Off by default.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Instruments {
    /// The thrust.
    pub thrust: Thrust,
    /// The thrust cell (`None`: no thrust column).
    pub thrust_cell: Option<ThrustCell>,
    /// The DC bus (`None`: no voltage, current and duty columns).
    pub bus: Option<Bus>,
}

/// Everything about a mechanism-level stand.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct MechConfig {
    /// Rotor and propeller.
    pub rotor: Rotor,
    /// The motor's electrical constants.
    pub motor: Motor,
    /// The drive's control.
    pub drive: Drive,
    /// The drive's sensing.
    pub sensing: Sensing,
    /// An external disturbance.
    pub disturbance: Disturbance,
    /// The feedback link.
    pub link: Link,
    /// Thrust cell and DC-bus measurement of a thrust stand (off by default).
    pub instruments: Instruments,
}

impl Default for MechConfig {
    /// A clean stand: a 7-inch propeller (J = 2·10⁻⁵ kg·m², c2 = 1.5·10⁻⁸) on a 2000 KV outrunner
    /// (Kt = 4.77 mN·m/A, R = 80 mΩ, L = 15 µH), 0.1 N·m at setpoint 1, 10 kHz control, 500 Hz
    /// feedback, and every mechanism off.
    fn default() -> Self {
        MechConfig {
            rotor: Rotor {
                inertia: 2.0e-5,
                drag: Drag {
                    k: 1.5e-8,
                    exponent: 2.0,
                    cq_slope: 0.0,
                    cq_reference_speed: 1500.0,
                },
                bearing: Bearing {
                    coulomb: 0.0,
                    breakaway: 0.0,
                    stribeck_speed: 10.0,
                    viscous: 0.0,
                },
                cogging: Cogging {
                    amplitude: 0.0,
                    harmonic: 6.0,
                    phase: 0.0,
                },
            },
            motor: Motor {
                kt: 60.0 / (std::f64::consts::TAU * 2000.0),
                resistance: 0.08,
                inductance: 15e-6,
                supply_voltage: f64::INFINITY,
            },
            drive: Drive {
                max_torque: 0.1,
                control_rate: 10_000.0,
                current_loop: None,
                kt_error: 0.0,
                braking: None,
            },
            sensing: Sensing {
                kinematics: Kinematics {
                    counts_per_rev: None,
                    velocity: VelocityEstimator::Ideal,
                    acceleration_filter: 0.0,
                },
                torque: TorqueReport::Current {
                    filter: 0.0,
                    offset: 0.0,
                    noise: 0.0,
                },
                noise: ReportNoise {
                    force: 0.0,
                    velocity: 0.0,
                    acceleration: 0.0,
                },
            },
            disturbance: Disturbance::None,
            link: Link {
                rate: 500.0,
                clock: DeviceClock {
                    rate_error: 0.0,
                    drift: 0.0,
                    offset: 0.0,
                    stamp_jitter: 0.0,
                },
                drop_probability: 0.0,
                latency: 0.0,
                latency_jitter: 0.0,
                host_offset: 1000.0,
            },
            instruments: Instruments {
                thrust: Thrust {
                    k: 0.0,
                    exponent: 2.0,
                    ct_slope: 0.0,
                    ct_reference_speed: 1500.0,
                },
                thrust_cell: None,
                bus: None,
            },
        }
    }
}

impl MechConfig {
    /// White report noise like propid's formula-level stand's defaults (force 2·10⁻⁴ N·m, velocity
    /// 0.5 rad/s, acceleration 20 rad/s²), leaving every mechanism as it is.
    pub fn with_typical_noise(mut self) -> Self {
        self.sensing.noise = ReportNoise {
            force: 2e-4,
            velocity: 0.5,
            acceleration: 20.0,
        };
        self
    }

    /// Checks every field once.
    pub fn validate(&self) -> Result<(), ConfigError> {
        let r = &self.rotor;
        positive(Field::RotorInertia, r.inertia)?;
        non_negative(Field::RotorDragK, r.drag.k)?;
        check(
            Field::RotorDragExponent,
            r.drag.exponent,
            "in [1, 4]",
            (1.0..=4.0).contains(&r.drag.exponent),
        )?;
        check(
            Field::RotorDragCqSlope,
            r.drag.cq_slope,
            "in (−1, 1)",
            r.drag.cq_slope.abs() < 1.0,
        )?;
        positive(Field::RotorDragCqReferenceSpeed, r.drag.cq_reference_speed)?;
        non_negative(Field::RotorBearingCoulomb, r.bearing.coulomb)?;
        non_negative(Field::RotorBearingBreakaway, r.bearing.breakaway)?;
        positive(Field::RotorBearingStribeckSpeed, r.bearing.stribeck_speed)?;
        non_negative(Field::RotorBearingViscous, r.bearing.viscous)?;
        non_negative(Field::RotorCoggingAmplitude, r.cogging.amplitude)?;
        check(
            Field::RotorCoggingHarmonic,
            r.cogging.harmonic,
            "a whole number ≥ 1",
            r.cogging.harmonic >= 1.0
                && r.cogging.harmonic.fract() == 0.0
                && r.cogging.harmonic <= 1e6,
        )?;
        finite(Field::RotorCoggingPhase, r.cogging.phase)?;

        let m = &self.motor;
        positive(Field::MotorKt, m.kt)?;
        positive(Field::MotorResistance, m.resistance)?;
        positive(Field::MotorInductance, m.inductance)?;
        check(
            Field::MotorSupplyVoltage,
            m.supply_voltage,
            "> 0 (infinity: no limit)",
            m.supply_voltage > 0.0,
        )?;

        let d = &self.drive;
        positive(Field::DriveMaxTorque, d.max_torque)?;
        check(
            Field::DriveControlRate,
            d.control_rate,
            "in [1 kHz, 100 kHz]",
            (1e3..=1e5).contains(&d.control_rate),
        )?;
        let h = 1.0 / d.control_rate;
        if let Some(cl) = d.current_loop {
            // RK4 is accurate to well under 1 % per step for |λ·h| ≤ 0.5 (the loop's pole −ω_c),
            // and stable and within 2 % per step for the fast electrical pole −R/L at |λ·h| ≤ 1.
            check(
                Field::DriveCurrentLoopBandwidth,
                cl.bandwidth,
                "> 0 and ≤ control_rate/2 rad/s",
                cl.bandwidth > 0.0 && cl.bandwidth * h <= 0.5,
            )?;
            check(
                Field::MotorInductance,
                m.inductance,
                "≥ R/control_rate when a current loop is simulated (electrical pole too fast for the step)",
                m.resistance * h / m.inductance <= 1.0,
            )?;
        }
        check(
            Field::DriveKtError,
            d.kt_error,
            "in (−0.5, 1)",
            d.kt_error > -0.5 && d.kt_error < 1.0,
        )?;
        if let Some(b) = d.braking {
            non_negative(Field::DriveBrakingTorque, b.torque)?;
            non_negative(Field::DriveBrakingOffThreshold, b.off_threshold)?;
            check(
                Field::DriveBrakingOnThreshold,
                b.on_threshold,
                "≥ off_threshold and finite",
                b.on_threshold >= b.off_threshold && b.on_threshold.is_finite(),
            )?;
        }

        let k = &self.sensing.kinematics;
        if let Some(n) = k.counts_per_rev {
            check(
                Field::SensingKinematicsCountsPerRev,
                n as f64,
                "≥ 1",
                n >= 1,
            )?;
        }
        if let VelocityEstimator::Pll {
            natural_hz,
            damping,
        } = k.velocity
        {
            check(
                Field::SensingKinematicsVelocityNaturalHz,
                natural_hz,
                "> 0 and ≤ control_rate/50",
                natural_hz > 0.0 && natural_hz * 50.0 <= d.control_rate,
            )?;
            check(
                Field::SensingKinematicsVelocityDamping,
                damping,
                "in [0.3, 3]",
                (0.3..=3.0).contains(&damping),
            )?;
        }
        check(
            Field::SensingKinematicsAccelerationFilter,
            k.acceleration_filter,
            "0 or ≥ 2/control_rate",
            k.acceleration_filter == 0.0
                || (k.acceleration_filter >= 2.0 * h && k.acceleration_filter.is_finite()),
        )?;
        match self.sensing.torque {
            TorqueReport::Setpoint => {}
            TorqueReport::Current {
                filter,
                offset,
                noise,
            } => {
                check(
                    Field::SensingTorqueFilter,
                    filter,
                    "0 or ≥ 2/control_rate",
                    filter == 0.0 || (filter >= 2.0 * h && filter.is_finite()),
                )?;
                finite(Field::SensingTorqueOffset, offset)?;
                non_negative(Field::SensingTorqueNoise, noise)?;
            }
            TorqueReport::LoadCell {
                natural_hz,
                damping,
                rate,
                offset,
                noise,
            } => {
                check(
                    Field::SensingTorqueNaturalHz,
                    natural_hz,
                    "> 0 and ≤ control_rate/20",
                    natural_hz > 0.0 && natural_hz * 20.0 <= d.control_rate,
                )?;
                check(
                    Field::SensingTorqueDamping,
                    damping,
                    "in [0.01, 3]",
                    (0.01..=3.0).contains(&damping),
                )?;
                check(
                    Field::SensingTorqueRate,
                    rate,
                    "> 0 and ≤ control_rate",
                    rate > 0.0 && rate <= d.control_rate,
                )?;
                finite(Field::SensingTorqueOffset, offset)?;
                non_negative(Field::SensingTorqueNoise, noise)?;
            }
        }
        let n = &self.sensing.noise;
        non_negative(Field::SensingNoiseForce, n.force)?;
        non_negative(Field::SensingNoiseVelocity, n.velocity)?;
        non_negative(Field::SensingNoiseAcceleration, n.acceleration)?;

        match self.disturbance {
            Disturbance::None => {}
            Disturbance::Periodic { amplitude, hz } => {
                finite(Field::DisturbanceAmplitude, amplitude)?;
                positive(Field::DisturbanceHz, hz)?;
            }
            Disturbance::Bump {
                amplitude,
                start,
                width,
            } => {
                finite(Field::DisturbanceAmplitude, amplitude)?;
                finite(Field::DisturbanceStart, start)?;
                positive(Field::DisturbanceWidth, width)?;
            }
        }

        let l = &self.link;
        check(
            Field::LinkRate,
            l.rate,
            "> 0 and ≤ control_rate/2",
            l.rate > 0.0 && l.rate * 2.0 <= d.control_rate,
        )?;
        check(
            Field::LinkClockRateError,
            l.clock.rate_error,
            "in (−0.1, 0.1)",
            l.clock.rate_error.abs() < 0.1,
        )?;
        check(
            Field::LinkClockDrift,
            l.clock.drift,
            "in (−10⁻³, 10⁻³) per second",
            l.clock.drift.abs() < 1e-3,
        )?;
        finite(Field::LinkClockOffset, l.clock.offset)?;
        check(
            Field::LinkClockStampJitter,
            l.clock.stamp_jitter,
            "≥ 0 and < 0.4/rate",
            l.clock.stamp_jitter >= 0.0 && l.clock.stamp_jitter * l.rate < 0.4,
        )?;
        check(
            Field::LinkDropProbability,
            l.drop_probability,
            "in [0, 1)",
            (0.0..1.0).contains(&l.drop_probability),
        )?;
        non_negative(Field::LinkLatency, l.latency)?;
        non_negative(Field::LinkLatencyJitter, l.latency_jitter)?;
        finite(Field::LinkHostOffset, l.host_offset)?;

        let ins = &self.instruments;
        non_negative(Field::InstrumentsThrustK, ins.thrust.k)?;
        check(
            Field::InstrumentsThrustExponent,
            ins.thrust.exponent,
            "in [1, 4]",
            (1.0..=4.0).contains(&ins.thrust.exponent),
        )?;
        check(
            Field::InstrumentsThrustCtSlope,
            ins.thrust.ct_slope,
            "in (−1, 1)",
            ins.thrust.ct_slope.abs() < 1.0,
        )?;
        positive(
            Field::InstrumentsThrustCtReferenceSpeed,
            ins.thrust.ct_reference_speed,
        )?;
        if let Some(c) = ins.thrust_cell {
            check(
                Field::InstrumentsThrustCellNaturalHz,
                c.natural_hz,
                "> 0 and ≤ control_rate/20",
                c.natural_hz > 0.0 && c.natural_hz * 20.0 <= d.control_rate,
            )?;
            check(
                Field::InstrumentsThrustCellDamping,
                c.damping,
                "in [0.01, 3]",
                (0.01..=3.0).contains(&c.damping),
            )?;
            check(
                Field::InstrumentsThrustCellRate,
                c.rate,
                "> 0 and ≤ control_rate",
                c.rate > 0.0 && c.rate <= d.control_rate,
            )?;
            finite(Field::InstrumentsThrustCellOffset, c.offset)?;
            non_negative(Field::InstrumentsThrustCellNoise, c.noise)?;
        }
        if let Some(b) = ins.bus {
            positive(Field::InstrumentsBusSourceVoltage, b.source_voltage)?;
            non_negative(Field::InstrumentsBusSourceResistance, b.source_resistance)?;
            check(
                Field::InstrumentsBusCurrentFilter,
                b.current_filter,
                "0 or ≥ 2/control_rate",
                b.current_filter == 0.0
                    || (b.current_filter >= 2.0 * h && b.current_filter.is_finite()),
            )?;
            non_negative(Field::InstrumentsBusNoiseVoltage, b.noise_voltage)?;
            non_negative(Field::InstrumentsBusNoiseCurrent, b.noise_current)?;
        }
        Ok(())
    }
}

/// The run: an init phase at a constant setpoint (not recorded, like the seed's driver), then the
/// pattern for `duration` seconds.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Run {
    /// Setpoint during the init phase (the seed uses the pattern's `hi`).
    pub init_setpoint: f64,
    /// Init phase length [s].
    pub init_duration: f64,
    /// Pattern length [s] (true time).
    pub duration: f64,
}

impl Run {
    /// Checks the run.
    pub fn validate(&self) -> Result<(), ConfigError> {
        check(
            Field::RunInitSetpoint,
            self.init_setpoint,
            "in [−1, 1]",
            (-1.0..=1.0).contains(&self.init_setpoint),
        )?;
        non_negative(Field::RunInitDuration, self.init_duration)?;
        positive(Field::RunDuration, self.duration)?;
        Ok(())
    }
}
