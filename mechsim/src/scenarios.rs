//! Named hidden-effect scenarios: one mechanism each, its magnitude drawn at random within a
//! realistic range, and what a correct diagnosis must report about it.
//!
//! A test picks a [`Bench`] (the clean stand it runs on: J, c2, rate, noise, setpoint range,
//! duration), draws a [`Scenario`] for each [`Hidden`] kind with its own RNG, simulates
//! `scenario.config` with any pattern, and checks the diagnosis against `scenario.expect` and
//! `scenario.fit`.
//!
//! ```
//! use propid_mechsim::scenarios::{Bench, Expect, Hidden};
//! use propid_mechsim::{pattern, MechConfig};
//! use rand::SeedableRng;
//!
//! let mut base = MechConfig::default().with_typical_noise(); // propid's default noise
//! base.link.rate = 500.0;
//! let bench = Bench { base, lo: 0.1, hi: 0.9, duration: 3.0, max_hz: 5.0 };
//! let mut rng = rand::rngs::StdRng::seed_from_u64(1);
//! let s = Hidden::CurrentLoopDemand.draw(&bench, &mut rng);
//! let records = s.simulate(pattern::chirp(0.1, 0.9, 2.0, bench.duration), 7).unwrap();
//! assert_eq!(records.len(), 1501);
//! // records[i].{t, force, velocity, acceleration, position} are the TSV columns (propid's Sample).
//! let Expect::Effect(e) = s.expect else { unreachable!() };
//! assert_eq!(e.name, "torque_lag");
//! assert!(e.value > 2.5e-3 && e.value < 20.1e-3); // 1/ω_c + h/2
//! assert_eq!(s.fit.inertia, 2e-5); // the extended model's J
//! ```
//!
//! The expected values are derived analytically from the mechanism, not from the diagnosis's
//! equations; each derivation is written where the value is computed, and `tests/derivations.rs`
//! measures each one on simulated data (truth against report) to within 3 %.

use rand::Rng;

use crate::config::{
    Braking, ConfigError, CurrentLoop, Disturbance, MechConfig, Run, TorqueReport,
    VelocityEstimator,
};
use crate::record::Record;

/// The clean stand a scenario is drawn on, and the run it will be used for.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Bench {
    /// The clean stand (J, drag, feedback rate, report noise…): its mechanisms must be off.
    pub base: MechConfig,
    /// Lowest setpoint of the pattern.
    pub lo: f64,
    /// Highest setpoint of the pattern.
    pub hi: f64,
    /// Pattern duration [s].
    pub duration: f64,
    /// The highest frequency the pattern excites [Hz] (1/period for the seed's sine, 10/period
    /// for propid's chirp). A 2nd-order stage of natural frequency f_n has the low-frequency
    /// delay 2ζ/ω_n, but the first-order lag that matches it up to f is longer by a factor
    /// 1 + (f/f_n)² (phase series of both to third order); that goes into `derivation_error`.
    pub max_hz: f64,
}

impl Bench {
    /// The steady speed at setpoint `s` on the base stand (torque = drag) [rad/s].
    pub fn steady_speed(&self, s: f64) -> f64 {
        let d = &self.base.rotor.drag;
        (s * self.base.drive.max_torque / d.k).powf(1.0 / d.exponent)
    }
}

/// Where unexplained structure sits.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Where {
    /// Periodic in time at this frequency [Hz of device time].
    Periodic {
        /// Frequency [Hz].
        hz: f64,
    },
    /// Concentrated in a window of time (seconds since the pattern began = device `t` with a
    /// perfect clock).
    TimeWindow {
        /// Start [s].
        from: f64,
        /// End [s].
        to: f64,
    },
    /// Concentrated in an operating condition.
    Condition(Condition),
}

/// An operating condition.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Condition {
    /// While the rotor slows down.
    Decelerating,
    /// At the low end of the speed range.
    LowSpeed,
    /// At the high end of the speed range.
    HighSpeed,
}

/// An effect a correct diagnosis must name.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ExpectedEffect {
    /// The effect's name in propid's reports (`torque_lag`, `force_offset`, …).
    pub name: &'static str,
    /// Its parameter, derived from the mechanism.
    pub value: f64,
    /// Unit of `value`.
    pub unit: &'static str,
    /// True if `propid diagnose` had a candidate of this name when the scenario was written;
    /// false for the candidates issue 12 asks for (`force_offset`, `braking_torque`, `time_base`).
    pub in_diagnose_today: bool,
    /// Another effect that explains the same data on a pattern that cannot separate them (an
    /// honest diagnosis may answer "ambiguous between the two"), with when that happens.
    pub ambiguous_with: Option<(&'static str, &'static str)>,
    /// Relative accuracy of the derivation itself (0 when exact), to add to a test's tolerance.
    pub derivation_error: f64,
}

/// What a correct diagnosis reports.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Expect {
    /// Nothing: the seed's model explains the data (the mechanism, if any, leaves no trace a
    /// model of the reported data could name).
    Nothing,
    /// This effect, alone.
    Effect(ExpectedEffect),
    /// An effect that exists but cannot be identified from these data: a correct diagnosis names
    /// nothing (and may say why); the fit absorbs it (see [`Scenario::fit`]).
    NotIdentifiable {
        /// Its name.
        name: &'static str,
        /// Its true value.
        value: f64,
        /// Why it cannot be identified.
        why: &'static str,
    },
    /// Structure outside propid's library of effects: "unexplained", with where.
    Unexplained {
        /// Where the remaining error sits.
        at: Where,
        /// What causes it, in words.
        what: &'static str,
    },
}

/// The J, drag coefficient and exponent a correct diagnosis's extended model finds.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ExpectedFit {
    /// Inertia [kg·m²].
    pub inertia: f64,
    /// Drag coefficient k of `k·|ω|^p` (the seed's c2 when p = 2).
    pub c2: f64,
    /// Drag exponent p.
    pub drag_exponent: f64,
}

/// One drawn scenario.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Scenario {
    /// Which mechanism is hidden.
    pub hidden: Hidden,
    /// The stand to simulate (the bench's base with the mechanism switched on).
    pub config: MechConfig,
    /// The drawn magnitude of the mechanism, in its own unit (see [`Hidden::describe`]).
    pub magnitude: f64,
    /// What a correct diagnosis reports.
    pub expect: Expect,
    /// What its extended model finds for J and the drag law.
    pub fit: ExpectedFit,
    /// The bench it was drawn on.
    pub bench: Bench,
}

impl Scenario {
    /// The run the scenario was drawn for: the seed's init phase (5 s at `hi`), then the pattern
    /// for the bench's duration.
    pub fn run(&self) -> Run {
        Run {
            init_setpoint: self.bench.hi,
            init_duration: 5.0,
            duration: self.bench.duration,
        }
    }

    /// Simulates the scenario with `pattern` and noise seed `seed`. Fails only if the bench
    /// itself is invalid (every kind draws a valid stand from a valid bench at 100–1000 Hz:
    /// `tests/derivations.rs`).
    pub fn simulate(
        &self,
        pattern: impl Fn(f64) -> f64,
        seed: u64,
    ) -> Result<Vec<Record>, ConfigError> {
        crate::simulate(self.config, &self.run(), pattern, seed)
    }
}

/// The hidden mechanisms.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum Hidden {
    /// Nothing hidden.
    Clean,
    /// A PI current loop of finite bandwidth, the drive reporting its torque demand.
    CurrentLoopDemand,
    /// The same loop, the drive reporting its measured current.
    CurrentLoopMeasured,
    /// A first-order filter on the measured current.
    CurrentSenseFilter,
    /// A quantised angle and a type-2 tracking observer for velocity (and acceleration from it).
    VelocityObserver,
    /// A low-pass filter on the acceleration estimate.
    AccelerationFilter,
    /// A load cell (mass-spring-damper, its own sample rate) reporting the torque.
    LoadCell,
    /// A zero offset of the current sense.
    ForceOffset,
    /// Active braking the current sense does not show.
    Braking,
    /// The device clock runs fast or slow.
    ClockRate,
    /// The drive's torque constant is wrong.
    KtError,
    /// Coulomb + Stribeck bearing friction.
    Stribeck,
    /// Viscous bearing friction.
    Viscous,
    /// A torque coefficient that varies as a power of the Reynolds number.
    ReynoldsDrag,
    /// Cogging torque.
    Cogging,
    /// An external torque periodic in time.
    PeriodicDisturbance,
    /// An external torque bump (a gust) late in the run.
    Gust,
    /// The supply voltage limits the torque at high speed, the drive reporting its demand.
    VoltageLimit,
    /// Lost feedback messages.
    DroppedMessages,
    /// Timestamp jitter and host latency jitter.
    TimestampJitter,
}

fn uniform<R: Rng + ?Sized>(rng: &mut R, lo: f64, hi: f64) -> f64 {
    lo + (hi - lo) * rng.random::<f64>()
}

fn signed<R: Rng + ?Sized>(rng: &mut R, lo: f64, hi: f64) -> f64 {
    let v = uniform(rng, lo, hi);
    if rng.random::<bool>() {
        v
    } else {
        -v
    }
}

fn effect(name: &'static str, value: f64, unit: &'static str, today: bool) -> Expect {
    Expect::Effect(ExpectedEffect {
        name,
        value,
        unit,
        in_diagnose_today: today,
        ambiguous_with: None,
        derivation_error: 0.0,
    })
}

impl Hidden {
    /// Every kind, in a fixed order.
    pub const ALL: [Hidden; 20] = [
        Hidden::Clean,
        Hidden::CurrentLoopDemand,
        Hidden::CurrentLoopMeasured,
        Hidden::CurrentSenseFilter,
        Hidden::VelocityObserver,
        Hidden::AccelerationFilter,
        Hidden::LoadCell,
        Hidden::ForceOffset,
        Hidden::Braking,
        Hidden::ClockRate,
        Hidden::KtError,
        Hidden::Stribeck,
        Hidden::Viscous,
        Hidden::ReynoldsDrag,
        Hidden::Cogging,
        Hidden::PeriodicDisturbance,
        Hidden::Gust,
        Hidden::VoltageLimit,
        Hidden::DroppedMessages,
        Hidden::TimestampJitter,
    ];

    /// A short name for test output.
    pub fn name(self) -> &'static str {
        match self {
            Hidden::Clean => "clean",
            Hidden::CurrentLoopDemand => "current_loop_demand",
            Hidden::CurrentLoopMeasured => "current_loop_measured",
            Hidden::CurrentSenseFilter => "current_sense_filter",
            Hidden::VelocityObserver => "velocity_observer",
            Hidden::AccelerationFilter => "acceleration_filter",
            Hidden::LoadCell => "load_cell",
            Hidden::ForceOffset => "force_offset",
            Hidden::Braking => "braking",
            Hidden::ClockRate => "clock_rate",
            Hidden::KtError => "kt_error",
            Hidden::Stribeck => "stribeck",
            Hidden::Viscous => "viscous",
            Hidden::ReynoldsDrag => "reynolds_drag",
            Hidden::Cogging => "cogging",
            Hidden::PeriodicDisturbance => "periodic_disturbance",
            Hidden::Gust => "gust",
            Hidden::VoltageLimit => "voltage_limit",
            Hidden::DroppedMessages => "dropped_messages",
            Hidden::TimestampJitter => "timestamp_jitter",
        }
    }

    /// The mechanism and the unit of [`Scenario::magnitude`].
    pub fn describe(self) -> &'static str {
        match self {
            Hidden::Clean => "nothing hidden (magnitude 0)",
            Hidden::CurrentLoopDemand => {
                "PI current loop, bandwidth ω_c [rad/s]; force = torque demand"
            }
            Hidden::CurrentLoopMeasured => {
                "PI current loop, bandwidth ω_c [rad/s]; force = Kt·measured current"
            }
            Hidden::CurrentSenseFilter => "first-order current-sense filter, time constant [s]",
            Hidden::VelocityObserver => {
                "4096-count angle, PLL observer, natural frequency [Hz] (25–80), ζ = 1/√2"
            }
            Hidden::AccelerationFilter => {
                "first-order filter on the acceleration estimate, time constant [s]"
            }
            Hidden::LoadCell => {
                "load cell, sample rate [Hz] (natural frequency and damping drawn too)"
            }
            Hidden::ForceOffset => "current-sense zero offset, as torque [N·m]",
            Hidden::Braking => "braking torque unseen by the current sense [N·m]",
            Hidden::ClockRate => "device clock rate error ε [–]",
            Hidden::KtError => "Kt_true/Kt_nominal [–]",
            Hidden::Stribeck => {
                "Coulomb friction F_c [N·m] (break-away F_s and Stribeck speed drawn too)"
            }
            Hidden::Viscous => "viscous bearing friction [N·m·s/rad]",
            Hidden::ReynoldsDrag => "drag exponent p = 2 − m of C_Q ∝ Re^(−m) [–]",
            Hidden::Cogging => "cogging amplitude [N·m] (harmonic 6 or 12)",
            Hidden::PeriodicDisturbance => "external torque amplitude [N·m] (frequency drawn too)",
            Hidden::Gust => "external torque bump peak [N·m] (start and width drawn too)",
            Hidden::VoltageLimit => "supply voltage [V]",
            Hidden::DroppedMessages => "probability of losing a message [–]",
            Hidden::TimestampJitter => {
                "timestamp jitter σ [s] (plus 2 ms latency with 0.5 ms jitter)"
            }
        }
    }

    /// Draws a scenario of this kind on `bench`.
    pub fn draw<R: Rng + ?Sized>(self, bench: &Bench, rng: &mut R) -> Scenario {
        let mut c = bench.base;
        let truth = ExpectedFit {
            inertia: c.rotor.inertia,
            c2: c.rotor.drag.k,
            drag_exponent: c.rotor.drag.exponent,
        };
        let mut fit = truth;
        let h = 1.0 / c.drive.control_rate;
        let (magnitude, expect) = match self {
            Hidden::Clean => (0.0, Expect::Nothing),
            Hidden::CurrentLoopDemand | Hidden::CurrentLoopMeasured => {
                // 2.5–20 ms: a slow loop (or a torque-ramp limit); fast loops leave nothing to see.
                let wc = uniform(rng, 50.0, 400.0);
                c.drive.current_loop = Some(CurrentLoop { bandwidth: wc });
                if self == Hidden::CurrentLoopDemand {
                    c.sensing.torque = TorqueReport::Setpoint;
                    // L·di/dt = v − R·i − Kt·ω with v = Kp·e + Ki∫e + Kt·ω, Kp = L·ω_c, Ki = R·ω_c:
                    // (L s + R) I = (L ω_c + R ω_c/s)(I* − I)  ⇒  I/I* = ω_c/(s + ω_c) exactly. The
                    // drive latches the demand once per control period h (zero-order hold, delay
                    // h/2), and reports the latched value. The felt torque Kt·i is the reported
                    // demand through a first-order lag 1/ω_c after a delay h/2:
                    // torque_lag = 1/ω_c + h/2.
                    (wc, effect("torque_lag", 1.0 / wc + h / 2.0, "s", true))
                } else {
                    // The reported force is Kt·i itself, the torque the rotor feels: the loop's
                    // dynamics are inside the report, and the seed's equation holds exactly.
                    (wc, Expect::Nothing)
                }
            }
            Hidden::CurrentSenseFilter => {
                let tau = uniform(rng, 3e-3, 25e-3);
                c.sensing.torque = TorqueReport::Current {
                    filter: tau,
                    offset: 0.0,
                    noise: 0.0,
                };
                // Reported = Kt·i/(1 + τ s): the report lags the felt torque by exactly τ.
                (tau, effect("force_sensor_lag", tau, "s", true))
            }
            Hidden::VelocityObserver => {
                // 25–80 Hz: sensorless observers and encoder PLLs of small drives.
                let fn_hz = uniform(rng, 25.0, 80.0);
                let zeta = std::f64::consts::FRAC_1_SQRT_2;
                c.sensing.kinematics.counts_per_rev = Some(4096);
                c.sensing.kinematics.velocity = VelocityEstimator::Pll {
                    natural_hz: fn_hz,
                    damping: zeta,
                };
                // e = θ_m − θ̂, θ̂' = ω̂ + k1 e, ω̂' = k2 e  ⇒  E = s²Θ/(s² + k1 s + k2) and
                // Ω̂ = k2 E/s = k2/(s² + k1 s + k2)·Ω: velocity (and its derivative, the reported
                // acceleration) pass a 2nd-order low-pass of group delay k1/k2 = 2ζ/ω_n at low
                // frequency (ζ = 1/√2: flat magnitude to 4th order). The angle is sampled and
                // held each control period h: another h/2 on both; the acceleration is the
                // observer's mean rate over the last period: h/2 more on it. Force is not delayed,
                // so the data obey J·a(t − d_a) = F(t) − k·ω(t − d_v)², i.e. the load seems to feel
                // the force late: torque_lag = 2ζ/ω_n + h (d_a; the inertia term carries the lag;
                // d_v is h/2 shorter, the derivation_error). An observer delay and a torque lag
                // are the same thing in these data.
                let wn = std::f64::consts::TAU * fn_hz;
                let d = 2.0 * zeta / wn + h;
                (
                    fn_hz,
                    Expect::Effect(ExpectedEffect {
                        name: "torque_lag",
                        value: d,
                        unit: "s",
                        in_diagnose_today: true,
                        ambiguous_with: None,
                        derivation_error: h / (2.0 * d) + (bench.max_hz / fn_hz).powi(2),
                    }),
                )
            }
            Hidden::AccelerationFilter => {
                let tau = uniform(rng, 3e-3, 25e-3);
                c.sensing.kinematics.acceleration_filter = tau;
                // Reported acceleration = (dω/dt)/(1 + τ s), velocity exact: acceleration_lag = τ.
                (tau, effect("acceleration_lag", tau, "s", true))
            }
            Hidden::LoadCell => {
                let rate = uniform(rng, 40.0, 100.0);
                let natural_hz = uniform(rng, 40.0, 150.0);
                let damping = uniform(rng, 0.05, 0.5);
                c.sensing.torque = TorqueReport::LoadCell {
                    natural_hz,
                    damping,
                    rate,
                    offset: 0.0,
                    noise: 0.0,
                };
                // The cell ω_n²/(s² + 2ζω_n s + ω_n²) has group delay 2ζ/ω_n at low frequency.
                // It carries the rotor–stator torque, which here (no bearing friction, no
                // cogging) is Kt·i. Each reading (noise included) is held until the next, every
                // T_c = 1/rate, and the rows (every T_r) show the latest. Each reading first
                // shows in the row at or after it: T_r/2 late on average. Rows faster than the
                // cell repeat its readings; a diagnosis that takes each reading at the row that
                // first shows it (as a user reading the log would) sees the cell 2ζ/ω_n + T_r/2
                // late. Rows slower than the cell see its latest reading, T_c/2 old on average.
                // force_sensor_lag = 2ζ/ω_n + min(T_c, T_r)/2. Read row by row instead, the
                // staircase would be T_c/2 late with a sawtooth error of RMS |Ḟ|·T_c/√12.
                let wn = std::f64::consts::TAU * natural_hz;
                let cell = 2.0 * damping / wn;
                let lag = cell + 0.5 / rate.max(c.link.rate);
                (
                    rate,
                    Expect::Effect(ExpectedEffect {
                        name: "force_sensor_lag",
                        value: lag,
                        unit: "s",
                        in_diagnose_today: true,
                        ambiguous_with: None,
                        derivation_error: cell / lag * (bench.max_hz / natural_hz).powi(2),
                    }),
                )
            }
            Hidden::ForceOffset => {
                let offset = signed(rng, 2e-3, 8e-3);
                let kt_nominal = c.motor.kt / (1.0 + c.drive.kt_error);
                c.sensing.torque = TorqueReport::Current {
                    filter: 0.0,
                    offset: offset / kt_nominal,
                    noise: 0.0,
                };
                // Reported = felt + offset: J·a = (F − offset) − k·ω². A Coulomb friction F_c gives
                // J·a = F − F_c·sgn ω − k·ω²: on a rotor that never reverses the two are the same
                // constant, with F_c = offset — physical (F_c > 0) only for a positive offset.
                let ambiguous = (offset > 0.0).then_some((
                    "coulomb_friction",
                    "the rotor never reverses (a positive offset equals a Coulomb friction of the same size)",
                ));
                (
                    offset,
                    Expect::Effect(ExpectedEffect {
                        name: "force_offset",
                        value: offset,
                        unit: "N·m",
                        in_diagnose_today: false,
                        ambiguous_with: ambiguous,
                        derivation_error: 0.0,
                    }),
                )
            }
            Hidden::Braking => {
                let b = uniform(rng, 2e-3, 8e-3);
                c.drive.braking = Some(Braking {
                    torque: b,
                    on_threshold: 50.0,
                    off_threshold: 20.0,
                });
                // The rotor feels −B·sgn ω while the drive's deceleration estimate exceeds the
                // thresholds (on at 50, off at 20 rad/s²); the report does not carry it. A model
                // "−B while a < 0" differs only in the few ms where 0 > a > −50 rad/s², which
                // tests/derivations.rs measures: braking_torque = B, decelerating only.
                (
                    b,
                    Expect::Effect(ExpectedEffect {
                        name: "braking_torque",
                        value: b,
                        unit: "N·m",
                        in_diagnose_today: false,
                        ambiguous_with: None,
                        derivation_error: 0.03,
                    }),
                )
            }
            Hidden::ClockRate => {
                // A drive on its internal RC oscillator: 0.3–2 %; a crystal's 50 ppm is invisible.
                let eps = signed(rng, 3e-3, 2e-2);
                c.link.clock.rate_error = eps;
                // Device time τ = (1 + ε)t. The drive reports ω/(1 + ε) and a/(1 + ε)² (per device
                // second); torque is unaffected. In device units J(1+ε)²·a_d = F − c2(1+ε)²·ω_d²:
                // a fit in device time finds J(1+ε)² and c2(1+ε)²; against ts_local (host time)
                // the device clock's rate is 1 + ε: time_base = ε. Corrected, J and c2 are true.
                (
                    eps,
                    Expect::Effect(ExpectedEffect {
                        name: "time_base",
                        value: eps,
                        unit: "1",
                        in_diagnose_today: false,
                        ambiguous_with: None,
                        derivation_error: 0.0,
                    }),
                )
            }
            Hidden::KtError => {
                let e = signed(rng, 0.05, 0.2);
                c.drive.kt_error = e;
                let r = 1.0 + e;
                // The drive commands i = τ*/Kt_nom and reports Kt_nom·i = τ*, the rotor feels
                // Kt·i = r·τ*: J·a = r·F − c2·ω²  ⇔  (J/r)·a = F − (c2/r)·ω². The data fit J/r
                // and c2/r exactly; nothing in them reveals r.
                fit.inertia = truth.inertia / r;
                fit.c2 = truth.c2 / r;
                (
                    r,
                    Expect::NotIdentifiable {
                        name: "torque_scale",
                        value: r,
                        why: "a torque scale error scales J and c2 alike; only an independent torque reference (a load cell, a known inertia) identifies it",
                    },
                )
            }
            Hidden::Stribeck => {
                let fc = uniform(rng, 1e-3, 5e-3);
                let fs = fc * uniform(rng, 1.5, 3.0);
                let ws = uniform(rng, 2.0, 20.0);
                let b = &mut c.rotor.bearing;
                b.coulomb = fc;
                b.breakaway = fs;
                b.stribeck_speed = ws;
                // (F_s − F_c)·exp(−(ω/ω_s)²) vanishes at stand speeds: at the lowest steady speed
                // (hundreds of rad/s) against ω_s ≤ 20 rad/s it is below e^(−100)·F_s. What is
                // left is F_c·sgn ω: coulomb_friction = F_c. (The Stribeck dip is only seen when
                // the rotor starts or reverses.)
                (fc, effect("coulomb_friction", fc, "N·m", true))
            }
            Hidden::Viscous => {
                let b = uniform(rng, 1e-6, 3e-6);
                c.rotor.bearing.viscous = b;
                (b, effect("viscous_friction", b, "N·m·s/rad", true))
            }
            Hidden::ReynoldsDrag => {
                let p = 2.0 + signed(rng, 0.1, 0.3);
                // C_Q ∝ Re^(−m) with Re ∝ ω: drag = k·ω^(2−m), p = 2 − m exactly. k is chosen so
                // the drag matches the base stand's at the middle of the speed range.
                let w_mid = bench.steady_speed(0.5 * (bench.lo + bench.hi));
                let k = truth.c2 * w_mid.powf(2.0 - p);
                c.rotor.drag.k = k;
                c.rotor.drag.exponent = p;
                fit.c2 = k;
                fit.drag_exponent = p;
                (p, effect("drag_exponent", p, "1", true))
            }
            Hidden::Cogging => {
                let a = uniform(rng, 1e-3, 5e-3);
                let n = if rng.random::<bool>() { 6.0 } else { 12.0 };
                c.rotor.cogging.amplitude = a;
                c.rotor.cogging.harmonic = n;
                c.rotor.cogging.phase = uniform(rng, 0.0, std::f64::consts::TAU);
                // A reluctance torque: the phase current does not carry it, so the reported
                // Kt·i misses A·sin(nθ + φ): torque_ripple = A at harmonic n.
                (a, effect("torque_ripple", a, "N·m", true))
            }
            Hidden::PeriodicDisturbance => {
                let a = uniform(rng, 2e-3, 6e-3);
                let hz = uniform(rng, 5.0, 15.0);
                c.disturbance = Disturbance::Periodic { amplitude: a, hz };
                (
                    a,
                    Expect::Unexplained {
                        at: Where::Periodic { hz },
                        what: "an external torque periodic in time (a vibrating fixture, a wake)",
                    },
                )
            }
            Hidden::Gust => {
                let a = signed(rng, 10e-3, 30e-3);
                let d = bench.duration;
                let width = uniform(rng, 0.03, 0.08) * d;
                // Late in the run, where a held-out last 30 % sees it.
                let start = uniform(rng, 0.75 * d, 0.95 * d - width);
                c.disturbance = Disturbance::Bump {
                    amplitude: a,
                    start,
                    width,
                };
                (
                    a,
                    Expect::Unexplained {
                        at: Where::TimeWindow {
                            from: start,
                            to: start + width,
                        },
                        what:
                            "an external torque for a few seconds (a gust, a hand on the fixture)",
                    },
                )
            }
            Hidden::VoltageLimit => {
                // The supply just reaches the steady state at u·ω_hi, u ∈ [0.8, 0.92]: above that
                // speed the current, and so the torque, falls short of the demand the drive
                // reports. Quasi-static (ideal current loop): |R·i + Kt·ω| ≤ V.
                let u = uniform(rng, 0.8, 0.92);
                let wx = u * bench.steady_speed(bench.hi);
                let d = &c.rotor.drag;
                let ix = d.k * wx.powf(d.exponent) / c.motor.kt;
                let v = c.motor.kt * wx + c.motor.resistance * ix;
                c.motor.supply_voltage = v;
                c.sensing.torque = TorqueReport::Setpoint;
                (
                    v,
                    Expect::Unexplained {
                        at: Where::Condition(Condition::HighSpeed),
                        what: "the supply voltage limits the current at high speed: the torque falls short of the reported demand",
                    },
                )
            }
            Hidden::DroppedMessages => {
                let p = uniform(rng, 0.02, 0.2);
                c.link.drop_probability = p;
                (p, Expect::Nothing)
            }
            Hidden::TimestampJitter => {
                let s = uniform(rng, 20e-6, 100e-6).min(0.3 / c.link.rate);
                c.link.clock.stamp_jitter = s;
                c.link.latency = 2e-3;
                c.link.latency_jitter = 0.5e-3;
                (s, Expect::Nothing)
            }
        };
        Scenario {
            hidden: self,
            config: c,
            magnitude,
            expect,
            fit,
            bench: *bench,
        }
    }
}
