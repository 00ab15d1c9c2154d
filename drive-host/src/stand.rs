//! The science's patterns and stand behind the protocol's traits: what `propid drive` plays
//! ([`Played`]) and what `propid sim-drive` simulates ([`StandPlant`]).
//!
//! ```text
//!  propid_science::excitation::Excitation ─► Played (Schedule checked once) ─► dyn Excitation
//!  propid_science::stand::Stand ─────────────► StandPlant ───────────────────► dyn Plant
//! ```

use std::fmt;

use propid_core::sample::Sample;
use propid_drive_proto::excitation::{Excitation as PlayedPattern, Schedule};
use propid_drive_proto::plant::Plant;
use propid_drive_proto::settings::{
    InitDuration, PatternDuration, Period, RangeError, SetpointRange, SetpointRangeError,
};
use propid_io::InputError;
use propid_science::excitation::{Excitation, Pattern};
use propid_science::stand::{Stand, StandConfig};

/// A pattern of the science, with its schedule checked: what the driver plays.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Played {
    schedule: Schedule,
    excitation: Excitation,
}

impl Played {
    /// `pattern` on `schedule`.
    pub fn new(schedule: Schedule, pattern: Pattern) -> Self {
        let excitation = Excitation {
            lo: schedule.range.lo(),
            hi: schedule.range.hi(),
            period: schedule.period.get(),
            duration: schedule.duration.get(),
            init_duration: schedule.init_duration.get(),
            pattern,
        };
        Played {
            schedule,
            excitation,
        }
    }

    /// The science's description of it (the same values).
    pub fn excitation(&self) -> &Excitation {
        &self.excitation
    }
}

/// Which part of an excitation cannot be played, and why.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum ScheduleError {
    /// The setpoint range.
    Range(SetpointRangeError),
    /// The period.
    Period(RangeError),
    /// The pattern's duration.
    Duration(RangeError),
    /// The init phase's duration.
    InitDuration(RangeError),
}

impl fmt::Display for ScheduleError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            ScheduleError::Range(e) => write!(f, "{e}"),
            ScheduleError::Period(e) => write!(f, "the period {e}"),
            ScheduleError::Duration(e) => write!(f, "the pattern duration {e}"),
            ScheduleError::InitDuration(e) => write!(f, "the init duration {e}"),
        }
    }
}

impl std::error::Error for ScheduleError {}

impl TryFrom<Excitation> for Played {
    type Error = ScheduleError;

    /// Checks an excitation made elsewhere (a pattern file of `propid plan`).
    fn try_from(e: Excitation) -> Result<Self, ScheduleError> {
        let schedule = Schedule {
            range: SetpointRange::new(e.lo, e.hi).map_err(ScheduleError::Range)?,
            period: Period::new(e.period).map_err(ScheduleError::Period)?,
            duration: PatternDuration::new(e.duration).map_err(ScheduleError::Duration)?,
            init_duration: InitDuration::new(e.init_duration)
                .map_err(ScheduleError::InitDuration)?,
        };
        Ok(Played::new(schedule, e.pattern))
    }
}

impl PlayedPattern for Played {
    fn schedule(&self) -> Schedule {
        self.schedule
    }

    fn setpoint(&self, t: f64) -> f64 {
        self.excitation.setpoint(t)
    }
}

/// The science's formula-level stand as the simulated Telega's load.
pub struct StandPlant(Stand);

impl StandPlant {
    /// A stand of `config` with noise seed `seed`; a configuration that makes no stand is
    /// refused.
    pub fn new(config: StandConfig, seed: u64) -> Result<Self, InputError> {
        config.validate()?;
        Ok(StandPlant(Stand::new(config, seed)))
    }

    /// [`StandPlant::new`], boxed for a `SimDrive`.
    pub fn boxed(config: StandConfig, seed: u64) -> Result<Box<dyn Plant>, InputError> {
        Ok(Box::new(StandPlant::new(config, seed)?))
    }
}

impl Plant for StandPlant {
    fn set_setpoint(&mut self, setpoint: f64) {
        self.0.set_setpoint(setpoint)
    }

    fn time(&self) -> f64 {
        self.0.time()
    }

    fn advance_to(&mut self, t: f64) {
        self.0.advance_to(t)
    }

    fn measure(&mut self) -> Sample {
        self.0.measure()
    }
}
