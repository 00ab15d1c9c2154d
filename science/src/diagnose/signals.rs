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
    /// Half-width of the slopes' window in samples (Ḟ's instrument reaches one sample beyond it,
    /// ȧ's three).
    pub slope_half_width: usize,
    /// Whether the rotor is slowing down at each sample: the slope of the measured velocity over
    /// ±20 ms opposes the velocity (not the reported acceleration, whose noise is in the
    /// equation's left-hand side).
    pub decelerating: Vec<bool>,
    /// [`Signals::decelerating`] with each spell's start and end moved to where the measured
    /// velocity kinks (see [`at_kinks`]).
    pub decelerating_at_kinks: Vec<bool>,
    /// Median sample rate [Hz].
    pub rate: f64,
    /// The largest |velocity| [rad/s].
    pub top_speed: f64,
    /// The reported acceleration's sample-to-sample noise σ [rad/s²]: from the median absolute
    /// deviation of a[i] − (a[i−1] + a[i+1])/2 (σ·√1.5 for white noise; robust to the steps a
    /// braking torque makes).
    pub acceleration_noise: f64,
    /// The same for the reported force [N·m].
    pub force_noise: f64,
    /// Where the force is a held sample that updates more slowly than the rows (a load cell read
    /// at 40 Hz in 500 Hz telemetry), how often it updates; `force` is then the reconstruction
    /// (see [`Updates::reconstruct`]).
    pub force_updates: Option<Updates>,
    /// Whether the force steps (see [`Signals::has_force_steps`]).
    force_steps: bool,
    /// First sample the regressions use: the first half second is a warm-up for the lag filters
    /// of the candidate models (their initial state is unknown), so every model is judged on the
    /// same samples.
    pub first: usize,
    /// Samples no fit or score reads (empty: none): the span of an event the model does not hold
    /// (see [`super::structure::event_span`]), found by a first diagnosis of the whole record.
    pub excluded: std::ops::Range<usize>,
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

/// Where each spell of `slowing` (the sign of the velocity's slope over ±`h` samples) really
/// starts and ends: where the measured velocity kinks. A braking torque B steps the acceleration
/// by B/J as it engages and as it releases, and a slope over ±h samples turns with the step
/// before the step is reached: on the independent stand (a 0.5 Hz sine, B/J = 400 rad/s², ±20 ms)
/// the spells started 6 samples (12 ms) early and ended 6 late on noise-free data, a systematic
/// error in when the braking acts that a torque lag or a viscous friction then partly absorbs.
/// The kink is found by least squares on the velocity within ±2h samples of each turn (bounded
/// half-way to the turns beside it): a quadratic plus a change of slope at a point between two
/// samples, scanned over ±h samples around the turn; the turn moves there where the change of
/// slope is three standard errors from zero with the sign the turn has (the rotor starts or
/// stops slowing), and stays where it is otherwise (a turn of a smooth velocity, a reversal
/// through zero).
fn at_kinks(t: &[f64], v: &[f64], slowing: &[bool], h: usize) -> Vec<bool> {
    use propid_core::estimate::NormalEquations;
    let n = slowing.len();
    let turns: Vec<usize> = (1..n).filter(|&i| slowing[i] != slowing[i - 1]).collect();
    let mut out = slowing.to_vec();
    for (e, &j) in turns.iter().enumerate() {
        let lo = j
            .saturating_sub(2 * h)
            .max(if e == 0 { 0 } else { (turns[e - 1] + j) / 2 });
        let hi = (j + 2 * h).min(turns.get(e + 1).map_or(n - 1, |&next| (next + j) / 2));
        if hi < lo + 8 {
            continue;
        }
        let dt = (t[hi] - t[lo]) / (hi - lo) as f64;
        let starts = slowing[j];
        let sign = v[j].signum();
        let mut best: Option<(f64, usize)> = None;
        for k in (j.saturating_sub(h)).max(lo + 3)..=(j + h).min(hi - 3) {
            // The kink between samples k − 1 and k.
            let at = 0.5 * (t[k - 1] + t[k]);
            let mut ne = NormalEquations::<f64, 4>::new();
            for i in lo..=hi {
                let u = (t[i] - at) / dt;
                ne.update(&[1.0, u, u * u, u.max(0.0)], v[i] - v[j]);
            }
            let Ok(fit) = ne.solve() else { continue };
            let change = fit.theta[3] * sign;
            let right_way = if starts { change < 0.0 } else { change > 0.0 };
            if !right_way || change.abs() < 3.0 * fit.stderr[3] {
                continue;
            }
            let rss = ne.residual_sum_of_squares(&fit.theta);
            if best.is_none_or(|(b, _)| rss < b) {
                best = Some((rss, k));
            }
        }
        if let Some((_, k)) = best {
            for (i, o) in out.iter_mut().enumerate().take(k.max(j)).skip(k.min(j)) {
                *o = (i >= k) == starts;
            }
        }
    }
    out
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
            return Err(InputError::invalid(format!(
                "{} complete samples; a diagnosis needs at least {MIN_SAMPLES}",
                samples.len()
            )));
        }
        if let Some(k) = samples.windows(2).position(|w| w[1].t < w[0].t) {
            return Err(InputError::invalid(format!(
                "time goes backwards at sample {} (t = {} after {})",
                k + 2,
                samples[k + 1].t,
                samples[k].t
            )));
        }
        let t: Vec<f64> = samples.iter().map(|s| s.t).collect();
        let mut force: Vec<f64> = samples.iter().map(|s| s.force).collect();
        let force_updates = Updates::of(&t, &force);
        if let Some(u) = &force_updates {
            force = u.reconstruct(&t, &force);
        }
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
            return Err(InputError::invalid(
                "all samples have the same time".to_string(),
            ));
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
            .collect::<Vec<bool>>();
        let decelerating_at_kinks = at_kinks(&t, &velocity, &decelerating, 2 * h);
        let acceleration_noise = noise_of(&acceleration);
        let force_noise = noise_of(&force);
        let force_rate = local_slope(&t, &force, h);
        let jerk = local_slope(&t, &acceleration, h);
        let n = t.len();
        let force_steps = (1..n)
            .filter(|&i| steps_at(&t, &force, force_noise, i))
            .count()
            * 1000
            >= n;
        let top_speed = velocity.iter().fold(0.0f64, |m, w| m.max(w.abs()));
        Ok(Signals {
            top_speed,
            first,
            slope_half_width: h,
            log_speed: velocity.iter().map(|w| w.abs().ln()).collect(),
            force_rate,
            jerk,
            velocity,
            decelerating,
            decelerating_at_kinks,
            t,
            force,
            acceleration,
            position,
            rate,
            acceleration_noise,
            force_noise,
            force_updates,
            force_steps,
            excluded: 0..0,
        })
    }

    /// Instrument for Ḟ at sample `i`: the difference quotient of the force samples just outside
    /// the slope's window (independent noise, the same change).
    pub fn force_rate_instrument(&self, i: usize) -> f64 {
        instrument(&self.t, &self.force, self.slope_half_width + 1, i)
    }

    /// The same for ȧ, two samples further out than Ḟ's: an acceleration estimated by differencing a
    /// velocity carries noise correlated over the difference's span (a forward difference's
    /// noise at one sample's distance, a central difference's — `propid import`'s from an rpm
    /// column — at two), so the samples just outside the window share noise with its edge, and
    /// that noise is in the equation's left-hand side too. With them, a 10 ms acceleration filter
    /// on the independent stand (forward-difference noise) read −9.2 ms; beyond the span, 9.7–10.2
    /// ms on six seeds.
    pub fn jerk_instrument(&self, i: usize) -> f64 {
        instrument(&self.t, &self.acceleration, self.slope_half_width + 3, i)
    }

    /// How fast the rotor is slowing at sample `i` by its reported acceleration [rad/s²]
    /// (positive: slowing).
    pub fn slowing(&self, i: usize) -> f64 {
        -self.acceleration[i] * self.velocity[i].signum()
    }

    /// Whether the force steps between samples i − 1 and i: it changes by more than eight times
    /// its noise, and four times as fast as over either neighbouring interval (a step of the
    /// command, not a steep stretch of a smooth one, nor the longer interval of a lost message:
    /// compared as changes, 17 % lost messages made 21 "steps" in 12,318 samples of a sine).
    pub fn force_steps_at(&self, i: usize) -> bool {
        steps_at(&self.t, &self.force, self.force_noise, i)
    }

    /// Whether the force has steps at all (one in a thousand intervals at least); counted once,
    /// in [`Signals::new`].
    pub fn has_force_steps(&self) -> bool {
        self.force_steps
    }

    /// Number of samples.
    pub fn len(&self) -> usize {
        self.t.len()
    }

    /// `x` (one value per sample) as the load felt it if the sensor reports it `delay` seconds
    /// late: x(tᵢ + delay), linear between samples (as the simulation takes every input), held
    /// past the last sample.
    pub fn advanced(&self, x: &[f64], delay: f64) -> Vec<f64> {
        advanced(&self.t, x, delay)
    }

    /// `force` (one value per sample) through a causal first-order lag `lag` (see
    /// [`first_order_lag`]); with `steps_at_samples`, a step of the reported force (see
    /// [`Signals::force_steps_at`]) is taken to happen at the sample that first shows it: the old
    /// value holds over the interval before.
    pub fn lagged(&self, force: &[f64], lag: f64, steps_at_samples: bool) -> Vec<f64> {
        first_order_lag(&self.t, force, lag, |i| {
            steps_at_samples && self.force_steps_at(i)
        })
    }
}

/// exp(−dt/L) for the intervals of a log, whose dt barely changes from one sample to the next:
/// the exponential of the last interval, corrected by the series of exp(−δ/L) to third order
/// where δ = dt − dt_last is small (error below 10⁻⁶ relative), the exponential itself
/// otherwise. (One `exp` per sample was a tenth of a diagnosis.)
pub(crate) struct Decay {
    lag: f64,
    dt: f64,
    e: f64,
}

impl Decay {
    /// For time constant `lag`.
    pub fn new(lag: f64) -> Decay {
        Decay {
            lag,
            dt: f64::NAN,
            e: f64::NAN,
        }
    }

    /// exp(−dt/lag).
    #[inline]
    pub fn at(&mut self, dt: f64) -> f64 {
        let d = (dt - self.dt) / self.lag;
        if d.abs() < 0.02 {
            self.e * (1.0 - d * (1.0 - d * (0.5 - d / 6.0)))
        } else {
            self.dt = dt;
            self.e = (-dt / self.lag).exp();
            self.e
        }
    }
}

/// `x` (at times `t`) through a causal first-order lag of time constant `lag`, discretised with
/// a first-order hold (the input linear between samples, exact for a continuous input; a
/// zero-order hold would apply each sample over the interval before it and make every fitted lag
/// half a sample long), except where `step_at(i)`: there the old value holds over the interval
/// and the step happens at sample i.
pub(crate) fn first_order_lag(
    t: &[f64],
    x: &[f64],
    lag: f64,
    step_at: impl Fn(usize) -> bool,
) -> Vec<f64> {
    let mut out = Vec::with_capacity(x.len());
    if lag <= 0.0 || x.is_empty() {
        out.extend_from_slice(x);
        return out;
    }
    let mut y = x[0];
    out.push(y);
    let mut decay = Decay::new(lag);
    for i in 1..x.len() {
        let dt = t[i] - t[i - 1];
        let (x0, x1) = (x[i - 1], x[i]);
        if dt > 0.0 && step_at(i) {
            y = x0 + decay.at(dt) * (y - x0);
        } else if dt > 0.0 {
            // y' = (x − y)/L with x linear from x0 to x1 over dt, solved exactly.
            let e = decay.at(dt);
            let slope = (x1 - x0) / dt;
            y = x1 - lag * slope + e * (y - x0 + lag * slope);
        }
        out.push(y);
    }
    out
}

/// Whether `x` (noise σ `noise`) steps between samples i − 1 and i (see
/// [`Signals::force_steps_at`]).
fn steps_at(t: &[f64], x: &[f64], noise: f64, i: usize) -> bool {
    let n = x.len();
    if i == 0 || i >= n {
        return false;
    }
    let d = |k: usize| (x[k] - x[k - 1]).abs();
    let rate = |k: usize| {
        let dt = t[k] - t[k - 1];
        if dt > 0.0 {
            d(k) / dt
        } else {
            f64::INFINITY
        }
    };
    let before = if i >= 2 { rate(i - 1) } else { 0.0 };
    let after = if i + 1 < n { rate(i + 1) } else { 0.0 };
    d(i) > 8.0 * noise && rate(i) > 4.0 * before.max(after)
}

/// How a held signal updates: each value repeated over several rows until the sensor's next
/// reading.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Updates {
    /// Median interval between updates [s].
    pub interval: f64,
    /// Share of the rows that repeat the previous row's value exactly.
    pub repeated: f64,
}

impl Updates {
    /// Share of repeated rows from which a signal counts as held (a signal with noise never
    /// repeats a value; a quantised one at rest does, in long runs the interval test refuses).
    /// A sensor at f_s in rows at f_r > f_s repeats 1 − f_s/f_r of them: 5 % is a cell at
    /// 0.95 f_r, whose readings are late by 1/(2 f_s) read row by row against 1/(2 f_r) read
    /// as held, 5 % apart. (At 20 %, an 84 Hz cell in 100 Hz rows, repeating 16 %, was read row
    /// by row, 0.9 ms later than its rows say.) The real logs in tests/data repeat none.
    const MIN_REPEATED: f64 = 0.05;
    /// Longest update interval of a held sensor [s]: values constant for longer are a constant
    /// signal (a staircase command), not a slow sensor.
    const MAX_INTERVAL: f64 = 0.1;

    /// Measures whether `x` (at times `t`) is held: at least [`Self::MIN_REPEATED`] of its rows
    /// repeat the previous value, and its values change every [`Self::MAX_INTERVAL`] or sooner
    /// (median).
    fn of(t: &[f64], x: &[f64]) -> Option<Updates> {
        let n = x.len();
        // Counted first: a signal that does not repeat (every noisy one) costs one pass and no
        // vector of change indices (16 MB on a 2-million-row log).
        let changed = |i: &usize| x[*i] != x[*i - 1];
        let count = (1..n).filter(changed).count();
        let repeated = 1.0 - count as f64 / (n - 1).max(1) as f64;
        if repeated < Self::MIN_REPEATED || count < 10 {
            return None;
        }
        let changes: Vec<usize> = (1..n).filter(changed).collect();
        let mut intervals: Vec<f64> = changes.windows(2).map(|w| t[w[1]] - t[w[0]]).collect();
        let mid = intervals.len() / 2;
        let interval = *intervals.select_nth_unstable_by(mid, f64::total_cmp).1;
        (interval > 0.0 && interval <= Self::MAX_INTERVAL).then_some(Updates { interval, repeated })
    }

    /// The held signal `x` as the sensor read it: each value at the row that first shows it,
    /// linear between those rows. Where a value stays for more than three update intervals it
    /// is a constant stretch of the signal itself, and is kept.
    ///
    /// Why: a held sample is the sensor's reading of some moment in the interval before it first
    /// shows, repeated until the next one. Taken row by row, the staircase delays the signal by
    /// half the update interval on average and scatters that delay sample to sample by ±half,
    /// an error ∝ |Ẋ| that a model of the load then fits (a 56 Hz load cell in 100 Hz rows read
    /// as a force-sensor lag plus a drag exponent of 2.14).
    fn reconstruct(&self, t: &[f64], x: &[f64]) -> Vec<f64> {
        let n = x.len();
        let mut out = x.to_vec();
        let mut knot = 0;
        for i in 1..n {
            if x[i] == x[i - 1] {
                continue;
            }
            let span = t[i] - t[knot];
            if knot > 0 && span > 0.0 && span <= 3.0 * self.interval {
                for (k, y) in out.iter_mut().enumerate().take(i).skip(knot + 1) {
                    *y = x[knot] + (x[i] - x[knot]) * (t[k] - t[knot]) / span;
                }
            }
            knot = i;
        }
        out
    }
}

/// The force `delay` seconds after each sample, F(tᵢ + delay), linear between samples and
/// held past the last: the torque the load felt at tᵢ, if the sensor reports it `delay` late (a
/// held or transported sample).
pub(crate) fn advanced(t: &[f64], force: &[f64], delay: f64) -> Vec<f64> {
    let n = force.len();
    let mut j = 0;
    (0..n)
        .map(|i| {
            let target = t[i] + delay;
            while j + 1 < n && t[j + 1] <= target {
                j += 1;
            }
            if j + 1 >= n {
                return force[n - 1];
            }
            let dt = t[j + 1] - t[j];
            let w = if dt > 0.0 {
                ((target - t[j]) / dt).clamp(0.0, 1.0)
            } else {
                0.0
            };
            force[j] + w * (force[j + 1] - force[j])
        })
        .collect()
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

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_held_signal_is_measured_and_read_at_its_updates() {
        // A reading every 3 rows (1 ms rows), each shown first at rows 0, 3, 6, …
        let t: Vec<f64> = (0..60).map(|i| i as f64 * 1e-3).collect();
        let x: Vec<f64> = (0..60).map(|i| (i / 3) as f64).collect();
        let u = Updates::of(&t, &x).expect("held");
        assert!((u.interval - 3e-3).abs() < 1e-12, "{u:?}");
        assert!((u.repeated - 40.0 / 59.0).abs() < 1e-12, "{u:?}");
        let y = u.reconstruct(&t, &x);
        // Before the first update the start is unknown: kept. Then linear between updates.
        assert_eq!(&y[..4], &[0.0, 0.0, 0.0, 1.0]);
        assert!((y[4] - 4.0 / 3.0).abs() < 1e-12 && (y[5] - 5.0 / 3.0).abs() < 1e-12);
        assert_eq!(y[6], 2.0);
        // After the last update nothing follows: kept.
        assert_eq!(&y[57..], &[19.0, 19.0, 19.0]);
    }

    #[test]
    fn a_noisy_or_slow_staircase_is_not_a_held_sensor() {
        let t: Vec<f64> = (0..600).map(|i| i as f64 * 1e-3).collect();
        // Every row new: not held.
        let noisy: Vec<f64> = (0..600).map(|i| ((i * 7919) % 101) as f64).collect();
        assert_eq!(Updates::of(&t, &noisy), None);
        // A command held 0.2 s at a time: a constant signal, not a slow sensor.
        let staircase: Vec<f64> = (0..600).map(|i| (i / 200) as f64).collect();
        assert_eq!(Updates::of(&t, &staircase), None);
    }

    #[test]
    fn a_long_constant_stretch_is_kept_in_a_held_signal() {
        // Updates every 2 rows, then one value for 20 rows (longer than three intervals).
        let t: Vec<f64> = (0..60).map(|i| i as f64 * 1e-3).collect();
        let mut x: Vec<f64> = (0..60).map(|i| (i / 2) as f64).collect();
        for v in &mut x[30..50] {
            *v = 15.0;
        }
        let u = Updates::of(&t, &x).expect("held");
        let y = u.reconstruct(&t, &x);
        assert!(y[30..50].iter().all(|v| *v == 15.0), "{:?}", &y[30..50]);
        assert_eq!(y[29], 14.5);
    }

    #[test]
    fn the_advanced_force_is_linear_between_samples_and_held_past_the_end() {
        let t = [0.0, 1.0, 2.0, 3.0];
        let f = [0.0, 10.0, 20.0, 40.0];
        assert_eq!(advanced(&t, &f, 0.25), vec![2.5, 12.5, 25.0, 40.0]);
        assert_eq!(advanced(&t, &f, 1.5), vec![15.0, 30.0, 40.0, 40.0]);
    }
}
