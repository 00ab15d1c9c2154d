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

    /// How fast the drive sees the rotor slowing at sample `i` [rad/s²], as a drive's braking
    /// logic does: the mean of the neighbouring samples' reported accelerations, against the
    /// velocity (positive: slowing). Sharp where a braking torque switches (it steps the
    /// acceleration), unlike the ±20 ms velocity slope of `decelerating`; the sample's own
    /// acceleration, the equation's left-hand side, is left out, so its noise does not choose
    /// the samples it is compared on.
    pub fn slowing(&self, i: usize) -> f64 {
        let n = self.len();
        let (a, b) = (i.saturating_sub(1), (i + 1).min(n - 1));
        -0.5 * (self.acceleration[a] + self.acceleration[b]) * self.velocity[i].signum()
    }

    /// Number of samples.
    pub fn len(&self) -> usize {
        self.t.len()
    }

    /// The reported torque through a causal first-order lag of time constant `lag`, discretised
    /// with a first-order hold (the torque taken as linear between samples, exact for a
    /// continuous torque; a zero-order hold would apply each sample over the interval before it
    /// and make every fitted lag half a sample long).
    pub fn lagged_force(&self, lag: f64) -> Vec<f64> {
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
            if dt > 0.0 {
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
