//! Diagnosis: what the fitted model gets wrong, why, and how much better an extended
//! model does.
//!
//! ## How data flows
//! ```text
//!  rows ─► effects measured from the rows (the device clock: `time_base`), corrected
//!  samples ─► gate (can these data support a verdict?) ─► Signals (F, ω, a, θ, Ḟ, ȧ)
//!    1. base fit: the seed's model J·a = F − c2·ω|ω| (c1 = 0), by NormalEquations
//!       ─► open-loop simulation from the measured F over the last 30 %     ("what is wrong")
//!    2. residual analysis: correlation with ω, sgn ω, Ḟ, a, t, θ; periodogram
//!    3. search (`search`): models of several effects (`candidate/`, one file each), stepwise
//!       forward and backward, each model scored fold by fold on held-out data by its
//!       acceleration-equation error and its simulated-velocity error; every decision taken by
//!       `select` from typed evidence (named, rejected with a reason, ambiguous, near miss)
//!    4. the extended model: its effects with values and units, ambiguities with what does not
//!       depend on the choice, near misses, structure left (periodic, or where in the record),
//!       parameters these data do not identify
//! ```
//! The criterion, the rules and the thresholds are in `select`'s documentation and in
//! docs/SCIENCE.md.

mod candidate;
mod compare;
mod diagnosis;
mod engine;
mod gate;
mod model;
mod report;
mod search;
mod select;
mod signals;
mod simulate;
mod steady;
mod structure;
mod text;
mod tune;

pub(crate) use candidate::Design;
pub use candidate::{EffectKind, Estimate, Inadmissible, RESOLVED};
pub use compare::{Compared, EffectSet, NotAdmissible, Preference};
#[doc(hidden)]
pub use engine::ROWS;
pub use gate::CannotJudge;
pub use model::LagShape;
pub use report::{
    Agreed, Ambiguity, BaseModel, DragLaw, EffectValue, NamedEffect, NearMiss, Parameter, Report,
    ResidualAnalysis, SeparatingRun, SimulationOnly, SimulationRms, Traces, Unexplained,
    Unidentified, Verdict, MAX_RELATIVE_STDERR,
};
pub use search::CandidateScore;
#[doc(hidden)]
pub use search::COUNTS;
pub use select::{
    Decision, Evidence, FoldErrors, Gain, Rejection, KEEP_GAIN, MIN_GAIN, NEAR_MISS_GAIN,
    SIGNIFICANT,
};
#[doc(hidden)]
pub use simulate::SIMULATED;
pub use structure::{Concentration, Condition, LeftOut, CONCENTRATION_RATIO, EVENT_SHARE};
pub use text::{figure as report_figure, left_out_sentence, simulation_only_sentence, to_text};

/// Where a diagnosis is, for a progress display (the library never prints): on a log of an hour
/// at 500 Hz the selection takes seconds per round.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Stage {
    /// The signals, the base fit and its residual analysis.
    Base,
    /// Round `round` (from 1) of the forward selection: `done` of `of` candidates tried.
    Candidates {
        /// Round, from 1.
        round: usize,
        /// Candidates tried so far in this round.
        done: usize,
        /// Candidates in this round.
        of: usize,
    },
    /// The extended model's fit, held-out simulation and residual analysis.
    Extended,
}

/// A progress callback; it may be called from several threads.
pub type Observer<'a> = &'a (dyn Fn(Stage) + Sync);
use signals::Signals;

use crate::plausibility::Reading;
use propid_io::tsv::{Row, Sample};
use propid_io::InputError;

/// Folds of the blocked cross-validation every model is scored by.
pub const FOLDS: usize = 10;
/// Share of the data (at the end) held out for the headline simulated-velocity comparison.
pub const HOLDOUT: f64 = 0.3;
/// Share of near-steady samples above which the steady-state drag law is also reported.
pub const STEADY_SHARE: f64 = 0.7;

/// Options of a diagnosis.
#[derive(Clone, Copy, Debug)]
pub struct Options {
    /// Largest number of effects to name (at least 1: a diagnosis that tries none cannot say
    /// the seed's model explains anything; the seed's model alone is `fit`).
    pub max_effects: usize,
    /// How the columns are read (a reversed torque sign, a velocity in rpm).
    pub reading: Reading,
    /// A model to fit and score beside the one named (`--compare`); empty: none.
    pub compare: EffectSet,
}

impl Default for Options {
    fn default() -> Self {
        Options {
            max_effects: 3,
            reading: Reading::default(),
            compare: EffectSet::EMPTY,
        }
    }
}

impl Options {
    /// Checks the options once, before any data is read.
    pub fn check(&self) -> Result<(), InputError> {
        if self.max_effects == 0 {
            return Err(InputError::invalid(
                "max_effects is 0: a diagnosis that tries no effect cannot tell whether the seed's model \
                 explains the data; give at least 1 (the seed's model alone is `propid fit`)"
                    .into(),
            ));
        }
        Ok(())
    }
}

/// Diagnoses a recording with host receive times (`ts_local`): as [`diagnose`], and first the
/// effects measured from the rows (a device clock against the host's, `time_base`): where one
/// is named, the samples are corrected before the diagnosis.
pub fn diagnose_rows(rows: Vec<Row>, options: Options) -> Result<Report, InputError> {
    diagnose_rows_observed(rows, options, &|_| {})
}

/// An effect measured from the rows, and what the selection decided about it.
struct Measured {
    kind: EffectKind,
    estimate: Estimate,
    decision: Decision,
}

/// [`diagnose_rows`], telling `progress` where it is.
pub fn diagnose_rows_observed(
    rows: Vec<Row>,
    options: Options,
    progress: Observer<'_>,
) -> Result<Report, InputError> {
    options.check()?;
    let mut measured = Vec::new();
    let mut untestable = Vec::new();
    for &kind in EffectKind::ALL {
        let candidate::Enters::Rows(effect) = kind.candidate().enters() else {
            continue;
        };
        match effect.measure(&rows) {
            Some(estimate) => {
                let decision = match candidate::admissible_measured(kind, estimate) {
                    Ok(()) => Decision::Named,
                    Err(why) => Decision::Rejected {
                        reason: Rejection::Inadmissible { why },
                    },
                };
                measured.push(Measured {
                    kind,
                    estimate,
                    decision,
                });
            }
            None => untestable.push(kind),
        }
    }
    let named: Vec<&Measured> = measured
        .iter()
        .filter(|m| m.decision == Decision::Named)
        .collect();
    // Consumes the rows (the allocation is reused where the layout allows): an hour-long log is
    // held once, not as rows, samples and complete samples side by side.
    let samples: Vec<Sample> = rows
        .into_iter()
        .map(|row| {
            let mut s = row.sample;
            options.reading.apply(&mut s);
            for m in &named {
                if let candidate::Enters::Rows(effect) = m.kind.candidate().enters() {
                    effect.correct(m.estimate.value, &mut s);
                }
            }
            s
        })
        .filter(Sample::is_finite)
        .collect();
    let mut report = diagnose_complete(samples, options, progress)?;
    if matches!(report.verdict, Verdict::CannotJudge { .. }) {
        return Ok(report);
    }
    for (k, m) in measured.iter().enumerate() {
        report.candidates.insert(
            k,
            CandidateScore {
                effect: m.kind,
                round: 0,
                value: m.estimate.value,
                stderr: m.estimate.stderr,
                cv_gain_percent: f64::NAN,
                simulation_gain_percent: f64::NAN,
                gain: Gain::NONE,
                decision: m.decision,
            },
        );
        if m.decision == Decision::Named {
            let e = model::Effect::new(m.kind, m.estimate.value);
            report.effects.insert(
                0,
                NamedEffect {
                    effect: m.kind,
                    value: m.estimate.value,
                    unit: m.kind.unit(),
                    stderr: m.estimate.stderr,
                    gain_percent: f64::NAN,
                    cv_gain_percent: f64::NAN,
                    gain: Gain::NONE,
                    lag_form: None,
                    lag_delay_s: None,
                    explanation: m.kind.candidate().explanation(&e, m.estimate.value),
                },
            );
        }
    }
    for kind in untestable {
        report.notes.push(format!(
            "no host time column (ts_local) on every row: {kind} cannot be tested"
        ));
    }
    report.conclude();
    Ok(report)
}

/// Diagnoses a recording.
///
/// Rows may lack the force (a slow load cell): dynamics are diagnosed on the rows that have it;
/// when those cannot identify the inertia (steady plateaus), the drag law is diagnosed instead.
pub fn diagnose(samples: &[Sample], options: Options) -> Result<Report, InputError> {
    options.check()?;
    diagnose_complete(
        samples
            .iter()
            .copied()
            .filter(Sample::is_finite)
            .map(|mut s| {
                options.reading.apply(&mut s);
                s
            })
            .collect(),
        options,
        &|_| {},
    )
}

/// The widest model a diagnosis naming up to `max_effects` effects can try (in columns).
fn widest(max_effects: usize) -> usize {
    (2 + 2 * max_effects).min(model::MAX_COLUMNS)
}

/// [`diagnose`] on complete samples, which it consumes: they are dropped once the signals are
/// built (the working set of a long log is the signals' columns, not three copies of it).
fn diagnose_complete(
    complete: Vec<Sample>,
    options: Options,
    progress: Observer<'_>,
) -> Result<Report, InputError> {
    progress(Stage::Base);
    let why = gate::check(&complete, widest(options.max_effects), &options.reading);
    let extent = Extent::of(&complete);
    if !why.is_empty() {
        return Ok(Report::cannot_judge(extent.samples, extent.duration_s, why));
    }
    let mut signals = Signals::new(complete)?;
    let mut first = diagnosis::run(&signals, options, progress);
    // An event in time the model does not hold (a load transient): diagnosed again without its
    // samples, so that neither the search nor the fit reads them.
    if let Some(rows) = first
        .as_ref()
        .ok()
        .and_then(|r| r.left_out.as_ref())
        .map(|l| l.rows.clone())
    {
        signals.excluded = rows;
        first = diagnosis::run(&signals, options, progress);
    }
    let report = match first {
        Ok(mut r) => {
            r.steady_state = steady::drag_law(&signals).filter(|_| r.steady_share > STEADY_SHARE);
            r
        }
        Err(dynamics) => match steady::drag_law(&signals) {
            Some(law) => steady::report(&signals, law, dynamics),
            None => {
                let condition_number = gate::condition_number(&signals.force, &signals.velocity);
                let mut r = Report::cannot_judge(
                    extent.samples,
                    extent.duration_s,
                    vec![CannotJudge::NoExcitation { condition_number }],
                );
                r.notes.push(dynamics.to_string());
                r
            }
        },
    };
    let mut report = checked(report, extent);
    if !matches!(report.verdict, Verdict::CannotJudge { .. }) {
        report.notes.push(
            "torque_scale cannot be tested: these data have no independent torque reference (a load cell \
             beside the drive's estimate, or a known inertia); a torque-scale error r gives J/r and c2/r and \
             leaves no other trace"
                .into(),
        );
    }
    Ok(report)
}

/// How many samples a recording has and the time they span (what a report says of data it could
/// not judge).
#[derive(Clone, Copy, Debug)]
struct Extent {
    samples: usize,
    duration_s: f64,
}

impl Extent {
    fn of(samples: &[Sample]) -> Extent {
        let n = samples.len();
        Extent {
            samples: n,
            duration_s: if n > 1 {
                samples[n - 1].t - samples[0].t
            } else {
                0.0
            },
        }
    }
}

/// The gate after the fit: a verdict stands only on finite parameters and errors.
fn checked(r: Report, extent: Extent) -> Report {
    if matches!(r.verdict, Verdict::CannotJudge { .. }) {
        return r;
    }
    let dynamic = r.steady_state.is_none() || r.base.inertia.is_finite();
    let mut fitted: Vec<(&'static str, f64)> = vec![("c2", r.base.c2)];
    if dynamic {
        fitted.extend([
            ("inertia J", r.base.inertia),
            ("extended inertia J", r.extended.inertia),
            ("extended c2", r.extended.c2),
            ("simulated-velocity error", r.simulation_rms.base),
            (
                "extended simulated-velocity error",
                r.simulation_rms.extended,
            ),
        ]);
    }
    fitted.extend(r.effects.iter().map(|e| (e.effect.name(), e.value)));
    match fitted.iter().find(|(_, v)| !v.is_finite()) {
        Some((what, _)) => {
            let mut out = Report::cannot_judge(
                extent.samples,
                extent.duration_s,
                vec![CannotJudge::NonFinite { what }],
            );
            out.notes = r.notes;
            out
        }
        None => r,
    }
}

/// Root mean square of `x`.
pub(crate) fn rms(x: &[f64]) -> f64 {
    (x.iter().map(|v| v * v).sum::<f64>() / x.len().max(1) as f64).sqrt()
}

/// Reads every complete row of a TSV with its host time (see [`read_samples`]).
pub fn read_rows(path: &std::path::Path) -> Result<(Vec<Row>, usize), InputError> {
    let table = propid_io::tsv::read_rows(path, |row| row.sample.is_finite())?;
    Ok((table.rows, table.skipped))
}

/// Reads every complete row of a TSV (rows with a non-finite t, force, velocity or acceleration
/// are skipped and counted).
pub fn read_samples(path: &std::path::Path) -> Result<(Vec<Sample>, usize), InputError> {
    let (rows, skipped) = read_rows(path)?;
    Ok((rows.into_iter().map(|r| r.sample).collect(), skipped))
}
