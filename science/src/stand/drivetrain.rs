//! The formula-level stand's thrust and motor: what an RCbenchmark-style stand logs beside the
//! drive's feedback (thrust, bus voltage and current, the ESC's duty), from textbook formulas
//! with every constant known, so that each figure `propid propulsion` identifies has a truth.
//!
//! ```text
//!  thrust        T = k_T·|ω|^p_T                                 (positive along the thrust axis)
//!  thrust cell   first-order lag τ_T, sampled at f_T and held, + zero offset + noise per sample
//!  motor         I_m = τ/K_t + I_0·sgn ω        V_m = K_e·ω + R·I_m      K_e = K_t = 60/(2π·Kv)
//!                (τ: the torque the load feels, so the no-load current I_0 is the motor's own
//!                loss, which the load model does not contain)
//!  supply        V_bus = (V_s + √(V_s² − 4·R_s·V_m·I_m))/2   (source resistance R_s: V_s − R_s·I_bus)
//!  ESC           d = V_m/V_bus,   I_bus = d·I_m   (lossless)
//!  reported      voltage = V_bus + noise,  current = L_τI[I_bus] + noise,  duty = d (exact)
//! ```
//! Off by default ([`DrivetrainConfig::default`]): a stand without it logs what it always did.
//! Its noise comes from its own random stream, so switching it on changes no other column.

use propid_core::plant::FirstOrderLag;
use rand::rngs::StdRng;
use rand::SeedableRng;
use rand_distr::{Distribution, Normal};

use propid_io::InputError;

/// Thrust law, thrust cell, motor, supply and ESC of the formula-level stand.
#[derive(Clone, Copy, Debug, PartialEq, serde::Serialize)]
pub struct DrivetrainConfig {
    /// k_T of T = k_T·|ω|^p_T [N·(s/rad)^p_T]; 0: no thrust column.
    pub thrust_k: f64,
    /// p_T.
    pub thrust_exponent: f64,
    /// Lag of the thrust cell [s].
    pub thrust_lag: f64,
    /// Sample rate of the thrust cell [Hz] (held between samples; 0: a new sample every row).
    pub thrust_rate: f64,
    /// Zero offset of the thrust cell [N].
    pub thrust_offset: f64,
    /// Noise per thrust sample [N].
    pub noise_thrust: f64,
    /// Kv [rpm/V]; 0: no electrical columns.
    pub kv: f64,
    /// Resistance in the motor current's path [Ω].
    pub resistance: f64,
    /// No-load current I_0 [A].
    pub no_load_current: f64,
    /// Supply voltage V_s [V].
    pub supply_voltage: f64,
    /// Source resistance R_s [Ω].
    pub source_resistance: f64,
    /// Time constant of the ESC's current filter [s].
    pub current_filter: f64,
    /// Noise on the reported bus voltage [V].
    pub noise_voltage: f64,
    /// Noise on the reported bus current [A].
    pub noise_current: f64,
}

impl Default for DrivetrainConfig {
    /// Everything off.
    fn default() -> Self {
        DrivetrainConfig {
            thrust_k: 0.0,
            thrust_exponent: 2.0,
            thrust_lag: 0.0,
            thrust_rate: 0.0,
            thrust_offset: 0.0,
            noise_thrust: 0.0,
            kv: 0.0,
            resistance: 0.0,
            no_load_current: 0.0,
            supply_voltage: 16.0,
            source_resistance: 0.0,
            current_filter: 0.0,
            noise_voltage: 0.0,
            noise_current: 0.0,
        }
    }
}

impl DrivetrainConfig {
    /// A 7-inch propeller's thrust (C_T = 0.12 at ρ = 1.225, D = 0.1778 m: k_T = 3.72·10⁻⁶
    /// N·s²/rad²) on a 2000 Kv motor (R = 80 mΩ, I_0 = 0.6 A) from a 4S supply (16 V, 20 mΩ),
    /// a thrust cell at 80 Hz with a 20 ms lag, a 2 ms ESC current filter and realistic noise.
    pub fn typical() -> Self {
        DrivetrainConfig {
            thrust_k: 0.12 * 1.225 * 0.1778f64.powi(4) / (std::f64::consts::TAU.powi(2)),
            thrust_exponent: 2.0,
            thrust_lag: 0.02,
            thrust_rate: 80.0,
            thrust_offset: 0.05,
            noise_thrust: 0.01,
            kv: 2000.0,
            resistance: 0.08,
            no_load_current: 0.6,
            supply_voltage: 16.0,
            source_resistance: 0.02,
            current_filter: 0.002,
            noise_voltage: 0.01,
            noise_current: 0.02,
        }
    }

    /// Whether the thrust column is simulated.
    pub fn has_thrust(&self) -> bool {
        self.thrust_k > 0.0
    }

    /// Whether the electrical columns are simulated.
    pub fn has_motor(&self) -> bool {
        self.kv > 0.0
    }

    /// K_e = K_t [V·s/rad].
    pub fn ke(&self) -> f64 {
        60.0 / (std::f64::consts::TAU * self.kv)
    }

    /// Checks the values; the error names the field.
    pub fn validate(&self) -> Result<(), InputError> {
        let checks = [
            ("thrust_k", self.thrust_k, self.thrust_k >= 0.0),
            (
                "thrust_exponent",
                self.thrust_exponent,
                (1.0..=4.0).contains(&self.thrust_exponent),
            ),
            ("thrust_lag", self.thrust_lag, self.thrust_lag >= 0.0),
            ("thrust_rate", self.thrust_rate, self.thrust_rate >= 0.0),
            ("thrust_offset", self.thrust_offset, true),
            ("noise_thrust", self.noise_thrust, self.noise_thrust >= 0.0),
            ("kv", self.kv, self.kv >= 0.0),
            ("resistance", self.resistance, self.resistance >= 0.0),
            (
                "no_load_current",
                self.no_load_current,
                self.no_load_current >= 0.0,
            ),
            (
                "supply_voltage",
                self.supply_voltage,
                self.supply_voltage > 0.0,
            ),
            (
                "source_resistance",
                self.source_resistance,
                self.source_resistance >= 0.0,
            ),
            (
                "current_filter",
                self.current_filter,
                self.current_filter >= 0.0,
            ),
            (
                "noise_voltage",
                self.noise_voltage,
                self.noise_voltage >= 0.0,
            ),
            (
                "noise_current",
                self.noise_current,
                self.noise_current >= 0.0,
            ),
        ];
        for (name, v, ok) in checks {
            if !(ok && v.is_finite()) {
                return Err(InputError::invalid(format!(
                    "{name} is out of range (got {v})"
                )));
            }
        }
        Ok(())
    }
}

/// What the stand logs beside the drive's feedback at one row (NaN for what is off).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct DrivetrainSample {
    /// Thrust as the cell reports it [N].
    pub thrust: f64,
    /// Bus voltage [V].
    pub voltage: f64,
    /// Bus current as the ESC reports it [A].
    pub current: f64,
    /// Duty (ratio).
    pub duty: f64,
}

impl DrivetrainSample {
    /// As the TSV's stand columns: the duty is the `command` (ratio).
    pub fn stand(&self) -> propid_io::tsv::Stand {
        propid_io::tsv::Stand {
            thrust: self.thrust,
            voltage: self.voltage,
            current: self.current,
            command: self.duty,
        }
    }
}

/// The true electrical state at a speed and a torque.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Electrical {
    /// Motor current [A].
    pub motor_current: f64,
    /// Motor voltage [V].
    pub motor_voltage: f64,
    /// Bus voltage [V].
    pub bus_voltage: f64,
    /// Bus current [A].
    pub bus_current: f64,
    /// Duty.
    pub duty: f64,
}

/// The simulated drivetrain's state.
pub struct Drivetrain {
    config: DrivetrainConfig,
    thrust_cell: FirstOrderLag<f64>,
    thrust_held: f64,
    next_thrust_sample: f64,
    current_sense: FirstOrderLag<f64>,
    initialised: bool,
    rng: StdRng,
}

fn normal(sigma: f64) -> Normal<f64> {
    Normal::new(0.0, sigma.max(0.0)).unwrap_or_else(|_| Normal::new(0.0, 0.0).expect("zero sigma"))
}

impl Drivetrain {
    /// A drivetrain at rest; its noise stream is seeded from `seed` apart from the stand's.
    pub fn new(config: DrivetrainConfig, seed: u64) -> Drivetrain {
        Drivetrain {
            config,
            thrust_cell: FirstOrderLag::new(config.thrust_lag, 0.0),
            thrust_held: config.thrust_offset,
            next_thrust_sample: 0.0,
            current_sense: FirstOrderLag::new(config.current_filter, 0.0),
            initialised: false,
            rng: StdRng::seed_from_u64(seed ^ 0x7472_7573_7400_0001),
        }
    }

    /// The configuration.
    pub fn config(&self) -> &DrivetrainConfig {
        &self.config
    }

    /// True thrust at ω [N].
    pub fn thrust(&self, omega: f64) -> f64 {
        self.config.thrust_k * omega.abs().powf(self.config.thrust_exponent)
    }

    /// The true electrical state at speed ω and motor torque τ.
    pub fn electrical(&self, omega: f64, torque: f64) -> Electrical {
        let c = &self.config;
        let ke = c.ke();
        let im =
            torque / ke + c.no_load_current * omega.signum() * f64::from(u8::from(omega != 0.0));
        let vm = ke * omega + c.resistance * im;
        let p = vm * im;
        let vs = c.supply_voltage;
        let disc = vs * vs - 4.0 * c.source_resistance * p;
        let vb = 0.5 * (vs + disc.max(0.0).sqrt());
        let duty = vm / vb;
        Electrical {
            motor_current: im,
            motor_voltage: vm,
            bus_voltage: vb,
            bus_current: duty * im,
            duty,
        }
    }

    /// Advances the cells' and filters' state by `dt` to time `time` at speed ω and torque τ.
    pub fn step(&mut self, time: f64, dt: f64, omega: f64, torque: f64) {
        let thrust = self.thrust(omega);
        let bus = if self.config.has_motor() {
            self.electrical(omega, torque).bus_current
        } else {
            0.0
        };
        if !self.initialised {
            self.thrust_cell.value = thrust;
            self.current_sense.value = bus;
            self.initialised = true;
        }
        self.thrust_cell.step(dt, thrust);
        self.current_sense.step(dt, bus);
        if self.config.thrust_rate > 0.0 {
            while time + 1e-12 >= self.next_thrust_sample {
                self.thrust_held = self.thrust_cell.value
                    + self.config.thrust_offset
                    + normal(self.config.noise_thrust).sample(&mut self.rng);
                self.next_thrust_sample += 1.0 / self.config.thrust_rate;
            }
        }
    }

    /// What the stand logs now.
    pub fn measure(&mut self, omega: f64, torque: f64) -> DrivetrainSample {
        let c = self.config;
        let thrust = if !c.has_thrust() {
            f64::NAN
        } else if c.thrust_rate > 0.0 {
            self.thrust_held
        } else {
            self.thrust_cell.value + c.thrust_offset + normal(c.noise_thrust).sample(&mut self.rng)
        };
        let (voltage, current, duty) = if c.has_motor() {
            let e = self.electrical(omega, torque);
            (
                e.bus_voltage + normal(c.noise_voltage).sample(&mut self.rng),
                self.current_sense.value + normal(c.noise_current).sample(&mut self.rng),
                e.duty,
            )
        } else {
            (f64::NAN, f64::NAN, f64::NAN)
        };
        DrivetrainSample {
            thrust,
            voltage,
            current,
            duty,
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_power_balance_holds() {
        let d = Drivetrain::new(DrivetrainConfig::typical(), 1);
        let e = d.electrical(1500.0, 0.05);
        // Bus power = motor power; motor power = ω·(τ + K_t·I_0) + R·I_m².
        let c = d.config();
        assert!((e.bus_voltage * e.bus_current - e.motor_voltage * e.motor_current).abs() < 1e-9);
        let mech = 1500.0 * (0.05 + c.ke() * c.no_load_current);
        assert!(
            (e.motor_voltage * e.motor_current - mech - c.resistance * e.motor_current.powi(2))
                .abs()
                < 1e-9
        );
        // The source sags by R_s·I_bus.
        assert!(
            (c.supply_voltage - c.source_resistance * e.bus_current - e.bus_voltage).abs() < 1e-9
        );
        assert!(e.duty > 0.0 && e.duty < 1.0, "{e:?}");
    }
}
