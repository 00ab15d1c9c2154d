//! # propid-science: what the measurements say about the load
//!
//! The science side of propid, as a library with no command line in it: it never prints, never
//! exits and never names a flag, so tests, the firmware-minded core and the `propid` command all
//! call the same functions.
//!
//! ```text
//!  excitation::Excitation (init at hi, then sine | steps | chirp) ──► setpoint(t)
//!        │                                          │
//!        ▼                                          ▼
//!  stand::Stand (formula-level simulator) ──► tsv::Sample stream ◄── drive, replay, importers (propid-io)
//!                                                   │
//!            ┌──────────────────────────────────────┴───────────────────┐
//!            ▼                                                          ▼
//!  fit::fit_path: the seed's trimming and bounds,           diagnose::diagnose: base fit → open-loop
//!  solved exactly by the core's NormalEquations             simulation → residual analysis → candidate
//!  ─► FitReport (J, c1, c2, stderr, C_Q)                    effects chosen on held-out data ─► Report
//!            │                                                          │
//!            └──────────────► figure::Figure (what to plot) ◄───────────┘
//! ```
//!
//! Every input is checked once (`Excitation::validate`, `StandConfig::validate`,
//! `FitOptions::check`) and bad input comes back as a [`propid_io::InputError`] whose message says
//! what is wrong, in the quantity's own name.
#![deny(missing_docs)]

pub mod diagnose;
pub mod excitation;
pub mod figure;
pub mod fit;
pub mod plan;
pub mod propulsion;
pub mod stand;

pub use propid_io::InputError;
