//! Structure left in a residual: its spectrum, its correlation with the rotor angle's
//! harmonics, and where in time or in which operating condition the held-out error sits.
//!
//! Where the error sits is searched over the whole record: every sample's residual is predicted
//! by the model fitted on the folds that do not hold it, so a load transient early in a run is
//! seen as well as one late.

use std::ops::Range;

use serde::Serialize;

use super::signals::Signals;
use super::tune::golden;

/// An operating condition, or a window of time, where the remaining error concentrates.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize)]
#[serde(rename_all = "snake_case")]
pub enum Condition {
    /// While the rotor slows down.
    Decelerating,
    /// The lowest third of the speeds.
    LowSpeed,
    /// The highest third of the speeds.
    HighSpeed,
    /// A window of time.
    TimeWindow,
}

impl Condition {
    /// In words, for a sentence ("while decelerating").
    pub fn words(self) -> &'static str {
        match self {
            Condition::Decelerating => "decelerating",
            Condition::LowSpeed => "at low speed",
            Condition::HighSpeed => "at high speed",
            Condition::TimeWindow => "in a window of time",
        }
    }
}

/// Where the remaining held-out error concentrates, when it does.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct Concentration {
    /// The operating condition or time window.
    pub condition: Condition,
    /// Share of the held-out squared acceleration error in it [%].
    pub error_percent: f64,
    /// Share of the samples in it [%].
    pub samples_percent: f64,
    /// Its mean squared error over the mean squared error of the rest of the record.
    pub ratio: f64,
    /// Start of the time window [s] (for a condition: the record's).
    pub from_s: f64,
    /// End [s].
    pub to_s: f64,
}

/// A span of time the extended model was fitted without: an event there that the model does not
/// hold (a load transient, a gust, a touch), whose samples would bias every parameter.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct LeftOut {
    /// Start of the span [s].
    pub from_s: f64,
    /// End of the span [s].
    pub to_s: f64,
    /// Samples left out.
    pub samples: usize,
    /// Their indices in the signals (what the second diagnosis excludes).
    #[serde(skip)]
    pub(crate) rows: Range<usize>,
    /// J fitted with them [kg·m²].
    pub inertia_with: f64,
    /// c2 (or its quadratic equivalent) fitted with them [N·m·s²/rad²].
    pub c2_with: f64,
}

/// Windows of time the record is searched in (each 1/`WINDOWS` of it, slid by half a window).
pub const WINDOWS: usize = 30;

/// A condition or window is reported when its mean squared held-out error is at least this many
/// times that of the rest of the record (a third of the speeds holding two thirds of the error;
/// the old rule's share of 40 % in a tenth of the held-out time was 6×).
pub const CONCENTRATION_RATIO: f64 = 4.0;

/// Where the squared held-out residual `r` (index 0 = sample `s.first`) concentrates: the
/// condition or window whose mean squared error is the largest multiple of the rest's, if that
/// multiple is at least [`CONCENTRATION_RATIO`].
pub(crate) fn concentration(s: &Signals, r: &[f64]) -> Option<Concentration> {
    let n = r.len();
    let first = s.first;
    if n < 100 {
        return None;
    }
    let total: f64 = r.iter().map(|x| x * x).sum();
    if total <= 0.0 || !total.is_finite() {
        return None;
    }
    let mut speeds: Vec<f64> = s.velocity[first..first + n]
        .iter()
        .map(|w| w.abs())
        .collect();
    speeds.sort_by(f64::total_cmp);
    let (low, high) = (speeds[n / 3], speeds[2 * n / 3]);
    let (t0, t1) = (s.t[first], s.t[first + n - 1]);
    let measure = |condition: Condition, inside: &dyn Fn(usize) -> bool, from: f64, to: f64| {
        let (mut e, mut k) = (0.0, 0usize);
        for (j, x) in r.iter().enumerate() {
            if inside(first + j) {
                e += x * x;
                k += 1;
            }
        }
        let (rest_e, rest_k) = (total - e, n - k);
        let ratio = if k == 0 || rest_k == 0 {
            0.0
        } else {
            (e / k as f64) / (rest_e / rest_k as f64).max(f64::MIN_POSITIVE)
        };
        Concentration {
            condition,
            error_percent: 100.0 * e / total,
            samples_percent: 100.0 * k as f64 / n as f64,
            ratio,
            from_s: from,
            to_s: to,
        }
    };
    let mut found = vec![
        measure(Condition::Decelerating, &|i| s.decelerating[i], t0, t1),
        measure(Condition::LowSpeed, &|i| s.velocity[i].abs() < low, t0, t1),
        measure(
            Condition::HighSpeed,
            &|i| s.velocity[i].abs() > high,
            t0,
            t1,
        ),
    ];
    let width = n / WINDOWS;
    if width >= 10 {
        for w in 0..2 * WINDOWS - 1 {
            let (a, b) = (
                first + w * width / 2,
                (first + w * width / 2 + width).min(first + n),
            );
            found.push(measure(
                Condition::TimeWindow,
                &|i| (a..b).contains(&i),
                s.t[a],
                s.t[b - 1],
            ));
        }
    }
    found
        .into_iter()
        .filter(|c| c.ratio >= CONCENTRATION_RATIO)
        .max_by(|a, b| a.ratio.total_cmp(&b.ratio))
}

/// The most of the record an event's span may take: beyond it the error is not an event in time
/// but the model's, and leaving its samples out would only hide it.
pub const EVENT_SHARE: f64 = 0.1;

/// Where a time-window concentration `c` of the held-out residual `r` (index 0 = sample
/// `s.first`) begins and ends, in samples: the window is cut into eight bins, and the span runs
/// from the first to the last bin whose mean squared error is at least [`CONCENTRATION_RATIO`]
/// times the rest of the record's, grown bin by bin beyond the window while the next bin is too.
/// A bin half covered by an event five times the noise holds 13 times the rest's error; one of
/// pure noise of 25 samples exceeds four times it with a probability below 10⁻⁵. `None` for a
/// condition, or a span longer than [`EVENT_SHARE`] of the record.
pub(crate) fn event_span(s: &Signals, r: &[f64], c: &Concentration) -> Option<Range<usize>> {
    if c.condition != Condition::TimeWindow {
        return None;
    }
    let first = s.first;
    let n = r.len();
    let index = |t: f64| s.t[first..first + n].partition_point(|&x| x < t);
    let (a, b) = (index(c.from_s), (index(c.to_s) + 1).min(n));
    let bin = ((b - a) / 8).max(25);
    if b <= a || n < 4 * bin {
        return None;
    }
    let inside: f64 = r[a..b].iter().map(|x| x * x).sum();
    let total: f64 = r.iter().map(|x| x * x).sum();
    let rest = (total - inside) / (n - (b - a)).max(1) as f64;
    let raised = |k: isize| -> bool {
        let lo = a as isize + k * bin as isize;
        let hi = lo + bin as isize;
        if lo < 0 || hi > n as isize {
            return false;
        }
        let e: f64 = r[lo as usize..hi as usize].iter().map(|x| x * x).sum();
        e / bin as f64 >= CONCENTRATION_RATIO * rest
    };
    let bins = ((b - a) / bin) as isize;
    let marked: Vec<isize> = (0..bins).filter(|&k| raised(k)).collect();
    let (mut lo, mut hi) = match (marked.first(), marked.last()) {
        (Some(&f), Some(&l)) => (f, l),
        _ => return None,
    };
    while raised(lo - 1) {
        lo -= 1;
    }
    while raised(hi + 1) {
        hi += 1;
    }
    let from = (a as isize + lo * bin as isize) as usize;
    let to = (a as isize + (hi + 1) * bin as isize) as usize;
    ((to - from) as f64 <= EVENT_SHARE * n as f64).then_some(first + from..first + to)
}

/// Pearson correlations of `r` with sin(kx) and cos(kx) of the rotor angle x, for k = 1…K, in
/// one pass: sin(kx), cos(kx) by the angle-addition recurrence from sin x, cos x (two trig calls
/// per sample instead of 2K, and no column per harmonic).
pub(crate) fn harmonic_correlations<const K: usize>(r: &[f64], x: &[f64]) -> [(f64, f64); K] {
    #[derive(Clone, Copy, Default)]
    struct Sums {
        v: f64,
        vv: f64,
        rv: f64,
    }
    let (mut sr, mut srr) = (0.0, 0.0);
    let mut sums = [[Sums::default(); 2]; K];
    let n = r.len().min(x.len());
    for (ri, xi) in r.iter().zip(x) {
        sr += ri;
        srr += ri * ri;
        let (s1, c1) = xi.sin_cos();
        let (mut sk, mut ck) = (s1, c1);
        for pair in sums.iter_mut() {
            for (acc, v) in pair.iter_mut().zip([sk, ck]) {
                acc.v += v;
                acc.vv += v * v;
                acc.rv += ri * v;
            }
            (sk, ck) = (sk * c1 + ck * s1, ck * c1 - sk * s1);
        }
    }
    let nf = n as f64;
    let corr = |a: &Sums| {
        let sxy = a.rv - sr * a.v / nf;
        let sxx = srr - sr * sr / nf;
        let syy = a.vv - a.v * a.v / nf;
        if n < 2 || sxx <= 0.0 || syy <= 0.0 {
            0.0
        } else {
            sxy / (sxx * syy).sqrt()
        }
    };
    core::array::from_fn(|k| (corr(&sums[k][0]), corr(&sums[k][1])))
}

/// Power of the (mean-removed) `r` at `f` [Hz], on the uniform time grid of the median rate.
fn power_at(r: &[f64], mean: f64, rate: f64, f: f64) -> f64 {
    let w = std::f64::consts::TAU * f / rate;
    let (sw, cw) = w.sin_cos();
    let (mut c, mut si, mut re, mut im) = (1.0f64, 0.0f64, 0.0, 0.0);
    for x in r {
        re += (x - mean) * c;
        im += (x - mean) * si;
        let c2 = c * cw - si * sw;
        si = si * cw + c * sw;
        c = c2;
    }
    re * re + im * im
}

/// The share of `x`'s variance (sampled at `rate`) that one sinusoid at `f` carries: 1 for a
/// pure sinusoid there, near 0 where `x` has no component at `f`.
pub(crate) fn sinusoid_share(x: &[f64], rate: f64, f: f64) -> f64 {
    let n = x.len() as f64;
    let mean = x.iter().sum::<f64>() / n.max(1.0);
    let variance: f64 = x.iter().map(|v| (v - mean) * (v - mean)).sum();
    if variance <= 0.0 {
        return 0.0;
    }
    2.0 * power_at(x, mean, rate, f) / (n * variance)
}

/// The largest peak of the residual's spectrum between 2/T and min(rate/2, 60 Hz): its frequency
/// and its power over the median power of the bins in that band. The spectrum is one real FFT of
/// the mean-removed residual, taken on the uniform grid of the median rate and zero-padded to at
/// least twice its length (bins at most half the resolution 1/T apart); the peak frequency is then
/// refined between its neighbours with the exact DFT. O(n log n) time, 2n + O(1) extra f64s.
pub(crate) fn periodogram(s: &Signals, r: &[f64]) -> (f64, f64) {
    let duration = (s.t[s.len() - 1] - s.t[0]).max(1e-9);
    let (fmin, fmax) = (2.0 / duration, (s.rate / 2.0).min(60.0));
    let mean = r.iter().sum::<f64>() / r.len() as f64;
    let m = (2 * r.len()).next_power_of_two().max(256);
    // In f32: half the memory of f64 (the transform is the largest buffer of a long log), and
    // ample for locating a peak 40× over the median; its height is then measured in f64.
    let fft = realfft::RealFftPlanner::<f32>::new().plan_fft_forward(m);
    let mut input = fft.make_input_vec();
    for (x, v) in input.iter_mut().zip(r) {
        *x = (v - mean) as f32;
    }
    let mut spectrum = fft.make_output_vec();
    // Cannot fail: both buffers come from the plan itself.
    if fft.process(&mut input, &mut spectrum).is_err() {
        return (0.0, 0.0);
    }
    drop(input);
    let df = s.rate / m as f64;
    let k0 = ((fmin / df).ceil() as usize).max(1);
    let k1 = ((fmax / df).floor() as usize)
        .min(spectrum.len() - 1)
        .max(k0);
    let powers: Vec<f64> = spectrum[k0..=k1]
        .iter()
        .map(|c| f64::from(c.norm_sqr()))
        .collect();
    drop(spectrum);
    let (peak_k, peak_p) = powers
        .iter()
        .copied()
        .enumerate()
        .max_by(|a, b| a.1.total_cmp(&b.1))
        .unwrap_or((0, 0.0));
    let mut sorted = powers;
    let mid = sorted.len() / 2;
    let median = *sorted.select_nth_unstable_by(mid, f64::total_cmp).1;
    let median = median.max(f64::MIN_POSITIVE);
    let peak_f = (k0 + peak_k) as f64 * df;
    let f = golden(
        peak_f - df,
        peak_f + df,
        |f| -power_at(r, mean, s.rate, f),
        20,
    );
    let p = power_at(r, mean, s.rate, f).max(peak_p);
    (f, p / median)
}
