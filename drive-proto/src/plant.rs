//! What the simulated Telega drives, behind a trait: a load that takes a ratiometric setpoint
//! and is measured at the times the drive publishes feedback (`propid_science::stand::Stand`
//! is one; the protocol does not need to know how it is modelled).

use propid_core::sample::Sample;

/// A simulated load with its sensors, advanced in time by the simulated drive.
pub trait Plant: Send {
    /// The ratiometric torque setpoint from now on.
    fn set_setpoint(&mut self, setpoint: f64);
    /// The plant's time [s] (0 at boot).
    fn time(&self) -> f64;
    /// Runs the plant up to `t` seconds (no step back).
    fn advance_to(&mut self, t: f64);
    /// What the drive's sensors report now.
    fn measure(&mut self) -> Sample;
}
