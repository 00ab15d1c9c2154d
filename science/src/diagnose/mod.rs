//! Diagnosis: what the fitted model gets wrong, why, and how much better an extended
//! model does.
//!
//! ## How data flows
//! ```text
//!  samples ─► Signals (F, ω, a, θ and the derivatives Ḟ, ȧ over a ±10 ms window)
//!    1. base fit: the seed's model J·a = F − c2·ω|ω| (c1 = 0), by NormalEquations
//!       ─► open-loop simulation from the measured F, compared with the measured ω   ("what is wrong")
//!    2. residual analysis: correlation with ω, sgn ω, Ḟ, a, t, θ; periodogram
//!    3. candidate effects, each an extension of the regression (see `effects`), scored by blocked
//!       5-fold cross-validation of the acceleration equation: fit on four blocks, judge on the fifth
//!       ─► forward selection while the held-out gain clears a threshold in (almost) every fold
//!    4. refit the extended model on the first 70 %, simulate the last 30 % open-loop
//!       ─► simulated-velocity RMS before/after (the gain), leftover periodic structure ("unexplained")
//! ```
//! Selection is by held-out evidence only: an effect is named when adding it lowers the error on
//! data the fit did not see, by at least [`MIN_GAIN`] on average and in at least four of the five
//! folds, when its parameter is physical, and when the model with it does not simulate the
//! held-out velocity worse (by more than [`MAX_SIM_LOSS`]). On clean simulated data no candidate passes (the tests
//! check several seeds).

mod effects;
mod gate;
mod report;
mod signals;
mod steady;

pub use steady::DragLaw;

use serde::Serialize;

pub use effects::{Effect, EffectKind, LagForm};
pub use gate::CannotJudge;

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
pub use report::{figure as report_figure, to_text};
use signals::Signals;

use propid_io::tsv::{Row, Sample};
use propid_io::InputError;

/// Smallest relative reduction of the held-out acceleration error for an effect to be named.
pub const MIN_GAIN: f64 = 0.03;
/// Held-out gain from which a candidate below [`MIN_GAIN`], better in every fold and with a
/// held-out simulation that agrees, is reported as a [`NearMiss`] [fraction]. On 80 mechanism-stand
/// runs with nothing to find, no candidate gained more than 0.08 %.
pub const NEAR_MISS_GAIN: f64 = 0.005;
/// Largest relative increase of the held-out simulated-velocity error an effect may cause (an
/// effect that fits the acceleration equation better by smoothing noise, but simulates worse, is
/// not named; a fast torque ripple barely moves the velocity, so no gain is demanded).
pub const MAX_SIM_LOSS: f64 = 0.01;
/// Folds of the blocked cross-validation.
pub const FOLDS: usize = 5;
/// Folds (of [`FOLDS`]) in which the extension must do better.
pub const MIN_FOLDS_BETTER: usize = 4;
/// Share of the data (at the end) held out for the simulated-velocity comparison.
pub const HOLDOUT: f64 = 0.3;
/// Share of the held-out error a condition or time window must hold to be reported [–].
pub const CONCENTRATED: f64 = 0.4;

/// Share of near-steady samples above which the steady-state drag law is also reported.
pub const STEADY_SHARE: f64 = 0.7;

/// Options of a diagnosis.
#[derive(Clone, Copy, Debug)]
pub struct Options {
    /// Largest number of effects to name.
    pub max_effects: usize,
}

impl Default for Options {
    fn default() -> Self {
        Options { max_effects: 3 }
    }
}

/// The base model's parameters.
#[derive(Clone, Debug, Serialize)]
pub struct BaseModel {
    /// Inertia J [kg·m²].
    pub mass: f64,
    /// Viscous coefficient (0: the seed's default bound).
    pub c1: f64,
    /// Drag coefficient of the quadratic law c2·ω|ω| [N·m·s²/rad²], always: for a drag law
    /// k·|ω|^p (`drag_exponent` named) it is the c2 whose quadratic torque equals k·|ω|^p at the
    /// data's RMS speed, and `k` and `p` hold the law itself.
    pub c2: f64,
    /// Standard error of J.
    pub mass_stderr: f64,
    /// Standard error of c2.
    pub c2_stderr: f64,
    /// k of a drag law k·|ω|^p [N·m·(s/rad)^p] (absent for the quadratic law).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub k: Option<f64>,
    /// p of a drag law k·|ω|^p (absent for the quadratic law).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub p: Option<f64>,
}

impl BaseModel {
    /// A drag law k·|ω|^p as its quadratic-equivalent c2 at the RMS speed `w_rms`.
    pub(crate) fn power_law(mut self, k: f64, k_stderr: f64, p: f64, w_rms: f64) -> BaseModel {
        let scale = w_rms.powf(p - 2.0);
        self.c2 = k * scale;
        self.c2_stderr = k_stderr * scale;
        self.k = Some(k);
        self.p = Some(p);
        self
    }
}

/// A named effect with its estimated parameter.
#[derive(Clone, Debug, Serialize)]
pub struct NamedEffect {
    /// Which effect (code matches on this; `name` is for people).
    #[serde(skip)]
    pub kind: EffectKind,
    /// Effect name (`torque_lag`, …).
    pub name: &'static str,
    /// Its parameter.
    pub value: f64,
    /// Unit of the parameter.
    pub unit: &'static str,
    /// Standard error of the parameter.
    pub stderr: f64,
    /// Held-out simulated-velocity gain of the base model plus this effect alone [%].
    pub gain_percent: f64,
    /// Held-out acceleration-equation gain when it was selected [%].
    pub cv_gain_percent: f64,
    /// For a lag, how it acts: `first_order` (a filter) or `delay` (a held or late sample).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub lag_form: Option<&'static str>,
    /// A sentence on what it means.
    pub explanation: String,
}

/// How a candidate scored.
#[derive(Clone, Debug, Serialize)]
pub struct CandidateScore {
    /// Which effect.
    #[serde(skip)]
    pub kind: EffectKind,
    /// Effect name.
    pub name: &'static str,
    /// Held-out acceleration-equation gain over the model it was tried on [%].
    pub cv_gain_percent: f64,
    /// Folds (of 5) in which it did better.
    pub folds_better: usize,
    /// Its fitted parameter.
    pub value: f64,
    /// Held-out simulated-velocity gain over the model it was tried on [%] (NaN when it failed
    /// an earlier test).
    pub simulation_gain_percent: f64,
    /// Whether it was named.
    pub selected: bool,
    /// Why not, when it was not.
    pub note: String,
}

/// Simulated-velocity error on the held-out data.
#[derive(Clone, Debug, Serialize)]
pub struct SimulationRms {
    /// Base model [rad/s].
    pub base: f64,
    /// Extended model [rad/s].
    pub extended: f64,
    /// 100·(1 − extended/base).
    pub gain_percent: f64,
}

/// Structure left in the residual that no candidate explains.
#[derive(Clone, Debug, Serialize)]
pub struct Unexplained {
    /// What it looks like.
    pub description: String,
    /// Dominant frequency [Hz].
    pub frequency_hz: f64,
}

/// Where the remaining held-out error concentrates, when it does.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct Concentration {
    /// The operating condition or time window: `decelerating`, `low_speed` (lowest third of the
    /// held-out speeds), `high_speed` (highest third) or `time_window`.
    pub condition: &'static str,
    /// Share of the held-out squared acceleration error in it [%].
    pub error_percent: f64,
    /// Share of the held-out samples in it [%].
    pub samples_percent: f64,
    /// Start and end of the time window [s] (for a condition: the held-out part).
    pub from_s: f64,
    /// End [s].
    pub to_s: f64,
}

/// A candidate with consistent held-out evidence below [`MIN_GAIN`]: not named, not a verdict,
/// and where to look. Listed only when the last round of the selection named nothing.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct NearMiss {
    /// Its name.
    pub name: &'static str,
    /// Its estimate.
    pub value: f64,
    /// Unit of the estimate.
    pub unit: &'static str,
    /// Held-out acceleration gain [%], at least [`NEAR_MISS_GAIN`] and below [`MIN_GAIN`].
    pub cv_gain_percent: f64,
    /// Held-out simulated-velocity gain [%] (positive: the simulation agrees).
    pub simulation_gain_percent: f64,
    /// The `propid drive` run that would show it more clearly, and why, in words.
    pub look_with: String,
    /// The same run as data.
    pub revealing_run: SeparatingRun,
}

/// Two candidates these data cannot tell apart.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct Ambiguity {
    /// Their names.
    pub between: [&'static str; 2],
    /// Their estimates.
    pub values: [f64; 2],
    /// Units of the estimates.
    pub units: [&'static str; 2],
    /// Held-out acceleration gains [%].
    pub cv_gain_percent: [f64; 2],
    /// The `propid drive` run that would separate them, and why, in words.
    pub separate_with: String,
    /// The same run as data (for a program that acts on the advice).
    pub separating_run: SeparatingRun,
}

/// A `propid drive` run that tells two ambiguous candidates apart.
#[derive(Clone, Copy, Debug, PartialEq, Serialize)]
pub struct SeparatingRun {
    /// `--pattern`: `chirp` or `steps`.
    pub pattern: &'static str,
    /// `--lo`, when the run needs its own (a negative one reverses the rotor).
    pub lo: Option<f64>,
    /// `--hi`, when the run needs its own.
    pub hi: Option<f64>,
    /// What the run shows that these data do not.
    pub why: &'static str,
}

impl SeparatingRun {
    /// The advice in words: the `propid drive` command, and what it shows.
    pub fn advice(&self) -> String {
        format!("`propid drive {}`: {}", self.flags(), self.why)
    }

    /// The `propid drive` flags.
    pub fn flags(&self) -> String {
        let mut s = format!("--pattern {}", self.pattern);
        if let Some(lo) = self.lo {
            s += &format!(" --lo {lo}");
        }
        if let Some(hi) = self.hi {
            s += &format!(" --hi {hi}");
        }
        s
    }
}

/// Correlations of the base model's acceleration residual with candidate explanatory signals.
#[derive(Clone, Debug, Serialize)]
pub struct ResidualAnalysis {
    /// (signal name, correlation coefficient).
    pub correlations: Vec<(&'static str, f64)>,
    /// Frequency of the largest periodogram peak of the residual [Hz].
    pub dominant_frequency_hz: f64,
    /// That peak's power over the median power.
    pub peak_to_median: f64,
}

/// What the diagnosis concludes. Code that acts on a diagnosis matches on this, never on the
/// wording of a note.
#[derive(Clone, Debug, PartialEq, Serialize)]
#[serde(tag = "kind", rename_all = "snake_case")]
pub enum Verdict {
    /// No candidate improves the held-out fit and no structure is left: the seed's model
    /// explains these data.
    NothingWrong,
    /// Effects were named and no structure is left.
    Explained,
    /// Structure is left that no candidate explains (with or without named effects).
    Unexplained,
    /// Two candidates explain the held-out data about equally well; neither is named (see
    /// [`Report::ambiguity`]).
    Ambiguous,
    /// The data cannot support a verdict; nothing else in the report is a conclusion.
    CannotJudge {
        /// Why.
        reasons: Vec<CannotJudge>,
    },
}

/// The diagnosis.
#[derive(Clone, Debug, Serialize)]
pub struct Report {
    /// The verdict.
    pub verdict: Verdict,
    /// Samples analysed.
    pub samples: usize,
    /// Duration [s].
    pub duration_s: f64,
    /// Median sample rate [Hz].
    pub rate_hz: f64,
    /// The seed's model fitted to all the data.
    pub base: BaseModel,
    /// The named effects.
    pub effects: Vec<NamedEffect>,
    /// The extended model (base plus the named effects) fitted to all the data.
    pub extended: BaseModel,
    /// Simulated-velocity RMS before and after, on held-out data.
    pub simulation_rms: SimulationRms,
    /// Leftover structure, if any.
    pub unexplained: Option<Unexplained>,
    /// The residual analysis of the base model.
    pub residual_analysis: ResidualAnalysis,
    /// Every candidate tried, in the last round of selection and the rounds before.
    pub candidates: Vec<CandidateScore>,
    /// The drag law from steady-state data, when the recording cannot identify the inertia
    /// (then `base.mass` is null and the simulation fields are null).
    pub steady_state: Option<DragLaw>,
    /// Where the remaining held-out error of the extended model concentrates (in an operating
    /// condition or a time window holding at least twice its share of the samples and
    /// [`CONCENTRATED`] of the error), if it does.
    pub concentration: Option<Concentration>,
    /// When the verdict is ambiguous: between which two, with both estimates.
    pub ambiguity: Option<Ambiguity>,
    /// Candidates that came close to being named (see [`NearMiss`]), best first.
    pub near_misses: Vec<NearMiss>,
    /// Share of the samples near steady state (|a|/2 < 1 % of |ω|): above
    /// [`STEADY_SHARE`] the data speak mostly about the drag law.
    pub steady_share: f64,
    /// Notes about the data (steady-state data, missing columns, …).
    pub notes: Vec<String>,
    /// Series for plots (not serialised).
    #[serde(skip)]
    pub traces: Traces,
}

/// Time series for the plots.
#[derive(Clone, Debug, Default)]
pub struct Traces {
    /// Time of the held-out part [s].
    pub t: Vec<f64>,
    /// Measured velocity.
    pub measured: Vec<f64>,
    /// Base model, simulated open-loop.
    pub base: Vec<f64>,
    /// Extended model, simulated open-loop.
    pub extended: Vec<f64>,
    /// Time of all samples.
    pub t_all: Vec<f64>,
    /// Acceleration residual of the base model.
    pub residual_base: Vec<f64>,
    /// Acceleration residual of the extended model.
    pub residual_extended: Vec<f64>,
}

/// Smallest device-clock rate error named as `time_base` (a crystal's 50 ppm is invisible in J
/// and c2; an RC oscillator's 0.3–2 % is not).
pub const MIN_TIME_BASE: f64 = 1e-3;

/// Largest device-clock rate error taken for a clock (an RC oscillator is off by 2 % at most);
/// beyond it the time columns disagree on units.
pub const MAX_TIME_BASE: f64 = 0.05;

/// The device clock's rate against the host's: the slope of `t` on `ts_local`, minus 1, and its
/// standard error. `None` without host times on (nearly) every row.
fn time_base(rows: &[Row]) -> Option<(f64, f64)> {
    let both: Vec<(f64, f64)> = rows
        .iter()
        .filter(|r| r.ts_local.is_finite() && r.sample.t.is_finite())
        .map(|r| (r.ts_local, r.sample.t))
        .collect();
    if both.len() < 100 || both.len() * 10 < rows.len() * 9 {
        return None;
    }
    let n = both.len() as f64;
    let (mx, my) = both
        .iter()
        .fold((0.0, 0.0), |(a, b), (x, y)| (a + x / n, b + y / n));
    let (mut sxx, mut sxy) = (0.0, 0.0);
    for (x, y) in &both {
        sxx += (x - mx) * (x - mx);
        sxy += (x - mx) * (y - my);
    }
    if sxx <= 0.0 {
        return None;
    }
    let slope = sxy / sxx;
    let rss: f64 = both
        .iter()
        .map(|(x, y)| (y - my - slope * (x - mx)).powi(2))
        .sum();
    let se = (rss / (n - 2.0).max(1.0) / sxx).sqrt();
    Some((slope - 1.0, se))
}

/// Diagnoses a recording with host receive times (`ts_local`): as [`diagnose`], and first the
/// device clock against the host's. A clock off by ε (an RC oscillator) reports velocity and
/// acceleration per device second, so J and c2 come out (1 + ε)² too large; when ε is at least
/// [`MIN_TIME_BASE`] and ten standard errors, it is named `time_base` and the samples are
/// converted to host seconds before the diagnosis.
pub fn diagnose_rows(rows: Vec<Row>, options: Options) -> Result<Report, InputError> {
    diagnose_rows_observed(rows, options, &|_| {})
}

/// [`diagnose_rows`], telling `progress` where it is.
pub fn diagnose_rows_observed(
    rows: Vec<Row>,
    options: Options,
    progress: Observer<'_>,
) -> Result<Report, InputError> {
    // Beyond MAX_TIME_BASE it is not a clock but a unit (t in ms against ts_local in s): left
    // to the gate.
    let clock = time_base(&rows).filter(|(e, se)| {
        e.abs() >= MIN_TIME_BASE && e.abs() <= MAX_TIME_BASE && e.abs() > 10.0 * se
    });
    let no_host_time = rows.iter().all(|r| r.ts_local.is_nan());
    let r = 1.0 + clock.map_or(0.0, |(eps, _)| eps);
    // Consumes the rows (the allocation is reused where the layout allows): an hour-long log is
    // held once, not as rows, samples and complete samples side by side.
    let samples: Vec<Sample> = rows
        .into_iter()
        .map(|row| {
            let mut s = row.sample;
            if clock.is_some() {
                s.t /= r;
                s.velocity *= r;
                s.acceleration *= r * r;
            }
            s
        })
        .filter(Sample::is_finite)
        .collect();
    let mut report = diagnose_complete(samples, options, progress)?;
    match clock {
        Some((eps, se)) if !matches!(report.verdict, Verdict::CannotJudge { .. }) => {
            report.effects.insert(
                0,
                NamedEffect {
                    kind: EffectKind::TimeBase,
                    name: EffectKind::TimeBase.name(),
                    value: eps,
                    unit: EffectKind::TimeBase.unit(),
                    stderr: se,
                    gain_percent: f64::NAN,
                    cv_gain_percent: f64::NAN,
                    lag_form: None,
                    explanation: effects::explanation(Effect::new(EffectKind::TimeBase, eps), eps),
                },
            );
            if report.verdict == Verdict::NothingWrong {
                report.verdict = Verdict::Explained;
            }
        }
        Some(_) => {}
        None if no_host_time => report
            .notes
            .push("no host time column (ts_local): time_base cannot be tested".into()),
        None => {}
    }
    Ok(report)
}

/// Diagnoses a recording.
///
/// Rows may lack the force (a slow load cell): dynamics are diagnosed on the rows that have it;
/// when those cannot identify the inertia (steady plateaus), the drag law is diagnosed instead.
pub fn diagnose(samples: &[Sample], options: Options) -> Result<Report, InputError> {
    diagnose_complete(
        samples.iter().copied().filter(Sample::is_finite).collect(),
        options,
        &|_| {},
    )
}

/// [`diagnose`] on complete samples, which it consumes: they are dropped once the signals are
/// built (the working set of a long log is the signals' seven columns, not three copies of it).
fn diagnose_complete(
    complete: Vec<Sample>,
    options: Options,
    progress: Observer<'_>,
) -> Result<Report, InputError> {
    progress(Stage::Base);
    let columns = effects::widest(options.max_effects);
    let why = gate::check(&complete, columns);
    let extent = Extent::of(&complete);
    if !why.is_empty() {
        return Ok(Report::cannot_judge(extent, why));
    }
    let signals = Signals::new(complete)?;
    let report = match effects::run(&signals, options, progress) {
        Ok(mut r) => {
            r.steady_state = steady::drag_law(&signals).filter(|_| r.steady_share > STEADY_SHARE);
            r
        }
        Err(dynamics) => match steady::drag_law(&signals) {
            Some(law) => steady_report(&signals, law, dynamics),
            None => {
                let condition_number = gate::condition_number(&signals.force, &signals.velocity);
                let mut r = Report::cannot_judge(
                    extent,
                    vec![CannotJudge::NoExcitation { condition_number }],
                );
                r.notes.push(dynamics.to_string());
                r
            }
        },
    };
    let mut report = report.checked(extent);
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

impl Report {
    /// A report that concludes nothing, for data the gate rejects.
    fn cannot_judge(extent: Extent, reasons: Vec<CannotJudge>) -> Report {
        let nan = BaseModel {
            mass: f64::NAN,
            c1: f64::NAN,
            c2: f64::NAN,
            mass_stderr: f64::NAN,
            c2_stderr: f64::NAN,
            k: None,
            p: None,
        };
        Report {
            verdict: Verdict::CannotJudge { reasons },
            samples: extent.samples,
            duration_s: extent.duration_s,
            rate_hz: f64::NAN,
            base: nan.clone(),
            effects: Vec::new(),
            extended: nan,
            simulation_rms: SimulationRms {
                base: f64::NAN,
                extended: f64::NAN,
                gain_percent: f64::NAN,
            },
            unexplained: None,
            residual_analysis: ResidualAnalysis {
                correlations: Vec::new(),
                dominant_frequency_hz: f64::NAN,
                peak_to_median: f64::NAN,
            },
            candidates: Vec::new(),
            steady_state: None,
            steady_share: f64::NAN,
            ambiguity: None,
            near_misses: Vec::new(),
            concentration: None,
            notes: Vec::new(),
            traces: Traces::default(),
        }
    }

    /// The gate after the fit: a verdict stands only on finite parameters and errors.
    fn checked(self, extent: Extent) -> Report {
        if matches!(self.verdict, Verdict::CannotJudge { .. }) {
            return self;
        }
        let dynamic = self.steady_state.is_none() || self.base.mass.is_finite();
        let mut fitted: Vec<(&'static str, f64)> = vec![("c2", self.base.c2)];
        if dynamic {
            fitted.extend([
                ("inertia J", self.base.mass),
                ("extended inertia J", self.extended.mass),
                ("extended c2", self.extended.c2),
                ("simulated-velocity error", self.simulation_rms.base),
                (
                    "extended simulated-velocity error",
                    self.simulation_rms.extended,
                ),
            ]);
        }
        fitted.extend(self.effects.iter().map(|e| (e.name, e.value)));
        match fitted.iter().find(|(_, v)| !v.is_finite()) {
            Some((what, _)) => {
                let mut r = Report::cannot_judge(extent, vec![CannotJudge::NonFinite { what }]);
                r.notes = self.notes;
                r
            }
            None => self,
        }
    }
}

/// Root mean square of `x`.
pub(crate) fn rms(x: &[f64]) -> f64 {
    (x.iter().map(|v| v * v).sum::<f64>() / x.len().max(1) as f64).sqrt()
}

fn steady_report(s: &Signals, law: DragLaw, why: InputError) -> Report {
    let mut effects = Vec::new();
    if law.selected {
        effects.push(NamedEffect {
            kind: EffectKind::DragExponent,
            name: EffectKind::DragExponent.name(),
            value: law.exponent,
            unit: "1",
            stderr: law.exponent_stderr,
            gain_percent: 100.0 * (1.0 - law.rms_extended / law.rms_seed),
            cv_gain_percent: law.cv_gain_percent,
            lag_form: None,
            explanation: format!(
                "the steady-state torque grows as |ω|^{:.3}, not ω²: the torque coefficient depends on speed",
                law.exponent
            ),
        });
    }
    let n = s.len();
    Report {
        verdict: if law.selected {
            Verdict::Explained
        } else {
            Verdict::NothingWrong
        },
        samples: n,
        duration_s: s.t[n - 1] - s.t[0],
        rate_hz: s.rate,
        base: BaseModel { mass: f64::NAN, c1: 0.0, c2: law.c2, mass_stderr: f64::NAN, c2_stderr: f64::NAN, k: None, p: None },
        effects,
        extended: BaseModel { mass: f64::NAN, c1: 0.0, c2: f64::NAN, mass_stderr: f64::NAN, c2_stderr: f64::NAN, k: None, p: None }
            .power_law(law.k, f64::NAN, law.exponent, rms(&s.velocity)),
        simulation_rms: SimulationRms {
            base: law.rms_seed,
            extended: law.rms_extended,
            gain_percent: 100.0 * (1.0 - law.rms_extended / law.rms_seed),
        },
        unexplained: None,
        residual_analysis: ResidualAnalysis { correlations: Vec::new(), dominant_frequency_hz: f64::NAN, peak_to_median: f64::NAN },
        candidates: Vec::new(),
        notes: vec![format!(
            "steady-state data: the dynamics cannot be fitted ({}); the drag law is diagnosed from {} torque samples instead, \
             and simulation_rms holds the torque residual [N·m] of the seed's law (F = c2·ω² + F₀) and of F = k·|ω|^p + F₀",
            why, law.samples
        )],
        steady_state: Some(law),
        steady_share: 1.0,
        ambiguity: None,
        near_misses: Vec::new(),
        concentration: None,
        traces: Traces::default(),
    }
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
