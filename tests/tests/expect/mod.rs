//! What a right diagnosis of a hidden effect looks like, shared by the hidden-effect tests: the
//! effects it names (or reports as ambiguous with one it names), their values, and the extended
//! model's J and drag law — checked whether or not the report is ambiguous.

#![allow(dead_code)]

use propid_science::diagnose::{EffectKind, Report, Verdict};

/// One effect a report must give, with its truth and relative tolerance.
#[derive(Clone, Copy, Debug)]
pub struct Expected {
    pub kind: EffectKind,
    pub value: f64,
    pub tolerance: f64,
}

/// Which ambiguities a report may give.
#[derive(Clone, Copy, Debug)]
pub enum Ties<'a> {
    /// Only these pairs (either order).
    Only(&'a [(EffectKind, EffectKind)]),
    /// Any pair with a named effect: the pattern cannot separate some effects (the seed's sine).
    Any,
}

impl Ties<'_> {
    fn allows(&self, a: EffectKind, b: EffectKind) -> bool {
        match self {
            Ties::Any => true,
            Ties::Only(pairs) => pairs
                .iter()
                .any(|&(x, y)| (x, y) == (a, b) || (x, y) == (b, a)),
        }
    }
}

/// A rotor that never reverses cannot tell a Coulomb friction from a force offset: the same
/// constant torque.
pub const CONSTANT_TWINS: (EffectKind, EffectKind) =
    (EffectKind::CoulombFriction, EffectKind::ForceOffset);

pub fn say(line: String) {
    // Straight to the stderr handle, so the table shows even when libtest captures output.
    std::io::Write::write_all(&mut std::io::stderr(), (line + "\n").as_bytes()).unwrap();
}

pub fn describe(r: &Report) -> String {
    let effects: Vec<String> = r
        .effects
        .iter()
        .map(|e| match e.lag_form {
            Some(form) => format!("{}={:.4e} ({})", e.effect, e.value, form.name()),
            None => format!("{}={:.4e}", e.effect, e.value),
        })
        .collect();
    let ties: Vec<String> = r
        .ambiguities
        .iter()
        .map(|a| {
            format!(
                "{}|{}={:.4e}{}",
                a.between[0],
                a.between[1],
                a.values[1],
                a.alongside
                    .as_ref()
                    .map_or(String::new(), |l| format!("+{}={:.4e}", l.effect, l.value))
            )
        })
        .collect();
    let near: Vec<String> = r
        .near_misses
        .iter()
        .map(|m| format!("{}={:.4e}", m.effect, m.value))
        .collect();
    format!(
        "{:?} [{}] ties [{}] near [{}] J {:.4e} c2 {:.4e}{} sim {:.2} → {:.2}{}{}{}",
        r.verdict,
        effects.join(", "),
        ties.join(", "),
        near.join(", "),
        r.extended.inertia,
        r.extended.c2,
        r.extended.p.map_or(String::new(), |p| format!(" p {p:.4}")),
        r.simulation_rms.base,
        r.simulation_rms.extended,
        r.concentration.as_ref().map_or(String::new(), |c| format!(
            " concentrated {:?} {:.1}–{:.1} s ×{:.1}",
            c.condition, c.from_s, c.to_s, c.ratio
        )),
        r.left_out.as_ref().map_or(String::new(), |l| format!(
            " left out {:.1}–{:.1} s (J with it {:+.1} %)",
            l.from_s,
            l.to_s,
            100.0 * (l.inertia_with / r.extended.inertia - 1.0)
        )),
        r.simulation_only
            .as_ref()
            .map_or(String::new(), |o| format!(
                " simulation only {}={:.4e} (sim {:+.1} %, equation {:+.2} %)",
                o.effect, o.value, o.simulation_gain_percent, o.equation_gain_percent
            ))
    )
}

/// The truth of a stand: its J and its speed-dependent torque c1·ω + k·|ω|^p, compared at `speed`
/// (inside the data: k alone is the torque at 1 rad/s, far below them). The viscous term counts
/// on both sides: over a narrow band of speeds c1·ω + c2·ω² and k·ω^p are one curve, and a model
/// that names one for the other has the torque right even where it has the wrong name.
#[derive(Clone, Copy, Debug)]
pub struct Truth {
    pub inertia: f64,
    pub c1: f64,
    pub k: f64,
    pub p: f64,
    pub speed: f64,
}

impl Truth {
    /// The speed-dependent torque at `self.speed` of a law c1·ω + k·ω^p.
    fn drag(&self, c1: f64, k: f64, p: f64) -> f64 {
        c1 * self.speed + k * self.speed.powf(p)
    }
}

/// One model a report gives: the extended one, or one where an ambiguous effect stands in place
/// of the one named.
#[derive(Clone)]
struct Reading {
    effects: Vec<(EffectKind, f64)>,
    inertia: f64,
    c1: f64,
    k: f64,
    p: f64,
}

/// A model's drag law as k·ω^p (the seed's c2·ω² where no exponent was fitted).
fn law(b: &propid_science::diagnose::BaseModel) -> (f64, f64) {
    match (b.k, b.p) {
        (Some(k), Some(p)) => (k, p),
        _ => (b.c2, 2.0),
    }
}

/// J's and the drag's relative errors against the truth of the model named, then of each tie's
/// alternative, in the report's order.
pub fn model_errors(r: &Report, t: Truth) -> Vec<(f64, f64)> {
    std::iter::once(&r.extended)
        .chain(r.ambiguities.iter().map(|a| &a.alternative))
        .map(|b| {
            let (k, p) = law(b);
            (
                b.inertia / t.inertia - 1.0,
                t.drag(b.c1, k, p) / t.drag(t.c1, t.k, t.p) - 1.0,
            )
        })
        .collect()
}

fn readings(r: &Report) -> Vec<Reading> {
    let (k, p) = law(&r.extended);
    let mut out = vec![Reading {
        effects: r.effects.iter().map(|e| (e.effect, e.value)).collect(),
        inertia: r.extended.inertia,
        c1: r.extended.c1,
        k,
        p,
    }];
    for a in &r.ambiguities {
        let (k, p) = law(&a.alternative);
        let mut effects: Vec<(EffectKind, f64)> = a
            .alternative_effects
            .iter()
            .map(|e| (e.effect, e.value))
            .collect();
        // Effects measured from the rows (the clock) are in every model.
        effects.extend(
            r.effects
                .iter()
                .filter(|e| e.effect == EffectKind::TimeBase)
                .map(|e| (e.effect, e.value)),
        );
        out.push(Reading {
            effects,
            inertia: a.alternative.inertia,
            c1: a.alternative.c1,
            k,
            p,
        });
    }
    // A second-order stage is, to first order in frequency, a lag of its low-frequency delay:
    // the model that names one reads as the model with a torque lag of that delay too.
    let stage = r
        .effects
        .iter()
        .find(|e| e.effect == EffectKind::SecondOrderLag)
        .and_then(|e| e.lag_delay_s);
    if let Some(delay) = stage {
        let first = Reading {
            effects: out[0]
                .effects
                .iter()
                .map(|&(k, v)| match k {
                    EffectKind::SecondOrderLag => (EffectKind::TorqueLag, delay),
                    k => (k, v),
                })
                .collect(),
            ..out[0].clone()
        };
        out.push(first);
    }
    // A twin tie (a Coulomb friction and an offset on a rotor that never reverses) is the same
    // column under two names, at the same value: either name reads every model.
    let twins = r.ambiguities.iter().any(|a| {
        let (x, y) = CONSTANT_TWINS;
        a.between == [x, y] || a.between == [y, x]
    });
    if twins {
        let swap = |k: EffectKind| match k {
            EffectKind::CoulombFriction => EffectKind::ForceOffset,
            EffectKind::ForceOffset => EffectKind::CoulombFriction,
            k => k,
        };
        let swapped: Vec<Reading> = out
            .iter()
            .map(|m| Reading {
                effects: m.effects.iter().map(|&(k, v)| (swap(k), v)).collect(),
                ..*m
            })
            .collect();
        out.extend(swapped);
    }
    out
}

/// What is wrong with one reading.
fn judge_reading(m: &Reading, expected: &[Expected], truth: Option<Truth>) -> Vec<String> {
    let mut bad = Vec::new();
    for e in expected {
        match m.effects.iter().find(|(k, _)| *k == e.kind) {
            None => bad.push(format!("{} not found", e.kind)),
            Some(&(_, v)) => {
                let error = ((v - e.value) / e.value).abs();
                if error.is_nan() || error > e.tolerance {
                    bad.push(format!(
                        "{} = {v:.4e}, truth {:.4e} within {:.0} %",
                        e.kind,
                        e.value,
                        e.tolerance * 100.0
                    ));
                }
            }
        }
    }
    for (k, _) in &m.effects {
        if *k != EffectKind::TimeBase && !expected.iter().any(|e| e.kind == *k) {
            bad.push(format!("also named {k}"));
        }
    }
    if let Some(t) = truth {
        let drag = t.drag(m.c1, m.k, m.p) / t.drag(t.c1, t.k, t.p);
        if !((m.inertia / t.inertia - 1.0).abs() <= 0.02 && (drag - 1.0).abs() <= 0.02) {
            bad.push(format!(
                "extended J {:.4e} (truth {:.4e}), drag {:.3e}·ω + {:.4e}·|ω|^{:.4} (truth {:.3e}·ω + {:.4e}·|ω|^{:.4}: {:+.1} % at {:.0} rad/s)",
                m.inertia, t.inertia, m.c1, m.k, m.p, t.c1, t.k, t.p, (drag - 1.0) * 100.0, t.speed
            ));
        }
    }
    bad
}

/// What is wrong with `r` against `expected` and, where given, the stand's J and drag law
/// (empty: right). Every ambiguity must be one `ties` allows. The report is right when the model
/// it names, or one of the models its ambiguities give (an ambiguous effect in place of the one
/// named), holds exactly the expected effects, each within its tolerance, with J and the drag
/// within 2 % of the truth: an ambiguity passes only with the right model among those it gives.
pub fn judge(r: &Report, expected: &[Expected], ties: Ties, truth: Option<Truth>) -> Vec<String> {
    let mut bad: Vec<String> = r
        .ambiguities
        .iter()
        .filter(|a| !ties.allows(a.between[0], a.between[1]))
        .map(|a| format!("ambiguous {}|{}", a.between[0], a.between[1]))
        .collect();
    let all: Vec<Vec<String>> = readings(r)
        .iter()
        .map(|m| judge_reading(m, expected, truth))
        .collect();
    if !all.iter().any(|b| b.is_empty()) {
        bad.extend(all.into_iter().next().unwrap_or_default());
    }
    bad
}

/// The extended model's J and its drag at the truth's speed, each relative to the truth's
/// (0: exact).
pub fn fit_errors(r: &Report, t: Truth) -> (f64, f64) {
    model_errors(r, t)[0]
}

/// What is wrong with the extended model's J and drag law against the truth, each within 2 %.
pub fn judge_fit(r: &Report, truth: Truth) -> Vec<String> {
    let m = &readings(r)[0];
    let t = truth;
    let (inertia, drag) = fit_errors(r, t);
    let drag = drag + 1.0;
    if inertia.abs() > 0.02 || (drag - 1.0).abs() > 0.02 || !m.inertia.is_finite() {
        vec![format!(
            "extended J {:.4e} (truth {:.4e}), drag {:.3e}·ω + {:.4e}·|ω|^{:.4} (truth {:.3e}·ω + {:.4e}·|ω|^{:.4}: {:+.1} % at {:.0} rad/s)",
            m.inertia, t.inertia, m.c1, m.k, m.p, t.c1, t.k, t.p, (drag - 1.0) * 100.0, t.speed
        )]
    } else {
        Vec::new()
    }
}

/// Whether a report is silently wrong: its verdict says the model (the seed's, or with the
/// effects named) explains the data while J or the drag is more than 2 % off.
pub fn silently_wrong(r: &Report, truth: Truth) -> bool {
    matches!(r.verdict, Verdict::NothingWrong | Verdict::Explained)
        && !judge_fit(r, truth).is_empty()
}

/// One run held to a test's ledger of known limits: what is wrong with it (empty: it is as the
/// ledger says). `wrong`: what the judge found; `listed`: the run is a known limit; `silent`:
/// [`silently_wrong`]; `listed_silent`: it is known to be. A listed run that became right, or a
/// silently wrong run that is no longer (or a new one), fails too, so the ledger and the docs
/// cannot drift.
pub fn against_ledger(
    what: &str,
    wrong: Vec<String>,
    listed: bool,
    silent: bool,
    listed_silent: bool,
) -> Vec<String> {
    let mut out = Vec::new();
    match (wrong.is_empty(), listed) {
        (true, true) => out.push(format!(
            "{what}: right now; take it off the known limits and the docs"
        )),
        (false, false) => out.extend(wrong.into_iter().map(|w| format!("{what}: {w}"))),
        _ => {}
    }
    if silent != listed_silent {
        out.push(format!(
            "{what}: {}",
            if silent {
                "a verdict that the model explains the data while J or the drag is off"
            } else {
                "no longer silently wrong: take it off the silently-wrong list and the docs"
            }
        ));
    }
    out
}

/// Every candidate of `r`, one line each, when `PROPID_VERBOSE` is set (to read why a draw went
/// the way it did).
pub fn verbose(r: &Report) {
    if std::env::var_os("PROPID_VERBOSE").is_none() {
        return;
    }
    for c in &r.candidates {
        say(format!(
            "      r{} {:<20} eq {:+8.3} % sim {:+8.3} % gain {:+.4} ± {:.4} ({}/10) value {:.4e} ± {:.1e} {:?}",
            c.round,
            c.effect.name(),
            c.cv_gain_percent,
            c.simulation_gain_percent,
            c.gain.mean,
            c.gain.stderr,
            c.gain.folds_better,
            c.value,
            c.stderr,
            c.decision
        ));
    }
    if let Some(u) = &r.simulation_only {
        say(format!("      simulation only: {u:?}"));
    }
    if let Some(u) = &r.unexplained {
        say(format!("      unexplained: {u:?}"));
    }
    if let Some(c) = &r.concentration {
        say(format!("      concentration: {c:?}"));
    }
    for n in &r.notes {
        say(format!("      note: {n}"));
    }
}
