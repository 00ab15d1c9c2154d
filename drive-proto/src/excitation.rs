//! What the driver commands over a run, behind a trait: the protocol needs the seed's timing
//! (an init phase at the high setpoint, then a pattern for a while) and the setpoint at a time,
//! not how a pattern is shaped (the shapes live with the science, `propid_science::excitation`).
//!
//! ```text
//!  Drive ── init phase: schedule().range.hi() for schedule().init_duration
//!        └─ pattern:    setpoint(t), t = 0 .. schedule().duration
//!  served registers: setpoint_rat_lo_hi, period, pattern_duration, init_duration ◄─ schedule()
//! ```

use crate::settings::{InitDuration, PatternDuration, Period, SetpointRange};

/// The seed's registers of a run, checked: they describe any pattern the driver plays.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Schedule {
    /// The setpoint range (`setpoint_rat_lo_hi`); the init phase holds `hi`.
    pub range: SetpointRange,
    /// The pattern's period (`period`).
    pub period: Period,
    /// How long the pattern runs (`pattern_duration`).
    pub duration: PatternDuration,
    /// How long the init phase lasts (`init_duration`).
    pub init_duration: InitDuration,
}

impl Schedule {
    /// The seed's: 0.1 to 0.9, a 2 s period, 200 s after a 5 s init phase.
    pub const SEED: Schedule = Schedule {
        range: SetpointRange::SEED,
        period: Period::from_const(2.0),
        duration: PatternDuration::from_const(200.0),
        init_duration: InitDuration::from_const(5.0),
    };
}

/// A pattern the driver plays.
pub trait Excitation: core::fmt::Debug + Send + Sync {
    /// Its timing and range.
    fn schedule(&self) -> Schedule;
    /// The ratiometric setpoint `t` seconds after the pattern began (init phase excluded),
    /// within the schedule's range.
    fn setpoint(&self, t: f64) -> f64;
}
