//! `propid sim`'s thrust-stand instruments: a thrust cell and the motor's DC side, on either
//! stand, so that `propid propulsion` has a truth to be tested against. Self-contained settings:
//! each flag is checked here and a bad one is refused by name.

use propid_mechsim::{Bus, Instruments, MechConfig, Thrust, ThrustCell};
use propid_science::stand::DrivetrainConfig;

use crate::InputError;

/// The instruments' options (both stands unless said).
#[derive(clap::Args, Debug, Clone, PartialEq)]
#[command(
    next_help_heading = "Thrust stand instruments (columns thrust, voltage, current, command)"
)]
pub struct InstrumentArgs {
    /// Thrust law T = k·|ω|^p: k [N·s²/rad² at p = 2]; 0 writes no thrust column.
    #[arg(long, default_value_t = 0.0)]
    pub thrust_k: f64,
    /// Its exponent p.
    #[arg(long, default_value_t = 2.0)]
    pub thrust_exponent: f64,
    /// The thrust cell's lag [s] (formula stand: a first-order lag).
    #[arg(long, default_value_t = 0.02)]
    pub thrust_lag: f64,
    /// The thrust cell's natural frequency [Hz] (mechanism stand: a mass-spring-damper).
    #[arg(long, default_value_t = 40.0)]
    pub thrust_cell_hz: f64,
    /// The thrust cell's damping ratio (mechanism stand).
    #[arg(long, default_value_t = 0.7)]
    pub thrust_cell_damping: f64,
    /// The thrust cell's sample rate [Hz] (held between samples).
    #[arg(long, default_value_t = 80.0)]
    pub thrust_rate: f64,
    /// The thrust cell's zero offset [N].
    #[arg(long, default_value_t = 0.0, allow_negative_numbers = true)]
    pub thrust_offset: f64,
    /// Noise per thrust sample [N].
    #[arg(long, default_value_t = 0.01)]
    pub noise_thrust: f64,
    /// Motor Kv [rpm/V] (formula stand; the mechanism stand's comes from --motor-kt).
    #[arg(long, default_value_t = 0.0)]
    pub kv: f64,
    /// Resistance in the motor current's path [Ω] (formula stand; mechanism: --motor-resistance).
    #[arg(long, default_value_t = 0.08)]
    pub winding_resistance: f64,
    /// No-load current [A] (formula stand; mechanism: from --coulomb and --c1).
    #[arg(long, default_value_t = 0.0)]
    pub no_load_current: f64,
    /// DC source voltage [V]: writes voltage, current and the duty as `command` (formula stand:
    /// with --kv).
    #[arg(long)]
    pub bus_voltage: Option<f64>,
    /// Source (battery, wiring) resistance [Ω].
    #[arg(long, default_value_t = 0.02)]
    pub source_resistance: f64,
    /// Time constant of the ESC's bus-current filter [s].
    #[arg(long, default_value_t = 0.0)]
    pub esc_current_filter: f64,
    /// Noise on the reported bus voltage [V].
    #[arg(long, default_value_t = 0.01)]
    pub noise_bus_voltage: f64,
    /// Noise on the reported bus current [A].
    #[arg(long, default_value_t = 0.02)]
    pub noise_bus_current: f64,
}

fn at_least(flag: &str, v: f64, min: f64) -> Result<(), InputError> {
    if v >= min && v.is_finite() {
        Ok(())
    } else {
        Err(InputError::invalid(format!(
            "{flag} must be ≥ {min} and finite (got {v})"
        )))
    }
}

impl InstrumentArgs {
    /// Whether any column is simulated.
    pub fn any(&self) -> bool {
        self.thrust_k > 0.0 || self.bus_voltage.is_some()
    }

    fn check(&self) -> Result<(), InputError> {
        at_least("--thrust-k", self.thrust_k, 0.0)?;
        if !(1.0..=4.0).contains(&self.thrust_exponent) {
            return Err(InputError::invalid(format!(
                "--thrust-exponent must be in [1, 4] (got {})",
                self.thrust_exponent
            )));
        }
        at_least("--thrust-lag", self.thrust_lag, 0.0)?;
        at_least("--thrust-rate", self.thrust_rate, 0.0)?;
        at_least("--noise-thrust", self.noise_thrust, 0.0)?;
        at_least("--thrust-offset", self.thrust_offset, f64::MIN)?;
        at_least("--kv", self.kv, 0.0)?;
        at_least("--winding-resistance", self.winding_resistance, 0.0)?;
        at_least("--no-load-current", self.no_load_current, 0.0)?;
        at_least("--source-resistance", self.source_resistance, 0.0)?;
        at_least("--esc-current-filter", self.esc_current_filter, 0.0)?;
        at_least("--noise-bus-voltage", self.noise_bus_voltage, 0.0)?;
        at_least("--noise-bus-current", self.noise_bus_current, 0.0)?;
        if let Some(v) = self.bus_voltage {
            if !(v > 0.0 && v.is_finite()) {
                return Err(InputError::invalid(format!(
                    "--bus-voltage must be positive (got {v})"
                )));
            }
        }
        Ok(())
    }

    /// The formula stand's drivetrain (`None` when no column is asked for).
    pub fn formula(&self) -> Result<Option<DrivetrainConfig>, InputError> {
        self.check()?;
        if !self.any() && self.kv == 0.0 {
            return Ok(None);
        }
        if self.bus_voltage.is_some() != (self.kv > 0.0) {
            return Err(InputError::invalid(
                "the formula stand's electrical columns need both --kv and --bus-voltage".into(),
            ));
        }
        Ok(Some(DrivetrainConfig {
            thrust_k: self.thrust_k,
            thrust_exponent: self.thrust_exponent,
            thrust_lag: self.thrust_lag,
            thrust_rate: self.thrust_rate,
            thrust_offset: self.thrust_offset,
            noise_thrust: self.noise_thrust,
            kv: self.kv,
            resistance: self.winding_resistance,
            no_load_current: self.no_load_current,
            supply_voltage: self.bus_voltage.unwrap_or(16.0),
            source_resistance: self.source_resistance,
            current_filter: self.esc_current_filter,
            noise_voltage: self.noise_bus_voltage,
            noise_current: self.noise_bus_current,
        }))
    }

    /// The mechanism stand's instruments, set into `c`.
    pub fn mechanism(&self, c: &mut MechConfig) -> Result<(), InputError> {
        self.check()?;
        if self.kv != 0.0 || self.no_load_current != 0.0 {
            return Err(InputError::invalid(
                "--kv and --no-load-current are the formula stand's: with --stand mechanism the motor is --motor-kt, --motor-resistance, and its friction --coulomb and --c1".into(),
            ));
        }
        c.instruments = Instruments {
            thrust: Thrust {
                k: self.thrust_k,
                exponent: self.thrust_exponent,
                ct_slope: 0.0,
                ct_reference_speed: 1500.0,
            },
            thrust_cell: (self.thrust_k > 0.0).then_some(ThrustCell {
                natural_hz: self.thrust_cell_hz,
                damping: self.thrust_cell_damping,
                rate: self.thrust_rate,
                offset: self.thrust_offset,
                noise: self.noise_thrust,
            }),
            bus: self.bus_voltage.map(|v| Bus {
                source_voltage: v,
                source_resistance: self.source_resistance,
                current_filter: self.esc_current_filter,
                noise_voltage: self.noise_bus_voltage,
                noise_current: self.noise_bus_current,
            }),
        };
        Ok(())
    }
}
