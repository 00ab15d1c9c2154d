//! Setpoint patterns (any `Fn(f64) -> f64` will do; these are the ones propid drives).
//!
//! Written from the seed's description, not from propid's excitation code: the sine is the seed's
//! `np.interp(sin(2π t / period), (−1, 1), (lo, hi))`.

use std::f64::consts::TAU;

fn lerp(lo: f64, hi: f64, s: f64) -> f64 {
    lo + (hi - lo) * (s + 1.0) / 2.0
}

/// The seed's sinusoid between `lo` and `hi` with the given period [s].
pub fn sine(lo: f64, hi: f64, period: f64) -> impl Fn(f64) -> f64 {
    move |t| lerp(lo, hi, (TAU * t / period).sin())
}

/// A linear sine sweep between `lo` and `hi` from `1/period` to `10/period` Hz over `duration` s.
pub fn chirp(lo: f64, hi: f64, period: f64, duration: f64) -> impl Fn(f64) -> f64 {
    let (f0, f1) = (1.0 / period, 10.0 / period);
    move |t| {
        lerp(
            lo,
            hi,
            (TAU * (f0 * t + (f1 - f0) * t * t / (2.0 * duration))).sin(),
        )
    }
}

/// A staircase between `lo` and `hi`: 0, ¼, ½, ¾, 1, ¾, ½, ¼ of the range, each held `period/2`.
pub fn steps(lo: f64, hi: f64, period: f64) -> impl Fn(f64) -> f64 {
    const LEVELS: [f64; 8] = [0.0, 0.25, 0.5, 0.75, 1.0, 0.75, 0.5, 0.25];
    move |t| {
        let k = (t / (period / 2.0)).floor().max(0.0) as usize % LEVELS.len();
        lo + (hi - lo) * LEVELS[k]
    }
}

/// A constant setpoint.
pub fn constant(value: f64) -> impl Fn(f64) -> f64 {
    move |_| value
}
