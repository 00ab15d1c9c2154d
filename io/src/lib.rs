//! # propid-io: the files propid reads and writes
//!
//! Every producer of measurements in propid — the driver, `replay`, the stand simulators, the
//! importers of other stands' logs — writes one format, and every consumer — `fit`, `diagnose`,
//! the plots — reads it: the TSV of [`tsv::Sample`]s (time, torque, velocity, acceleration,
//! position), with what a test stand measures beside them in optional columns ([`tsv::Stand`]:
//! thrust, bus voltage and current, the command). This crate owns that currency and the ways
//! into it:
//!
//! ```text
//!  candump -L log ──► candump::parse_candump_line ─► Frame ─► Reassembler ─► DoF3rdTs ─┐
//!  Tyto/RCbenchmark CSV, ESC32 CSV ──► import::* (units, signs, rates measured) ────────┼─► tsv::Row
//!                                                                                       │
//!  tsv::TsvReader (streaming, constant memory, errors name file/line/column) ◄── TSV ◄──┘ tsv::TsvWriter
//! ```
//!
//! Nothing here prints or exits: bad input is an [`InputError`] — where (file, line, column) and
//! what ([`ErrorKind`]) — for the command-line tool to show. Files come in through
//! [`input::open`] (standard input for `-`, gzip read transparently, lines bounded, every OS
//! error once with its path) and go out through [`output::AtomicOutput`] (never over an input,
//! never half-written).
#![deny(missing_docs)]

pub mod candump;
pub mod error;
pub mod glitch;
mod header;
pub mod import;
pub mod input;
pub mod output;
pub mod tsv;

pub use error::{Compression, ErrorKind, Importer, InputError, Place};
