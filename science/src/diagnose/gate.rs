//! The gate before any verdict: can these data support one at all?
//!
//! A diagnosis that says "nothing is wrong" next to J = NaN is worse than none. Every check here
//! is about the data, not about a model: a value no stand produces (1e300), a force that is zero
//! throughout, a sample rate or time unit no stand uses (time in milliseconds reads as a 0.2 Hz
//! stand whose velocity changes a thousand times slower than its acceleration says), too few
//! samples for the effects tested, the plausibility gate shared with `fit` (a flipped torque
//! sign, a velocity in rpm: [`crate::plausibility`]), regressors that do not vary independently (condition number),
//! and, after the fit, parameters that are not finite. Each failure is a [`CannotJudge`] reason;
//! the report's verdict is then [`super::Verdict::CannotJudge`] and nothing else is concluded.

use propid_core::estimate::LoadEstimator;
use propid_io::tsv::Sample;

use crate::plausibility::{self, Implausible};
use serde::Serialize;

/// Why the data cannot support a verdict.
#[derive(Clone, Debug, PartialEq, Serialize)]
#[serde(tag = "reason", rename_all = "snake_case")]
pub enum CannotJudge {
    /// Fewer complete samples than the effects tested need.
    TooFewSamples {
        /// Complete samples.
        samples: usize,
        /// Samples needed.
        needed: usize,
    },
    /// The median sample rate is outside what a stand produces.
    ImplausibleRate {
        /// Median sample rate [Hz].
        rate_hz: f64,
    },
    /// The columns are not what the model assumes: a flipped torque sign, a velocity or a time
    /// in another unit ([`crate::plausibility`]).
    Implausible {
        /// What the plausibility gate found.
        #[serde(flatten)]
        finding: Implausible,
    },
    /// A value no propeller stand produces.
    AbsurdValue {
        /// The column.
        column: &'static str,
        /// Index of the sample among the complete samples (from 1).
        sample: usize,
        /// The value.
        value: f64,
    },
    /// The force is zero in every sample.
    ZeroForce,
    /// The regressors of the seed's model do not vary independently.
    NoExcitation {
        /// Condition number of the column-scaled normal matrix of [F, ω|ω|] (infinite when a
        /// column is constant zero or the fit is singular).
        condition_number: f64,
    },
    /// A fitted quantity is not finite.
    NonFinite {
        /// Which.
        what: &'static str,
    },
}

impl std::fmt::Display for CannotJudge {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            CannotJudge::TooFewSamples { samples, needed } => write!(
                f,
                "{samples} complete samples; the effects tested need at least {needed}"
            ),
            CannotJudge::ImplausibleRate { rate_hz } => write!(
                f,
                "the median sample rate is {rate_hz:.3} Hz, outside {MIN_RATE}–{MAX_RATE} Hz: is the time column in seconds?"
            ),
            CannotJudge::Implausible { finding } => write!(f, "{finding}"),
            CannotJudge::AbsurdValue {
                column,
                sample,
                value,
            } => write!(
                f,
                "sample {sample} has {column} = {value:e}, beyond anything a propeller stand produces"
            ),
            CannotJudge::ZeroForce => {
                write!(f, "the force is zero in every sample: nothing drives the load")
            }
            CannotJudge::NoExcitation { condition_number } => write!(
                f,
                "the force and the drag term do not vary independently (condition number {condition_number:.2e}): \
                 the data cannot separate inertia from drag"
            ),
            CannotJudge::NonFinite { what } => write!(f, "the fitted {what} is not finite"),
        }
    }
}

/// Lowest plausible median sample rate [Hz] (a slow load cell logs at a few Hz).
pub const MIN_RATE: f64 = 2.0;
/// Highest plausible median sample rate [Hz].
pub const MAX_RATE: f64 = 100_000.0;
/// Plausibility bounds on the magnitude of each column: a 1 km·N·m torque, 10⁵ rad/s (≈ 10⁶ rpm),
/// 10⁸ rad/s², and 10¹⁰ s (a Unix time in seconds passes, one in milliseconds does not).
const BOUNDS: [(&str, f64); 4] = [
    ("t", 1e10),
    ("force", 1e3),
    ("velocity", 1e5),
    ("acceleration", 1e8),
];
/// Samples per fold and regression column that a held-out score needs.
const SAMPLES_PER_COLUMN_AND_FOLD: usize = 5;

/// Samples the effects tested need: every fold of the cross-validation holds five samples per
/// column of the widest model (ten folds: the fifty samples per column five folds of ten held).
pub fn samples_needed(columns: usize) -> usize {
    super::FOLDS * SAMPLES_PER_COLUMN_AND_FOLD * columns
}

/// Checks the complete samples (in time order) before any model is fitted.
pub fn check(
    samples: &[Sample],
    columns: usize,
    reading: &plausibility::Reading,
) -> Vec<CannotJudge> {
    let mut why = Vec::new();
    let needed = samples_needed(columns);
    if samples.len() < needed {
        why.push(CannotJudge::TooFewSamples {
            samples: samples.len(),
            needed,
        });
        return why;
    }
    // A named unit first: a velocity in deg/s passes 10⁵ "rad/s", which is a unit, not an
    // absurd value.
    let units = plausibility::velocity_scale(samples).and_then(plausibility::units_of);
    if let Some(finding @ (Implausible::VelocityUnit { .. } | Implausible::TimeUnit { .. })) = units
    {
        why.push(CannotJudge::Implausible { finding });
        return why;
    }
    for (k, s) in samples.iter().enumerate() {
        let values = [s.t, s.force, s.velocity, s.acceleration];
        if let Some((column, value)) = BOUNDS
            .iter()
            .zip(values)
            .find(|((_, bound), v)| v.abs() > *bound)
            .map(|((c, _), v)| (*c, v))
        {
            why.push(CannotJudge::AbsurdValue {
                column,
                sample: k + 1,
                value,
            });
            return why;
        }
    }
    if samples.iter().all(|s| s.force == 0.0) {
        why.push(CannotJudge::ZeroForce);
    }
    let mut dts: Vec<f64> = samples
        .windows(2)
        .map(|w| w[1].t - w[0].t)
        .filter(|d| *d > 0.0)
        .collect();
    if !dts.is_empty() {
        dts.sort_by(f64::total_cmp);
        let rate = 1.0 / dts[dts.len() / 2];
        if !(MIN_RATE..=MAX_RATE).contains(&rate) {
            why.push(CannotJudge::ImplausibleRate { rate_hz: rate });
        }
    }
    if why.is_empty() {
        let mut equations = LoadEstimator::new();
        for s in samples {
            equations.update(s.force, s.velocity, s.acceleration);
        }
        why.extend(
            plausibility::check(samples, &equations, reading)
                .into_iter()
                .map(|finding| CannotJudge::Implausible { finding }),
        );
    }
    why
}

/// Condition number of the column-scaled 2×2 normal matrix of the seed's regressors [F, ω|ω|].
pub fn condition_number(force: &[f64], velocity: &[f64]) -> f64 {
    let (mut a, mut b, mut c) = (0.0, 0.0, 0.0);
    for (f, w) in force.iter().zip(velocity) {
        let d = w * w.abs();
        a += f * f;
        b += f * d;
        c += d * d;
    }
    if a <= 0.0 || c <= 0.0 || !(a.is_finite() && c.is_finite()) {
        return f64::INFINITY;
    }
    // Unit diagonal: [[1, ρ], [ρ, 1]], eigenvalues 1 ± |ρ|.
    let rho = (b / (a * c).sqrt()).abs().min(1.0);
    if rho >= 1.0 {
        f64::INFINITY
    } else {
        (1.0 + rho) / (1.0 - rho)
    }
}
