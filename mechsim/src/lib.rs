//! # A mechanism-level test-stand simulator
//!
//! propid's own simulator (`propid sim`) injects the very formulas `propid diagnose` then looks
//! for: a first-order "torque lag", a `c2·ω|ω|` drag, a Coulomb term. Tested on it, the diagnosis
//! can only agree with itself. This crate is the other side of that test. It simulates the chain
//! a Telega stand really has, part by part, from physics, and shares no code with propid's fit,
//! diagnosis, plant model or formula-level simulator; it was written from the seed document and
//! textbook models. Whatever a mechanism does to the data — including what the diagnosis has no
//! formula for — comes out of the mechanism, not out of a formula chosen to be found.
//!
//! ## What is modelled
//! ```text
//!  pattern(t) ──► setpoint ∈ [−1, 1] ──► torque command = setpoint · max_torque
//!        (init phase at a constant setpoint first, not recorded, like the seed's driver)
//!  current reference i* = command / Kt_nominal                (Kt error: Kt_true ≠ Kt_nominal)
//!  PI current loop: L di/dt = v − R i − Ke ω,  v = sat_V(Kp e + ∫Ki e + Ke ω)   (or ideal)
//!  rotor:  J ω' = Kt i + cogging(θ) + brake − bearing(ω) − drag(ω) + disturbance(t)
//!          drag = k |ω|^p (1 + α(|ω|/ω_ref − 1)) sgn ω;  bearing = Coulomb + Stribeck + viscous
//!          brake: engaged by the drive's own deceleration estimate, invisible to its current sense
//!  drive's sensing at the control rate (10 kHz):  angle quantised to N counts, held;
//!          velocity: exact, or a type-2 tracking observer (PLL);  acceleration: its derivative,
//!          optionally low-pass filtered
//!  reported force: the command | Kt_nominal·(filtered measured current + offset + noise)
//!          | a load cell under the stator (mass-spring-damper on the rotor–stator torque, its
//!            own sample rate and zero-order hold, offset, noise)
//!  feedback messages at the link rate on the device clock (rate error, drift, stamp jitter),
//!          lost with a probability, received at ts_local = host time + latency (+ jitter)
//!  a thrust stand's instruments (off by default): thrust k·|ω|^p through a mass-spring-damper
//!          cell read at its own rate and held; the DC bus: source with resistance, lossless ESC
//!          (V_bus·I_bus = v·i, duty v/V_bus), bus current through the ESC's first-order filter
//!  ──► Record { ts_local, t, force, velocity, acceleration, position, setpoint, thrust,
//!               voltage, current, duty, truth }
//!  ──► write_tsv: the TSV propid reads
//! ```
//! Every mechanism is off in [`MechConfig::default`]: a clean stand whose data satisfy
//! `J·a = F − k·ω^p` to integration accuracy. The continuous state (current, PI integrator, speed,
//! angle, observer, filters, load cell and three energy integrals) is integrated by RK4 over each
//! control period with the drive's discrete decisions held; see [`stand`].
//!
//! ## Why it can catch the diagnosis's blind spots
//! The mechanisms do not map one-to-one onto the diagnosis's candidates, and some map onto none.
//! A current loop is a torque lag only if the drive reports its demand; if it reports its
//! measured current, nothing is wrong. A velocity observer delays velocity *and* acceleration,
//! which in the data is the same as a torque lag. A load cell does not see bearing friction. A
//! torque-constant error is invisible without an independent torque reference. [`scenarios`]
//! draws such cases at random magnitudes and states, for each, what a correct diagnosis must
//! report, with the value derived analytically from the mechanism (each derivation is written
//! next to it and checked numerically by a unit test).
//!
//! ## Cost
//! One RK4 step per control period (10 kHz by default, 1.2 million steps for 120 s). Measured
//! with `examples/time120.rs` under `/usr/bin/time` (release build, a 2-core machine shared with
//! other builds, load ≈ 8): 120 s at 1 kHz feedback take 0.19 s of CPU on a clean stand and
//! 0.40 s with a current loop, PLL, acceleration filter, friction, cogging, a drag exponent and a
//! disturbance on (the libm `sin` and `pow` calls are most of that). `benches/simulate.rs` times
//! the same with criterion; its wall-clock figures on that loaded machine were 0.43 s and 1.4 s.

#![deny(missing_docs)]

pub mod config;
pub mod pattern;
pub mod record;
pub mod scenarios;
pub mod stand;

pub use config::{
    Bearing, Braking, Bus, Cogging, ConfigError, CurrentLoop, DeviceClock, Disturbance, Drag,
    Drive, Field, Instruments, Kinematics, Link, MechConfig, Motor, ReportNoise, Rotor, Run,
    Sensing, Thrust, ThrustCell, TorqueReport, VelocityEstimator,
};
pub use record::{write_tsv, Energy, Record, Truth, TsvSink, STAND_HEADER, TSV_HEADER};
pub use stand::{simulate, MechStand};
