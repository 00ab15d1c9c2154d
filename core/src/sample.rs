//! The one currency between the bus side and the science side: a [`Sample`] of the drive's
//! dynamics (time, torque, velocity, acceleration, angle).
//!
//! ```text
//!  DoF3rdTs (the drive's feedback message) ─► Sample::from ─► a row of the TSV (propid-io)
//!  stand simulators, importers, replay ──────► Sample ──────► a row of the TSV
//! ```
//! Every producer (the driver, `replay`, the simulators, the importers) makes these, and every
//! consumer (the TSV writer, the fit, the diagnosis, the live page) takes them. The field names
//! are the seed's file columns.

use crate::dsdl::DoF3rdTs;

/// One measurement of the drive's dynamics feedback.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Sample {
    /// Device time [s].
    pub t: f64,
    /// Torque (the drive's estimate) [N·m].
    pub force: f64,
    /// Angular velocity [rad/s].
    pub velocity: f64,
    /// Angular acceleration [rad/s²].
    pub acceleration: f64,
    /// Rotor angle [rad], when the source has it (NaN otherwise).
    pub position: f64,
}

impl Sample {
    /// True if time, force, velocity and acceleration are all finite (position may be NaN).
    pub fn is_finite(&self) -> bool {
        self.t.is_finite()
            && self.force.is_finite()
            && self.velocity.is_finite()
            && self.acceleration.is_finite()
    }
}

impl From<&DoF3rdTs> for Sample {
    /// The sample a feedback message carries (time from the drive's timestamp).
    fn from(fb: &DoF3rdTs) -> Self {
        let k = &fb.value.kinematics;
        Sample {
            t: fb.timestamp.microsecond as f64 * 1e-6,
            force: f64::from(fb.value.force),
            velocity: f64::from(k.base.velocity),
            acceleration: f64::from(k.acceleration),
            position: f64::from(k.base.position),
        }
    }
}
