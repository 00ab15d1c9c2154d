//! The limits that stop a runaway rotor: a maximum speed, a soft start, a speed watchdog.
//!
//! ```text
//!  soft start   a low setpoint in the direction of hi for a short time, before any high torque:
//!               at its end the feedback must have arrived and the rotor must have sped up the
//!               commanded way, with the reported torque of the command's sign; else the stop
//!               says which (no feedback, the wrong way, not at all, the torque reported reversed).
//!               The watchdog runs meanwhile: a rotor speeding up against the torque stops it at
//!               once, in the soft start's words
//!  ramp         (optional) from the soft start's setpoint to hi, linearly
//!  max speed    |ω| above the maximum in two consecutive samples
//!  watchdog     the speed may only grow as far as the torque the drive reports can drive it:
//!                 d|ω|/dt = (sign(ω)·τ − drag) / J  ≤  max(sign(ω)·τ, 0) / J_min
//!               (drag never helps the rotor along). So Q = |ω| − ∫ max(sign(ω)·τ, 0)/J_min dt
//!               never rises; it rising by more than the margin is a runaway.
//!                 J_min unknown (no soft start, no precise model yet): the torque credits any
//!                   growth while it pushes the rotation; growth while it pushes against the
//!                   rotation is a runaway (the torque sign is reversed)
//!                 after the soft start: J_min = its impulse estimate ∫τ dt / Δω ÷ 4 (the
//!                   estimate is high: drag and friction are left out)
//!                 once the running fit's J is known to 5 %, inside its bounds and not above twice
//!                   the soft start's estimate: J_min = J ÷ 3
//!               τ is the largest push of the last 50 ms, so a torque the rotor feels a little
//!               after the drive reports it (a lag) is not a runaway
//! ```
//! What trips is a [`LimitStop`]; the driver stops as it stops for any fault (STANDBY and a zero
//! setpoint first). Everything here reads only the feedback and the commanded setpoint: no
//! register of the drive, no model the run has not measured.

use std::collections::VecDeque;
use std::fmt;

use propid_core::sample::Sample;

use crate::settings::{
    MaxSpeed, RampDuration, SoftStartDuration, SoftStartSetpoint, WatchdogMargin, RAD_S_PER_RPM,
};

/// The soft start: a setpoint magnitude and how long it is held.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct SoftStart {
    /// The setpoint's magnitude (applied in the direction of `hi`, at most |hi|).
    pub setpoint: SoftStartSetpoint,
    /// How long it is held.
    pub duration: SoftStartDuration,
}

impl SoftStart {
    /// 10 % of full torque for 1 s.
    pub const DEFAULT: SoftStart = SoftStart {
        setpoint: SoftStartSetpoint::from_const(0.1),
        duration: SoftStartDuration::from_const(1.0),
    };
}

/// The run's limits; each `None` is off.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Limits {
    /// The highest speed allowed.
    pub max_speed: Option<MaxSpeed>,
    /// The soft start before the init phase.
    pub soft_start: Option<SoftStart>,
    /// A ramp to `hi` after the soft start.
    pub ramp: Option<RampDuration>,
    /// The speed watchdog and its margin.
    pub watchdog: Option<WatchdogMargin>,
}

impl Limits {
    /// What `propid drive` runs with unless told otherwise: the soft start and the watchdog
    /// (50 rad/s margin), no ramp, no maximum speed (only the user knows the propeller's).
    pub const DEFAULT: Limits = Limits {
        max_speed: None,
        soft_start: Some(SoftStart::DEFAULT),
        ramp: None,
        watchdog: Some(WatchdogMargin::from_const(50.0)),
    };

    /// None at all: the seed's sequence exactly.
    pub const OFF: Limits = Limits {
        max_speed: None,
        soft_start: None,
        ramp: None,
        watchdog: None,
    };
}

impl Default for Limits {
    fn default() -> Self {
        Limits::DEFAULT
    }
}

/// The speed in rad/s and rpm, for people.
struct Speed(f64);

impl fmt::Display for Speed {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(f, "{:.0} rad/s ({:.0} rpm)", self.0, self.0 / RAD_S_PER_RPM)
    }
}

/// Which limit stopped the run, with what was measured. Displays as a sentence.
#[derive(Clone, Debug, PartialEq)]
pub enum LimitStop {
    /// The speed passed the maximum.
    MaxSpeed {
        /// The speed seen [rad/s] (its magnitude).
        speed: f64,
        /// The maximum [rad/s].
        max: f64,
    },
    /// The speed grew more than the reported torque can explain.
    Runaway {
        /// The speed the growth started from [rad/s] (magnitude).
        from: f64,
        /// The speed it reached [rad/s] (magnitude).
        to: f64,
        /// Over this long [s].
        seconds: f64,
        /// By how much more than the torque allows [rad/s].
        excess: f64,
        /// The inertia bound used [kg·m²] (`None`: only the torque's direction was known).
        inertia_bound: Option<f64>,
    },
    /// No (or too little) feedback arrived during the soft start.
    SoftStartNoFeedback {
        /// Feedback messages received.
        messages: usize,
        /// The soft start's duration [s].
        seconds: f64,
        /// The feedback subject listened to.
        subject: u16,
    },
    /// The rotor sped up against the command.
    SoftStartWrongWay {
        /// The soft start's setpoint.
        setpoint: f64,
        /// Speed at its start [rad/s].
        from: f64,
        /// Speed at its end [rad/s].
        to: f64,
    },
    /// The rotor did not speed up the commanded way.
    SoftStartNoMotion {
        /// The soft start's setpoint.
        setpoint: f64,
        /// Its duration [s].
        seconds: f64,
        /// Speed at its start [rad/s].
        from: f64,
        /// Speed at its end [rad/s].
        to: f64,
    },
    /// The rotor sped up the commanded way, but the drive reports a torque against it.
    SoftStartTorqueReversed {
        /// The soft start's setpoint.
        setpoint: f64,
        /// The mean reported torque [N·m].
        torque: f64,
    },
}

impl fmt::Display for LimitStop {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            LimitStop::MaxSpeed { speed, max } => write!(
                f,
                "the speed limit: the rotor reached {}, above the maximum of {}",
                Speed(*speed),
                Speed(*max)
            ),
            LimitStop::Runaway {
                from,
                to,
                seconds,
                excess,
                inertia_bound,
            } => {
                write!(
                    f,
                    "the speed ran away from the torque: it rose from {} to {} in {seconds:.3} s, {excess:.0} rad/s more than the torque the drive reports can explain ",
                    Speed(*from),
                    Speed(*to)
                )?;
                match inertia_bound {
                    Some(j) => write!(f, "with an inertia of at least {j:.3e} kg·m²")?,
                    None => write!(f, "(it pushed against the rotation)")?,
                }
                write!(
                    f,
                    ": the torque sign is reversed, the propeller came loose, or the torque scale is wrong"
                )
            }
            LimitStop::SoftStartNoFeedback {
                messages,
                seconds,
                subject,
            } => write!(
                f,
                "no feedback during the soft start: {messages} messages on subject {subject} in {seconds} s; check that the drive publishes its dynamics there (its uavcan.pub.dynamics.id) at 100 Hz or more (mns.pub_interval_min) and that it is powered and engaged"
            ),
            LimitStop::SoftStartWrongWay { setpoint, from, to } => write!(
                f,
                "the rotor accelerated the wrong way: the torque sign is reversed (at setpoint {setpoint:+} its speed went from {from:.1} to {to:.1} rad/s); reverse the motor's direction in the drive's configuration (or swap two motor phases) and run again"
            ),
            LimitStop::SoftStartNoMotion {
                setpoint,
                seconds,
                from,
                to,
            } => write!(
                f,
                "the rotor did not speed up during the soft start (at setpoint {setpoint:+} for {seconds} s its speed went from {from:.1} to {to:.1} rad/s): the drive is not engaged, the rotor is blocked, or the setpoint is too low to overcome friction"
            ),
            LimitStop::SoftStartTorqueReversed { setpoint, torque } => write!(
                f,
                "the drive reports a torque against the command during the soft start (mean {torque:.3e} N·m at setpoint {setpoint:+}) while the rotor speeds up the commanded way: the feedback's torque sign is reversed"
            ),
        }
    }
}

/// What a passed soft start measured.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct SoftStartPassed {
    /// Speed at its start [rad/s].
    pub from: f64,
    /// Speed at its end [rad/s].
    pub to: f64,
    /// Feedback messages received.
    pub messages: usize,
    /// The impulse estimate of the inertia [kg·m²] (high: drag is left out), if the torque was
    /// reported.
    pub inertia: Option<f64>,
}

/// Consecutive samples above the maximum speed that stop the run (one spike does not).
const MAX_SPEED_SAMPLES: u32 = 2;
/// Fewer feedback messages than this in the soft start is no feedback to judge by.
const MIN_SOFT_START_MESSAGES: usize = 5;
/// Below this change of speed [rad/s] the rotor did not move, whatever the noise.
const MIN_MOTION: f64 = 2.0;
/// How many noise standard deviations of the mean speed a change must exceed.
const MOTION_SIGMAS: f64 = 6.0;
/// The soft start's impulse estimate of J is divided by this for the watchdog's bound.
const SOFT_START_INERTIA_MARGIN: f64 = 4.0;
/// The running fit's J is divided by this for the watchdog's bound.
const MODEL_INERTIA_MARGIN: f64 = 3.0;
/// The running fit's J is used once its relative standard error is below this.
const MODEL_INERTIA_PRECISION: f64 = 0.05;
/// A torque counts for this long after it was reported (the rotor may feel it later).
const TORQUE_GRACE: f64 = 0.05;
/// A feedback gap longer than this [s] credits no more torque than this long.
const MAX_STEP: f64 = 0.5;

/// Which clock the watchdog's time is on.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum TimeBase {
    /// The drive's own timestamps (a burst after a host stall keeps its spacing).
    Drive,
    /// Arrival on the host (a drive that does not stamp its feedback).
    Host,
}

/// The speed watchdog's state (see the module documentation).
#[derive(Clone, Debug)]
struct Watchdog {
    margin: f64,
    inertia_bound: Option<f64>,
    base: Option<TimeBase>,
    /// Recent (time, torque).
    recent: VecDeque<(f64, f64)>,
    last_t: Option<f64>,
    credit: f64,
    /// The lowest Q so far, the speed and the time then.
    low: Option<(f64, f64, f64)>,
}

impl Watchdog {
    fn new(margin: f64) -> Self {
        Watchdog {
            margin,
            inertia_bound: None,
            base: None,
            recent: VecDeque::new(),
            last_t: None,
            credit: 0.0,
            low: None,
        }
    }

    /// A new inertia bound: the torque's credit accrues at it from here on (Q stays
    /// continuous, so growth already under way is still measured).
    fn set_inertia_bound(&mut self, j: f64) {
        if j.is_finite() && j > 0.0 {
            self.inertia_bound = Some(j);
        }
    }

    /// One sample: the drive's time when it stamped it, the host's arrival time.
    fn feedback(
        &mut self,
        drive_time: Option<f64>,
        host_time: f64,
        velocity: f64,
        torque: f64,
    ) -> Option<LimitStop> {
        if !(velocity.is_finite() && torque.is_finite()) {
            return None;
        }
        // The drive's clock once it has stamped a sample (a drive's clock starts at 0, which
        // Cyphal reads as "unknown": such a sample moves no time on it).
        let t = match (drive_time, self.base) {
            (Some(t), Some(TimeBase::Drive)) => t,
            (Some(t), _) => {
                self.base = Some(TimeBase::Drive);
                self.last_t = None;
                self.recent.clear();
                t
            }
            (None, Some(TimeBase::Drive)) => self.last_t.unwrap_or(0.0),
            (None, _) => {
                self.base = Some(TimeBase::Host);
                host_time
            }
        };
        if !t.is_finite() {
            return None;
        }
        let dt = match self.last_t {
            Some(last) if t > last => (t - last).min(MAX_STEP),
            Some(_) => 0.0,
            None => 0.0,
        };
        self.last_t = Some(self.last_t.map_or(t, |l| l.max(t)));
        self.recent.push_back((t, torque));
        while self
            .recent
            .front()
            .is_some_and(|(s, _)| *s < t - TORQUE_GRACE)
        {
            self.recent.pop_front();
        }
        let direction = if velocity < 0.0 { -1.0 } else { 1.0 };
        let push = self
            .recent
            .iter()
            .map(|(_, tau)| direction * tau)
            .fold(0.0f64, f64::max);
        let speed = velocity.abs();
        let q = match self.inertia_bound {
            Some(j) => {
                self.credit += push * dt / j;
                speed - self.credit
            }
            None => {
                if push > 0.0 {
                    // The torque pushes the rotation: any growth is possible.
                    self.low = None;
                }
                speed
            }
        };
        let (low, from, since) = *self.low.get_or_insert((q, speed, t));
        if q < low {
            self.low = Some((q, speed, t));
            return None;
        }
        let excess = q - low;
        (excess > self.margin).then_some(LimitStop::Runaway {
            from,
            to: speed,
            seconds: t - since,
            excess,
            inertia_bound: self.inertia_bound,
        })
    }
}

/// The limits at work during a run: fed every feedback sample while torque is commanded.
#[derive(Clone, Debug)]
pub struct Guard {
    limits: Limits,
    above_max: u32,
    /// (drive time if stamped, host time, velocity, torque) during the soft start.
    soft: Vec<(Option<f64>, f64, f64, f64)>,
    /// The soft start's impulse estimate of J (high: drag and friction left out).
    soft_inertia: Option<f64>,
    watchdog: Option<Watchdog>,
}

impl Guard {
    /// A guard for `limits`.
    pub fn new(limits: Limits) -> Self {
        Guard {
            limits,
            above_max: 0,
            soft: Vec::new(),
            soft_inertia: None,
            watchdog: limits.watchdog.map(|m| Watchdog::new(m.get())),
        }
    }

    /// The limits it applies.
    pub fn limits(&self) -> &Limits {
        &self.limits
    }

    /// One feedback sample, received at `host_time` [s]; its time on the drive's clock is
    /// `sample.t` when `stamped` (a drive that does not stamp sends 0, "unknown"). During the
    /// soft start, `soft_start` is its setpoint, and the sample is kept for its verdict. A limit
    /// that trips is returned; the watchdog tripping during the soft start says what the soft
    /// start would have said, sooner.
    pub fn feedback(
        &mut self,
        sample: &Sample,
        stamped: bool,
        host_time: f64,
        soft_start: Option<f64>,
    ) -> Option<LimitStop> {
        let (velocity, torque) = (sample.velocity, sample.force);
        let drive_time = stamped.then_some(sample.t);
        if soft_start.is_some() && velocity.is_finite() && torque.is_finite() {
            self.soft.push((drive_time, host_time, velocity, torque));
        }
        if let Some(max) = self.limits.max_speed {
            if velocity.abs() > max.get() {
                self.above_max += 1;
                if self.above_max >= MAX_SPEED_SAMPLES {
                    return Some(LimitStop::MaxSpeed {
                        speed: velocity.abs(),
                        max: max.get(),
                    });
                }
            } else {
                self.above_max = 0;
            }
        }
        let trip = self
            .watchdog
            .as_mut()?
            .feedback(drive_time, host_time, velocity, torque)?;
        Some(match (soft_start, &trip) {
            (Some(setpoint), LimitStop::Runaway { from, to, .. }) => {
                if velocity * setpoint < 0.0 {
                    // Speeding up against the command.
                    LimitStop::SoftStartWrongWay {
                        setpoint,
                        from: from.copysign(velocity),
                        to: *to * velocity.signum(),
                    }
                } else {
                    // The way commanded, with the reported torque against it.
                    let n = self.soft.len().max(1) as f64;
                    LimitStop::SoftStartTorqueReversed {
                        setpoint,
                        torque: self.soft.iter().map(|x| x.3).sum::<f64>() / n,
                    }
                }
            }
            _ => trip,
        })
    }

    /// The soft start's verdict, at its end: `setpoint` is what it commanded, `subject` the
    /// feedback subject listened to.
    pub fn end_soft_start(
        &mut self,
        setpoint: f64,
        subject: u16,
    ) -> Result<SoftStartPassed, LimitStop> {
        let seconds = self.limits.soft_start.map_or(0.0, |s| s.duration.get());
        // On the drive's clock when it stamps (its first sample may say 0, "unknown"), else on
        // the host's.
        let stamped = self.soft.iter().any(|x| x.0.is_some());
        let soft: Vec<(f64, f64, f64)> = std::mem::take(&mut self.soft)
            .into_iter()
            .filter_map(|(drive, host, w, tau)| match (stamped, drive) {
                (true, Some(t)) => Some((t, w, tau)),
                (true, None) => None,
                (false, _) => Some((host, w, tau)),
            })
            .collect();
        let n = soft.len();
        if n < MIN_SOFT_START_MESSAGES {
            return Err(LimitStop::SoftStartNoFeedback {
                messages: n,
                seconds,
                subject,
            });
        }
        // The mean speed over the first and the last fifth, and the noise of such a mean from
        // the sample-to-sample differences (a trend adds little to those).
        let k = (n / 5).max(2);
        let mean = |s: &[(f64, f64, f64)], f: fn(&(f64, f64, f64)) -> f64| {
            s.iter().map(f).sum::<f64>() / s.len() as f64
        };
        let (first, last) = (&soft[..k], &soft[n - k..]);
        let (from, to) = (mean(first, |x| x.1), mean(last, |x| x.1));
        let diff2 = soft
            .windows(2)
            .map(|w| (w[1].1 - w[0].1).powi(2))
            .sum::<f64>()
            / (n - 1) as f64;
        let sigma = (diff2 / 2.0).sqrt();
        let threshold = MIN_MOTION.max(MOTION_SIGMAS * sigma * (2.0 / k as f64).sqrt());
        let direction = if setpoint < 0.0 { -1.0 } else { 1.0 };
        let change = (to - from) * direction;
        let torque = mean(&soft[n / 2..], |x| x.2);
        if change > threshold {
            if torque * direction < 0.0 {
                return Err(LimitStop::SoftStartTorqueReversed { setpoint, torque });
            }
            let (t0, t1) = (mean(first, |x| x.0), mean(last, |x| x.0));
            let impulse = mean(&soft, |x| x.2) * (t1 - t0);
            let inertia = (impulse / (to - from))
                .is_finite()
                .then_some(impulse / (to - from))
                .filter(|j| *j > 0.0);
            self.soft_inertia = inertia;
            if let (Some(j), Some(w)) = (inertia, self.watchdog.as_mut()) {
                w.set_inertia_bound(j / SOFT_START_INERTIA_MARGIN);
            }
            return Ok(SoftStartPassed {
                from,
                to,
                messages: n,
                inertia,
            });
        }
        if change < -threshold && to.abs() > from.abs() {
            return Err(LimitStop::SoftStartWrongWay { setpoint, from, to });
        }
        Err(LimitStop::SoftStartNoMotion {
            setpoint,
            seconds,
            from,
            to,
        })
    }

    /// The running fit's inertia and its standard error: once precise, and not above twice what
    /// the soft start measured (which is high already), the watchdog's bound.
    pub fn model_inertia(&mut self, j: f64, j_stderr: f64) {
        let consistent = self.soft_inertia.is_none_or(|soft| j <= 2.0 * soft);
        if j > 0.0 && j_stderr.is_finite() && j_stderr <= MODEL_INERTIA_PRECISION * j && consistent
        {
            if let Some(w) = self.watchdog.as_mut() {
                w.set_inertia_bound(j / MODEL_INERTIA_MARGIN);
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn sample(t: f64, velocity: f64, force: f64) -> Sample {
        Sample {
            t,
            force,
            velocity,
            acceleration: 0.0,
            position: 0.0,
        }
    }

    /// A rotor of inertia `j` under `force`, 2 ms apart on the drive's clock, all arriving at the
    /// same host time after a stall; the first stamped 0 ("unknown").
    fn feed(guard: &mut Guard, j: f64, force: f64, n: usize) -> Option<LimitStop> {
        (0..n).find_map(|k| {
            let t = k as f64 * 0.002;
            guard.feedback(&sample(t, force / j * t, force), k > 0, 7.0, None)
        })
    }

    #[test]
    fn a_burst_after_a_stall_is_judged_on_the_drives_clock() {
        // 1 s of a correct rotor delivered at once: the drive's clock says it is all possible.
        let mut g = Guard::new(Limits::DEFAULT);
        g.model_inertia(2e-5, 1e-7);
        assert_eq!(feed(&mut g, 2e-5, 0.05, 500), None);
        // The same with a rotor 4 times lighter than the bound allows: a runaway.
        let mut g = Guard::new(Limits::DEFAULT);
        g.model_inertia(2e-5, 1e-7);
        let trip = feed(&mut g, 2e-5 / 12.0, 0.05, 500).expect("a runaway");
        let LimitStop::Runaway {
            inertia_bound,
            seconds,
            ..
        } = trip
        else {
            panic!("{trip:?}")
        };
        assert_eq!(inertia_bound, Some(2e-5 / 3.0));
        // Growth of 2/3 of 7500 rad/s² per second past the bound: the 50 rad/s margin in ~10 ms.
        assert!(seconds < 0.02, "{seconds}");
    }

    #[test]
    fn an_imprecise_fit_sets_no_bound_and_the_torques_direction_decides() {
        let mut g = Guard::new(Limits::DEFAULT);
        g.model_inertia(2e-5, 2e-6); // 10 %: not used
                                     // Any growth is possible while the torque pushes the rotation.
        assert_eq!(feed(&mut g, 2e-6, 0.05, 500), None);
        // Growth against the torque is not.
        let mut g = Guard::new(Limits::DEFAULT);
        let trip = feed(&mut g, -2e-5, 0.05, 500).expect("a runaway");
        assert!(
            matches!(
                trip,
                LimitStop::Runaway {
                    inertia_bound: None,
                    ..
                }
            ),
            "{trip:?}"
        );
    }

    #[test]
    fn the_maximum_speed_needs_two_samples_above_it() {
        let mut g = Guard::new(Limits {
            max_speed: Some(MaxSpeed::new(100.0).unwrap()),
            ..Limits::OFF
        });
        let at = |v| sample(0.0, v, 0.01);
        assert_eq!(g.feedback(&at(150.0), false, 0.0, None), None, "one spike");
        assert_eq!(g.feedback(&at(90.0), false, 0.0, None), None);
        assert_eq!(g.feedback(&at(-101.0), false, 0.0, None), None);
        assert_eq!(
            g.feedback(&at(-102.0), false, 0.0, None),
            Some(LimitStop::MaxSpeed {
                speed: 102.0,
                max: 100.0
            })
        );
    }
}
