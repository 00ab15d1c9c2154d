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
//! Nothing here prints or exits: bad input is an [`InputError`] (or a [`tsv::TsvError`]) whose
//! message names the file, the line and the column, for the command-line tool to show.
#![deny(missing_docs)]

pub mod candump;
pub mod import;
pub mod tsv;

/// An error caused by bad input (a file's content, a value given by the user). Its message names
/// where (file, line, column, frame) and what is wrong.
#[derive(Clone, Debug, PartialEq, Eq, thiserror::Error)]
#[error("{0}")]
pub struct InputError(pub String);
