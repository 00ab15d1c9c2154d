//! Quantities as a propeller person writes them: `6N`, `600g`, `1.2kgf`, `7in`, `0.1778m`,
//! `12000rpm`, `0.1Nm`, `16V`, `4S`, `5000mAh`, `20C`, `1013hPa`.
//!
//! [`parse`] turns such a text into SI units for one [`Dimension`]. A bare number is read in the
//! dimension's SI unit (N, m, rad/s, N·m, V, A, A·h → C is *not* used: capacities stay in A·h,
//! kg, K, Pa, kg/m³) and says so ([`Parsed::unit`] is `None`), so a caller can warn about a bare
//! diameter of 7 (metres? inches?). Grams and kilograms given as a force mean gram-force and
//! kilogram-force, as every thrust stand labels them. A LiPo cell count (`4S`) is a voltage of
//! 3.7 V per cell (nominal); write volts for another chemistry.

/// Standard gravity [m/s²] (gram-force, kilogram-force, pound-force).
pub const G0: f64 = 9.806_65;
const POUND: f64 = 0.453_592_37;
const INCH: f64 = 0.0254;
const OUNCE: f64 = POUND / 16.0;

/// What is measured.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Dimension {
    /// Force (thrust) [N].
    Force,
    /// Length (diameter, chord) [m].
    Length,
    /// Angular speed [rad/s].
    Speed,
    /// Torque [N·m].
    Torque,
    /// Voltage [V].
    Voltage,
    /// Current [A].
    Current,
    /// Battery capacity [A·h].
    Capacity,
    /// Mass [kg].
    Mass,
    /// Temperature [K].
    Temperature,
    /// Pressure [Pa].
    Pressure,
    /// Density [kg/m³].
    Density,
    /// Resistance [Ω].
    Resistance,
    /// Motor velocity constant [rpm/V].
    Kv,
}

impl Dimension {
    /// The unit a bare number is read in.
    pub fn si_unit(self) -> &'static str {
        match self {
            Dimension::Force => "N",
            Dimension::Length => "m",
            Dimension::Speed => "rad/s",
            Dimension::Torque => "N·m",
            Dimension::Voltage => "V",
            Dimension::Current => "A",
            Dimension::Capacity => "A·h",
            Dimension::Mass => "kg",
            Dimension::Temperature => "K",
            Dimension::Pressure => "Pa",
            Dimension::Density => "kg/m³",
            Dimension::Resistance => "Ω",
            Dimension::Kv => "rpm/V",
        }
    }

    /// (unit spellings, factor to SI, offset to SI) — SI = value × factor + offset. Spellings are
    /// compared after [`normalise`].
    fn units(self) -> &'static [(&'static [&'static str], f64, f64)] {
        use std::f64::consts::TAU;
        match self {
            Dimension::Force => &[
                (&["n"], 1.0, 0.0),
                (&["mn"], 1e-3, 0.0),
                (&["kn"], 1e3, 0.0),
                (&["g", "gf"], G0 * 1e-3, 0.0),
                (&["kg", "kgf"], G0, 0.0),
                (&["lb", "lbf", "lbs"], G0 * POUND, 0.0),
                (&["oz", "ozf"], G0 * OUNCE, 0.0),
            ],
            Dimension::Length => &[
                (&["m"], 1.0, 0.0),
                (&["cm"], 1e-2, 0.0),
                (&["mm"], 1e-3, 0.0),
                (&["in", "inch", "inches", "\""], INCH, 0.0),
                (&["ft", "feet"], 12.0 * INCH, 0.0),
            ],
            Dimension::Speed => &[
                (&["rad/s", "rads", "rad/sec"], 1.0, 0.0),
                (&["rpm", "rev/min", "1/min"], TAU / 60.0, 0.0),
                (&["krpm"], TAU * 1000.0 / 60.0, 0.0),
                (&["rev/s", "rps", "hz"], TAU, 0.0),
                (&["deg/s"], TAU / 360.0, 0.0),
            ],
            Dimension::Torque => &[
                (&["nm", "n·m", "n*m", "n-m"], 1.0, 0.0),
                (&["mnm", "mn·m", "mn*m"], 1e-3, 0.0),
                (&["kgfcm", "kgcm", "kgf·cm"], G0 * 1e-2, 0.0),
                (&["gfcm", "gcm"], G0 * 1e-5, 0.0),
                (&["ozfin", "ozin", "ozf·in"], G0 * OUNCE * INCH, 0.0),
                (&["lbfin", "lbin"], G0 * POUND * INCH, 0.0),
                (
                    &["lbfft", "lbft", "ftlb", "ftlbf"],
                    G0 * POUND * 12.0 * INCH,
                    0.0,
                ),
            ],
            Dimension::Voltage => &[
                (&["v"], 1.0, 0.0),
                (&["mv"], 1e-3, 0.0),
                (&["s"], LIPO_NOMINAL_CELL, 0.0),
            ],
            Dimension::Current => &[(&["a"], 1.0, 0.0), (&["ma"], 1e-3, 0.0)],
            Dimension::Capacity => &[(&["ah"], 1.0, 0.0), (&["mah"], 1e-3, 0.0)],
            Dimension::Mass => &[
                (&["kg"], 1.0, 0.0),
                (&["g"], 1e-3, 0.0),
                (&["lb", "lbs"], POUND, 0.0),
                (&["oz"], OUNCE, 0.0),
            ],
            Dimension::Temperature => &[
                (&["k"], 1.0, 0.0),
                (&["c", "°c", "degc"], 1.0, 273.15),
                (&["f", "°f", "degf"], 5.0 / 9.0, 273.15 - 32.0 * 5.0 / 9.0),
            ],
            Dimension::Pressure => &[
                (&["pa"], 1.0, 0.0),
                (&["hpa", "mbar"], 100.0, 0.0),
                (&["kpa"], 1e3, 0.0),
                (&["bar"], 1e5, 0.0),
                (&["atm"], 101_325.0, 0.0),
                (&["inhg"], 3386.389, 0.0),
                (&["psi"], 6894.757, 0.0),
            ],
            Dimension::Density => &[(&["kg/m3", "kg/m³", "kg/m^3"], 1.0, 0.0)],
            Dimension::Resistance => &[
                (&["ohm", "ω", "ohms"], 1.0, 0.0),
                (&["mohm", "mω"], 1e-3, 0.0),
            ],
            Dimension::Kv => &[(&["rpm/v", "kv"], 1.0, 0.0)],
        }
    }
}

/// Nominal voltage of a lithium-polymer cell [V] (`4S` = 14.8 V).
pub const LIPO_NOMINAL_CELL: f64 = 3.7;

/// A parsed quantity.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Parsed {
    /// The value in the dimension's SI unit ([`Dimension::si_unit`]).
    pub si: f64,
    /// The unit as written (its canonical spelling), or `None` for a bare number.
    pub unit: Option<&'static str>,
}

/// Lower case, no spaces, `·`/`⋅`/`.` between letters kept as `·`.
fn normalise(unit: &str) -> String {
    unit.trim()
        .to_lowercase()
        .replace(['⋅', '.', '*'], "·")
        .replace(' ', "")
        .replace("n·m", "nm")
        .replace("f·cm", "fcm")
        .replace("f·in", "fin")
        .replace("·", "")
}

/// Parses `text` as a quantity of `dimension`. The error says what was expected, with examples.
pub fn parse(text: &str, dimension: Dimension) -> Result<Parsed, String> {
    let t = text.trim();
    // The longest prefix that parses as a number.
    let split = (1..=t.len())
        .rev()
        .filter(|&i| t.is_char_boundary(i))
        .find(|&i| t[..i].trim().parse::<f64>().is_ok());
    let examples = || {
        let names: Vec<&str> = dimension
            .units()
            .iter()
            .map(|(names, _, _)| names[0])
            .collect();
        format!(
            "a number with a unit ({}; a bare number is {})",
            names.join(", "),
            dimension.si_unit()
        )
    };
    let Some(split) = split else {
        return Err(format!("`{text}` is not {}", examples()));
    };
    // "inf"/"nan" parse as f64; a quantity is finite.
    let number: f64 = t[..split].trim().parse().unwrap_or(f64::NAN);
    if !number.is_finite()
        || t[..split]
            .trim()
            .chars()
            .any(|c| c.is_alphabetic() && c != 'e' && c != 'E')
    {
        return Err(format!("`{text}` is not {}", examples()));
    }
    let rest = normalise(&t[split..]);
    if rest.is_empty() {
        return Ok(Parsed {
            si: number,
            unit: None,
        });
    }
    for (names, factor, offset) in dimension.units() {
        if names.iter().any(|n| normalise(n) == rest) {
            return Ok(Parsed {
                si: number * factor + offset,
                unit: Some(names[0]),
            });
        }
    }
    Err(format!(
        "`{text}`: unknown unit `{}`; expected {}",
        t[split..].trim(),
        examples()
    ))
}

/// Formats a force in newtons with grams-force beside it: "6.000 N (611.8 gf)".
pub fn describe_force(newtons: f64) -> String {
    format!("{newtons:.3} N ({:.1} gf)", newtons / (G0 * 1e-3))
}

#[cfg(test)]
mod tests {
    use super::*;

    fn si(text: &str, d: Dimension) -> f64 {
        parse(text, d).unwrap().si
    }

    #[test]
    fn units_a_propeller_person_writes() {
        assert_eq!(si("6N", Dimension::Force), 6.0);
        assert!((si("600g", Dimension::Force) - 5.883_99).abs() < 1e-5);
        assert!((si("1.2 kgf", Dimension::Force) - 11.767_98).abs() < 1e-5);
        assert!((si("1lbf", Dimension::Force) - 4.448_222).abs() < 1e-6);
        assert!((si("7in", Dimension::Length) - 0.1778).abs() < 1e-12);
        assert_eq!(si("0.1778m", Dimension::Length), 0.1778);
        assert!((si("12000rpm", Dimension::Speed) - 1256.637).abs() < 1e-3);
        assert!((si("200 rev/s", Dimension::Speed) - 1256.637).abs() < 1e-3);
        assert_eq!(si("0.1N·m", Dimension::Torque), 0.1);
        assert_eq!(si("0.1 N.m", Dimension::Torque), 0.1);
        assert!((si("100mNm", Dimension::Torque) - 0.1).abs() < 1e-15);
        assert!((si("4S", Dimension::Voltage) - 14.8).abs() < 1e-12);
        assert!((si("5000mAh", Dimension::Capacity) - 5.0).abs() < 1e-12);
        assert!((si("20C", Dimension::Temperature) - 293.15).abs() < 1e-12);
        assert!((si("68F", Dimension::Temperature) - 293.15).abs() < 1e-9);
        assert_eq!(si("1013hPa", Dimension::Pressure), 101_300.0);
        assert_eq!(si("1.1e-3", Dimension::Length), 1.1e-3);
        assert_eq!(parse("7", Dimension::Length).unwrap().unit, None);
    }

    #[test]
    fn errors_say_what_is_expected() {
        let e = parse("7 furlongs", Dimension::Length).unwrap_err();
        assert!(
            e.contains("unknown unit `furlongs`") && e.contains("in"),
            "{e}"
        );
        let e = parse("fast", Dimension::Speed).unwrap_err();
        assert!(
            e.contains("rpm") && e.contains("bare number is rad/s"),
            "{e}"
        );
        assert!(parse("inf", Dimension::Force).is_err());
        assert!(parse("nanN", Dimension::Force).is_err());
    }
}
