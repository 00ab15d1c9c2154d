//! Excitation: the setpoint the driver applies, as a function of time.
//!
//! The seed applies `hi` for an init phase, then a sinusoid between `lo` and `hi`; propid adds
//! steps and a chirp (docs/SCIENCE.md: one sinusoid cannot separate some effects). The driver,
//! the simulators and the simulated drive all evaluate the same [`Excitation::setpoint`].

use propid_io::InputError;

/// The shape of the setpoint after the init phase.
#[derive(Clone, Copy, Debug, PartialEq, Eq, serde::Serialize, serde::Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum Pattern {
    /// The seed's sinusoid between lo and hi.
    Sine,
    /// Steps between lo and hi, a staircase of 5 levels up and down, each held half a period.
    Steps,
    /// A sine sweep between lo and hi from 1/period to 10/period.
    Chirp,
    /// A square wave: hi and lo alternately, each held half a period (bang-bang: the largest
    /// accelerations the range allows).
    Square,
    /// A pseudo-random binary sequence: lo or hi, a new draw every half period (fixed sequence,
    /// so a run is repeatable); broadband, it separates lags from friction.
    Prbs,
    /// Eight sines at 1/period … 8/period with Schroeder phases (low crest factor), scaled to
    /// span lo..hi.
    Multisine,
}

impl Pattern {
    /// Every pattern, in the order the help lists them.
    pub const ALL: [Pattern; 6] = [
        Pattern::Sine,
        Pattern::Steps,
        Pattern::Chirp,
        Pattern::Square,
        Pattern::Prbs,
        Pattern::Multisine,
    ];

    /// The pattern's name as the command line and the files spell it.
    pub fn name(self) -> &'static str {
        match self {
            Pattern::Sine => "sine",
            Pattern::Steps => "steps",
            Pattern::Chirp => "chirp",
            Pattern::Square => "square",
            Pattern::Prbs => "prbs",
            Pattern::Multisine => "multisine",
        }
    }
}

impl core::fmt::Display for Pattern {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        f.write_str(self.name())
    }
}

impl core::str::FromStr for Pattern {
    type Err = InputError;

    fn from_str(s: &str) -> Result<Self, InputError> {
        Pattern::ALL
            .into_iter()
            .find(|p| p.name() == s)
            .ok_or_else(|| {
                let names: Vec<_> = Pattern::ALL.iter().map(|p| p.name()).collect();
                InputError::invalid(format!(
                    "unknown pattern `{s}` (one of: {})",
                    names.join(", ")
                ))
            })
    }
}

/// The excitation the driver applies (the same for `drive`, `sim` and `sim-drive`).
#[derive(Clone, Copy, Debug, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct Excitation {
    /// Low setpoint (ratiometric, −1..1).
    pub lo: f64,
    /// High setpoint.
    pub hi: f64,
    /// Period of the sinusoid [s].
    pub period: f64,
    /// Duration of the pattern after the init phase [s].
    pub duration: f64,
    /// Init phase at `hi` before the pattern [s].
    pub init_duration: f64,
    /// The pattern.
    pub pattern: Pattern,
}

impl Excitation {
    /// The setpoint `t` seconds after the pattern began (init phase excluded).
    pub fn setpoint(&self, t: f64) -> f64 {
        let (lo, hi) = (self.lo, self.hi);
        let lerp = |s: f64| lo + (hi - lo) * (s + 1.0) / 2.0;
        match self.pattern {
            // The seed: np.interp(sin(now / (period / 2π)), (−1, 1), (lo, hi)).
            Pattern::Sine => lerp((std::f64::consts::TAU * t / self.period).sin()),
            Pattern::Steps => {
                const LEVELS: [f64; 8] = [0.0, 0.25, 0.5, 0.75, 1.0, 0.75, 0.5, 0.25];
                let k = (t / (self.period / 2.0)).floor().max(0.0) as usize % LEVELS.len();
                lo + (hi - lo) * LEVELS[k]
            }
            Pattern::Chirp => {
                let (f0, f1) = (1.0 / self.period, 10.0 / self.period);
                let d = self.duration.max(1e-9);
                let phase = std::f64::consts::TAU * (f0 * t + (f1 - f0) * t * t / (2.0 * d));
                lerp(phase.sin())
            }
            Pattern::Square => {
                let half = (t / (self.period / 2.0)).floor();
                if half.rem_euclid(2.0) < 1.0 {
                    hi
                } else {
                    lo
                }
            }
            Pattern::Prbs => {
                let k = (t / (self.period / 2.0)).floor().max(0.0) as u64;
                if splitmix64(k) & 1 == 1 {
                    hi
                } else {
                    lo
                }
            }
            Pattern::Multisine => lerp(multisine(t / self.period)),
        }
    }

    /// Checks the values a user may get wrong.
    pub fn validate(&self) -> Result<(), InputError> {
        if self.lo.is_nan()
            || self.hi.is_nan()
            || self.lo >= self.hi
            || self.lo < -1.0
            || self.hi > 1.0
        {
            return Err(InputError::invalid(format!(
                "setpoint range must satisfy -1 ≤ lo < hi ≤ 1 (got lo = {}, hi = {})",
                self.lo, self.hi
            )));
        }
        // Finite and at most a day: a duration is turned into a `Duration` and a deadline.
        const DAY: f64 = 86_400.0;
        for (name, v, min_ok) in [
            ("period", self.period, self.period > 0.0),
            ("pattern duration", self.duration, self.duration > 0.0),
            (
                "init duration",
                self.init_duration,
                self.init_duration >= 0.0,
            ),
        ] {
            if !(min_ok && v.is_finite() && v <= DAY) {
                return Err(InputError::invalid(format!(
                    "{name} must be {} and at most {DAY} s (got {v})",
                    if name == "init duration" {
                        "≥ 0"
                    } else {
                        "positive"
                    }
                )));
            }
        }
        Ok(())
    }
}

/// SplitMix64: a fixed, well-mixed pseudo-random bit per index (the PRBS pattern's draws).
fn splitmix64(k: u64) -> u64 {
    let mut z = k.wrapping_add(0x9E37_79B9_7F4A_7C15);
    z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
    z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
    z ^ (z >> 31)
}

/// Harmonics of the multisine.
const MULTISINE_HARMONICS: usize = 8;

/// The multisine at `x` periods, before scaling: Σ sin(2π k x + φ_k), Schroeder phases.
fn multisine_raw(x: f64) -> f64 {
    let n = MULTISINE_HARMONICS as f64;
    (1..=MULTISINE_HARMONICS)
        .map(|k| {
            let k = k as f64;
            let phase = -std::f64::consts::PI * k * (k - 1.0) / n;
            (std::f64::consts::TAU * k * x + phase).sin()
        })
        .sum()
}

/// The multisine scaled to [−1, 1] (its peak over a period, found once on a fine grid, maps to 1).
fn multisine(x: f64) -> f64 {
    static PEAK: std::sync::OnceLock<f64> = std::sync::OnceLock::new();
    let peak = *PEAK.get_or_init(|| {
        (0..20_000)
            .map(|i| multisine_raw(i as f64 / 20_000.0).abs())
            .fold(0.0, f64::max)
            * 1.000_001
    });
    (multisine_raw(x) / peak).clamp(-1.0, 1.0)
}
