//! Rules 9 and 10 of the search: two effects named together where each masks the other, and a
//! term named first exchanged for a lag and one of its rivals (see `select::pair` and
//! `select::exchange_for_pair` for the decisions, this module for the trials).

use std::sync::atomic::Ordering;

use super::*;
use crate::diagnose::candidate::Slot;

/// The candidates a pair look-ahead combines: the best this many of a round that named nothing,
/// by held-out acceleration gain (a bound on its cost, not a rule of the decision).
const PAIR_CANDIDATES: usize = 3;

/// Pairs are tried only after a round whose best candidate lowered the held-out acceleration
/// error by at least this share: an effect that masks another still moves the fit (a cost
/// bound: data with nothing left to explain try no pairs).
const PAIR_WORTH: f64 = 0.01;

impl Search<'_> {
    /// Rule 9 after a round that named nothing (`trials`): the best pairs of its candidates;
    /// whether a pair was named.
    pub(super) fn pairs(&mut self, trials: &[Trial]) -> bool {
        if self.current.model.effects.len() + 2 > self.max_effects {
            return false;
        }
        let parent = self.current.clone();
        let worth = trials.iter().any(|t| {
            t.scored.scores.equation_pooled < (1.0 - PAIR_WORTH) * parent.scores.equation_pooled
        });
        if !worth {
            return false;
        }
        let mut best: Vec<&Trial> = Vec::new();
        let mut ranked: Vec<&Trial> = trials.iter().collect();
        ranked.sort_by(|a, b| {
            a.scored
                .scores
                .equation_pooled
                .total_cmp(&b.scored.scores.equation_pooled)
        });
        for t in ranked {
            // A twin (the same column under another name) adds no other pair.
            if best.len() < PAIR_CANDIDATES
                && !best
                    .iter()
                    .any(|b| b.scored.scores.equation == t.scored.scores.equation)
            {
                best.push(t);
            }
        }
        let mut pairs = Vec::new();
        for i in 0..best.len() {
            for j in i + 1..best.len() {
                pairs.push((best[i].effect, best[j].effect.kind));
            }
        }
        let (s, plan) = (self.s, self.plan);
        let against = parent.errors();
        let outcomes = in_parallel(&pairs, |&(a, b)| {
            try_pair(a, b, &parent, s, plan)
                .filter(|p| select::pair(&against, &p.evidence))
                .map(|p| p.scored)
        });
        let Some(pair) = outcomes.into_iter().flatten().max_by(|x, y| {
            Gain::of(&parent.errors(), &x.errors())
                .mean
                .total_cmp(&Gain::of(&parent.errors(), &y.errors()).mean)
        }) else {
            return false;
        };
        let n = pair.model.effects.len();
        self.named_pair(&parent, &pair);
        // A member's twins (the same column under another name) are ambiguous with it.
        for k in [n - 2, n - 1] {
            let member = pair.model.effects[k].kind;
            let Some(single) = trials.iter().find(|t| t.effect.kind == member) else {
                continue;
            };
            for t in trials {
                if t.effect.kind != member
                    && t.scored.scores.equation == single.scored.scores.equation
                {
                    self.found.ties.push(Tie::of(member, t.effect));
                    self.excluded.push(t.effect.kind);
                }
            }
        }
        self.found.notes.push(format!(
            "{} and {} were named together: neither gains alone, each masks the other",
            pair.model.effects[n - 2].kind,
            pair.model.effects[n - 1].kind
        ));
        self.adopt(pair);
        true
    }

    /// Rule 10, after a round that named nothing, alone or in pairs: a term named first can stand
    /// in for a lag and another term together (a constant torque takes a lag's place beside a
    /// viscous friction; a viscous term a current-sense filter's beside an offset), and a lag
    /// tried on top of it then gains nothing. Each term of the model is tried exchanged for a
    /// lag and one of the terms it outdid when it was named (its rivals), the pair named by rule
    /// 9 against the model as it is, and separated (rule 5) from the best model of its size that
    /// keeps the term (the term beside one admissible effect of the round, `trials`): the best such
    /// exchange is made. Where none is, the best pair the data cannot tell from the model as it
    /// is (`select::pair_tie`) is recorded as ambiguous with its term. Whether it named a pair.
    pub(super) fn exchange_for_pair(&mut self, trials: &[Trial]) -> bool {
        let parent = self.current.clone();
        if parent.model.effects.len() + 1 > self.max_effects || parent.model.has_lag() {
            return false;
        }
        let (s, plan) = (self.s, self.plan);
        let lags: Vec<EffectKind> = EffectKind::searched()
            .filter(|k| {
                k.candidate().slot() == Slot::Lag
                    && k.refines().is_none()
                    && !self.excluded.contains(k)
            })
            .collect();
        let against = parent.errors();
        let same_size = trials
            .iter()
            .filter(|t| t.evidence.admissible.is_ok())
            .max_by(|a, b| {
                Gain::of(&against, &a.evidence.errors)
                    .mean
                    .total_cmp(&Gain::of(&against, &b.evidence.errors).mean)
            })
            .map(|t| &t.evidence.errors);
        let gain = |p: &PairTrial| Gain::of(&against, &p.evidence.both).mean;
        let mut exchanges: Vec<TermExchange> = Vec::new();
        for i in 0..parent.model.effects.len() {
            let old = parent.model.effects[i];
            if old.candidate().slot() != Slot::Term {
                continue;
            }
            let terms: Vec<EffectKind> = self
                .rivals_of(old.kind)
                .into_iter()
                .filter(|k| k.candidate().slot() == Slot::Term && !parent.model.has(*k))
                .collect();
            if terms.is_empty() {
                continue;
            }
            let Some(rest) = Scored::of(parent.model.without(i), s, plan) else {
                continue;
            };
            let jobs: Vec<(EffectKind, EffectKind)> = terms
                .iter()
                .flat_map(|&t| lags.iter().map(move |&l| (t, l)))
                .collect();
            let outcomes = in_parallel(&jobs, |&(term, lag)| {
                let tuner = Tuner {
                    model: &rest.model,
                    s,
                    kind: term,
                    parent: &rest.cv,
                    seed: None,
                    plan,
                };
                let (a, _) = term.candidate().tune(&tuner)?;
                try_pair(a, lag, &rest, s, plan)
            });
            let tried = jobs
                .iter()
                .zip(outcomes)
                .filter_map(|(&(term, _), p)| p.map(|p| (term, p)))
                .collect();
            exchanges.push(TermExchange { at: i, rest, tried });
        }
        // The best exchange rule 10 names; else the best pair tied with the model.
        let best_where = |ok: &dyn Fn(&PairTrial) -> bool| {
            let mut best: Option<(usize, usize)> = None;
            for (e, x) in exchanges.iter().enumerate() {
                for (k, (_, p)) in x.tried.iter().enumerate() {
                    // The first best, as the terms and their pairs were tried.
                    if ok(p)
                        && best.is_none_or(|(be, bk)| gain(p) > gain(&exchanges[be].tried[bk].1))
                    {
                        best = Some((e, k));
                    }
                }
            }
            best
        };
        let Some((e, top)) =
            best_where(&|p| select::exchange_for_pair(&against, &p.evidence, same_size))
        else {
            if let Some((e, top)) = best_where(&|p| select::pair_tie(&against, &p.evidence)) {
                let TermExchange { at: i, rest, tried } = &exchanges[e];
                let pair = &tried[top].1.scored;
                let n = pair.model.effects.len();
                self.found.ties.push(Tie {
                    named: parent.model.effects[*i].kind,
                    alternative: pair.model.effects[n - 2],
                    alongside: Some(pair.model.effects[n - 1]),
                    cv_gain_percent: Some([
                        pooled_percent(&rest.scores.equation, &parent.scores.equation),
                        pooled_percent(&rest.scores.equation, &pair.scores.equation),
                    ]),
                });
            }
            return false;
        };
        let TermExchange { at: i, rest, tried } = exchanges.swap_remove(e);
        let pair = tried[top].1.scored.clone();

        // A member's twins (the same column under another name: the pair with it instead
        // scores alike) are ambiguous with it.
        for (term, p) in tried
            .iter()
            .filter(|(_, p)| select::exchange_for_pair(&against, &p.evidence, same_size))
        {
            let p = &p.scored;
            let n = p.model.effects.len();
            let twin = p.scores.equation == pair.scores.equation
                && !pair.model.has(*term)
                && p.model.effects[n - 1].kind == pair.model.effects[n - 1].kind;
            if twin {
                let named = pair.model.effects[n - 2].kind;
                self.found.ties.push(Tie::of(named, p.model.effects[n - 2]));
                self.excluded.push(*term);
            }
        }
        let old = parent.model.effects[i].kind;
        let n = pair.model.effects.len();
        self.named_pair(&parent, &pair);
        self.found.notes.push(format!(
            "{} and {} replaced {} after round {}: a term named first can stand in for a lag and another term, and together, in its place, they are the better model on held-out data",
            pair.model.effects[n - 2].kind,
            pair.model.effects[n - 1].kind,
            old,
            self.round
        ));
        self.drop_record(old, &parent, &rest);
        self.adopt(pair);
        true
    }

    /// Records that the two effects ending `pair`'s model were named together over `parent`
    /// (rule 9 or 10): each one's value from the pair's joint fit, the pair's gain as its entry
    /// gain, and no rivals.
    fn named_pair(&mut self, parent: &Scored, pair: &Scored) {
        let n = pair.model.effects.len();
        let gain = Gain::of(&parent.errors(), &pair.errors());
        let cv_gain_percent = pooled_percent(&parent.scores.equation, &pair.scores.equation);
        let simulation_gain_percent =
            pooled_percent(&parent.scores.simulation, &pair.scores.simulation);
        let fit = fit_on_all(&pair.model, self.s);
        for k in [n - 2, n - 1] {
            let effect = pair.model.effects[k].kind;
            let estimate = fit.as_ref().map_or(Estimate::new(f64::NAN, f64::NAN), |f| {
                judged(&pair.model, k, f, self.s).0
            });
            self.found.candidates.push(CandidateScore {
                effect,
                round: self.round,
                value: estimate.value,
                stderr: estimate.stderr,
                cv_gain_percent,
                simulation_gain_percent,
                gain,
                decision: Decision::Named,
            });
            self.found
                .entered_with
                .push((effect, cv_gain_percent, gain));
            self.rivals.push((effect, Vec::new()));
        }
    }
}

/// Rule 10's trials for one term of the model: the term exchanged for each lag beside each of
/// its rivals.
struct TermExchange {
    /// The term's index in the model.
    at: usize,
    /// The model without it.
    rest: Scored,
    /// Each pair tried in its place, with the rival in it.
    tried: Vec<(EffectKind, PairTrial)>,
}

/// A pair tried: its model, and what rules 9 and 10 judge it by.
struct PairTrial {
    /// The model with the pair (its two effects last), re-tuned jointly.
    scored: Scored,
    /// Its held-out errors, with and without each member, and whether both are admissible.
    evidence: select::PairEvidence,
}

/// `a` (tuned on `parent`) and `kind` tuned on the model with it, re-tuned jointly, and scored
/// with and without each.
fn try_pair(
    a: Effect,
    kind: EffectKind,
    parent: &Scored,
    s: &Signals,
    plan: &SimPlan,
) -> Option<PairTrial> {
    COUNTS[1].fetch_add(1, Ordering::Relaxed);
    let with_a = parent.model.with(a)?;
    let cv = cross_validate(&with_a, s)?;
    let tuner = Tuner {
        model: &with_a,
        s,
        kind,
        parent: &cv,
        seed: None,
        plan,
    };
    let (b, _) = kind.candidate().tune(&tuner)?;
    let both = retune(with_a.with(b)?, s, plan, None);
    let n = both.effects.len();
    let fit = fit_on_all(&both, s)?;
    let admissible = (n - 2..n).all(|k| judged(&both, k, &fit, s).1.is_ok())
        && spoiled(&both, n - 1, &fit).is_none();
    let scored = Scored::of(both, s, plan)?;
    let evidence = select::PairEvidence {
        both: scored.errors(),
        without_first: Scored::of(scored.model.without(n - 2), s, plan)?.errors(),
        without_second: Scored::of(scored.model.without(n - 1), s, plan)?.errors(),
        admissible,
    };
    Some(PairTrial { scored, evidence })
}
