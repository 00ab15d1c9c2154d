//! `time_base`: the device clock runs at 1 + ε host seconds per second (an RC oscillator). Not a
//! term of the acceleration equation: measured before any fit as the slope of the device time
//! `t` on the host's receive time `ts_local`, minus 1. A clock off by ε reports velocity and
//! acceleration per device second, so J and c2 come out (1 + ε)² too large; a named clock is
//! corrected in the samples (t, ω, a to host seconds) before the diagnosis.

use propid_io::tsv::{Row, Sample};

use super::{EffectKind, 
    BaseTerm, Candidate, Design, Enters, Estimate, Fitted, Inadmissible, RowEffect, Shape, Slot,
};
use crate::diagnose::model::{At, Effect, Lag, Prepared};
use crate::diagnose::signals::Signals;
use crate::diagnose::tune::{Tuned, Tuner};
use crate::diagnose::SeparatingRun;
use crate::excitation::Pattern;

/// See the module documentation.
pub(crate) struct TimeBase;

/// Smallest clock rate error named (a crystal's 50 ppm is invisible in J and c2; an RC
/// oscillator's 0.3–2 % is not).
pub const MIN_TIME_BASE: f64 = 1e-3;

/// Largest clock rate error taken for a clock (an RC oscillator is off by 2 % at most); beyond it
/// the time columns disagree on units (t in ms against ts_local in s), which the gate reports.
pub const MAX_TIME_BASE: f64 = 0.05;

/// Standard errors a clock error must lie from zero: the slope over a whole log is measured to
/// parts per million, so a named clock must stand far out of its own noise.
const CLOCK_RESOLVED: f64 = 10.0;

impl RowEffect for TimeBase {
    fn measure(&self, rows: &[Row]) -> Option<Estimate> {
        let both: Vec<(f64, f64)> = rows
            .iter()
            .filter(|r| r.ts_local.is_finite() && r.sample.t.is_finite())
            .map(|r| (r.ts_local, r.sample.t))
            .collect();
        if both.len() < 100 || both.len() * 10 < rows.len() * 9 {
            return None;
        }
        let n = both.len() as f64;
        let (mx, my) = both
            .iter()
            .fold((0.0, 0.0), |(a, b), (x, y)| (a + x / n, b + y / n));
        let (mut sxx, mut sxy) = (0.0, 0.0);
        for (x, y) in &both {
            sxx += (x - mx) * (x - mx);
            sxy += (x - mx) * (y - my);
        }
        if sxx <= 0.0 {
            return None;
        }
        let slope = sxy / sxx;
        let rss: f64 = both
            .iter()
            .map(|(x, y)| (y - my - slope * (x - mx)).powi(2))
            .sum();
        let se = (rss / (n - 2.0).max(1.0) / sxx).sqrt();
        Some(Estimate::new(slope - 1.0, se))
    }

    fn correct(&self, value: f64, s: &mut Sample) {
        let r = 1.0 + value;
        s.t /= r;
        s.velocity *= r;
        s.acceleration *= r * r;
    }
}

impl Candidate for TimeBase {
    fn name(&self) -> &'static str {
        "time_base"
    }
    fn unit(&self) -> &'static str {
        "1"
    }
    fn enters(&self) -> Enters {
        Enters::Rows(&TimeBase)
    }
    fn slot(&self) -> Slot {
        Slot::Term
    }
    fn parameters(&self) -> usize {
        1
    }
    fn columns(&self, _: &Effect) -> usize {
        0
    }
    fn prepare(&self, _: &Effect, _: &Signals, _: &mut Prepared) {}
    fn row(&self, _: &Effect, _: &At, _: &mut [f64]) {}
    fn differentiated(&self, _: &Effect) -> bool {
        false
    }
    fn instrument(&self, _: &Effect, _: &Signals, _: usize, _: &mut [f64]) {}
    fn held_in_simulation(&self) -> bool {
        false
    }
    /// Measured from the rows, not tuned.
    fn refines(&self) -> Option<EffectKind> {
        None
    }
    fn tune(&self, _: &Tuner) -> Option<Tuned> {
        None
    }
    fn retune(&self, _: &Effect, _: &Tuner) -> Option<Tuned> {
        None
    }
    fn estimate(&self, e: &Effect, _: &Fitted) -> Estimate {
        Estimate::new(e.param, f64::NAN)
    }
    fn admissible(&self, _: &Effect, v: Estimate, _: &Fitted) -> Result<(), Inadmissible> {
        if !v.value.is_finite() {
            Err(Inadmissible::NotFinite)
        } else if v.value.abs() > MAX_TIME_BASE {
            Err(Inadmissible::OutOfRange { value: v.value })
        } else if v.value.abs() < MIN_TIME_BASE || !v.resolved_from(0.0, CLOCK_RESOLVED) {
            Err(Inadmissible::NotResolved {
                value: v.value,
                stderr: v.stderr,
            })
        } else {
            Ok(())
        }
    }
    fn explanation(&self, _: &Effect, value: f64) -> String {
        format!("the device clock runs {:+.3} % fast against the host's (an RC oscillator): velocity and acceleration are per device second; corrected before the fit", value * 100.0)
    }
    fn shape(&self) -> Shape {
        Shape::Clock
    }
    fn lag(&self, _: &Effect, _: f64) -> Option<Lag> {
        None
    }
    fn revealing_run(&self) -> SeparatingRun {
        SeparatingRun {
            pattern: Pattern::Sine,
            lo: None,
            hi: None,
            why: "any run recorded with the host's receive times (ts_local)",
        }
    }
    fn simulation_sees(&self) -> bool {
        true
    }
    /// Measured from the rows, not tuned.
    fn tuned_by_simulation(&self) -> bool {
        false
    }
    fn base_term(&self, _: &Effect, _: Estimate) -> BaseTerm {
        BaseTerm::None
    }
    fn design_column(&self, _: &Design) -> Option<Vec<f64>> {
        None
    }
}
