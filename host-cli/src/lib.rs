//! # propid (the command)
//!
//! The `propid` binary is thin: clap arguments, files and standard streams, progress bars,
//! plots, signal handlers and exit codes. Everything it computes lives in libraries that tests
//! call directly:
//!
//! ```text
//!  propid-core       no_std Cyphal/CAN stack, DSDL codecs, estimator, load model
//!  propid-transport  CanTransport: SLCAN (all OSes), SocketCAN (Linux), memory bus
//!  propid-io         the TSV sample stream, importers, candump logs
//!  propid-science    excitation, stand simulators, fit, diagnosis
//!  propid-drive-proto  the driver, the simulated Telega, the register client: Sans-IO machines
//!  propid-drive-host   those machines on a real bus and clock, recording to files; the live view's model
//!  propid-mechsim    a mechanism-level stand, independent of the science (`sim --stand mechanism`)
//!  propid (here)     cli — the command line, also run in-process (the Python package's `propid`);
//!                    settings — each setting a type (flag, register, variable, parse); raw → checked;
//!                    cmd::* — one module per subcommand: its settings → library call → output
//! ```
#![deny(missing_docs)]

pub mod bus;
pub mod cli;
pub mod cmd;
pub mod html;
pub mod live;
pub mod plot;
pub mod settings;
pub mod signals;

pub use cli::{exit_status, run};
pub use propid_io::InputError;

/// The run was interrupted (SIGINT or SIGTERM, or STOP on the live page) and stopped as it
/// should: [`run`] exits with 130, the shell's status for an interrupt.
#[derive(Debug)]
pub struct Interrupted;

impl std::fmt::Display for Interrupted {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str("interrupted")
    }
}

impl std::error::Error for Interrupted {}

/// The data cannot support a verdict (`propid diagnose`): exit status 3, distinct from bad input.
#[derive(Debug)]
pub struct CannotJudge(pub String);

impl std::fmt::Display for CannotJudge {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(&self.0)
    }
}

impl std::error::Error for CannotJudge {}

/// The operating system's words for `e`, without Rust's " (os error N)" suffix.
pub fn os_words(e: &std::io::Error) -> String {
    let text = e.to_string();
    match text.rfind(" (os error ") {
        Some(i) if text.ends_with(')') => text[..i].to_string(),
        _ => text,
    }
}

/// Exit status of `propid diagnose` when the data cannot support a verdict.
pub const EXIT_CANNOT_JUDGE: u8 = 3;

/// The exit status for an error: 3 when the data cannot support a verdict, 2 for bad input,
/// 1 otherwise.
pub fn exit_status_for(err: &anyhow::Error) -> u8 {
    if err
        .chain()
        .any(|e| e.downcast_ref::<CannotJudge>().is_some())
    {
        return EXIT_CANNOT_JUDGE;
    }
    use propid_io::candump::ReplayError;
    use propid_science::fit::FitError;
    // The libraries' error enums wrap bad input transparently (their `source()` is the inner
    // error's source), so look at the enums themselves too.
    let bad_input = err.chain().any(|e| {
        e.downcast_ref::<InputError>().is_some()
            || e.downcast_ref::<settings::ConfigErrors>().is_some()
            || e.downcast_ref::<propid_io::tsv::TsvError>().is_some()
            || matches!(
                e.downcast_ref::<FitError>(),
                Some(FitError::Input(_) | FitError::Tsv(_))
            )
            || matches!(e.downcast_ref::<ReplayError>(), Some(ReplayError::Input(_)))
    });
    if bad_input {
        2
    } else {
        1
    }
}
