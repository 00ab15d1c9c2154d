//! The measured signals and the derived ones every candidate effect draws on.

use propid_io::tsv::Sample;
use propid_io::InputError;

/// Half-width of the derivative window [s]: Ḟ and ȧ are local straight-line slopes over ±this.
const DERIVATIVE_HALF_WINDOW: f64 = 0.01;

/// Columns of a recording, plus derivatives.
pub struct Signals {
    /// Time [s].
    pub t: Vec<f64>,
    /// Reported torque [N·m].
    pub force: Vec<f64>,
    /// Velocity [rad/s].
    pub velocity: Vec<f64>,
    /// ln|velocity| (−∞ at rest), for drag laws |ω|^p = exp(p·ln|ω|).
    pub log_speed: Vec<f64>,
    /// Reported acceleration [rad/s²].
    pub acceleration: Vec<f64>,
    /// Rotor angle [rad], if the recording has it.
    pub position: Option<Vec<f64>>,
    /// dF/dt, the local slope over ±10 ms [N·m/s].
    pub force_rate: Vec<f64>,
    /// d(acceleration)/dt, the same way [rad/s³].
    pub jerk: Vec<f64>,
    /// Half-width of the slopes' window in samples (the instruments reach one sample beyond it).
    pub slope_half_width: usize,
    /// Whether the rotor is slowing down at each sample: the slope of the measured velocity over
    /// ±20 ms opposes the velocity (not the reported acceleration, whose noise is in the
    /// equation's left-hand side).
    pub decelerating: Vec<bool>,
    /// Median sample rate [Hz].
    pub rate: f64,
    /// The reported acceleration's sample-to-sample noise σ [rad/s²]: from the median absolute
    /// deviation of a[i] − (a[i−1] + a[i+1])/2 (σ·√1.5 for white noise; robust to the steps a
    /// braking torque makes).
    pub acceleration_noise: f64,
    /// The same for the reported force [N·m].
    pub force_noise: f64,
    /// First sample the regressions use: the first half second is a warm-up for the lag filters
    /// of the candidate models (their initial state is unknown), so every model is judged on the
    /// same samples.
    pub first: usize,
}

/// The slope of a straight line fitted by least squares to the samples within ±`h` of each one
/// (a Savitzky–Golay first derivative): zero phase, and much less noisy than a two-point
/// difference over the same span.
fn local_slope(t: &[f64], x: &[f64], h: usize) -> Vec<f64> {
    let n = x.len();
    (0..n)
        .map(|i| {
            let (lo, hi) = (i.saturating_sub(h), (i + h).min(n - 1));
            let m = (hi - lo + 1) as f64;
            let tm = t[lo..=hi].iter().sum::<f64>() / m;
            let xm = x[lo..=hi].iter().sum::<f64>() / m;
            let (mut sxy, mut sxx) = (0.0, 0.0);
            for k in lo..=hi {
                sxy += (t[k] - tm) * (x[k] - xm);
                sxx += (t[k] - tm) * (t[k] - tm);
            }
            if sxx > 0.0 {
                sxy / sxx
            } else {
                0.0
            }
        })
        .collect()
}

/// The instrument of a local slope over ±h samples at `i`: the difference quotient of the samples
/// just outside that window, (x[i+g] − x[i−g]) / (t[i+g] − t[i−g]) with g = h + 1 (one-sided at
/// the ends). It shares no sample with the slope at i (independent noise) and sees the same
/// change, a smooth one or a step. Computed where it is used: two more columns of n would cost
/// 32 MB on a 2-million-row log.
fn instrument(t: &[f64], x: &[f64], g: usize, i: usize) -> f64 {
    let n = x.len();
    let (a, b) = (i.saturating_sub(g), (i + g).min(n - 1));
    let dt = t[b] - t[a];
    if dt > 0.0 && a != b {
        (x[b] - x[a]) / dt
    } else {
        0.0
    }
}

impl Signals {
    /// Builds the signals; the samples must be complete (finite t, force, velocity,
    /// acceleration) and in time order. They are consumed: dropped as soon as their columns are
    /// taken, before the derived signals are computed (the peak memory of a long log).
    pub fn new(samples: Vec<Sample>) -> Result<Signals, InputError> {
        const MIN_SAMPLES: usize = 200;
        if samples.len() < MIN_SAMPLES {
            return Err(InputError(format!(
                "{} complete samples; a diagnosis needs at least {MIN_SAMPLES}",
                samples.len()
            )));
        }
        if let Some(k) = samples.windows(2).position(|w| w[1].t < w[0].t) {
            return Err(InputError(format!(
                "time goes backwards at sample {} (t = {} after {})",
                k + 2,
                samples[k + 1].t,
                samples[k].t
            )));
        }
        let t: Vec<f64> = samples.iter().map(|s| s.t).collect();
        let force: Vec<f64> = samples.iter().map(|s| s.force).collect();
        let acceleration: Vec<f64> = samples.iter().map(|s| s.acceleration).collect();
        let velocity: Vec<f64> = samples.iter().map(|s| s.velocity).collect();
        let position: Option<Vec<f64>> = samples
            .iter()
            .all(|s| s.position.is_finite())
            .then(|| samples.iter().map(|s| s.position).collect());
        drop(samples);
        let mut dts: Vec<f64> = t
            .windows(2)
            .map(|w| w[1] - w[0])
            .filter(|d| *d > 0.0)
            .collect();
        if dts.is_empty() {
            return Err(InputError("all samples have the same time".into()));
        }
        let mid = dts.len() / 2;
        let rate = 1.0 / *dts.select_nth_unstable_by(mid, f64::total_cmp).1;
        drop(dts);
        let h = ((DERIVATIVE_HALF_WINDOW * rate).round() as usize).max(1);
        let warm_up = t[0] + 0.5;
        let first = t
            .iter()
            .position(|x| *x >= warm_up)
            .unwrap_or(0)
            .min(t.len() / 2);
        let slowing = local_slope(&t, &velocity, 2 * h);
        let decelerating = slowing
            .iter()
            .zip(&velocity)
            .map(|(d, w)| d * w.signum() < 0.0)
            .collect();
        let acceleration_noise = noise_of(&acceleration);
        let force_noise = noise_of(&force);
        let force_rate = local_slope(&t, &force, h);
        let jerk = local_slope(&t, &acceleration, h);
        Ok(Signals {
            first,
            slope_half_width: h,
            log_speed: velocity.iter().map(|w| w.abs().ln()).collect(),
            force_rate,
            jerk,
            velocity,
            decelerating,
            t,
            force,
            acceleration,
            position,
            rate,
            acceleration_noise,
            force_noise,
        })
    }

    /// Instrument for Ḟ at sample `i`: the difference quotient of the force samples just outside
    /// the slope's window (independent noise, the same change).
    pub fn force_rate_instrument(&self, i: usize) -> f64 {
        instrument(&self.t, &self.force, self.slope_half_width + 1, i)
    }

    /// The same for ȧ.
    pub fn jerk_instrument(&self, i: usize) -> f64 {
        instrument(&self.t, &self.acceleration, self.slope_half_width + 1, i)
    }

    /// How fast the rotor is slowing at sample `i` by its reported acceleration [rad/s²]
    /// (positive: slowing).
    pub fn slowing(&self, i: usize) -> f64 {
        -self.acceleration[i] * self.velocity[i].signum()
    }

    /// Whether the force steps between samples i − 1 and i: it changes by more than eight times
    /// its noise and four times as much as over either neighbouring interval (a step of the
    /// command, not a steep stretch of a smooth one).
    pub fn force_steps_at(&self, i: usize) -> bool {
        let n = self.len();
        if i == 0 || i >= n {
            return false;
        }
        let d = |k: usize| (self.force[k] - self.force[k - 1]).abs();
        let here = d(i);
        let before = if i >= 2 { d(i - 1) } else { 0.0 };
        let after = if i + 1 < n { d(i + 1) } else { 0.0 };
        here > 8.0 * self.force_noise && here > 4.0 * before.max(after)
    }

    /// Whether the force has steps at all (one in a thousand intervals at least).
    pub fn has_force_steps(&self) -> bool {
        let n = self.len();
        (1..n).filter(|&i| self.force_steps_at(i)).count() * 1000 >= n
    }

    /// Number of samples.
    pub fn len(&self) -> usize {
        self.t.len()
    }

    /// The reported torque through a causal first-order lag of time constant `lag`, discretised
    /// with a first-order hold (the torque taken as linear between samples, exact for a
    /// continuous torque; a zero-order hold would apply each sample over the interval before it
    /// and make every fitted lag half a sample long).
    ///
    /// With `steps_at_samples`, a step of the force (see [`Signals::force_steps_at`]) is taken to
    /// happen at the sample that first shows it: the old value holds over the interval before.
    pub fn lagged_force(&self, lag: f64, steps_at_samples: bool) -> Vec<f64> {
        let mut out = Vec::with_capacity(self.len());
        if lag <= 0.0 {
            out.extend_from_slice(&self.force);
            return out;
        }
        let mut y = self.force[0];
        out.push(y);
        for i in 1..self.len() {
            let dt = self.t[i] - self.t[i - 1];
            let (x0, x1) = (self.force[i - 1], self.force[i]);
            if dt > 0.0 && steps_at_samples && self.force_steps_at(i) {
                y = x0 + (-dt / lag).exp() * (y - x0);
            } else if dt > 0.0 {
                // y' = (x − y)/L with x linear from x0 to x1 over dt, solved exactly.
                let e = (-dt / lag).exp();
                let slope = (x1 - x0) / dt;
                y = x1 - lag * slope + e * (y - x0 + lag * slope);
            }
            out.push(y);
        }
        out
    }
}

/// A signal's sample-to-sample noise σ: from the median absolute deviation of
/// x[i] − (x[i−1] + x[i+1])/2 (σ·√1.5 for white noise; robust to steps).
fn noise_of(x: &[f64]) -> f64 {
    let mut d: Vec<f64> = x
        .windows(3)
        .map(|w| (w[1] - 0.5 * (w[0] + w[2])).abs())
        .collect();
    if d.is_empty() {
        return 0.0;
    }
    let mid = d.len() / 2;
    1.4826 * *d.select_nth_unstable_by(mid, f64::total_cmp).1 / 1.5f64.sqrt()
}

/// Pearson correlation (0 if either side is constant).
pub fn correlation(x: &[f64], y: &[f64]) -> f64 {
    let n = x.len().min(y.len()) as f64;
    if n < 2.0 {
        return 0.0;
    }
    let mx = x.iter().sum::<f64>() / n;
    let my = y.iter().sum::<f64>() / n;
    let (mut sxy, mut sxx, mut syy) = (0.0, 0.0, 0.0);
    for (a, b) in x.iter().zip(y) {
        sxy += (a - mx) * (b - my);
        sxx += (a - mx) * (a - mx);
        syy += (b - my) * (b - my);
    }
    if sxx <= 0.0 || syy <= 0.0 {
        0.0
    } else {
        sxy / (sxx * syy).sqrt()
    }
}
