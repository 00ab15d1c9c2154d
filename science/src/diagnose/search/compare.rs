//! The model asked about (`--compare`, [`crate::diagnose::EffectSet`]), fitted as the search fits
//! one: its effects added best first by the selection's criterion, each tuned on the effects
//! before it, the others' nonlinear parameters re-tuned with it (`try_effect`); a refining
//! effect (a second-order stage) tuned from the effect it refines, as in a round.

use super::{in_parallel, retune, try_effect, Scored, Trial};
use crate::diagnose::compare::EffectSet;
use crate::diagnose::model::Model;
use crate::diagnose::select::Gain;
use crate::diagnose::signals::Signals;
use crate::diagnose::simulate::SimPlan;
use crate::diagnose::EffectKind;

/// The model of the effects of `set`, scored; `None` where one cannot be fitted on these data.
pub(crate) fn fit_set(set: EffectSet, s: &Signals, plan: &SimPlan) -> Option<Scored> {
    let mut current = Scored::of(Model::default(), s, plan)?;
    let mut left: Vec<EffectKind> = set.iter().collect();
    while !left.is_empty() {
        let trials = in_parallel(&left, |&k| trial_of(k, &current, s, plan));
        let gain = |t: &Trial| Gain::of(&current.errors(), &t.evidence.errors).mean;
        let (i, best) = trials
            .into_iter()
            .enumerate()
            .filter_map(|(i, t)| t.map(|t| (i, t)))
            .max_by(|a, b| gain(&a.1).total_cmp(&gain(&b.1)))?;
        current = best.scored;
        left.remove(i);
    }
    // Then every nonlinear parameter re-tuned on the others until none moves (coordinate
    // descent, a bounded number of sweeps): the joint fit of the model asked about, which the
    // search's one sweep per trial need not reach.
    for _ in 0..SWEEPS {
        let next = retune(current.model.clone(), s, plan, None);
        if next == current.model {
            break;
        }
        current = Scored::of(next, s, plan)?;
    }
    Some(current)
}

/// Most sweeps of the joint re-tuning.
const SWEEPS: usize = 8;

/// `kind` tried on `parent`: from the effect it refines, tuned on the same model, where it
/// refines one.
fn trial_of(kind: EffectKind, parent: &Scored, s: &Signals, plan: &SimPlan) -> Option<Trial> {
    let seed = match kind.refines() {
        Some(refined) => Some(try_effect(refined, parent, None, s, plan).ok()?.effect),
        None => None,
    };
    try_effect(kind, parent, seed, s, plan).ok()
}
