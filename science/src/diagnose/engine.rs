//! Fitting a model and cross-validating it: the regression rows summed per block of samples into
//! the core's `NormalEquations` (or, where a column is the slope of a noisy signal,
//! `InstrumentalEquations`), blocks merged by addition.
//!
//! Why instruments: Ḟ and ȧ are slopes of noisy samples, and noise in a regressor biases its
//! least-squares coefficient towards zero by var(noise)/var(regressor). The instrument of Ḟ at
//! sample i is the difference quotient of the samples just outside the slope's window: it shares
//! no sample with the slope at i, so θ = (ZᵀΦ)⁻¹Zᵀy has no noise bias. Held-out prediction is
//! scored with least squares (the best linear predictor from the regressors as measured); the
//! reported parameters, and the parameters a held-out simulation uses, come from the instruments.

use std::ops::Range;

use propid_core::estimate::{InstrumentalEquations, NormalEquations};

use super::model::{measured_rows, Model, Prepared, Speed, MAX_COLUMNS};
use super::signals::Signals;
use super::FOLDS;

/// A fit on some samples.
#[derive(Clone, Debug)]
pub(crate) struct Fit {
    /// Coefficients (θ₀ = 1/J, θ₁ = c2/J, then the effects'), without the bias the force's noise
    /// puts on its own (see [`without_force_noise`]): the parameters reported.
    pub theta: Vec<f64>,
    /// Their standard errors.
    pub stderr: Vec<f64>,
    /// The coefficients as the measured regressors fit them (the force's noise in its regressor
    /// left in): the predictor of the acceleration from the signals as measured, whose residual
    /// the structure analyses read and whose sum of squares is [`Fit::rss`].
    pub predictor: Vec<f64>,
    /// Residual sum of squares of [`Fit::predictor`] (with the force noise a transformation
    /// took out put back).
    pub rss: f64,
    /// Samples.
    pub n: f64,
}

/// Held-out scores of the acceleration equation.
#[derive(Clone, Debug, PartialEq)]
pub(crate) struct Cv {
    /// Pooled held-out mean squared error.
    pub mse: f64,
    /// Held-out mean squared error per fold.
    pub folds: [f64; FOLDS],
    /// Held-out simulated-velocity mean squared error per fold, where it was computed (a lag's
    /// tuning: see `tune`).
    pub simulation: Option<[f64; FOLDS]>,
}

impl Cv {
    /// What a tuning minimises: with the simulation, the selection's own score, the mean over
    /// the folds of ln eq_k + ln sim_k (a parameter is tuned where the model gains most by the
    /// criterion that then judges it); without, the pooled equation error (its logarithm: the
    /// same order).
    pub fn objective(&self) -> f64 {
        match &self.simulation {
            Some(sim) => {
                self.folds
                    .iter()
                    .zip(sim)
                    .map(|(e, s)| e.ln() + s.ln())
                    .sum::<f64>()
                    / FOLDS as f64
            }
            None => self.mse.ln(),
        }
    }
}

/// A cross-validation with the parameters fitted without each fold (for its simulation).
pub(crate) struct CrossFit {
    /// The held-out acceleration scores.
    pub cv: Cv,
    /// Per fold, the parameters fitted on the other folds.
    pub thetas: Vec<Vec<f64>>,
}

/// The sums of one block of samples.
#[derive(Clone, Copy, Debug)]
enum Stats<const N: usize> {
    /// Least squares.
    Ls(NormalEquations<f64, N>),
    /// Instrumental variables (their least-squares sums inside).
    Iv(InstrumentalEquations<f64, N>),
}

impl<const N: usize> Stats<N> {
    fn new(iv: bool) -> Self {
        if iv {
            Stats::Iv(InstrumentalEquations::new())
        } else {
            Stats::Ls(NormalEquations::new())
        }
    }

    #[inline(always)]
    fn update(&mut self, phi: &[f64; N], z: &[f64; N], y: f64) {
        match self {
            Stats::Ls(ne) => ne.update(phi, y),
            Stats::Iv(iv) => iv.update(phi, z, y),
        }
    }

    fn merge(&mut self, other: &Self) {
        match (self, other) {
            (Stats::Ls(a), Stats::Ls(b)) => a.merge(b),
            (Stats::Iv(a), Stats::Iv(b)) => a.merge(b),
            (Stats::Ls(a), Stats::Iv(b)) => a.merge(b.least_squares()),
            (s @ Stats::Iv(_), Stats::Ls(b)) => {
                let mut a = *s.least_squares();
                a.merge(b);
                *s = Stats::Ls(a);
            }
        }
    }

    fn least_squares(&self) -> &NormalEquations<f64, N> {
        match self {
            Stats::Ls(ne) => ne,
            Stats::Iv(iv) => iv.least_squares(),
        }
    }

    /// θ and its standard errors: instrumental variables where summed, else least squares.
    fn solve(&self) -> Option<([f64; N], [f64; N])> {
        match self {
            Stats::Ls(ne) => ne.solve().ok().map(|s| (s.theta, s.stderr)),
            Stats::Iv(iv) => iv.solve().ok().map(|s| (s.theta, s.stderr)),
        }
    }
}

/// Most rows the cross-validation of a tuning reads: on a longer log it reads every k-th block of
/// [`BLOCK_ROWS`] rows, spread over the whole record (a nonlinear parameter is located as well
/// from 400,000 samples as from two million, at a fifth of the cost). The scores the selection
/// decides on, and every reported fit, read every row.
pub const TUNING_ROWS: usize = 400_000;

/// Contiguous rows kept together when a tuning reads part of a long log.
const BLOCK_ROWS: usize = 1024;

/// Rows accumulated (a profiling count).
pub static ROWS: std::sync::atomic::AtomicUsize = std::sync::atomic::AtomicUsize::new(0);

/// Which rows of a range a sum reads.
struct Read {
    /// With k > 1, only every k-th block of [`BLOCK_ROWS`] rows.
    stride: usize,
    /// Rows it leaves out (an excluded event, see [`Signals::excluded`]).
    skip: Range<usize>,
}

/// Sums the rows of `range` (as `read` says) into `folds` contiguous blocks.
fn accumulate<const N: usize>(
    model: &Model,
    p: &Prepared,
    s: &Signals,
    range: Range<usize>,
    folds: usize,
    iv: bool,
    read: Read,
) -> Vec<Stats<N>> {
    let Read { stride, skip } = read;
    ROWS.fetch_add(range.len() / stride, std::sync::atomic::Ordering::Relaxed);
    let mut eqs = vec![Stats::<N>::new(iv); folds];
    let len = range.len().max(1);
    let start = range.start;
    let kept =
        |i: usize| (stride == 1 || ((i - start) / BLOCK_ROWS) % stride == 0) && !skip.contains(&i);
    let mut add = |i: usize, row: [f64; MAX_COLUMNS]| {
        let fold = (i - range.start) * folds / len;
        let phi: [f64; N] = core::array::from_fn(|k| row[k]);
        let z = if iv {
            let zr = Model::instruments(p, s, i, row);
            core::array::from_fn(|k| zr[k])
        } else {
            phi
        };
        eqs[fold].update(&phi, &z, s.acceleration[i]);
    };
    if p.model_side_lag.is_some() {
        for (i, row) in measured_rows(model, p, s, range.clone()) {
            if kept(i) {
                add(i, row);
            }
        }
    } else {
        // The hot loop of every cross-validation: rows straight from the signals.
        for i in range.clone() {
            if kept(i) {
                add(i, model.row(p, s, i, Speed::Measured, false, 0.0));
            }
        }
    }
    eqs
}

/// The mean squared acceleration error a transformation of the force removed with the force's
/// noise, put back (see [`super::model::force_noise_gain`]): θ₀²·σ_F²·(1 − gain).
fn unfiltered_noise(theta: &[f64], p: &Prepared, s: &Signals) -> f64 {
    theta[0] * theta[0] * s.force_noise * s.force_noise * (1.0 - p.force_noise_gain)
}

fn fit_n<const N: usize>(
    model: &Model,
    p: &Prepared,
    s: &Signals,
    range: Range<usize>,
    skip: Range<usize>,
) -> Option<Fit> {
    let read = Read { stride: 1, skip };
    let eq = accumulate::<N>(model, p, s, range, 1, model.differentiated(), read).pop()?;
    let (predictor, stderr) = eq.solve()?;
    // The parameters without the force noise's bias, with the standard errors of the sums as
    // measured (that noise is in the residual the errors are scaled by).
    let (theta, _) = corrected(&eq, p, s).solve()?;
    let n = eq.least_squares().count();
    Some(Fit {
        theta: theta.to_vec(),
        stderr: stderr.to_vec(),
        predictor: predictor.to_vec(),
        rss: eq.least_squares().residual_sum_of_squares(&predictor)
            + unfiltered_noise(&predictor, p, s) * n,
        n,
    })
}

/// The parameters with the force's noise taken out of its regressor: the measured force carries
/// white noise of σ_F (`Signals::force_noise`, as much of it as the model's transformation of the
/// force lets through), which adds n·σ_F² to the force's diagonal of ΦᵀΦ (and of ZᵀΦ: the force
/// is its own instrument) and reads its coefficient 1/J low by that share of the force's variance
/// left after the other regressors (errors in the regressor; on a slow pattern the drag takes
/// most of the force's variance, and on the independent stand J came out 0.3–3 % high). Those
/// parameters simulate the held-out folds: a simulation integrates the J error over seconds, and
/// a lag that smooths the force's noise (any lag, of any length) would otherwise gain there for
/// shrinking the bias, not for being there — a 0.5 ms "torque lag" on clean data gained 17 % in
/// simulation.
fn without_force_noise<const N: usize>(
    train: &Stats<N>,
    p: &Prepared,
    s: &Signals,
) -> Option<[f64; N]> {
    corrected(train, p, s).solve().map(|(theta, _)| theta)
}

/// `sums` with the force's noise taken out of the force's diagonal (see [`without_force_noise`]).
fn corrected<const N: usize>(sums: &Stats<N>, p: &Prepared, s: &Signals) -> Stats<N> {
    let c = sums.least_squares().count() * s.force_noise * s.force_noise * p.force_noise_gain;
    let mut corrected = *sums;
    if c > 0.0 && c.is_finite() {
        let mut phi = [0.0; N];
        phi[0] = c.sqrt();
        match &mut corrected {
            Stats::Ls(ne) => ne.update_weighted(&phi, 0.0, -1.0),
            Stats::Iv(iv) => iv.update(&phi, &phi.map(|x| -x), 0.0),
        }
    }
    corrected
}

fn cross_fit_n<const N: usize>(
    model: &Model,
    p: &Prepared,
    s: &Signals,
    thetas: bool,
    stride: usize,
) -> Option<CrossFit> {
    let iv = thetas && model.differentiated();
    let read = Read {
        stride,
        skip: s.excluded.clone(),
    };
    let eqs = accumulate::<N>(model, p, s, s.first..s.len(), FOLDS, iv, read);
    let mut folds = [0.0; FOLDS];
    let (mut total, mut count) = (0.0, 0.0);
    let mut fitted = Vec::new();
    for k in 0..FOLDS {
        let mut train = Stats::<N>::new(iv);
        for (j, e) in eqs.iter().enumerate() {
            if j != k {
                train.merge(e);
            }
        }
        let theta = train.least_squares().solve().ok()?.theta;
        let held_out = eqs[k].least_squares();
        let n = held_out.count();
        let rss = held_out.residual_sum_of_squares(&theta) + unfiltered_noise(&theta, p, s) * n;
        folds[k] = rss / n.max(1.0);
        total += rss;
        count += n;
        if thetas {
            fitted.push(without_force_noise(&train, p, s)?.to_vec());
        }
    }
    Some(CrossFit {
        cv: Cv {
            mse: total / count.max(1.0),
            folds,
            simulation: None,
        },
        thetas: fitted,
    })
}

/// Calls the const-generic `$f::<N>` for the model's number of columns.
macro_rules! by_width {
    ($model:expr, $f:ident, $($arg:expr),*) => {
        match $model.columns() {
            2 => $f::<2>($($arg),*),
            3 => $f::<3>($($arg),*),
            4 => $f::<4>($($arg),*),
            5 => $f::<5>($($arg),*),
            6 => $f::<6>($($arg),*),
            7 => $f::<7>($($arg),*),
            8 => $f::<8>($($arg),*),
            9 => $f::<9>($($arg),*),
            10 => $f::<10>($($arg),*),
            // `Model::with` builds no model wider than MAX_COLUMNS.
            _ => None,
        }
    };
}

const _: () = assert!(MAX_COLUMNS == 10, "by_width dispatches up to 10 columns");

/// Fits `model` (inputs prepared as `p`) on the samples in `range`.
pub(crate) fn fit_prepared(
    model: &Model,
    p: &Prepared,
    s: &Signals,
    range: Range<usize>,
) -> Option<Fit> {
    by_width!(model, fit_n, model, p, s, range, s.excluded.clone())
}

/// Fits `model` on the samples in `range`.
pub(crate) fn fit(model: &Model, s: &Signals, range: Range<usize>) -> Option<Fit> {
    fit_prepared(model, &model.prepare(s), s, range)
}

/// Fits `model` on every sample after the warm-up.
pub(crate) fn fit_on_all(model: &Model, s: &Signals) -> Option<Fit> {
    fit(model, s, s.first..s.len())
}

/// Fits `model` on every sample after the warm-up, the excluded span included (what its samples
/// do to the parameters).
pub(crate) fn fit_every_row(model: &Model, s: &Signals) -> Option<Fit> {
    let p = model.prepare(s);
    by_width!(model, fit_n, model, &p, s, s.first..s.len(), 0..0)
}

/// The held-out acceleration scores of `model` (blocked [`FOLDS`]-fold cross-validation), as a
/// tuning reads them: on at most about [`TUNING_ROWS`] rows.
pub(crate) fn cross_validate(model: &Model, s: &Signals) -> Option<Cv> {
    let p = model.prepare(s);
    let stride = (s.len() - s.first).div_ceil(TUNING_ROWS).max(1);
    by_width!(model, cross_fit_n, model, &p, s, false, stride).map(|c| c.cv)
}

/// As [`cross_fit`], on the rows a tuning reads (at most about [`TUNING_ROWS`]).
pub(crate) fn cross_fit_for_tuning(model: &Model, p: &Prepared, s: &Signals) -> Option<CrossFit> {
    let stride = (s.len() - s.first).div_ceil(TUNING_ROWS).max(1);
    by_width!(model, cross_fit_n, model, p, s, true, stride)
}

/// The held-out acceleration scores of `model` on every row, with, per fold, the parameters
/// fitted on the other folds.
pub(crate) fn cross_fit(model: &Model, p: &Prepared, s: &Signals) -> Option<CrossFit> {
    by_width!(model, cross_fit_n, model, p, s, true, 1)
}

/// The acceleration residual of `model` fitted as `fit` (its predictor), at every sample.
pub(crate) fn residuals(model: &Model, fit: &Fit, s: &Signals) -> Vec<f64> {
    let p = model.prepare(s);
    measured_rows(model, &p, s, 0..s.len())
        .map(|(i, r)| {
            s.acceleration[i] - fit.predictor.iter().zip(r).map(|(a, b)| a * b).sum::<f64>()
        })
        .collect()
}

/// The acceleration residual of every sample after the warm-up, each predicted by the model
/// fitted on the folds that do not hold it (index 0 is the sample `s.first`).
pub(crate) fn held_out_residuals(model: &Model, s: &Signals) -> Option<Vec<f64>> {
    let p = model.prepare(s);
    let cf = cross_fit(model, &p, s)?;
    let len = (s.len() - s.first).max(1);
    Some(
        measured_rows(model, &p, s, s.first..s.len())
            .map(|(i, r)| {
                let theta = &cf.thetas[(i - s.first) * FOLDS / len];
                s.acceleration[i] - theta.iter().zip(r).map(|(a, b)| a * b).sum::<f64>()
            })
            .collect(),
    )
}
