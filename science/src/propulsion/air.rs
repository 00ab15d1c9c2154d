//! The air the propeller works in: density, viscosity, speed of sound, and the Reynolds and Mach
//! numbers a coefficient belongs to.
//!
//! ```text
//!  ρ = p / (R·T)                 dry air, R = 287.05 J/(kg·K)              (ideal gas law)
//!  μ = μ₀ (T/T₀)^1.5 (T₀+S)/(T+S) μ₀ = 1.716e-5 Pa·s, T₀ = 273.15 K, S = 110.4 K (Sutherland)
//!  a = √(γ·R·T)                  γ = 1.4
//!  Re_D   = ρ·n·D²/μ             the rotational Reynolds number (needs no blade geometry)
//!  Re_0.75 = ρ·(0.75·π·n·D)·c/μ  the blade section's at 75 % radius, chord c (when given)
//!  M_tip  = π·n·D / a
//! ```
//! The default is ISA sea level (15 °C, 101 325 Pa: ρ = 1.225 kg/m³), the convention of
//! published static propeller data. Humidity is ignored (moist air is up to ~1 % lighter).

use serde::{Deserialize, Serialize};

/// Specific gas constant of dry air [J/(kg·K)].
pub const R_AIR: f64 = 287.05;
/// Ratio of specific heats of air.
pub const GAMMA: f64 = 1.4;
/// ISA sea-level temperature [K].
pub const ISA_TEMPERATURE: f64 = 288.15;
/// ISA sea-level pressure [Pa].
pub const ISA_PRESSURE: f64 = 101_325.0;
/// ISA sea-level density [kg/m³], as the standard states it (p/(R·T) with R = 287.05 gives
/// 1.22503; every propeller table, and every propid command, quotes 1.225).
pub const ISA_DENSITY: f64 = 1.225;

/// Where the density came from.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
#[serde(tag = "from", rename_all = "snake_case")]
pub enum AirSource {
    /// Nothing was given: ISA sea level.
    IsaSeaLevel,
    /// The density was given.
    Given,
    /// From a temperature [K] and a pressure [Pa].
    TemperaturePressure {
        /// [K].
        temperature: f64,
        /// [Pa].
        pressure: f64,
    },
}

/// The air.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct Air {
    /// Density ρ [kg/m³].
    pub density: f64,
    /// Temperature used for viscosity and the speed of sound [K].
    pub temperature: f64,
    /// Dynamic viscosity μ [Pa·s].
    pub viscosity: f64,
    /// Where the density came from.
    pub source: AirSource,
}

/// Sutherland's law for air.
pub fn viscosity(temperature: f64) -> f64 {
    const MU0: f64 = 1.716e-5;
    const T0: f64 = 273.15;
    const S: f64 = 110.4;
    MU0 * (temperature / T0).powf(1.5) * (T0 + S) / (temperature + S)
}

impl Air {
    /// ISA sea level: 15 °C, 101 325 Pa.
    pub fn isa() -> Air {
        Air {
            density: ISA_DENSITY,
            temperature: ISA_TEMPERATURE,
            viscosity: viscosity(ISA_TEMPERATURE),
            source: AirSource::IsaSeaLevel,
        }
    }

    /// From temperature [K] and pressure [Pa]; an error names what is out of range.
    pub fn from_temperature_pressure(temperature: f64, pressure: f64) -> Result<Air, String> {
        if !(150.0..=400.0).contains(&temperature) {
            return Err(format!(
                "temperature {temperature:.2} K ({:.1} °C) is outside 150–400 K: is the unit right (20C, 293K, 68F)?",
                temperature - 273.15
            ));
        }
        if !(10_000.0..=200_000.0).contains(&pressure) {
            return Err(format!(
                "pressure {pressure} Pa is outside 10–200 kPa: is the unit right (1013hPa, 101325Pa, 29.92inHg)?"
            ));
        }
        Ok(Air {
            density: pressure / (R_AIR * temperature),
            temperature,
            viscosity: viscosity(temperature),
            source: AirSource::TemperaturePressure {
                temperature,
                pressure,
            },
        })
    }

    /// A given density (viscosity and speed of sound at `temperature`, ISA's when `None`).
    pub fn with_density(density: f64, temperature: Option<f64>) -> Result<Air, String> {
        if !(0.05..=2.0).contains(&density) {
            return Err(format!(
                "air density {density} kg/m³ is outside 0.05–2 kg/m³ (sea level is 1.225)"
            ));
        }
        let temperature = temperature.unwrap_or(ISA_TEMPERATURE);
        Ok(Air {
            density,
            temperature,
            viscosity: viscosity(temperature),
            source: AirSource::Given,
        })
    }

    /// Speed of sound [m/s].
    pub fn speed_of_sound(&self) -> f64 {
        (GAMMA * R_AIR * self.temperature).sqrt()
    }

    /// Rotational Reynolds number ρ·n·D²/μ (n in rev/s, D in m).
    pub fn reynolds_rotational(&self, n: f64, diameter: f64) -> f64 {
        self.density * n * diameter * diameter / self.viscosity
    }

    /// Blade Reynolds number at 75 % radius, chord `chord` [m].
    pub fn reynolds_075(&self, n: f64, diameter: f64, chord: f64) -> f64 {
        self.density * 0.75 * std::f64::consts::PI * n * diameter * chord / self.viscosity
    }

    /// Tip Mach number.
    pub fn tip_mach(&self, n: f64, diameter: f64) -> f64 {
        std::f64::consts::PI * n * diameter / self.speed_of_sound()
    }

    /// "ρ = 1.225 kg/m³ (ISA sea level, 15 °C, 1013.25 hPa)".
    pub fn describe(&self) -> String {
        let from = match self.source {
            AirSource::IsaSeaLevel => "ISA sea level, 15 °C, 1013.25 hPa: not measured".to_string(),
            AirSource::Given => "given".to_string(),
            AirSource::TemperaturePressure {
                temperature,
                pressure,
            } => format!(
                "dry air at {:.1} °C and {:.1} hPa",
                temperature - 273.15,
                pressure / 100.0
            ),
        };
        format!("ρ = {:.4} kg/m³ ({from})", self.density)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn isa_sea_level_is_the_textbook_air() {
        let a = Air::isa();
        assert!((a.density - 1.2250).abs() < 5e-5, "{}", a.density);
        assert!((a.viscosity - 1.789e-5).abs() < 1e-8, "{}", a.viscosity);
        assert!((a.speed_of_sound() - 340.3).abs() < 0.1);
        let warm = Air::from_temperature_pressure(303.15, 100_000.0).unwrap();
        assert!((warm.density - 1.1492).abs() < 1e-4, "{}", warm.density);
        assert!(Air::from_temperature_pressure(20.0, 101_325.0).is_err());
        assert!(Air::with_density(1225.0, None).is_err());
    }
}
