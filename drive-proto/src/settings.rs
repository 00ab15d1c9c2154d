//! The machines' settings as types: a value out of range cannot be built, so a machine never
//! checks one again (linfa's `ParamGuard` idea; the core's `NodeId` and `SubjectId` are the same
//! for IDs).
//!
//! ```text
//!  f64 from a flag, a register, a file ─► SetpointPeriod::try_from ─┬─► SetpointPeriod (in range)
//!                                                                   └─► RangeError { range, got }
//!  (lo, hi) ─► SetpointRange::new ─► SetpointRange (-1 ≤ lo < hi ≤ 1) | SetpointRangeError
//! ```
//! Errors are values, not sentences: the caller knows which setting it was checking and names
//! it (a flag, a register, an environment variable) in its own words; the error's `Display` says
//! only what is wrong with the value.

use core::fmt;
use std::time::Duration;

/// A day: the longest duration any setting may have (durations become deadlines).
pub const DAY: f64 = 86_400.0;

/// The interval a number must lie in.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Range {
    /// The lower bound.
    pub lo: f64,
    /// The lower bound itself is excluded.
    pub lo_open: bool,
    /// The upper bound.
    pub hi: f64,
    /// The upper bound itself is excluded.
    pub hi_open: bool,
    /// The unit, for people ("s"; empty for none).
    pub unit: &'static str,
}

impl Range {
    /// True when `v` is finite and within the range.
    pub fn contains(&self, v: f64) -> bool {
        let above = if self.lo_open {
            v > self.lo
        } else {
            v >= self.lo
        };
        let below = if self.hi_open {
            v < self.hi
        } else {
            v <= self.hi
        };
        v.is_finite() && above && below
    }
}

/// A number outside its setting's [`Range`].
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct RangeError {
    /// Where it must lie.
    pub range: Range,
    /// What was given.
    pub got: f64,
}

impl fmt::Display for RangeError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        let r = &self.range;
        let lo = if r.lo_open { "above" } else { "at least" };
        let hi = if r.hi_open { "below" } else { "at most" };
        let unit = if r.unit.is_empty() {
            String::new()
        } else {
            format!(" {}", r.unit)
        };
        write!(
            f,
            "must be a finite number {lo} {} and {hi} {}{unit} (got {})",
            r.lo, r.hi, self.got
        )
    }
}

impl std::error::Error for RangeError {}

/// Defines a number type that holds only values within its range.
macro_rules! bounded {
    ($(#[$doc:meta])* $name:ident, $lo:literal $lo_open:literal, $hi:expr, $hi_open:literal, $unit:literal) => {
        $(#[$doc])*
        #[derive(Clone, Copy, Debug, PartialEq, PartialOrd)]
        pub struct $name(f64);

        impl $name {
            /// The values it holds.
            pub const RANGE: Range = Range {
                lo: $lo,
                lo_open: $lo_open,
                hi: $hi,
                hi_open: $hi_open,
                unit: $unit,
            };

            /// `v`, or why it is out of range.
            pub fn new(v: f64) -> Result<Self, RangeError> {
                if Self::RANGE.contains(v) {
                    Ok($name(v))
                } else {
                    Err(RangeError {
                        range: Self::RANGE,
                        got: v,
                    })
                }
            }

            /// The value for a constant; an out-of-range constant fails to compile when used in
            /// a `const`.
            pub const fn from_const(v: f64) -> Self {
                let above = if $lo_open { v > $lo } else { v >= $lo };
                let below = if $hi_open { v < $hi } else { v <= $hi };
                assert!(above && below, "constant out of range");
                $name(v)
            }

            /// The number.
            pub const fn get(self) -> f64 {
                self.0
            }
        }

        impl TryFrom<f64> for $name {
            type Error = RangeError;
            fn try_from(v: f64) -> Result<Self, RangeError> {
                $name::new(v)
            }
        }

        impl From<$name> for f64 {
            fn from(v: $name) -> f64 {
                v.0
            }
        }

        impl fmt::Display for $name {
            fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
                fmt::Display::fmt(&self.0, f)
            }
        }
    };
}

/// Seconds that may become a [`Duration`] (finite, non-negative by their range).
macro_rules! seconds {
    ($(#[$doc:meta])* $name:ident, $lo:literal $lo_open:literal, $hi:expr) => {
        bounded!($(#[$doc])* $name, $lo $lo_open, $hi, false, "s");

        impl $name {
            /// As a [`Duration`].
            pub fn duration(self) -> Duration {
                Duration::from_secs_f64(self.0)
            }
        }
    };
}

seconds!(
    /// How often the driver publishes the setpoint [s]: above 0, at most 0.5 (the seed: 5 ms).
    SetpointPeriod,
    0.0 true,
    0.5
);
seconds!(
    /// How long the driver waits for feedback during the pattern before it stops [s].
    Deadman,
    0.0 true,
    60.0
);
seconds!(
    /// The pattern's period [s] (the seed's sine: 2 s).
    Period,
    0.0 true,
    DAY
);
seconds!(
    /// How long the pattern runs after the init phase [s] (the seed: 200 s).
    PatternDuration,
    0.0 true,
    DAY
);
seconds!(
    /// How long the init phase holds the high setpoint before the pattern [s] (the seed: 5 s).
    InitDuration,
    0.0 false,
    DAY
);
seconds!(
    /// The simulated drive's feedback interval [s] (Telega's `mns.pub_interval_min`), 0.1 ms to
    /// 1 s.
    FeedbackInterval,
    1e-4 false,
    1.0
);
seconds!(
    /// How long a simulated drive runs before it stops by itself [s].
    RunLimit,
    0.0 true,
    DAY
);
bounded!(
    /// A relative standard error to stop at (`--until-stderr`), as a fraction in (0, 1).
    RelativeError,
    0.0 true,
    1.0,
    true,
    ""
);

bounded!(
    /// The highest speed the rotor may reach [rad/s] (`max_speed`), above 0 and at most 100,000.
    MaxSpeed,
    0.0 true,
    1e5,
    false,
    "rad/s"
);
bounded!(
    /// The soft start's setpoint (`soft_start_setpoint`): a ratiometric magnitude in (0, 1],
    /// applied in the direction of `hi`.
    SoftStartSetpoint,
    0.0 true,
    1.0,
    false,
    ""
);
seconds!(
    /// How long the soft start lasts [s] (`soft_start_duration`), above 0 and at most 60.
    SoftStartDuration,
    0.0 true,
    60.0
);
seconds!(
    /// How long the ramp from the soft start's setpoint to `hi` lasts [s] (`ramp_duration`).
    RampDuration,
    0.0 true,
    DAY
);
bounded!(
    /// How far the speed may run past what the reported torque can explain before the watchdog
    /// stops the run [rad/s] (`speed_watchdog`), above 0 and at most 100,000.
    WatchdogMargin,
    0.0 true,
    1e5,
    false,
    "rad/s"
);

bounded!(
    /// The torque a simulated motor makes per torque it is commanded and reports, −10 to 10: −1
    /// reverses its sign, 0 makes none (`propid sim-drive --torque-scale`, for trying the limits).
    TorqueScale,
    -10.0 false,
    10.0,
    false,
    ""
);

/// rad/s per rpm.
pub const RAD_S_PER_RPM: f64 = std::f64::consts::PI / 30.0;

/// A speed as people write it: rad/s by default (`1256.6`, `1256.6rad/s`) or rpm (`12000rpm`,
/// `12000 rpm`); the value in rad/s, or `None` when the text is not one.
pub fn parse_speed(text: &str) -> Option<f64> {
    let t = text.trim();
    let (number, scale) = if let Some(n) = t.strip_suffix("rpm") {
        (n, RAD_S_PER_RPM)
    } else if let Some(n) = t.strip_suffix("rad/s") {
        (n, 1.0)
    } else {
        (t, 1.0)
    };
    let v: f64 = number.trim().parse().ok()?;
    v.is_finite().then_some(v * scale)
}

impl SetpointPeriod {
    /// The seed's: 5 ms.
    pub const SEED: SetpointPeriod = SetpointPeriod::from_const(0.005);
}

impl Deadman {
    /// What `propid drive` waits by default: 0.5 s.
    pub const DEFAULT: Deadman = Deadman::from_const(0.5);
}

/// The ratiometric setpoint range `lo..hi` of the pattern (the seed's `setpoint_rat_lo_hi`):
/// finite, −1 ≤ lo < hi ≤ 1.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct SetpointRange {
    lo: f64,
    hi: f64,
}

/// A setpoint range that is not −1 ≤ lo < hi ≤ 1.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct SetpointRangeError {
    /// The low value given.
    pub lo: f64,
    /// The high value given.
    pub hi: f64,
}

impl fmt::Display for SetpointRangeError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(
            f,
            "the setpoint range must satisfy -1 ≤ lo < hi ≤ 1 (got lo = {}, hi = {})",
            self.lo, self.hi
        )
    }
}

impl std::error::Error for SetpointRangeError {}

impl SetpointRange {
    /// The seed's: 0.1 to 0.9.
    pub const SEED: SetpointRange = SetpointRange { lo: 0.1, hi: 0.9 };

    /// `lo..hi`, or why not.
    pub fn new(lo: f64, hi: f64) -> Result<Self, SetpointRangeError> {
        let ok = lo.is_finite() && hi.is_finite() && -1.0 <= lo && lo < hi && hi <= 1.0;
        if ok {
            Ok(SetpointRange { lo, hi })
        } else {
            Err(SetpointRangeError { lo, hi })
        }
    }

    /// The low setpoint.
    pub fn lo(self) -> f64 {
        self.lo
    }

    /// The high setpoint (the init phase's).
    pub fn hi(self) -> f64 {
        self.hi
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn speeds_are_read_in_rad_s_or_rpm() {
        assert_eq!(parse_speed("1256.5"), Some(1256.5));
        assert_eq!(parse_speed(" 300 rad/s "), Some(300.0));
        let rpm = parse_speed("12000rpm").unwrap();
        assert!((rpm - 1256.637).abs() < 1e-3, "{rpm}");
        assert_eq!(parse_speed("12000 rpm"), parse_speed("12000rpm"));
        for bad in ["", "fast", "12000 rps", "inf", "NaNrpm"] {
            assert_eq!(parse_speed(bad), None, "{bad}");
        }
        assert!(MaxSpeed::new(0.0).is_err());
        assert_eq!(
            MaxSpeed::new(-5.0).unwrap_err().to_string(),
            "must be a finite number above 0 and at most 100000 rad/s (got -5)"
        );
    }

    #[test]
    fn out_of_range_values_cannot_be_built() {
        assert_eq!(SetpointPeriod::new(0.005), Ok(SetpointPeriod::SEED));
        for bad in [0.0, -1.0, 0.6, f64::NAN, f64::INFINITY] {
            let e = SetpointPeriod::new(bad).unwrap_err();
            assert_eq!(e.got.to_bits(), bad.to_bits());
        }
        assert_eq!(
            SetpointPeriod::new(0.0).unwrap_err().to_string(),
            "must be a finite number above 0 and at most 0.5 s (got 0)"
        );
        assert_eq!(InitDuration::new(0.0).map(InitDuration::get), Ok(0.0));
        assert_eq!(
            RelativeError::new(1.0).unwrap_err().to_string(),
            "must be a finite number above 0 and below 1 (got 1)"
        );
        assert!(FeedbackInterval::new(5e-5).is_err());
        assert_eq!(
            PatternDuration::new(200.0).unwrap().duration(),
            Duration::from_secs(200)
        );
        assert!(SetpointRange::new(0.9, 0.1).is_err());
        assert!(SetpointRange::new(0.1, f64::INFINITY).is_err());
        assert!(SetpointRange::new(-1.0, 1.0).is_ok());
        assert_eq!(
            SetpointRange::new(f64::NAN, 0.5).unwrap_err().to_string(),
            "the setpoint range must satisfy -1 ≤ lo < hi ≤ 1 (got lo = NaN, hi = 0.5)"
        );
    }
}
