//! A measured quantity with its honesty gate: identified (value ± standard error), not
//! identified (the value and why it cannot be trusted), or cannot judge (no value at all).
//!
//! The same rules as the inertia and c2 of `propid fit`: a relative standard error above
//! [`MAX_RELATIVE_STDERR`] or a value on a bound is *not identified*; a value or standard error
//! that is not finite, or a standard error of zero (the data gave no uncertainty, which is never
//! true of a measurement), is *cannot judge*. No NaN and no zero standard error ever leaves this
//! type: JSON has no NaN, and "± 0" reads as perfect precision.

use serde::{Deserialize, Serialize};

/// Above this relative standard error a value is reported as not identified.
pub const MAX_RELATIVE_STDERR: f64 = 0.3;

/// A quantity as the data support it.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(tag = "status", rename_all = "snake_case")]
pub enum Quantity {
    /// The data identify it: value ± one standard error.
    Identified {
        /// The value.
        value: f64,
        /// One standard error (finite, > 0).
        stderr: f64,
        /// Its unit.
        unit: String,
    },
    /// A value came out, but the data do not pin it down.
    NotIdentified {
        /// The value (finite).
        value: f64,
        /// Its standard error (finite, > 0).
        stderr: f64,
        /// Its unit.
        unit: String,
        /// Why it is not identified, in words.
        reason: String,
    },
    /// No value can be given.
    CannotJudge {
        /// The unit the value would have.
        unit: String,
        /// Why, in words.
        reason: String,
    },
}

impl Quantity {
    /// Applies the gates to an estimate.
    pub fn judge(value: f64, stderr: f64, unit: &str) -> Quantity {
        Quantity::judge_relative(value, stderr, unit, MAX_RELATIVE_STDERR)
    }

    /// [`Quantity::judge`] with another limit on the relative standard error (for quantities
    /// near zero, such as an offset, pass `f64::INFINITY`: only finiteness is checked).
    pub fn judge_relative(value: f64, stderr: f64, unit: &str, max_relative: f64) -> Quantity {
        let unit = unit.to_string();
        if !value.is_finite() {
            return Quantity::CannotJudge {
                unit,
                reason: "the fit gave no finite value".into(),
            };
        }
        if !(stderr.is_finite() && stderr > 0.0) {
            return Quantity::CannotJudge {
                unit,
                reason: if stderr == 0.0 {
                    "the data gave no uncertainty (fewer independent points than parameters?)"
                        .into()
                } else {
                    "the fit gave no finite uncertainty".into()
                },
            };
        }
        let relative = stderr / value.abs();
        if relative > max_relative {
            return Quantity::NotIdentified {
                value,
                stderr,
                unit,
                reason: format!(
                    "its standard error is {:.0} % of its value (more than {:.0} %)",
                    100.0 * relative,
                    100.0 * max_relative
                ),
            };
        }
        Quantity::Identified {
            value,
            stderr,
            unit,
        }
    }

    /// Cannot judge, with a reason.
    pub fn cannot_judge(unit: &str, reason: impl Into<String>) -> Quantity {
        Quantity::CannotJudge {
            unit: unit.to_string(),
            reason: reason.into(),
        }
    }

    /// The same value marked as not identified for `reason` (a value on a bound, a model the
    /// data reject); cannot-judge stays as it is.
    pub fn not_identified(self, reason: impl Into<String>) -> Quantity {
        match self {
            Quantity::Identified {
                value,
                stderr,
                unit,
            }
            | Quantity::NotIdentified {
                value,
                stderr,
                unit,
                ..
            } => Quantity::NotIdentified {
                value,
                stderr,
                unit,
                reason: reason.into(),
            },
            other => other,
        }
    }

    /// The value when identified.
    pub fn identified(&self) -> Option<f64> {
        match self {
            Quantity::Identified { value, .. } => Some(*value),
            _ => None,
        }
    }

    /// The value, identified or not.
    pub fn value(&self) -> Option<f64> {
        match self {
            Quantity::Identified { value, .. } | Quantity::NotIdentified { value, .. } => {
                Some(*value)
            }
            Quantity::CannotJudge { .. } => None,
        }
    }

    /// The standard error, identified or not.
    pub fn stderr(&self) -> Option<f64> {
        match self {
            Quantity::Identified { stderr, .. } | Quantity::NotIdentified { stderr, .. } => {
                Some(*stderr)
            }
            Quantity::CannotJudge { .. } => None,
        }
    }

    /// The unit.
    pub fn unit(&self) -> &str {
        match self {
            Quantity::Identified { unit, .. }
            | Quantity::NotIdentified { unit, .. }
            | Quantity::CannotJudge { unit, .. } => unit,
        }
    }

    /// The same quantity in another unit: value and standard error times `factor`.
    pub fn scaled(&self, factor: f64, unit: &str) -> Quantity {
        match self.clone() {
            Quantity::Identified { value, stderr, .. } => Quantity::Identified {
                value: value * factor,
                stderr: stderr * factor.abs(),
                unit: unit.into(),
            },
            Quantity::NotIdentified {
                value,
                stderr,
                reason,
                ..
            } => Quantity::NotIdentified {
                value: value * factor,
                stderr: stderr * factor.abs(),
                unit: unit.into(),
                reason,
            },
            Quantity::CannotJudge { reason, .. } => Quantity::CannotJudge {
                unit: unit.into(),
                reason,
            },
        }
    }

    /// "0.1412 ± 0.0006 1", "0.14 ± 0.09 1 (not identified: …)", "cannot judge: …" (the value
    /// to the standard error's second significant digit).
    pub fn describe(&self) -> String {
        match self {
            Quantity::Identified {
                value,
                stderr,
                unit,
            } => format!("{}{}", plus_minus(*value, *stderr), with_unit(unit)),
            Quantity::NotIdentified {
                value,
                stderr,
                unit,
                reason,
            } => format!(
                "{}{} (not identified: {reason})",
                plus_minus(*value, *stderr),
                with_unit(unit)
            ),
            Quantity::CannotJudge { reason, .. } => format!("cannot judge: {reason}"),
        }
    }
}

/// " N·m", or nothing for a dimensionless "1" (how every report writes a unit after a value).
pub(crate) fn with_unit(unit: &str) -> String {
    if unit == "1" || unit.is_empty() {
        String::new()
    } else {
        format!(" {unit}")
    }
}

/// "value ± stderr" with the value given to the standard error's second significant digit.
pub fn plus_minus(value: f64, stderr: f64) -> String {
    let digits = if stderr > 0.0 && stderr.is_finite() && value != 0.0 {
        // Decimal places so that the standard error shows two significant digits.
        let e = stderr.abs().log10().floor() as i32;
        (1 - e).max(0) as usize
    } else {
        4
    };
    if value.abs() >= 1e5 || (value != 0.0 && value.abs() < 1e-3) {
        let e = value.abs().log10().floor() as i32;
        let scale = 10f64.powi(e);
        let sd = (stderr / scale).abs();
        let d = if sd > 0.0 && sd.is_finite() {
            ((1 - sd.log10().floor() as i32).max(0) as usize).min(8)
        } else {
            4
        };
        format!("({:.d$} ± {:.d$})e{e}", value / scale, sd, d = d)
    } else {
        format!("{value:.digits$} ± {stderr:.digits$}")
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn gates_never_pass_nan_or_a_zero_stderr() {
        assert!(matches!(
            Quantity::judge(f64::NAN, 1.0, "1"),
            Quantity::CannotJudge { .. }
        ));
        assert!(matches!(
            Quantity::judge(1.0, 0.0, "1"),
            Quantity::CannotJudge { .. }
        ));
        assert!(matches!(
            Quantity::judge(1.0, f64::INFINITY, "1"),
            Quantity::CannotJudge { .. }
        ));
        assert!(matches!(
            Quantity::judge(1.0, 0.31, "1"),
            Quantity::NotIdentified { .. }
        ));
        assert_eq!(Quantity::judge(1.0, 0.29, "1").identified(), Some(1.0));
        let json = serde_json::to_string(&Quantity::judge(0.14, 0.002, "1")).unwrap();
        assert_eq!(
            json,
            r#"{"status":"identified","value":0.14,"stderr":0.002,"unit":"1"}"#
        );
    }

    #[test]
    fn plus_minus_shows_two_digits_of_the_error() {
        assert_eq!(plus_minus(0.14123, 0.00061), "0.14123 ± 0.00061");
        assert_eq!(plus_minus(2102.4, 35.0), "2102 ± 35");
        assert_eq!(plus_minus(5.9e-8, 1.2e-10), "(5.900 ± 0.012)e-8");
    }
}
