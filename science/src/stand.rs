//! The formula-level stand simulator: the TSV `propid drive` would have recorded, from the same
//! load equations the diagnosis tests for (see the mechanism-level simulator for an independent one).
//!
//! ## How data flows
//! ```text
//!  Excitation (init at hi, then sine | steps | chirp)  ──► setpoint ∈ [−1, 1]
//!  Drive: setpoint × max torque = commanded torque ──► [torque lag] [second-order stage]
//!         ──► torque the load feels, − [braking] while the rotor slows past a threshold
//!  Load (propid_core::plant): J, c1, c2, p, Coulomb, ripple  (+ an optional periodic disturbance)
//!  Sensors, sampled at `rate` with timestamp jitter:
//!    force        = commanded torque, or the motor's torque through [force-sensor lag]
//!                   (+ [offset]) (+ noise)
//!    velocity     = ω (+ noise);   acceleration = dω/dt through [acceleration lag] (+ noise)
//!    position     = θ wrapped to [0, 2π)
//!  ──► tsv::Row (ts_local, t, force, velocity, acceleration, position)
//! ```
//! Every effect `propid diagnose` looks for can be switched on with a magnitude, so tests can
//! hide one in the data and check that diagnose finds it. [`Stand`] is a stepping object, so the
//! same model also runs in real time behind a Cyphal node (`propid sim-drive`).

use propid_core::plant::{FirstOrderLag, Load, LoadParams};
use rand::rngs::StdRng;
use rand::SeedableRng;
use rand_distr::{Distribution, Normal};

use propid_io::tsv::{Row, Sample};
use propid_io::InputError;

use crate::excitation::Excitation;

mod drivetrain;
pub use drivetrain::{Drivetrain, DrivetrainConfig, DrivetrainSample, Electrical};

/// Everything about the simulated stand.
#[derive(Clone, Copy, Debug, PartialEq, serde::Serialize)]
pub struct StandConfig {
    /// Inertia J [kg·m²].
    pub inertia: f64,
    /// Viscous friction c1 [N·m·s/rad].
    pub c1: f64,
    /// Drag coefficient c2 [N·m·s²/rad²] (at exponent 2).
    pub c2: f64,
    /// Drag exponent p.
    pub drag_exponent: f64,
    /// Coulomb friction [N·m].
    pub coulomb: f64,
    /// Torque ripple amplitude [N·m].
    pub ripple: f64,
    /// Ripple periods per revolution.
    pub ripple_harmonic: f64,
    /// Torque at setpoint 1 [N·m].
    pub max_torque: f64,
    /// Lag of the torque the load feels behind the commanded (and reported) torque [s].
    pub torque_lag: f64,
    /// Lag of the reported torque behind the torque the load feels [s].
    pub force_sensor_lag: f64,
    /// Lag of the reported acceleration behind the true one [s].
    pub acceleration_lag: f64,
    /// Natural frequency of a second-order stage between the commanded torque and the torque the
    /// load feels [Hz] (0: none).
    pub second_order_hz: f64,
    /// Its damping.
    pub second_order_damping: f64,
    /// What the reported force reads when no torque acts [N·m].
    pub force_offset: f64,
    /// A torque braking the rotor while it slows, which the reported force does not show [N·m].
    pub braking: f64,
    /// Deceleration beyond which the drive brakes [rad/s²] (it releases below `braking_off`).
    pub braking_on: f64,
    /// Deceleration below which the drive releases the brake [rad/s²].
    pub braking_off: f64,
    /// Amplitude of an external periodic torque disturbance [N·m] (not a modelled effect).
    pub disturbance: f64,
    /// Its frequency [Hz].
    pub disturbance_hz: f64,
    /// Feedback rate [Hz].
    pub rate: f64,
    /// Noise (standard deviation) on the reported torque [N·m].
    pub noise_force: f64,
    /// Noise on the reported velocity [rad/s].
    pub noise_velocity: f64,
    /// Noise on the reported acceleration [rad/s²].
    pub noise_acceleration: f64,
    /// Timestamp jitter of the sampling instants (standard deviation) [s].
    pub jitter: f64,
}

impl Default for StandConfig {
    /// A 7-inch propeller on a small outrunner, with realistic sensor noise and no hidden effect.
    fn default() -> Self {
        StandConfig {
            inertia: 2.0e-5,
            c1: 0.0,
            c2: 1.5e-8,
            drag_exponent: 2.0,
            coulomb: 0.0,
            ripple: 0.0,
            ripple_harmonic: 6.0,
            max_torque: 0.1,
            torque_lag: 0.0,
            force_sensor_lag: 0.0,
            acceleration_lag: 0.0,
            second_order_hz: 0.0,
            second_order_damping: std::f64::consts::FRAC_1_SQRT_2,
            force_offset: 0.0,
            braking: 0.0,
            braking_on: 50.0,
            braking_off: 20.0,
            disturbance: 0.0,
            disturbance_hz: 7.0,
            rate: 500.0,
            noise_force: 2e-4,
            noise_velocity: 0.5,
            noise_acceleration: 20.0,
            jitter: 50e-6,
        }
    }
}

impl StandConfig {
    /// Checks that the values make a stand (positive inertia, rate, …).
    pub fn validate(&self) -> Result<(), InputError> {
        let positive = [
            ("inertia", self.inertia),
            ("rate", self.rate),
            ("max_torque", self.max_torque),
            ("drag_exponent", self.drag_exponent),
        ];
        for (name, v) in positive {
            if !(v > 0.0 && v.is_finite()) {
                return Err(InputError::invalid(format!(
                    "{name} must be positive (got {v})"
                )));
            }
        }
        let non_negative = [
            ("c1", self.c1),
            ("c2", self.c2),
            ("coulomb", self.coulomb),
            ("torque_lag", self.torque_lag),
            ("force_sensor_lag", self.force_sensor_lag),
            ("acceleration_lag", self.acceleration_lag),
            ("second_order_hz", self.second_order_hz),
            ("second_order_damping", self.second_order_damping),
            ("braking", self.braking),
            ("braking_on", self.braking_on),
            ("braking_off", self.braking_off),
            ("noise_force", self.noise_force),
            ("noise_velocity", self.noise_velocity),
            ("noise_acceleration", self.noise_acceleration),
            ("jitter", self.jitter),
        ];
        for (name, v) in non_negative {
            if !(v >= 0.0 && v.is_finite()) {
                return Err(InputError::invalid(format!("{name} must be ≥ 0 (got {v})")));
            }
        }
        if !self.force_offset.is_finite() {
            return Err(InputError::invalid(format!(
                "force_offset must be finite (got {})",
                self.force_offset
            )));
        }
        Ok(())
    }

    /// The load parameters for the core model.
    pub fn load_params(&self) -> LoadParams<f64> {
        LoadParams {
            inertia: self.inertia,
            c1: self.c1,
            c2: self.c2,
            drag_exponent: self.drag_exponent,
            coulomb: self.coulomb,
            ripple_amplitude: self.ripple,
            ripple_harmonic: self.ripple_harmonic,
            ripple_phase: 0.3,
        }
    }
}

/// Internal integration step [s].
const DT: f64 = 5e-5;
/// How often `run` updates the setpoint (as a current loop latches it: 10 kHz).
const SETPOINT_STEP: f64 = 1e-4;

/// The simulated stand: feed it setpoints, advance time, read what the drive would report.
pub struct Stand {
    config: StandConfig,
    load: Load<f64>,
    /// Time since start [s].
    time: f64,
    setpoint: f64,
    torque_actuator: FirstOrderLag<f64>,
    /// The second-order stage's output and its rate.
    stage: (f64, f64),
    /// Whether the drive is braking.
    braking: bool,
    force_sensor: FirstOrderLag<f64>,
    acceleration_sensor: FirstOrderLag<f64>,
    rng: StdRng,
    /// Thrust and motor, when simulated ([`Stand::with_drivetrain`]).
    drivetrain: Option<Drivetrain>,
}

fn normal(sigma: f64) -> Normal<f64> {
    Normal::new(0.0, sigma.max(0.0)).unwrap_or_else(|_| Normal::new(0.0, 0.0).expect("zero sigma"))
}

impl Stand {
    /// A stand at rest with the given configuration and noise seed.
    pub fn new(config: StandConfig, seed: u64) -> Self {
        Stand {
            load: Load::new(config.load_params(), 0.0),
            time: 0.0,
            setpoint: 0.0,
            torque_actuator: FirstOrderLag::new(config.torque_lag, 0.0),
            stage: (0.0, 0.0),
            braking: false,
            force_sensor: FirstOrderLag::new(config.force_sensor_lag, 0.0),
            acceleration_sensor: FirstOrderLag::new(config.acceleration_lag, 0.0),
            rng: StdRng::seed_from_u64(seed),
            config,
            drivetrain: None,
        }
    }

    /// Simulates a thrust cell and the motor's electrical side too (seeded from `seed`, apart
    /// from the stand's own noise: no other column changes).
    pub fn with_drivetrain(mut self, config: DrivetrainConfig, seed: u64) -> Self {
        self.drivetrain = Some(Drivetrain::new(config, seed));
        self
    }

    /// What the stand logs beside the drive's feedback now (`None` without a drivetrain).
    pub fn measure_drivetrain(&mut self) -> Option<DrivetrainSample> {
        let (omega, torque) = (self.load.velocity, self.motor_torque());
        self.drivetrain.as_mut().map(|d| d.measure(omega, torque))
    }

    /// The configuration.
    pub fn config(&self) -> &StandConfig {
        &self.config
    }

    /// Sets the ratiometric setpoint (clamped to [−1, 1]; NaN reads as 0).
    pub fn set_setpoint(&mut self, setpoint: f64) {
        self.setpoint = if setpoint.is_nan() {
            0.0
        } else {
            setpoint.clamp(-1.0, 1.0)
        };
    }

    /// Seconds since the start.
    pub fn time(&self) -> f64 {
        self.time
    }

    /// True velocity [rad/s].
    pub fn velocity(&self) -> f64 {
        self.load.velocity
    }

    /// The torque the motor produces (the command, through the torque lag or the second-order
    /// stage if any).
    fn motor_torque(&self) -> f64 {
        if self.config.second_order_hz > 0.0 {
            self.stage.0
        } else if self.config.torque_lag > 0.0 {
            self.torque_actuator.value
        } else {
            self.setpoint * self.config.max_torque
        }
    }

    /// The torque the load feels: the motor's, minus braking while it acts, plus the external
    /// disturbance.
    fn felt_torque(&self) -> f64 {
        let c = &self.config;
        let disturbance = if c.disturbance != 0.0 {
            c.disturbance * (std::f64::consts::TAU * c.disturbance_hz * self.time).sin()
        } else {
            0.0
        };
        let braking = if self.braking {
            -c.braking * self.load.velocity.signum()
        } else {
            0.0
        };
        self.motor_torque() + braking + disturbance
    }

    /// Advances the second-order stage by `dt` towards `command` (RK2: the step is far below
    /// the stage's period).
    fn step_stage(&mut self, dt: f64, command: f64) {
        let c = &self.config;
        if c.second_order_hz <= 0.0 {
            return;
        }
        let wn = std::f64::consts::TAU * c.second_order_hz;
        let f = |(y, v): (f64, f64)| {
            (
                v,
                wn * wn * (command - y) - 2.0 * c.second_order_damping * wn * v,
            )
        };
        let (y, v) = self.stage;
        let k1 = f((y, v));
        let mid = (y + 0.5 * dt * k1.0, v + 0.5 * dt * k1.1);
        let k2 = f(mid);
        self.stage = (y + dt * k2.0, v + dt * k2.1);
    }

    /// The drive's braking state from the load's deceleration (with hysteresis).
    fn update_braking(&mut self, felt_without_braking: f64) {
        let c = &self.config;
        if c.braking <= 0.0 {
            return;
        }
        let w = self.load.velocity;
        let slowing = -self.load.acceleration(
            felt_without_braking
                + if self.braking {
                    -c.braking * w.signum()
                } else {
                    0.0
                },
        ) * w.signum();
        self.braking = if self.braking {
            slowing > c.braking_off
        } else {
            slowing > c.braking_on
        };
    }

    /// Advances the simulation to `t` seconds since the start.
    pub fn advance_to(&mut self, t: f64) {
        while self.time + 1e-12 < t {
            let dt = DT.min(t - self.time);
            let command = self.setpoint * self.config.max_torque;
            self.torque_actuator.step(dt, command);
            self.step_stage(dt, command);
            self.force_sensor.step(dt, self.motor_torque());
            let unbraked = self.motor_torque();
            self.update_braking(unbraked);
            let felt = self.felt_torque();
            let a = self.load.acceleration(felt);
            self.acceleration_sensor.step(dt, a);
            self.load.step(dt, felt);
            self.time += dt;
            let (omega, torque) = (self.load.velocity, self.motor_torque());
            if let Some(d) = &mut self.drivetrain {
                d.step(self.time, dt, omega, torque);
            }
        }
    }

    /// What the drive reports now (noise drawn afresh).
    pub fn measure(&mut self) -> Sample {
        let c = self.config;
        let command = self.setpoint * c.max_torque;
        let force = if c.force_sensor_lag > 0.0 {
            self.force_sensor.value
        } else {
            command
        } + c.force_offset;
        let acceleration = if c.acceleration_lag > 0.0 {
            self.acceleration_sensor.value
        } else {
            self.load.acceleration(self.felt_torque())
        };
        let r = &mut self.rng;
        Sample {
            t: self.time,
            force: force + normal(c.noise_force).sample(r),
            velocity: self.load.velocity + normal(c.noise_velocity).sample(r),
            acceleration: acceleration + normal(c.noise_acceleration).sample(r),
            position: self.load.position.rem_euclid(std::f64::consts::TAU),
        }
    }

    /// Runs the excitation (init phase not recorded, like the driver) and calls `sink` with each
    /// recorded row (its stand columns filled when a drivetrain is simulated: thrust, bus
    /// voltage and current, and the duty as `command`).
    pub fn run<E>(
        &mut self,
        excitation: &Excitation,
        mut sink: impl FnMut(Row) -> Result<(), E>,
    ) -> Result<u64, E> {
        let c = self.config;
        let start = self.time + excitation.init_duration;
        self.set_setpoint(excitation.hi);
        self.advance_to(start);
        let jitter = normal(c.jitter);
        let n = (excitation.duration * c.rate).floor() as u64;
        for k in 0..n {
            let nominal = k as f64 / c.rate;
            let dt_jitter = jitter
                .sample(&mut self.rng)
                .clamp(-0.4 / c.rate, 0.4 / c.rate);
            let t = (nominal + dt_jitter).max(0.0);
            // The driver updates the setpoint asynchronously and faster than the feedback, and a
            // drive's current loop latches it at tens of kHz: the torque demand is continuous on
            // the scale of a sample, never a staircase aligned with the samples (which would lead
            // the torque by half a sample and bias every lag estimate by Δt/2).
            while self.time + 1e-12 < start + t {
                let step_end = (self.time + SETPOINT_STEP).min(start + t);
                self.set_setpoint(excitation.setpoint(0.5 * (self.time + step_end) - start));
                self.advance_to(step_end);
            }
            // The demand at the sampling instant (the first sample included: it belongs to
            // the pattern, not to the init phase).
            self.set_setpoint(excitation.setpoint(t));
            let mut sample = self.measure();
            sample.t = t;
            let delay = 0.002 + jitter.sample(&mut self.rng).abs();
            let mut row = Row::new(1000.0 + t + delay, sample);
            if let Some(d) = self.measure_drivetrain() {
                row.stand = d.stand();
            }
            sink(row)?;
        }
        Ok(n)
    }
}

/// Simulates `excitation` on a stand and returns the recorded samples.
pub fn simulate(config: StandConfig, excitation: &Excitation, seed: u64) -> Vec<Sample> {
    let mut out = Vec::new();
    let mut stand = Stand::new(config, seed);
    // The sink never fails.
    let Ok(_) = stand.run(excitation, |row| {
        out.push(row.sample);
        Ok::<(), core::convert::Infallible>(())
    });
    out
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::excitation::Pattern;

    fn excitation(duration: f64) -> Excitation {
        Excitation {
            lo: 0.1,
            hi: 0.9,
            period: 2.0,
            duration,
            init_duration: 2.0,
            pattern: Pattern::Sine,
        }
    }

    #[test]
    fn noiseless_samples_obey_the_load_equation() {
        let config = StandConfig {
            noise_force: 0.0,
            noise_velocity: 0.0,
            noise_acceleration: 0.0,
            jitter: 0.0,
            ..StandConfig::default()
        };
        let s = simulate(config, &excitation(4.0), 1);
        assert_eq!(s.len(), 2000);
        for x in &s {
            let a = (x.force - config.c2 * x.velocity * x.velocity) / config.inertia;
            assert!(
                (a - x.acceleration).abs() < 1e-6 * a.abs().max(1.0),
                "{x:?}"
            );
        }
        // The seed's setpoint formula: t = 0 is the middle of the range.
        assert!((s[0].force - 0.05).abs() < 1e-12);
        let top = s.iter().map(|x| x.force).fold(0.0, f64::max);
        assert!((top - 0.09).abs() < 1e-6);
    }

    #[test]
    fn same_seed_same_data_and_patterns_stay_in_range() {
        let a = simulate(StandConfig::default(), &excitation(1.0), 7);
        let b = simulate(StandConfig::default(), &excitation(1.0), 7);
        assert_eq!(a, b);
        for pattern in Pattern::ALL {
            let e = Excitation {
                pattern,
                ..excitation(30.0)
            };
            for k in 0..3000 {
                let sp = e.setpoint(k as f64 * 0.01);
                assert!(
                    (0.1 - 1e-12..=0.9 + 1e-12).contains(&sp),
                    "{pattern:?} {sp}"
                );
            }
        }
        assert!(Excitation {
            lo: 0.5,
            hi: 0.4,
            ..excitation(1.0)
        }
        .validate()
        .is_err());
    }
}
