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

/// A limit stopped the rotor (`propid drive`): exit status 4.
#[derive(Debug)]
pub struct LimitStopped(pub String);

impl std::fmt::Display for LimitStopped {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(f, "stopped by a limit: {}", self.0)
    }
}

impl std::error::Error for LimitStopped {}

/// Exit status of `propid drive` when a limit stopped the rotor (soft start, maximum speed,
/// speed watchdog).
pub const EXIT_LIMIT: u8 = 4;

/// The exit status for an error, for every command: 4 when a limit stopped the rotor, 3 when
/// the data cannot support a verdict, 2 for bad input (a file's content, a path that cannot be
/// read, a flag's value), 1 otherwise. The one place where errors become exit statuses.
pub fn exit_status_for(err: &anyhow::Error) -> u8 {
    if err
        .chain()
        .any(|e| e.downcast_ref::<LimitStopped>().is_some())
    {
        return EXIT_LIMIT;
    }
    use propid_io::candump::ReplayError;
    use propid_science::fit::FitError;
    // The libraries' error enums wrap bad input transparently (their `source()` is the inner
    // error's source), so look into the enums themselves too.
    let input = err.chain().find_map(|e| {
        e.downcast_ref::<InputError>()
            .or(match e.downcast_ref::<FitError>() {
                Some(FitError::Input(e)) => Some(e),
                None => None,
            })
            .or(match e.downcast_ref::<ReplayError>() {
                Some(ReplayError::Input(e)) => Some(e),
                _ => None,
            })
    });
    let cannot_judge = err
        .chain()
        .any(|e| e.downcast_ref::<CannotJudge>().is_some())
        || input.is_some_and(InputError::is_cannot_judge);
    if cannot_judge {
        EXIT_CANNOT_JUDGE
    } else if input.is_some()
        || err
            .chain()
            .any(|e| e.downcast_ref::<settings::ConfigErrors>().is_some())
    {
        EXIT_BAD_INPUT
    } else {
        1
    }
}

/// Exit status for bad input.
pub const EXIT_BAD_INPUT: u8 = 2;
