//! The plausibility gate before any verdict, shared by `fit` and `diagnose`.
//!
//! A fit solves whatever it is given: a torque column with the opposite sign convention gives
//! J on its bound, a velocity logged in rpm gives c2 91× too small, and both look like numbers.
//! These checks ask whether the data are what the model assumes before any model is believed:
//!
//! - **the torque sign**: a propeller absorbs power, so Q·ω must be positive on the whole: a
//!   torque negatively correlated with the speed is a flipped sign when the torque also works
//!   against the acceleration it causes (1/J of a = Q/J − (c1/J)·ω − (c2/J)·ω|ω|, fitted without
//!   bounds, negative with t < −[`SIGN_T`]) or the correlation is clear (below
//!   [`POWER_CORRELATION`]). The free 1/J alone does not decide: a load cell that lags and holds
//!   its samples turns it negative on steady plateaus (t = −11.9 on a real RCbenchmark log whose
//!   torque·speed correlation is +0.97).
//! - **the units of velocity and time**: Δω over a short window must equal ∫a·dt. The ratio
//!   names the mistake: 60/2π = 9.549 is a velocity in rpm beside an acceleration in rad/s²,
//!   1/2π a velocity in rev/s, 180/π one in deg/s, 10⁻³ a time column in milliseconds.
//! - **identification** (after the fit): a parameter on a bound, or with a relative standard
//!   error above [`MAX_RELATIVE_STDERR`], is not identified, and its standard error is not a
//!   precision.
//!
//! Rows copied twice and a last line cut while the file was written are found where the file is
//! read (`propid_io::tsv`), and announced there.

use propid_core::estimate::LoadEstimator;
use propid_io::tsv::Sample;
use serde::Serialize;

/// |t| of the freely fitted 1/J beyond which its sign is taken as the data's.
pub const SIGN_T: f64 = 3.0;
/// Correlation of torque with speed below which a steady run's torque sign is taken as flipped.
pub const POWER_CORRELATION: f64 = -0.3;
/// Relative standard error above which a parameter is not identified.
pub const MAX_RELATIVE_STDERR: f64 = 0.3;

/// A velocity unit a stand logs in.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize)]
#[serde(rename_all = "snake_case")]
pub enum SpeedUnit {
    /// rad/s (propid's unit).
    RadPerSecond,
    /// Revolutions per minute.
    Rpm,
    /// Revolutions per second.
    RevPerSecond,
    /// Degrees per second.
    DegPerSecond,
}

impl SpeedUnit {
    /// Every unit, propid's first.
    pub const ALL: [SpeedUnit; 4] = [
        SpeedUnit::RadPerSecond,
        SpeedUnit::Rpm,
        SpeedUnit::RevPerSecond,
        SpeedUnit::DegPerSecond,
    ];

    /// rad/s per unit.
    pub fn to_rad_per_second(self) -> f64 {
        use std::f64::consts::PI;
        match self {
            SpeedUnit::RadPerSecond => 1.0,
            SpeedUnit::Rpm => 2.0 * PI / 60.0,
            SpeedUnit::RevPerSecond => 2.0 * PI,
            SpeedUnit::DegPerSecond => PI / 180.0,
        }
    }

    /// Its name as written (`rpm`, `rev/s`, …).
    pub fn name(self) -> &'static str {
        match self {
            SpeedUnit::RadPerSecond => "rad/s",
            SpeedUnit::Rpm => "rpm",
            SpeedUnit::RevPerSecond => "rev/s",
            SpeedUnit::DegPerSecond => "deg/s",
        }
    }

    /// The unit named `text` (`rad/s`, `rpm`, `rev/s`, `deg/s`).
    pub fn parse(text: &str) -> Result<SpeedUnit, String> {
        let t = text.trim().to_lowercase();
        Self::ALL
            .into_iter()
            .find(|u| u.name() == t || (t == "rps" && *u == SpeedUnit::RevPerSecond))
            .ok_or_else(|| format!("`{text}` is not a speed unit: rad/s, rpm, rev/s or deg/s"))
    }
}

impl std::fmt::Display for SpeedUnit {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(self.name())
    }
}

/// How to read the columns before anything is fitted: the user's answer to a finding.
#[derive(Clone, Copy, Debug, PartialEq, Serialize)]
pub struct Reading {
    /// The force column's sign is reversed (`--flip-torque`).
    pub flip_torque: bool,
    /// The velocity column's unit (`--velocity-unit`); the acceleration stays in rad/s².
    pub velocity_unit: SpeedUnit,
}

impl Default for Reading {
    fn default() -> Self {
        Reading {
            flip_torque: false,
            velocity_unit: SpeedUnit::RadPerSecond,
        }
    }
}

impl Reading {
    /// True when the columns are read as they are.
    pub fn is_identity(&self) -> bool {
        *self == Reading::default()
    }

    /// Factors on (torque, velocity).
    pub fn factors(&self) -> (f64, f64) {
        (
            if self.flip_torque { -1.0 } else { 1.0 },
            self.velocity_unit.to_rad_per_second(),
        )
    }

    /// A sample in propid's units and sign.
    pub fn apply(&self, s: &mut Sample) {
        let (q, w) = self.factors();
        s.force *= q;
        s.velocity *= w;
    }

    /// The estimator of the same rows read this way: the regressors (Q, −ω, −ω|ω|) scale by
    /// (q, w, w²), so the sums scale exactly ([`LoadEstimator::scale_regressors`]).
    pub fn apply_to_estimator(&self, e: &LoadEstimator<f64>) -> LoadEstimator<f64> {
        let (q, w) = self.factors();
        let mut e = *e;
        if !self.is_identity() {
            e.scale_regressors(&[q, w, w * w]);
        }
        e
    }
}

/// Something about the data that the model's assumptions cannot survive: no verdict until it is
/// answered.
#[derive(Clone, Copy, Debug, PartialEq, Serialize)]
#[serde(tag = "check", rename_all = "snake_case")]
pub enum Implausible {
    /// The torque moves against the acceleration it should cause, or absorbs negative power.
    TorqueSign {
        /// t-statistic of the freely fitted 1/J (negative: flipped), when the fit exists.
        t_statistic: f64,
        /// Correlation of torque and speed (negative: flipped on a steady run).
        power_correlation: f64,
        /// The force column was already read with `--flip-torque`: the flag is what flips it.
        flip_torque_given: bool,
    },
    /// The velocity changes a named unit's multiple of the integrated acceleration.
    VelocityUnit {
        /// Δω / ∫a·dt.
        scale: f64,
        /// The unit that ratio names.
        unit: SpeedUnit,
    },
    /// The velocity changes about 10⁻³ (10⁻⁶) of the integrated acceleration: t in ms (µs).
    TimeUnit {
        /// Δω / ∫a·dt.
        scale: f64,
        /// The unit the time column is in.
        unit: &'static str,
    },
    /// Velocity and integrated acceleration disagree by a ratio no unit explains.
    Inconsistent {
        /// Δω / ∫a·dt.
        scale: f64,
    },
}

impl std::fmt::Display for Implausible {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match *self {
            Implausible::TorqueSign {
                t_statistic,
                power_correlation,
                flip_torque_given,
            } => write!(
                f,
                "the torque sign looks flipped: the torque works against the motion it drives \
                 (1/J fitted without bounds has t = {t_statistic:.1}, torque·speed correlation \
                 {power_correlation:.2}; both are positive when torque and speed share a sign \
                 convention): {}",
                if flip_torque_given {
                    "the force column is read with --flip-torque: drop it, its sign is right as recorded"
                } else {
                    "use --flip-torque if the force column's sign is reversed"
                }
            ),
            Implausible::VelocityUnit { scale, unit } => write!(
                f,
                "the velocity looks like it is in {unit}, not rad/s: it changes {scale:.3} times \
                 what the integrated acceleration predicts ({:.3} for {unit}): use \
                 --velocity-unit {unit}, or convert the column to rad/s",
                1.0 / unit.to_rad_per_second()
            ),
            Implausible::TimeUnit { scale, unit } => write!(
                f,
                "the time column looks like it is in {unit}, not seconds: the velocity changes \
                 {scale:.3e} times what the integrated acceleration predicts: convert t to seconds"
            ),
            Implausible::Inconsistent { scale } => write!(
                f,
                "the velocity changes {scale:.3e} times what the integrated acceleration \
                 predicts (1 when t is in s, velocity in rad/s, acceleration in rad/s²; \
                 9.549 is rpm, 0.159 rev/s, 57.3 deg/s, 0.001 time in ms): check the columns' units"
            ),
        }
    }
}

/// Δω against ∫a·dt over windows of 50 samples, fitted through the origin; `None` when the two
/// are not clearly related (|correlation| < 0.8: too little motion to judge the unit by).
pub fn velocity_scale(samples: &[Sample]) -> Option<f64> {
    const WINDOW: usize = 50;
    let (mut sxy, mut sxx, mut syy) = (0.0, 0.0, 0.0);
    for w in samples.chunks_exact(WINDOW) {
        let dw = w[WINDOW - 1].velocity - w[0].velocity;
        let ia: f64 = w
            .windows(2)
            .map(|p| 0.5 * (p[0].acceleration + p[1].acceleration) * (p[1].t - p[0].t))
            .sum();
        sxy += dw * ia;
        sxx += ia * ia;
        syy += dw * dw;
    }
    if sxx <= 0.0 || syy <= 0.0 || !(sxx.is_finite() && syy.is_finite()) {
        return None;
    }
    let r = sxy / (sxx * syy).sqrt();
    (r.abs() >= 0.8).then(|| sxy / sxx)
}

/// What a ratio Δω / ∫a·dt says about the units, `None` when it is consistent (0.5–2: a
/// filtered or noisy velocity, never a unit).
pub fn units_of(scale: f64) -> Option<Implausible> {
    let near = |target: f64| (scale / target - 1.0).abs() < 0.1;
    if (0.5..=2.0).contains(&scale) {
        return None;
    }
    for unit in [
        SpeedUnit::Rpm,
        SpeedUnit::RevPerSecond,
        SpeedUnit::DegPerSecond,
    ] {
        if near(1.0 / unit.to_rad_per_second()) {
            return Some(Implausible::VelocityUnit { scale, unit });
        }
    }
    for (target, unit) in [(1e-3, "ms"), (1e-6, "µs")] {
        if near(target) {
            return Some(Implausible::TimeUnit { scale, unit });
        }
    }
    // Between 0.2 and 5 the windows may simply be too noisy to name a unit.
    (!(0.2..=5.0).contains(&scale)).then_some(Implausible::Inconsistent { scale })
}

/// The torque-sign check on the normal equations of the fitted rows: the freely fitted 1/J, and
/// the correlation of torque with speed (−Σ Q·(−ω) over √(ΣQ²·Σω²), from the same sums);
/// `flip_torque_given`: the rows were read with `--flip-torque` (the advice then drops it).
pub fn torque_sign(equations: &LoadEstimator<f64>, flip_torque_given: bool) -> Option<Implausible> {
    let a = equations.equations().matrix();
    let power_correlation = if a[0][0] > 0.0 && a[1][1] > 0.0 {
        -a[0][1] / (a[0][0] * a[1][1]).sqrt()
    } else {
        0.0
    };
    let t_statistic = match equations.equations().solve() {
        Ok(s) if s.stderr[0] > 0.0 && s.stderr[0].is_finite() => s.theta[0] / s.stderr[0],
        _ => 0.0,
    };
    // The power a propeller absorbs decides (a lagging load cell can turn the acceleration's
    // fit negative on plateaus, never the power); the fit's sign settles a weak correlation.
    let flipped =
        power_correlation < 0.0 && (t_statistic < -SIGN_T || power_correlation < POWER_CORRELATION);
    flipped.then_some(Implausible::TorqueSign {
        t_statistic,
        power_correlation,
        flip_torque_given,
    })
}

/// Every check on the data: `samples` a contiguous stretch of the fitted rows (in time order),
/// `equations` the sums over all of them, both already read as the user asked (`reading`, which
/// the advice takes into account).
pub fn check(
    samples: &[Sample],
    equations: &LoadEstimator<f64>,
    reading: &Reading,
) -> Vec<Implausible> {
    let mut found = Vec::new();
    if let Some(units) = velocity_scale(samples).and_then(units_of) {
        found.push(units);
    }
    // A unit error makes the sign test meaningless (the columns do not belong together).
    if found.is_empty() {
        found.extend(torque_sign(equations, reading.flip_torque));
    }
    found
}

/// Why a parameter is not identified.
#[derive(Clone, Copy, Debug, PartialEq, Serialize)]
#[serde(tag = "why", rename_all = "snake_case")]
pub enum NotIdentified {
    /// It sits on one of its bounds: its standard error with the bound active is not a precision.
    AtBound {
        /// The bound.
        bound: f64,
    },
    /// Its standard error is above [`MAX_RELATIVE_STDERR`] of its value, or not finite.
    Imprecise {
        /// Standard error over |value|.
        relative_stderr: f64,
    },
    /// The torque's own noise is so large a share of its variation that least squares reads J
    /// high by more than [`MAX_RELATIVE_STDERR`] (errors in the regressor: the fitted 1/J shrinks
    /// by var(signal)/var(torque)), which no standard error shows.
    NoisyTorque {
        /// The predicted relative bias of J.
        bias: f64,
    },
}

/// A predicted bias of J worth saying (below [`MAX_RELATIVE_STDERR`], where J is still taken as
/// identified): what J is measured to.
pub const BIAS_WORTH_SAYING: f64 = 0.02;

/// The words for a bias `bias` of the parameter `name` from the torque's noise.
pub fn torque_noise_words(name: &str, bias: f64) -> String {
    format!(
        "the torque's noise is large beside its swing: least squares reads {name} about {:.0} % high \
         (errors in the regressor, which no standard error shows); a wider lo..hi would shrink it",
        100.0 * bias.min(99.99)
    )
}

/// The words for the same bias where the fit has taken it out (`propid diagnose`: the force's
/// noise σ² subtracted from its own sums, see `diagnose::engine`): the value given is corrected,
/// and the correction rests on that noise being white.
pub fn torque_noise_corrected_words(name: &str, bias: f64) -> String {
    format!(
        "the torque's noise is large beside its swing: least squares would read {name} about {:.0} % high \
         (errors in the regressor); the {name} given is corrected for it, which holds where that noise is \
         white (measured from sample-to-sample differences); a wider lo..hi would make the correction small",
        100.0 * bias.min(99.99)
    )
}

/// [`torque_noise_corrected_words`] as a warning, for a bias between [`BIAS_WORTH_SAYING`] and
/// [`MAX_RELATIVE_STDERR`] (above it the parameter is not taken as identified).
pub fn torque_noise_corrected_warning(name: &str, bias: f64) -> Option<String> {
    worth_a_warning(bias).then(|| torque_noise_corrected_words(name, bias))
}

/// Whether a predicted bias is said as a warning: above [`BIAS_WORTH_SAYING`], and not above
/// [`MAX_RELATIVE_STDERR`] (where the parameter is not taken as identified instead).
fn worth_a_warning(bias: f64) -> bool {
    bias > BIAS_WORTH_SAYING && bias <= MAX_RELATIVE_STDERR
}

/// The warning for a bias of `name` between [`BIAS_WORTH_SAYING`] and [`MAX_RELATIVE_STDERR`]
/// (above it the parameter is not identified: [`NotIdentified::NoisyTorque`]).
pub fn torque_noise_warning(name: &str, bias: f64) -> Option<String> {
    worth_a_warning(bias).then(|| torque_noise_words(name, bias))
}

/// The relative bias of J that the torque column's white noise predicts for a least-squares fit
/// of the seed's model: with σ² the noise variance (robustly from the sample-to-sample
/// differences: 1.4826·MAD/√2, so steps and a held load cell's repeats do not count as noise) and
/// V the variance of the torque left after its regression on the drag regressor ω|ω| (only that
/// part identifies 1/J), the fitted 1/J is attenuated by (V − σ²)/V, so J reads σ²/(V − σ²) high.
/// 0 when it cannot be estimated.
pub fn torque_noise_bias(force: &[f64], speed: &[f64]) -> f64 {
    let (f, drag): (Vec<f64>, Vec<f64>) = force
        .iter()
        .zip(speed)
        .filter(|(f, w)| f.is_finite() && w.is_finite())
        .map(|(&f, &w)| (f, w * w.abs()))
        .unzip();
    if f.len() < 100 {
        return 0.0;
    }
    let mut d: Vec<f64> = f.windows(2).map(|w| w[1] - w[0]).collect();
    let median = |x: &mut Vec<f64>| {
        x.sort_by(f64::total_cmp);
        x[x.len() / 2]
    };
    let m = median(&mut d);
    let mut dev: Vec<f64> = d.iter().map(|x| (x - m).abs()).collect();
    let sigma = 1.4826 * median(&mut dev) / std::f64::consts::SQRT_2;
    // The torque's variance left after the drag regressor (with a mean) takes its share.
    let n = f.len() as f64;
    let (mf, md) = (f.iter().sum::<f64>() / n, drag.iter().sum::<f64>() / n);
    let sdd: f64 = drag.iter().map(|d| (d - md) * (d - md)).sum();
    let sfd: f64 = f.iter().zip(&drag).map(|(x, d)| (x - mf) * (d - md)).sum();
    let beta = if sdd > 0.0 { sfd / sdd } else { 0.0 };
    let var = f
        .iter()
        .zip(&drag)
        .map(|(x, d)| {
            let r = (x - mf) - beta * (d - md);
            r * r
        })
        .sum::<f64>()
        / n;
    let noise = sigma * sigma;
    if !(var > 0.0 && noise.is_finite()) {
        return 0.0;
    }
    if noise >= var {
        f64::INFINITY
    } else {
        noise / (var - noise)
    }
}

/// Whether a fitted value with its standard error is identified (`at_bound` when the fit put it
/// on a bound).
pub fn identified(value: f64, stderr: f64, at_bound: Option<f64>) -> Option<NotIdentified> {
    if let Some(bound) = at_bound {
        return Some(NotIdentified::AtBound { bound });
    }
    let relative_stderr = stderr / value.abs();
    (!(relative_stderr.is_finite() && relative_stderr <= MAX_RELATIVE_STDERR && stderr > 0.0))
        .then_some(NotIdentified::Imprecise { relative_stderr })
}

impl NotIdentified {
    /// The finding in words, for a parameter named `name`.
    pub fn describe(&self, name: &str, value: f64) -> String {
        match *self {
            NotIdentified::AtBound { bound } => format!(
                "{name} is not identified: it sits on its bound ({bound:e}), where the data pushed it; \
                 its value {value:e} is the bound's, not a measurement"
            ),
            NotIdentified::Imprecise { relative_stderr } if relative_stderr.is_finite() => format!(
                "{name} is not identified: its standard error is {:.0} % of its value {value:e} \
                 (above {:.0} %)",
                100.0 * relative_stderr,
                100.0 * MAX_RELATIVE_STDERR
            ),
            NotIdentified::Imprecise { .. } => format!(
                "{name} is not identified: the data give its value {value:e} no finite standard error"
            ),
            NotIdentified::NoisyTorque { bias } => format!(
                "{name} is not identified ({value:e}): {}",
                torque_noise_words(name, bias)
            ),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn run(flip: f64, unit: SpeedUnit) -> (Vec<Sample>, LoadEstimator<f64>) {
        // J = 2e-5, c2 = 1.5e-8, a torque sine with an offset, Euler at 1 kHz.
        let (j, c2, dt) = (2e-5, 1.5e-8, 1e-3);
        let mut w = 100.0;
        let mut out = Vec::new();
        let mut est = LoadEstimator::new();
        for k in 0..20_000 {
            let t = k as f64 * dt;
            let q = 0.02 + 0.015 * (2.0 * std::f64::consts::PI * 1.3 * t).sin();
            let a = (q - c2 * w * f64::abs(w)) / j;
            let s = Sample {
                t,
                force: flip * q,
                velocity: w / unit.to_rad_per_second(),
                acceleration: a,
                position: f64::NAN,
            };
            est.update(s.force, s.velocity, s.acceleration);
            out.push(s);
            w += a * dt;
        }
        (out, est)
    }

    #[test]
    fn a_clean_run_passes_and_each_mistake_is_named() {
        let (s, e) = run(1.0, SpeedUnit::RadPerSecond);
        assert_eq!(check(&s, &e, &Reading::default()), vec![]);
        let (s, e) = run(-1.0, SpeedUnit::RadPerSecond);
        let found = check(&s, &e, &Reading::default());
        assert!(matches!(found[..], [Implausible::TorqueSign { .. }]));
        assert!(found[0].to_string().contains("use --flip-torque"));
        // A right sign read with --flip-torque: the flag is the mistake, and the words say so.
        let flipped = Reading {
            flip_torque: true,
            velocity_unit: SpeedUnit::RadPerSecond,
        };
        let (mut s, e) = run(1.0, SpeedUnit::RadPerSecond);
        s.iter_mut().for_each(|x| flipped.apply(x));
        let found = check(&s, &flipped.apply_to_estimator(&e), &flipped);
        assert!(
            matches!(
                found[..],
                [Implausible::TorqueSign {
                    flip_torque_given: true,
                    ..
                }]
            ) && found[0].to_string().contains("drop it")
                && !found[0].to_string().contains("use --flip-torque"),
            "{found:?}"
        );
        for unit in [
            SpeedUnit::Rpm,
            SpeedUnit::RevPerSecond,
            SpeedUnit::DegPerSecond,
        ] {
            let (s, e) = run(1.0, unit);
            let found = check(&s, &e, &Reading::default());
            assert!(
                matches!(found[..], [Implausible::VelocityUnit { unit: u, .. }] if u == unit),
                "{unit}: {found:?}"
            );
            // Read in the unit named, the same rows pass.
            let reading = Reading {
                flip_torque: false,
                velocity_unit: unit,
            };
            let mut fixed = s.clone();
            fixed.iter_mut().for_each(|x| reading.apply(x));
            assert_eq!(
                check(&fixed, &reading.apply_to_estimator(&e), &reading),
                vec![]
            );
        }
        let mut ms = run(1.0, SpeedUnit::RadPerSecond).0;
        ms.iter_mut().for_each(|s| s.t *= 1e3);
        assert!(matches!(
            units_of(velocity_scale(&ms).unwrap()),
            Some(Implausible::TimeUnit { unit: "ms", .. })
        ));
    }

    #[test]
    fn the_flipped_estimator_is_the_estimator_of_flipped_rows() {
        let (s, e) = run(-1.0, SpeedUnit::Rpm);
        let reading = Reading {
            flip_torque: true,
            velocity_unit: SpeedUnit::Rpm,
        };
        let mut direct = LoadEstimator::new();
        for mut x in s {
            reading.apply(&mut x);
            direct.update(x.force, x.velocity, x.acceleration);
        }
        let scaled = reading.apply_to_estimator(&e);
        let (a, b) = (direct.equations().matrix(), scaled.equations().matrix());
        for i in 0..3 {
            for k in 0..3 {
                assert!((a[i][k] / b[i][k] - 1.0).abs() < 1e-9, "{i}{k}");
            }
        }
        assert!(torque_sign(&scaled, false).is_none());
    }

    #[test]
    fn identification_never_trusts_a_bound_or_a_zero_error() {
        assert!(identified(1.0, 0.01, None).is_none());
        assert!(identified(1.0, 0.0, None).is_some());
        assert!(identified(1.0, 0.5, None).is_some());
        assert!(identified(f64::NAN, 0.1, None).is_some());
        assert!(identified(1e3, 0.0, Some(1e3)).is_some());
    }
}
