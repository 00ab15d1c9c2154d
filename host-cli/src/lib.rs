//! # propid (host library and CLI)
//!
//! Everything the `propid` command does lives here as a library, so tests call it directly and
//! the binary stays a thin argument parser. Data flows through one currency, [`tsv::Sample`]:
//! producers (`drive`, `replay`, `sim`, the importers) write the canonical TSV, consumers (`fit`,
//! `diagnose`, plots) read it.
#![deny(missing_docs)]

pub mod bus;
pub mod demo;
pub mod diagnose;
pub mod drive;
pub mod fit;
pub mod import;
pub mod plot;
pub mod replay;
pub mod sim;
pub mod sim_drive;
pub mod steady;
pub mod tsv;

/// An error caused by bad input (a file's content, an argument's value). The binary exits with
/// status 2 for these and 1 for everything else.
#[derive(Clone, Debug, thiserror::Error)]
#[error("{0}")]
pub struct InputError(pub String);

/// The exit status for an error: 2 for bad input, 1 otherwise.
pub fn exit_status_for(err: &anyhow::Error) -> u8 {
    let bad_input = err.chain().any(|e| {
        e.downcast_ref::<InputError>().is_some() || e.downcast_ref::<tsv::TsvError>().is_some()
    });
    if bad_input {
        2
    } else {
        1
    }
}
