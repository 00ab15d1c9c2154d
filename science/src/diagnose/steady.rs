//! The drag law from steady-state data, when the inertia cannot be identified.
//!
//! A stand whose torque is sampled slowly (an RCbenchmark load cell at ~6.7 Hz) and driven in held
//! steps says almost nothing about J, but a lot about the drag law: at each plateau the torque is
//! the aerodynamic torque. Two laws are compared on the samples above 10 % of the top speed:
//!
//! ```text
//!  seed:     F = c2·ω² + F₀          (F₀ absorbs the load cell's zero offset)
//!  extended: F = k·|ω|^p + F₀        (p by the held-out error: grid, then golden section)
//! ```
//! by 5-fold cross-validation with interleaved folds (every fifth sample), because held steps put
//! each speed in one contiguous block. p is named (`drag_exponent`) when it lowers the held-out
//! error by at least [`super::MIN_GAIN`] in at least four folds.

use propid_core::estimate::NormalEquations;

use super::signals::Signals;
use super::{FOLDS, MIN_FOLDS_BETTER, MIN_GAIN};

/// The fitted law.
#[derive(Clone, Debug, serde::Serialize)]
pub struct DragLaw {
    /// Samples used (finite torque, speed above 10 % of the top).
    pub samples: usize,
    /// c2 of the seed's law F = c2·ω² + F₀ [N·m·s²/rad²].
    pub c2: f64,
    /// Offset F₀ of the seed's law [N·m].
    pub offset: f64,
    /// Exponent of the extended law.
    pub exponent: f64,
    /// Its standard error.
    pub exponent_stderr: f64,
    /// k of the extended law [N·m·(s/rad)^p].
    pub k: f64,
    /// Held-out gain of the extended law over the seed's [%].
    pub cv_gain_percent: f64,
    /// Folds in which it did better.
    pub folds_better: usize,
    /// RMS torque residual of the seed's law [N·m].
    pub rms_seed: f64,
    /// RMS torque residual of the extended law [N·m].
    pub rms_extended: f64,
    /// Whether the exponent is named.
    pub selected: bool,
}

fn folds(s: &Signals, idx: &[usize], p: f64) -> [NormalEquations<f64, 2>; FOLDS] {
    let mut eqs = [NormalEquations::<f64, 2>::new(); FOLDS];
    for (n, &i) in idx.iter().enumerate() {
        let w = s.velocity[i].abs();
        eqs[n % FOLDS].update(&[w.powf(p), 1.0], s.force[i]);
    }
    eqs
}

/// How a law with exponent p scores.
struct Score {
    /// Pooled held-out mean squared error.
    mse: f64,
    /// Held-out MSE per fold.
    folds: [f64; FOLDS],
    /// (k, F₀) fitted to all samples.
    theta: [f64; 2],
    /// In-sample residual sum of squares.
    rss: f64,
    /// Samples.
    n: f64,
}

fn score(s: &Signals, idx: &[usize], p: f64) -> Option<Score> {
    let eqs = folds(s, idx, p);
    let mut per = [0.0; FOLDS];
    let (mut total, mut count) = (0.0, 0.0);
    let mut all = NormalEquations::<f64, 2>::new();
    for e in &eqs {
        all.merge(e);
    }
    for k in 0..FOLDS {
        let mut train = NormalEquations::<f64, 2>::new();
        for (j, e) in eqs.iter().enumerate() {
            if j != k {
                train.merge(e);
            }
        }
        let theta = train.solve().ok()?.theta;
        let rss = eqs[k].residual_sum_of_squares(&theta);
        per[k] = rss / eqs[k].count().max(1.0);
        total += rss;
        count += eqs[k].count();
    }
    let sol = all.solve().ok()?;
    let rss = all.residual_sum_of_squares(&sol.theta);
    Some(Score {
        mse: total / count.max(1.0),
        folds: per,
        theta: sol.theta,
        rss,
        n: all.count(),
    })
}

/// Fits both laws; `None` if there are too few usable samples.
pub fn drag_law(s: &Signals) -> Option<DragLaw> {
    let top = s.velocity.iter().map(|w| w.abs()).fold(0.0, f64::max);
    let idx: Vec<usize> = (0..s.len())
        .filter(|&i| s.force[i].is_finite() && s.velocity[i].abs() > 0.1 * top)
        .collect();
    if idx.len() < 20 {
        return None;
    }
    let seed = score(s, &idx, 2.0)?;
    let (mse2, per2, th2, rss2, n) = (seed.mse, seed.folds, seed.theta, seed.rss, seed.n);
    let cv = |p: f64| score(s, &idx, p).map_or(f64::INFINITY, |x| x.mse);
    let grid: Vec<f64> = (0..=20).map(|k| 1.2 + 0.1 * k as f64).collect();
    let scores: Vec<f64> = grid.iter().map(|&p| cv(p)).collect();
    let k = (0..grid.len()).min_by(|a, b| scores[*a].total_cmp(&scores[*b]))?;
    let p = super::effects::golden(
        grid[k.saturating_sub(1)],
        grid[(k + 1).min(grid.len() - 1)],
        cv,
        24,
    );
    let free = score(s, &idx, p)?;
    let (msep, perp, thp, rssp) = (free.mse, free.folds, free.theta, free.rss);
    // Standard error of p from the curvature of the in-sample residual.
    let h = 0.01;
    let rss_at = |q: f64| score(s, &idx, q).map_or(f64::NAN, |x| x.rss);
    let curvature = (rss_at(p + h) - 2.0 * rssp + rss_at(p - h)) / (h * h);
    let sigma2 = rssp / (n - 3.0).max(1.0);
    let stderr = if curvature > 0.0 {
        (2.0 * sigma2 / curvature).sqrt()
    } else {
        f64::NAN
    };
    let gain = 1.0 - msep / mse2;
    let wins = perp.iter().zip(&per2).filter(|(a, b)| a < b).count();
    Some(DragLaw {
        samples: idx.len(),
        c2: th2[0],
        offset: th2[1],
        exponent: p,
        exponent_stderr: stderr,
        k: thp[0],
        cv_gain_percent: gain * 100.0,
        folds_better: wins,
        rms_seed: (rss2 / n).sqrt(),
        rms_extended: (rssp / n).sqrt(),
        selected: gain >= MIN_GAIN && wins >= MIN_FOLDS_BETTER && (p - 2.0).abs() > 0.02,
    })
}
