//! Steady plateaus and the load cells' zero.
//!
//! A row is *steady* when the speed over the `settle` seconds before it stayed within a band of
//! `tolerance` × speed (or eight times the speed's noise, whichever is wider): the rotor has
//! reached its speed and a load cell behind it has settled. A *plateau* is a run of steady rows
//! lasting at least `min_duration`; its last quarter-`settle` is cut (the command has changed a
//! little before the speed leaves the band). On each plateau every channel is averaged over its own
//! samples (a slow load cell logs a few per second, the speed every row), with a standard error
//! that counts only independent samples: repeated values of a held sensor count once, and the
//! lag-1 autocorrelation of what remains reduces the count further (n_eff = n(1 − r)/(1 + r)).
//! Rest rows within [`REST_MARGIN`] of the motion are not used for the zero: the command has
//! already changed before the speed leaves the rest band.
//!
//! ## The zero of a load cell
//! A thrust or torque cell reads something at rest, and that something drifts while the motor
//! warms its mount. The rows at rest before the first spin-up and after the last stop give two
//! zeros; between them the zero is taken as linear in time, and the difference between them, as
//! a uniform uncertainty of the zero, has a standard deviation of |z_end − z_start|/√12 that
//! enters every coefficient as a systematic error. With one rest segment the zero is that
//! segment's mean and its drift is unknown (said so); with none the zero is fitted with the law.

use serde::{Deserialize, Serialize};

use super::Recording;

/// Which measured channel.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum Channel {
    /// Thrust [N].
    Thrust,
    /// Shaft torque [N·m].
    Torque,
    /// DC bus voltage [V].
    Voltage,
    /// DC bus current [A].
    Current,
    /// Duty (ratio 0–1).
    Duty,
}

impl Channel {
    /// Every channel.
    pub const ALL: [Channel; 5] = [
        Channel::Thrust,
        Channel::Torque,
        Channel::Voltage,
        Channel::Current,
        Channel::Duty,
    ];

    /// Its name in messages and in the TSV.
    pub fn name(self) -> &'static str {
        match self {
            Channel::Thrust => "thrust",
            Channel::Torque => "torque",
            Channel::Voltage => "voltage",
            Channel::Current => "current",
            Channel::Duty => "duty",
        }
    }

    /// Its unit.
    pub fn unit(self) -> &'static str {
        match self {
            Channel::Thrust => "N",
            Channel::Torque => "N·m",
            Channel::Voltage => "V",
            Channel::Current => "A",
            Channel::Duty => "1",
        }
    }

    /// Whether a load cell measures it (zero offset and drift apply).
    pub fn has_zero(self) -> bool {
        matches!(self, Channel::Thrust | Channel::Torque)
    }
}

/// How plateaus are found.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct PlateauOptions {
    /// Time the speed must have been steady before a row counts [s].
    pub settle: f64,
    /// Relative width of the band the speed must stay in.
    pub tolerance: f64,
    /// Shortest plateau (steady rows) [s].
    pub min_duration: f64,
    /// Speeds below this fraction of the top speed are not plateaus (the rotor at rest or
    /// idling).
    pub min_speed: f64,
}

impl Default for PlateauOptions {
    fn default() -> Self {
        PlateauOptions {
            settle: 1.0,
            tolerance: 0.02,
            min_duration: 0.5,
            min_speed: 0.05,
        }
    }
}

/// A mean with its standard error.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct Mean {
    /// The mean.
    pub value: f64,
    /// Its standard error (independent samples only).
    pub stderr: f64,
    /// Independent samples behind it.
    pub samples: usize,
}

/// One steady plateau.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct Plateau {
    /// First steady row's time [s].
    pub start: f64,
    /// Last steady row's time [s].
    pub end: f64,
    /// Mean speed [rad/s].
    pub speed: Mean,
    /// Thrust, zero-corrected [N].
    pub thrust: Option<Mean>,
    /// Torque, zero-corrected [N·m].
    pub torque: Option<Mean>,
    /// Bus voltage [V].
    pub voltage: Option<Mean>,
    /// Bus current [A].
    pub current: Option<Mean>,
    /// Duty.
    pub duty: Option<Mean>,
    /// Mean electrical power V·I over the plateau's rows [W].
    pub electrical_power: Option<Mean>,
}

impl Plateau {
    /// A channel's mean.
    pub fn get(&self, c: Channel) -> Option<Mean> {
        match c {
            Channel::Thrust => self.thrust,
            Channel::Torque => self.torque,
            Channel::Voltage => self.voltage,
            Channel::Current => self.current,
            Channel::Duty => self.duty,
        }
    }

    fn set(&mut self, c: Channel, m: Option<Mean>) {
        match c {
            Channel::Thrust => self.thrust = m,
            Channel::Torque => self.torque = m,
            Channel::Voltage => self.voltage = m,
            Channel::Current => self.current = m,
            Channel::Duty => self.duty = m,
        }
    }
}

/// Time left out of a rest segment next to the motion [s].
pub const REST_MARGIN: f64 = 0.5;

/// A load cell's zero as the rest segments show it.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
#[serde(tag = "from", rename_all = "snake_case")]
pub enum Zero {
    /// Rest before and after: linear in time between them.
    Drifting {
        /// Mean at the rest before the run.
        start: f64,
        /// Time at which the start rest ends [s].
        start_time: f64,
        /// Mean at the rest after the run.
        end: f64,
        /// Time at which the end rest begins [s].
        end_time: f64,
        /// Standard uncertainty of the zero: |end − start|/√12 and the means' own errors.
        stderr: f64,
    },
    /// One rest segment: its mean, drift unknown.
    Constant {
        /// The mean at rest.
        value: f64,
        /// Its standard error.
        stderr: f64,
    },
    /// No rest segment: the zero is not measured.
    Unknown,
}

impl Zero {
    /// The zero at time `t`.
    pub fn at(&self, t: f64) -> f64 {
        match *self {
            Zero::Drifting {
                start,
                start_time,
                end,
                end_time,
                ..
            } => {
                let f = if end_time > start_time {
                    ((t - start_time) / (end_time - start_time)).clamp(0.0, 1.0)
                } else {
                    0.5
                };
                start + f * (end - start)
            }
            Zero::Constant { value, .. } => value,
            Zero::Unknown => 0.0,
        }
    }

    /// Standard uncertainty of the zero (0 when unknown: the fit then carries it).
    pub fn stderr(&self) -> f64 {
        match *self {
            Zero::Drifting { stderr, .. } | Zero::Constant { stderr, .. } => stderr,
            Zero::Unknown => 0.0,
        }
    }

    /// "zero +1.2 → +22.7 gf-equivalent …" in the channel's unit.
    pub fn describe(&self, unit: &str) -> String {
        match *self {
            Zero::Drifting {
                start, end, stderr, ..
            } => format!(
                "zero {start:+.4} {unit} at rest before, {end:+.4} {unit} after (taken as linear in time; ± {stderr:.4} {unit})"
            ),
            Zero::Constant { value, stderr } => format!(
                "zero {value:+.4} ± {stderr:.4} {unit} at rest (one rest segment: its drift is not known)"
            ),
            Zero::Unknown => "no rows at rest: the zero is fitted with the law".into(),
        }
    }
}

/// Plateaus and zeros of a recording.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct Steady {
    /// The plateaus, in time order.
    pub plateaus: Vec<Plateau>,
    /// The thrust cell's zero.
    pub thrust_zero: Option<Zero>,
    /// The torque cell's zero.
    pub torque_zero: Option<Zero>,
    /// Noise of the speed (standard deviation) [rad/s], from successive differences.
    pub speed_noise: f64,
    /// Highest speed [rad/s].
    pub top_speed: f64,
}

/// Standard deviation of white noise on `x` from the median absolute second difference
/// x[k+1] − 2x[k] + x[k−1] (which a signal changing smoothly between rows hardly moves, unlike a
/// first difference on a fast run): for Gaussian noise its median is 0.6745·√6·σ.
pub(crate) fn noise_of(x: &[f64]) -> f64 {
    let mut d: Vec<f64> = x
        .windows(3)
        .map(|w| (w[2] - 2.0 * w[1] + w[0]).abs())
        .filter(|v| v.is_finite())
        .collect();
    if d.is_empty() {
        return 0.0;
    }
    d.sort_by(f64::total_cmp);
    d[d.len() / 2] / (0.6745 * 6f64.sqrt())
}

/// Mean and standard error of the independent samples in `values` (a held value repeated in
/// consecutive rows counts once). A value held throughout (at least three rows) has a standard
/// error of 0; otherwise `None` with fewer than three independent samples.
pub fn mean_of(values: impl Iterator<Item = f64>) -> Option<Mean> {
    let mut v: Vec<f64> = Vec::new();
    let mut raw = 0usize;
    for x in values.filter(|x| x.is_finite()) {
        raw += 1;
        if v.last() != Some(&x) {
            v.push(x);
        }
    }
    let n = v.len();
    if n == 1 && raw >= 3 {
        // A value held throughout (a command, a quantised reading): no scatter to measure.
        return Some(Mean {
            value: v[0],
            stderr: 0.0,
            samples: 1,
        });
    }
    if n < 3 {
        return None;
    }
    let m = v.iter().sum::<f64>() / n as f64;
    let var = v.iter().map(|x| (x - m).powi(2)).sum::<f64>() / (n - 1) as f64;
    // Lag-1 autocorrelation of the deviations.
    let c1: f64 = v.windows(2).map(|w| (w[0] - m) * (w[1] - m)).sum::<f64>();
    let c0: f64 = v.iter().map(|x| (x - m).powi(2)).sum::<f64>();
    let r = if c0 > 0.0 {
        (c1 / c0).clamp(0.0, 0.95)
    } else {
        0.0
    };
    let n_eff = (n as f64 * (1.0 - r) / (1.0 + r)).max(2.0);
    Some(Mean {
        value: m,
        stderr: (var / n_eff).sqrt(),
        samples: n,
    })
}

/// The zero of a load-cell channel from the rows at rest before the first and after the last
/// motion.
fn zero_of(rec: &Recording, values: &[f64], moving: &[bool]) -> Zero {
    let first = moving.iter().position(|&m| m);
    let last = moving.iter().rposition(|&m| m);
    let (Some(first), Some(last)) = (first, last) else {
        return Zero::Unknown;
    };
    // The rows just before the speed rises past the rest limit already carry the motor's torque
    // (and after the stop, the cells still ring): a margin of REST_MARGIN is left out on both
    // sides of the motion.
    let t = &rec.time;
    let before_end = t[first] - REST_MARGIN;
    let after_start = t[last] + REST_MARGIN;
    let before = mean_of((0..first).filter(|&k| t[k] < before_end).map(|k| values[k]));
    let after = mean_of(
        (last + 1..values.len())
            .filter(|&k| t[k] > after_start)
            .map(|k| values[k]),
    );
    match (before, after) {
        (Some(b), Some(a)) => {
            let drift = (a.value - b.value).abs() / 12f64.sqrt();
            let own = 0.5 * (a.stderr.powi(2) + b.stderr.powi(2)).sqrt();
            Zero::Drifting {
                start: b.value,
                start_time: rec.time[first],
                end: a.value,
                end_time: rec.time[last],
                stderr: (drift * drift + own * own).sqrt(),
            }
        }
        (Some(m), None) | (None, Some(m)) => Zero::Constant {
            value: m.value,
            stderr: m.stderr,
        },
        (None, None) => Zero::Unknown,
    }
}

/// Finds the plateaus and the zeros.
pub fn find(rec: &Recording, options: &PlateauOptions) -> Steady {
    let n = rec.time.len();
    let speed = &rec.speed;
    let top = speed
        .iter()
        .map(|w| w.abs())
        .filter(|w| w.is_finite())
        .fold(0.0, f64::max);
    let noise = noise_of(speed);
    // At rest: below 1 % of the top speed (or the noise).
    let rest_limit = (0.01 * top).max(4.0 * noise);
    let moving: Vec<bool> = speed
        .iter()
        .map(|w| w.is_finite() && w.abs() > rest_limit)
        .collect();
    let zero = |c: Channel| rec.channel(c).map(|v| zero_of(rec, v, &moving));
    let thrust_zero = zero(Channel::Thrust);
    let torque_zero = zero(Channel::Torque);

    // Steady rows: a sliding window [t − settle, t] with its speed range (monotone deques).
    let mut steady = vec![false; n];
    let mut maxq: std::collections::VecDeque<usize> = Default::default();
    let mut minq: std::collections::VecDeque<usize> = Default::default();
    let mut lo = 0;
    for k in 0..n {
        let w = speed[k];
        if !w.is_finite() {
            maxq.clear();
            minq.clear();
            lo = k + 1;
            continue;
        }
        while maxq.back().is_some_and(|&j| speed[j] <= w) {
            maxq.pop_back();
        }
        maxq.push_back(k);
        while minq.back().is_some_and(|&j| speed[j] >= w) {
            minq.pop_back();
        }
        minq.push_back(k);
        while rec.time[lo] < rec.time[k] - options.settle {
            lo += 1;
        }
        while maxq.front().is_some_and(|&j| j < lo) {
            maxq.pop_front();
        }
        while minq.front().is_some_and(|&j| j < lo) {
            minq.pop_front();
        }
        let (Some(&hi_i), Some(&lo_i)) = (maxq.front(), minq.front()) else {
            continue;
        };
        let covered = rec.time[k] - rec.time[lo.min(k)] >= 0.95 * options.settle;
        let band = (options.tolerance * w.abs()).max(8.0 * noise);
        steady[k] =
            covered && w.abs() > options.min_speed * top && speed[hi_i] - speed[lo_i] <= band;
    }

    let mut plateaus = Vec::new();
    let mut k = 0;
    while k < n {
        if !steady[k] {
            k += 1;
            continue;
        }
        let mut j = k;
        while j + 1 < n && steady[j + 1] {
            j += 1;
        }
        let next = j + 1;
        // The rows just before the speed leaves the band already follow the next command (the
        // speed needs tens of milliseconds to move 2 %): a quarter of the settling time is cut.
        let end_time = rec.time[j] - 0.25 * options.settle;
        while j > k && rec.time[j] > end_time {
            j -= 1;
        }
        if rec.time[j] - rec.time[k] >= options.min_duration {
            plateaus.push(plateau(rec, k, j, thrust_zero, torque_zero));
        }
        k = next;
    }
    Steady {
        plateaus,
        thrust_zero,
        torque_zero,
        speed_noise: noise,
        top_speed: top,
    }
}

fn plateau(
    rec: &Recording,
    a: usize,
    b: usize,
    thrust_zero: Option<Zero>,
    torque_zero: Option<Zero>,
) -> Plateau {
    let speed = mean_of(rec.speed[a..=b].iter().copied()).unwrap_or(Mean {
        value: rec.speed[a..=b].iter().sum::<f64>() / (b - a + 1) as f64,
        stderr: 0.0,
        samples: b - a + 1,
    });
    let mut p = Plateau {
        start: rec.time[a],
        end: rec.time[b],
        speed,
        thrust: None,
        torque: None,
        voltage: None,
        current: None,
        duty: None,
        electrical_power: None,
    };
    for c in Channel::ALL {
        let Some(values) = rec.channel(c) else {
            continue;
        };
        let zero = match c {
            Channel::Thrust => thrust_zero,
            Channel::Torque => torque_zero,
            _ => None,
        };
        let m = mean_of((a..=b).map(|i| {
            values[i]
                - zero.map_or(0.0, |z| {
                    if values[i].is_finite() {
                        z.at(rec.time[i])
                    } else {
                        0.0
                    }
                })
        }));
        p.set(c, m);
    }
    if let (Some(v), Some(i)) = (rec.channel(Channel::Voltage), rec.channel(Channel::Current)) {
        p.electrical_power = mean_of((a..=b).map(|k| v[k] * i[k]));
    }
    p
}

#[cfg(test)]
mod tests {
    use super::*;

    fn staircase() -> Recording {
        // 2 s at rest, then 4 s at each of 100, 200, 300 rad/s with 0.3 s ramps, 2 s at rest.
        let mut rec = Recording::new(Vec::new(), Vec::new());
        let mut thrust = Vec::new();
        let dt: f64 = 0.01;
        let levels = [0.0, 100.0, 200.0, 300.0, 0.0];
        let mut w: f64 = 0.0;
        let mut t = 0.0;
        for (k, &target) in levels.iter().enumerate() {
            let hold = if k == 0 || k == 4 { 2.0 } else { 4.0 };
            let steps = (hold / dt) as usize;
            for _ in 0..steps {
                w += (target - w) * (dt / 0.1).min(1.0);
                rec.time.push(t);
                rec.speed.push(w);
                rec.acceleration.push(f64::NAN);
                // A thrust cell with a zero drifting from 0.01 to 0.03 N over the run.
                thrust.push(
                    1e-5 * w * w + 0.01 + 0.02 * t / 16.0 + 0.001 * ((k * 7 + steps) as f64).sin(),
                );
                t += dt;
            }
        }
        rec.thrust = Some(thrust);
        rec
    }

    #[test]
    fn finds_each_held_speed_and_the_drifting_zero() {
        let rec = staircase();
        let s = find(&rec, &PlateauOptions::default());
        assert_eq!(s.plateaus.len(), 3, "{:?}", s.plateaus);
        for (p, w) in s.plateaus.iter().zip([100.0, 200.0, 300.0]) {
            assert!((p.speed.value - w).abs() < 0.01, "{p:?}");
            let t = p.thrust.unwrap();
            assert!((t.value - 1e-5 * w * w).abs() < 2e-3, "{t:?} at {w}");
        }
        match s.thrust_zero.unwrap() {
            Zero::Drifting { start, end, .. } => {
                assert!((start - 0.0113).abs() < 0.003 && (end - 0.0287).abs() < 0.003)
            }
            z => panic!("{z:?}"),
        }
    }

    #[test]
    fn a_held_sensor_counts_each_reading_once() {
        let m = mean_of([1.0, 1.0, 1.0, 2.0, 2.0, 3.0, 3.0, 3.0].into_iter()).unwrap();
        assert_eq!(m.samples, 3);
        assert!((m.value - 2.0).abs() < 1e-12);
        assert_eq!(mean_of([1.0, 1.0, 1.0].into_iter()).unwrap().stderr, 0.0);
        assert!(mean_of([1.0, 2.0].into_iter()).is_none());
    }
}
