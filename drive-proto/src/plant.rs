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

/// A plant whose drive applies `scale` times the torque it is commanded and reports: a torque
/// sign reversed (−1), a wrong torque constant (≠ 1), or a motor that makes no torque (0, and
/// reports none). Otherwise the reported torque stays the commanded one, as a drive that believes
/// its own scale reports it — unless [`TorqueScaled::reporting`] scales the report too (a torque
/// reported with the wrong sign).
pub struct TorqueScaled {
    inner: Box<dyn Plant>,
    scale: f64,
    reported: f64,
}

impl TorqueScaled {
    /// `inner` driven with `scale` times the commanded torque.
    pub fn new(inner: Box<dyn Plant>, scale: f64) -> Self {
        TorqueScaled {
            inner,
            scale,
            reported: 1.0,
        }
    }

    /// The same, reporting `reported` times the torque it would report (−1: the feedback's
    /// torque sign reversed).
    pub fn reporting(self, reported: f64) -> Self {
        TorqueScaled { reported, ..self }
    }
}

impl Plant for TorqueScaled {
    fn set_setpoint(&mut self, setpoint: f64) {
        self.inner.set_setpoint(setpoint * self.scale);
    }

    fn time(&self) -> f64 {
        self.inner.time()
    }

    fn advance_to(&mut self, t: f64) {
        self.inner.advance_to(t)
    }

    fn measure(&mut self) -> Sample {
        let mut s = self.inner.measure();
        // What the drive reports: the torque it believes it makes (the inner plant's reading,
        // noise and lags included, taken back to the commanded scale).
        if self.scale != 0.0 {
            s.force /= self.scale;
        }
        s.force *= self.reported;
        s
    }
}
