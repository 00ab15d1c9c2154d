//! The search over models of several effects: stepwise, forward and backward, every nonlinear
//! parameter re-tuned jointly after each addition, every decision taken by `select`.
//!
//! ```text
//!  model M (the seed's, at first), its held-out errors
//!    round: every effect not in M (nor tied with one in it, nor dropped) tuned on M,
//!           scored on held-out data ─► Evidence ─► select::forward ─► a decision for each
//!      named e:  M ← M + e; re-tune every nonlinear parameter of M given the others;
//!                backward: drop the effect whose removal (the others re-tuned without it)
//!                costs least while select::keep says it may go; re-tune again
//!      tied with e: recorded as ambiguous with it, not tried again: the rest of the model is
//!                searched on top of the tied class
//!  stop: no effect passes, or M holds max_effects effects
//! ```

use std::sync::atomic::{AtomicUsize, Ordering};

use serde::Serialize;

use super::candidate::{EffectKind, Estimate, Fitted, Inadmissible};
use super::engine::{cross_validate, fit_on_all, Cv, Fit};
use super::model::{Effect, Model};
use super::select::{self, Decision, Evidence, FoldErrors, Gain, Rejection};
use super::signals::Signals;
use super::simulate::{fold_scores, FoldScores, SimPlan};
use super::tune::{objective_of, Tuner};
use super::{Observer, Stage};

mod compare;
mod pairs;

pub(crate) use compare::fit_set;

/// How one effect scored when it was tried.
#[derive(Clone, Debug, Serialize)]
pub struct CandidateScore {
    /// Which effect.
    #[serde(rename = "name")]
    pub effect: EffectKind,
    /// The round of the search it was tried in (from 1).
    pub round: usize,
    /// Its value, from the model with it fitted to all the data.
    pub value: f64,
    /// Its standard error.
    pub stderr: f64,
    /// Pooled held-out acceleration-equation gain over the model it was tried on [%].
    pub cv_gain_percent: f64,
    /// Pooled held-out simulated-velocity gain over that model [%].
    pub simulation_gain_percent: f64,
    /// The selection's criterion: the mean per-fold gain and its standard error.
    pub gain: Gain,
    /// What the selection decided.
    pub decision: Decision,
}

/// A model and its held-out errors.
#[derive(Clone)]
pub(crate) struct Scored {
    pub model: Model,
    pub scores: FoldScores,
    pub cv: Cv,
}

impl Scored {
    pub fn of(model: Model, s: &Signals, plan: &SimPlan) -> Option<Scored> {
        let scores = fold_scores(&model, s, plan)?;
        let cv = Cv {
            mse: scores.equation_pooled,
            folds: scores.equation,
            simulation: Some(scores.simulation),
        };
        Some(Scored { model, scores, cv })
    }

    pub fn errors(&self) -> FoldErrors {
        errors_of(&self.scores)
    }
}

fn errors_of(s: &FoldScores) -> FoldErrors {
    FoldErrors {
        equation: s.equation,
        simulation: Some(s.simulation),
    }
}

/// An effect the data cannot tell from one in the model (or a term and a lag in its place,
/// rule 10's tie).
#[derive(Clone, Debug)]
pub(crate) struct Tie {
    /// The effect in the model.
    pub named: EffectKind,
    /// The alternative, as tuned.
    pub alternative: Effect,
    /// The lag the alternative holds beside it (rule 10's tie), as tuned with it.
    pub alongside: Option<Effect>,
    /// The held-out acceleration gains of the named effect and of the alternative over the model
    /// without either [%], where they were not each a candidate's of one round (rule 10's tie).
    pub cv_gain_percent: Option<[f64; 2]>,
}

impl Tie {
    /// `alternative` in place of `named`.
    pub fn of(named: EffectKind, alternative: Effect) -> Tie {
        Tie {
            named,
            alternative,
            alongside: None,
            cv_gain_percent: None,
        }
    }
}

/// What the search found.
pub(crate) struct Found {
    /// The final model and its errors.
    pub model: Scored,
    /// Every effect tried, every round.
    pub candidates: Vec<CandidateScore>,
    /// For each effect of the model, the held-out acceleration gain when it entered [%].
    pub entered_with: Vec<(EffectKind, f64, Gain)>,
    /// Effects tied with one in the model.
    pub ties: Vec<Tie>,
    /// Notes on the search.
    pub notes: Vec<String>,
    /// Of the last round, the candidates the held-out errors would name but the rules do not
    /// (see [`Unconfirmed`]), best first.
    pub unconfirmed: Vec<Unconfirmed>,
}

/// A candidate of the round that ended the search which gains what naming asks, consistently,
/// but is not named: rule 4 rejects it (the simulated velocity improves and the acceleration
/// equation, where the effect is a term, does not), or rule 1 does for a value not resolved from
/// zero while the equation's share of the gain is consistent too. The model then does not explain
/// the data: where J or c2 move with the first kind, and always for the second, the report says
/// so (`diagnosis`).
#[derive(Clone)]
pub(crate) struct Unconfirmed {
    /// The effect as tuned, and the model with it.
    pub effect: Effect,
    pub model: Model,
    /// Its value.
    pub estimate: Estimate,
    /// Its gain over the final model, and the two pooled gains [%].
    pub gain: Gain,
    pub equation_percent: f64,
    pub simulation_percent: f64,
    /// Whether it was rejected for a value not resolved from zero (not for an equation gain too
    /// small).
    pub unresolved: bool,
}

/// One effect tried on a model: its tuned form and its evidence.
struct Trial {
    effect: Effect,
    scored: Scored,
    evidence: Evidence,
}

/// What effect `index` of `model` reads its value from in `fit` (`profile`: the standard error
/// of its nonlinear parameter, computed only if asked).
fn fitted<'a>(
    model: &Model,
    index: usize,
    fit: &'a Fit,
    profile: &'a dyn Fn() -> f64,
) -> Fitted<'a> {
    Fitted {
        theta: &fit.theta,
        stderr: &fit.stderr,
        column: model.column_of(index),
        rms: (fit.rss / fit.n.max(1.0)).sqrt(),
        profile,
    }
}

/// The value of effect `index` of `model` from `fit`, and whether it can be the effect.
pub(crate) fn judged(
    model: &Model,
    index: usize,
    fit: &Fit,
    s: &Signals,
) -> (Estimate, Result<(), Inadmissible>) {
    let e = model.effects[index];
    let profile = || profiled(model, index, fit, s);
    let fitted = fitted(model, index, fit, &profile);
    let v = e.candidate().estimate(&e, &fitted);
    (v, e.candidate().admissible(&e, v, &fitted))
}

/// The first effect of `model` other than `except` whose value in the joint fit `fit` is one its
/// mechanism cannot have (a sign, a range, not finite), whether or not it is resolved: a model is
/// physical only when every effect in it is. Cheap: no profiling (the sign does not need the
/// nonlinear parameter's standard error).
pub(crate) fn spoiled(model: &Model, except: usize, fit: &Fit) -> Option<EffectKind> {
    let no_profile = || f64::NAN;
    (0..model.effects.len())
        .filter(|&i| i != except)
        .find_map(|i| {
            let e = model.effects[i];
            let fitted = fitted(model, i, fit, &no_profile);
            let v = e.candidate().estimate(&e, &fitted);
            // Its sign and range alone: as if resolved.
            let sure = Estimate { stderr: 0.0, ..v };
            match e.candidate().admissible(&e, sure, &fitted) {
                Err(
                    Inadmissible::WrongSign
                    | Inadmissible::NotFinite
                    | Inadmissible::OutOfRange { .. },
                ) => Some(e.kind),
                _ => None,
            }
        })
}

/// The value of effect `index` of `model` from `fit`.
pub(crate) fn estimate_of(model: &Model, index: usize, fit: &Fit, s: &Signals) -> Estimate {
    judged(model, index, fit, s).0
}

/// A nonlinear parameter's standard error from the curvature of the residual sum of squares:
/// var(q) ≈ 2σ² / RSS''(q).
fn profiled(model: &Model, index: usize, fit: &Fit, s: &Signals) -> f64 {
    let q = model.effects[index].param;
    let h = (q.abs() * 0.02).max(1e-5);
    let rss = |x: f64| {
        let mut m = model.clone();
        m.effects[index].param = x;
        fit_on_all(&m, s).map_or(f64::NAN, |f| f.rss)
    };
    let (r0, rp, rm) = (fit.rss, rss(q + h), rss((q - h).max(1e-6)));
    let curvature = (rp - 2.0 * r0 + rm) / (h * h);
    let sigma2 = fit.rss / (fit.n - fit.theta.len() as f64 - 1.0).max(1.0);
    if curvature > 0.0 {
        (2.0 * sigma2 / curvature).sqrt()
    } else {
        f64::NAN
    }
}

/// `kind` tuned on `parent`, scored, with its evidence; `Err` with the reason it could not be.
fn try_effect(
    kind: EffectKind,
    parent: &Scored,
    seed: Option<Effect>,
    s: &Signals,
    plan: &SimPlan,
) -> Result<Trial, Rejection> {
    COUNTS[0].fetch_add(1, Ordering::Relaxed);
    let candidate = kind.candidate();
    let tuner = Tuner {
        model: &parent.model,
        s,
        kind,
        parent: &parent.cv,
        seed,
        plan,
    };
    let (effect, _) = candidate.tune(&tuner).ok_or(Rejection::NotFitted)?;
    let model = parent.model.with(effect).ok_or(Rejection::TooWide)?;
    let last = model.effects.len() - 1;
    let evaluate = |model: Model| -> Result<Trial, Rejection> {
        let effect = model.effects[last];
        let fit = fit_on_all(&model, s).ok_or(Rejection::NotFitted)?;
        let (estimate, mut admissible) = judged(&model, last, &fit, s);
        if let (Ok(()), Some(effect)) = (admissible, spoiled(&model, last, &fit)) {
            admissible = Err(Inadmissible::Spoils { effect });
        }
        let scored = Scored::of(model, s, plan).ok_or(Rejection::NotFitted)?;
        let evidence = Evidence {
            effect: kind,
            parameters: candidate.parameters(),
            estimate,
            admissible,
            errors: scored.errors(),
            simulation_sees: candidate.simulation_sees(),
            // A lag whose value is a regression column's coefficient (a force sensor's
            // first-order lag: the force's slope) is a term of the equation, judged like one.
            lag_in_samples: (candidate.tuned_by_simulation() && candidate.columns(&effect) == 0)
                .then(|| candidate.lag(&effect, estimate.value))
                .flatten()
                .map(|l| l.delay * s.rate),
        };
        Ok(Trial {
            effect,
            scored,
            evidence,
        })
    };
    let trial = evaluate(model.clone())?;
    // Where the trial may be named (or come close), or its value can be the effect, the model's
    // other nonlinear parameters are re-tuned with it: a lag tuned alone absorbs part of a
    // constant torque, and keeps it unless re-tuned when the torque enters; an exponent tuned
    // alone absorbs an offset, which then gains nothing until the exponent moves. (Only there:
    // it is the costliest step of a trial.)
    let contender = trial.evidence.admissible.is_ok()
        || matches!(
            select::judge(&parent.errors(), &trial.evidence),
            None | Some(Decision::NearMiss)
        );
    if !contender || last == 0 {
        return Ok(trial);
    }
    let joint = retune(model.clone(), s, plan, Some(last));
    if joint == model {
        return Ok(trial);
    }
    let retuned = evaluate(joint)?;
    let gain = |t: &Trial| Gain::of(&parent.errors(), &t.evidence.errors).mean;
    Ok(if gain(&retuned) > gain(&trial) {
        retuned
    } else {
        trial
    })
}

/// Trials, pair trials and exchange trials run (profiling counts).
pub static COUNTS: [AtomicUsize; 3] = [
    AtomicUsize::new(0),
    AtomicUsize::new(0),
    AtomicUsize::new(0),
];

/// The pooled gain of `after` over `before` [%].
fn pooled_percent(before: &[f64], after: &[f64]) -> f64 {
    100.0 * (1.0 - after.iter().sum::<f64>() / before.iter().sum::<f64>())
}

fn score_of(round: usize, parent: &Scored, t: &Trial, decision: Decision) -> CandidateScore {
    CandidateScore {
        effect: t.evidence.effect,
        round,
        value: t.evidence.estimate.value,
        stderr: t.evidence.estimate.stderr,
        cv_gain_percent: pooled_percent(&parent.scores.equation, &t.scored.scores.equation),
        simulation_gain_percent: pooled_percent(
            &parent.scores.simulation,
            &t.scored.scores.simulation,
        ),
        gain: Gain::of(&parent.errors(), &t.evidence.errors),
        decision,
    }
}

/// Re-tunes the nonlinear parameters of `m`'s effects near their values, each given the others
/// (one sweep, in order; `skip`: an effect just tuned on the others): the joint refit of every
/// nonlinear parameter of a model. A re-tuned parameter is kept where it lowers what its tuning
/// minimises (`tune`'s objective: for a lag, the simulation's error too).
fn retune(m: Model, s: &Signals, plan: &SimPlan, skip: Option<usize>) -> Model {
    let mut model = m;
    let Some(mut cv) = cross_validate(&model, s) else {
        return model;
    };
    for i in 0..model.effects.len() {
        if Some(i) == skip {
            continue;
        }
        let e = model.effects[i];
        let rest = model.without(i);
        let tuner = Tuner {
            model: &rest,
            s,
            kind: e.kind,
            parent: &cv,
            seed: None,
            plan,
        };
        let Some((next, Some(next_cv))) = e.candidate().retune(&e, &tuner) else {
            continue;
        };
        if next_cv.objective() < objective_of(&tuner.cv(e)) {
            let mut m = rest;
            m.effects.insert(i, next);
            model = m;
            cv = next_cv;
        }
    }
    model
}

/// Rivals of a named effect tried in its place (rule 8): those that passed rules 1–4 in the
/// round it was named with at least this share of its gain (a bound on the cost).
const RIVAL_SHARE: f64 = 0.5;

/// The search's state.
struct Search<'a> {
    s: &'a Signals,
    plan: &'a SimPlan,
    progress: Observer<'a>,
    current: Scored,
    found: Found,
    /// Effects not to try again: tied with one in the model, or dropped.
    excluded: Vec<EffectKind>,
    /// For each effect in the model, the rivals it passed in the round it was named.
    rivals: Vec<(EffectKind, Vec<EffectKind>)>,
    round: usize,
    max_effects: usize,
}

impl Search<'_> {
    /// The effects that may be tried on `model`.
    fn open(&self, model: &Model) -> Vec<EffectKind> {
        EffectKind::searched()
            .filter(|&k| {
                !self.excluded.contains(&k)
                    && !model.has(k)
                    && (k.candidate().slot() != super::candidate::Slot::Lag || !model.has_lag())
            })
            .collect()
    }

    /// `kinds` tried on `parent`, in parallel; those that could not be tried recorded in the
    /// first round. An effect that refines another is tried after it, and only where it passes
    /// rules 1–4: in the same job, so that the chain starts first and runs beside the other
    /// candidates rather than alone after them.
    fn trials(&mut self, kinds: &[EffectKind], parent: &Scored) -> Vec<Trial> {
        let (s, plan, progress, round) = (self.s, self.plan, self.progress, self.round);
        let done = AtomicUsize::new(0);
        let of = kinds.len();
        progress(Stage::Candidates { round, done: 0, of });
        let tick = |n: usize| {
            let d = done.fetch_add(n, Ordering::Relaxed) + n;
            progress(Stage::Candidates { round, done: d, of });
        };
        let (first, refining): (Vec<EffectKind>, Vec<EffectKind>) =
            kinds.iter().partition(|k| k.refines().is_none());
        // Each first-tried kind with the kinds that refine it; chains first.
        let mut jobs: Vec<(EffectKind, Vec<EffectKind>)> = first
            .iter()
            .map(|&k| {
                let refiners = refining
                    .iter()
                    .copied()
                    .filter(|r| r.refines() == Some(k))
                    .collect();
                (k, refiners)
            })
            .collect();
        jobs.sort_by_key(|(_, refiners)| std::cmp::Reverse(refiners.len()));
        let chained: Vec<Vec<(EffectKind, Result<Trial, Rejection>)>> =
            in_parallel(&jobs, |(k, refiners)| {
                let r = try_effect(*k, parent, None, s, plan);
                tick(1);
                let passed = match &r {
                    Ok(t) => matches!(
                        select::judge(&parent.errors(), &t.evidence),
                        None | Some(Decision::NearMiss)
                    )
                    .then_some(t.effect),
                    Err(_) => None,
                };
                let mut out = vec![(*k, r)];
                for &refiner in refiners {
                    if let Some(seed) = passed {
                        out.push((refiner, try_effect(refiner, parent, Some(seed), s, plan)));
                    }
                    // Refiners not tried count as done.
                    tick(1);
                }
                out
            });
        // Kinds that refine one not asked for are not tried; they count as done.
        let orphans = refining
            .iter()
            .filter(|r| !jobs.iter().any(|(_, rs)| rs.contains(r)))
            .count();
        if orphans > 0 {
            tick(orphans);
        }
        // In the order asked for, the refiners after the rest (the same report whatever the
        // order of work).
        let mut outcomes: Vec<(EffectKind, Result<Trial, Rejection>)> =
            chained.into_iter().flatten().collect();
        outcomes.sort_by_key(|(k, _)| (k.refines().is_some(), kinds.iter().position(|x| x == k)));
        let mut trials = Vec::new();
        for (k, outcome) in outcomes {
            match outcome {
                Ok(t) => trials.push(t),
                // Tried and could not be: said once, in the first round.
                Err(reason) if round == 1 => self.found.candidates.push(CandidateScore {
                    effect: k,
                    round,
                    value: f64::NAN,
                    stderr: f64::NAN,
                    cv_gain_percent: f64::NAN,
                    simulation_gain_percent: f64::NAN,
                    gain: Gain::NONE,
                    decision: Decision::Rejected { reason },
                }),
                Err(_) => {}
            }
        }
        // In the order of the kinds asked for (the same report whatever the order of work).
        trials.sort_by_key(|t| kinds.iter().position(|k| *k == t.effect.kind));
        trials
    }

    /// Makes `next` (a model derived from the current one) current, re-tuned jointly.
    fn adopt(&mut self, next: Scored) {
        let joint = retune(next.model.clone(), self.s, self.plan, None);
        self.current = if joint == next.model {
            next
        } else {
            // Kept where it does not lose by the selection's criterion: a parameter tuned by
            // the equation alone (a force sensor's delay) can move where the equation gains a
            // sliver and the simulated velocity loses much (a load cell's 15 Hz stage, named as
            // a delay, went from about 14 to 17.9 ms, the model's held-out gain fell by 1.2,
            // and an offset later took its place).
            match Scored::of(joint, self.s, self.plan) {
                Some(j) if Gain::of(&next.errors(), &j.errors()).mean >= 0.0 => j,
                _ => next,
            }
        };
    }

    /// Records that `t` entered the model, with what it gained over `parent`.
    fn entered(&mut self, parent: &Scored, t: &Trial, rivals: Vec<EffectKind>) {
        self.found.entered_with.push((
            t.effect.kind,
            pooled_percent(&parent.scores.equation, &t.scored.scores.equation),
            Gain::of(&parent.errors(), &t.evidence.errors),
        ));
        self.rivals.push((t.effect.kind, rivals));
    }

    /// A forward round (rules 1–6); whether it named an effect.
    fn forward(&mut self) -> Option<Vec<Trial>> {
        let parent = self.current.clone();
        let kinds = self.open(&parent.model);
        let trials = self.trials(&kinds, &parent);
        let evidence: Vec<Evidence> = trials.iter().map(|t| t.evidence.clone()).collect();
        let step = select::forward(&parent.errors(), &evidence);
        for (t, d) in trials.iter().zip(&step.decisions) {
            self.found
                .candidates
                .push(score_of(self.round, &parent, t, *d));
        }
        let Some(named) = step.named else {
            return Some(trials);
        };
        for (t, d) in trials.iter().zip(&step.decisions) {
            if let Decision::Ambiguous { with } = d {
                self.found.ties.push(Tie::of(*with, t.effect));
                self.excluded.push(t.effect.kind);
            }
        }
        let winner = Gain::of(&parent.errors(), &trials[named].evidence.errors).mean;
        let rivals = trials
            .iter()
            .zip(&step.decisions)
            .filter(|(t, d)| {
                matches!(
                    d,
                    Decision::Rejected {
                        reason: Rejection::Outdone { .. }
                    }
                ) && Gain::of(&parent.errors(), &t.evidence.errors).mean >= RIVAL_SHARE * winner
            })
            .map(|(t, _)| t.effect.kind)
            .collect();
        let chosen = trials.into_iter().nth(named)?;
        self.entered(&parent, &chosen, rivals);
        self.adopt(chosen.scored);
        None
    }

    /// Records the candidates of the round that ended the search (`trials`, tried on the model
    /// as it is) that only rule 4 kept from being named.
    fn unconfirmed(&mut self, trials: &[Trial]) {
        let parent = self.current.errors();
        let mut found: Vec<Unconfirmed> = trials
            .iter()
            .filter_map(|t| match select::judge(&parent, &t.evidence) {
                Some(Decision::Rejected {
                    reason: Rejection::EquationSilent,
                }) => Some((t, false)),
                // A consistent gain the equation shares, for a value the data do not resolve: a
                // term that stands in for something the model lacks (on the independent stand at
                // a quarter of its noise, a 1.4 ± 1.0 ms force-sensor lag beside an offset and an
                // exponent the sensor's 10 ms filter had bent: J 3 % low, said to be explained).
                Some(Decision::Rejected {
                    reason:
                        Rejection::Inadmissible {
                            why: Inadmissible::NotResolved { .. },
                        },
                }) if Gain::of(&parent, &t.evidence.errors).significant()
                    && Gain::parts(&parent, &t.evidence.errors).0.significant() =>
                {
                    Some((t, true))
                }
                _ => None,
            })
            .map(|(t, unresolved)| Unconfirmed {
                effect: t.effect,
                model: t.scored.model.clone(),
                estimate: t.evidence.estimate,
                gain: Gain::of(&parent, &t.evidence.errors),
                equation_percent: pooled_percent(
                    &self.current.scores.equation,
                    &t.scored.scores.equation,
                ),
                simulation_percent: pooled_percent(
                    &self.current.scores.simulation,
                    &t.scored.scores.simulation,
                ),
                unresolved,
            })
            // It gains what naming asks.
            .filter(|u| u.gain.mean >= select::MIN_GAIN)
            .collect();
        found.sort_by(|a, b| b.gain.mean.total_cmp(&a.gain.mean));
        self.found.unconfirmed = found;
    }

    /// The rivals effect `kind` passed in the round it was named (none if it has no record).
    fn rivals_of(&self, kind: EffectKind) -> Vec<EffectKind> {
        self.rivals
            .iter()
            .find(|(k, _)| *k == kind)
            .map(|(_, r)| r.clone())
            .unwrap_or_default()
    }

    /// Rule 8 for every effect but the newest: its rivals, and the effects tied with it, in its
    /// place.
    fn exchange(&mut self) {
        let newest = self.current.model.effects.len().saturating_sub(1);
        for i in 0..newest {
            let parent = self.current.clone();
            let old = parent.model.effects[i];
            let without = parent.model.without(i);
            // Its rivals (tied with another effect or not), and the effects tied with it, which
            // no later round tries: an exchange is where a tie of the rounds before is settled,
            // as the model around it grows.
            let mut candidates = self.rivals_of(old.kind);
            for t in &self.found.ties {
                if t.named == old.kind && !candidates.contains(&t.alternative.kind) {
                    candidates.push(t.alternative.kind);
                }
            }
            let rivals: Vec<EffectKind> = candidates
                .into_iter()
                .filter(|k| {
                    !without.has(*k)
                        && (k.candidate().slot() != super::candidate::Slot::Lag
                            || !without.has_lag())
                })
                .collect();
            if rivals.is_empty() {
                continue;
            }
            // Scored only where there is something to try in its place.
            let Some(rest) = Scored::of(without, self.s, self.plan) else {
                continue;
            };
            COUNTS[2].fetch_add(rivals.len(), Ordering::Relaxed);
            let trials = self.trials(&rivals, &rest);
            let parameters = old.candidate().parameters();
            let mut replace: Option<Trial> = None;
            for t in trials {
                match select::exchange(&parent.errors(), parameters, &t.evidence) {
                    select::Exchange::Replace => {
                        let better = replace.as_ref().is_none_or(|r| {
                            Gain::of(&parent.errors(), &t.evidence.errors).mean
                                > Gain::of(&parent.errors(), &r.evidence.errors).mean
                        });
                        if better {
                            replace = Some(t);
                        }
                    }
                    select::Exchange::Tie => {
                        self.found.candidates.push(score_of(
                            self.round,
                            &parent,
                            &t,
                            Decision::Ambiguous { with: old.kind },
                        ));
                        if !self
                            .found
                            .ties
                            .iter()
                            .any(|x| x.named == old.kind && x.alternative.kind == t.effect.kind)
                        {
                            self.found.ties.push(Tie::of(old.kind, t.effect));
                        }
                        self.excluded.push(t.effect.kind);
                    }
                    select::Exchange::Keep => {}
                }
            }
            if let Some(t) = replace {
                self.found.notes.push(format!(
                    "{} replaced {} after round {}: with the effects named since, the model with it instead is better on held-out data",
                    t.effect.kind, old.kind, self.round
                ));
                self.found
                    .candidates
                    .push(score_of(self.round, &parent, &t, Decision::Named));
                self.drop_record(old.kind, &parent, &rest);
                self.entered(&rest, &t, Vec::new());
                self.adopt(t.scored);
            }
        }
    }

    /// Records that `gone` left the model `with` (leaving `without`).
    fn drop_record(&mut self, gone: EffectKind, with: &Scored, without: &Scored) {
        self.found.candidates.push(CandidateScore {
            effect: gone,
            round: self.round,
            value: f64::NAN,
            stderr: f64::NAN,
            cv_gain_percent: pooled_percent(&without.scores.equation, &with.scores.equation),
            simulation_gain_percent: pooled_percent(
                &without.scores.simulation,
                &with.scores.simulation,
            ),
            gain: Gain::of(&without.errors(), &with.errors()),
            decision: Decision::Dropped,
        });
        self.found.entered_with.retain(|(k, _, _)| *k != gone);
        self.found.ties.retain(|t| t.named != gone);
        self.rivals.retain(|(k, _)| *k != gone);
        self.excluded.push(gone);
    }

    /// Rule 7: drops what the model no longer needs, the cheapest loss first.
    fn backward(&mut self) {
        while self.current.model.effects.len() > 1 {
            let current = self.current.clone();
            // Each effect's removal is scored on the model without it with the others' nonlinear
            // parameters re-tuned: the smaller model as a joint fit would have it. Without the
            // re-tuning, an effect that a parameter tuned beside it came to need stays: on the
            // independent stand's noise-free 10 ms torque lag beside viscous friction, the search
            // ended on a 6.3 ms lag, a viscous term 35 % low and an offset the truth does not
            // have, because the lag tuned beside the offset lost without it; re-tuned, it is the
            // truth's 10.0 ms and the offset goes.
            let removal: Vec<(usize, Scored)> = (0..current.model.effects.len())
                .filter_map(|i| {
                    let without = retune(current.model.without(i), self.s, self.plan, None);
                    Scored::of(without, self.s, self.plan).map(|w| (i, w))
                })
                .filter(|(_, w)| !select::keep(&w.errors(), &current.errors()))
                .collect();
            let Some((i, without)) = removal.into_iter().min_by(|a, b| {
                let ga = Gain::of(&a.1.errors(), &current.errors()).mean;
                let gb = Gain::of(&b.1.errors(), &current.errors()).mean;
                ga.total_cmp(&gb)
            }) else {
                break;
            };
            let gone = current.model.effects[i].kind;
            self.found.notes.push(format!(
                "{gone} was dropped after round {}: with the effects named since, the model without it is not significantly worse",
                self.round
            ));
            self.drop_record(gone, &current, &without);
            self.adopt(without);
        }
    }
}

/// The stepwise search (see the module documentation).
pub(crate) fn search(
    s: &Signals,
    plan: &SimPlan,
    max_effects: usize,
    progress: Observer<'_>,
) -> Option<Found> {
    let current = Scored::of(Model::default(), s, plan)?;
    let mut search = Search {
        s,
        plan,
        progress,
        found: Found {
            model: current.clone(),
            candidates: Vec::new(),
            entered_with: Vec::new(),
            ties: Vec::new(),
            notes: Vec::new(),
            unconfirmed: Vec::new(),
        },
        current,
        excluded: Vec::new(),
        rivals: Vec::new(),
        round: 0,
        max_effects,
    };
    let signal_power = s.acceleration[s.first..].iter().map(|a| a * a).sum::<f64>()
        / (s.len() - s.first).max(1) as f64;
    // Each round names an effect (or a pair) or ends the search; an effect dropped or tied is
    // not tried again, so rounds are bounded by twice the effects there are.
    for round in 1..=2 * EffectKind::ALL.len() {
        search.round = round;
        if search.current.model.effects.len() >= max_effects {
            break;
        }
        // A model that already fits to rounding error leaves nothing to explain.
        if search.current.cv.mse < 1e-18 * signal_power {
            break;
        }
        if let Some(trials) = search.forward() {
            if !search.pairs(&trials) && !search.exchange_for_pair(&trials) {
                search.unconfirmed(&trials);
                break;
            }
        }
        search.exchange();
        search.backward();
    }
    search.found.model = search.current;
    Some(search.found)
}

/// `f` over `items` on up to as many threads as the machine has cores, results in item order.
pub(crate) fn in_parallel<T: Sync, R: Send>(items: &[T], f: impl Fn(&T) -> R + Sync) -> Vec<R> {
    let threads = std::thread::available_parallelism()
        .map_or(1, |n| n.get())
        .min(items.len())
        .max(1);
    if threads == 1 {
        return items.iter().map(f).collect();
    }
    let next = AtomicUsize::new(0);
    let mut done: Vec<(usize, R)> = std::thread::scope(|scope| {
        let workers: Vec<_> = (0..threads)
            .map(|_| {
                scope.spawn(|| {
                    let mut mine = Vec::new();
                    loop {
                        let i = next.fetch_add(1, Ordering::Relaxed);
                        let Some(item) = items.get(i) else { break };
                        mine.push((i, f(item)));
                    }
                    mine
                })
            })
            .collect();
        workers
            .into_iter()
            .flat_map(|w| match w.join() {
                Ok(v) => v,
                Err(panic) => std::panic::resume_unwind(panic),
            })
            .collect()
    });
    done.sort_by_key(|(i, _)| *i);
    done.into_iter().map(|(_, r)| r).collect()
}
