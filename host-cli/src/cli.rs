//! The command line as a library: what `main` runs, callable in-process too (the Python
//! package's `propid` command runs it inside the interpreter; its `simulate` parses flags with it).

use std::ffi::OsString;
use std::process::ExitCode;

use clap::{Parser, Subcommand};

/// Identify the dynamics of a propeller or fan on a Zubax Telega drive over Cyphal/CAN.
#[derive(Parser)]
#[command(name = "propid", version, about, long_about = None)]
pub struct Cli {
    /// The subcommand.
    #[command(subcommand)]
    pub command: Command,
}

/// The subcommands.
#[derive(Subcommand)]
pub enum Command {
    /// Drive a Telega over Cyphal/CAN with the identification pattern and record its feedback as TSV.
    Drive(crate::cmd::drive::Args),
    /// Fit inertia and drag (m, c1, c2) to a recorded TSV, like the seed regressor but exact.
    Fit(crate::cmd::fit::Args),
    /// Simulate a test stand and write the TSV `drive` would have recorded.
    Sim(crate::cmd::sim::Args),
    /// Find what the fitted model gets wrong, name the cause, extend the model and measure the gain.
    Diagnose(crate::cmd::diagnose::Args),
    /// Convert measured logs from other test stands into propid's TSV.
    #[command(subcommand)]
    Import(crate::cmd::import::Command),
    /// Run a simulated Telega as a Cyphal node on a CAN interface.
    SimDrive(crate::cmd::sim_drive::Args),
    /// Reassemble a candump log and write the feedback subject as TSV.
    Replay(crate::cmd::replay::Args),
    /// Design the excitation from a prior: the most precise J and c2 within the setpoint range.
    Plan(crate::cmd::plan::Args),
    /// Write one self-contained HTML report of a recording: fit, diagnosis, interactive plots.
    Report(crate::cmd::report::Args),
    /// Propeller and motor from a stand's log: C_T and C_Q over speed, thrust per watt, figure of
    /// merit, Kv, resistance, no-load current, efficiency.
    Propulsion(crate::cmd::propulsion::Args),
    /// Size the drivetrain: speed, torque, power, current, DC link and battery for a thrust.
    Size(crate::cmd::size::Args),
    /// Find Telega drives on the bus, check their registers for identification, fix and store them.
    Telega(crate::cmd::telega::Args),
    /// Run the whole pipeline on a simulated stand over a virtual SLCAN bus; no hardware needed.
    Demo(crate::cmd::demo::Args),
}

impl Cli {
    /// Runs the parsed command.
    pub fn run(self) -> anyhow::Result<()> {
        use crate::cmd;
        match self.command {
            Command::Drive(a) => cmd::drive::run(a),
            Command::Fit(a) => cmd::fit::run(a),
            Command::Sim(a) => cmd::sim::run(a),
            Command::Diagnose(a) => cmd::diagnose::run(a),
            Command::Import(c) => cmd::import::run(c),
            Command::SimDrive(a) => cmd::sim_drive::run(a),
            Command::Replay(a) => cmd::replay::run(a),
            Command::Plan(a) => cmd::plan::run(a),
            Command::Report(a) => cmd::report::run(a),
            Command::Demo(a) => cmd::demo::run(a),
            Command::Telega(a) => cmd::telega::run(a),
            Command::Propulsion(a) => cmd::propulsion::run(a),
            Command::Size(a) => cmd::size::run(a),
        }
    }
}

/// Runs the command line `args` (the program name first) as `main` does: usage errors and
/// failures are printed on stderr as `error: …`; returns the exit status (0 done, 1 failed,
/// 2 bad input or usage, 3 cannot judge).
pub fn exit_status<I, T>(args: I) -> u8
where
    I: IntoIterator<Item = T>,
    T: Into<OsString> + Clone,
{
    let cli = match Cli::try_parse_from(args) {
        Ok(cli) => cli,
        Err(e) => {
            // --help and --version print on stdout and exit 0; usage errors on stderr, 2.
            let _ = e.print();
            return u8::try_from(e.exit_code()).unwrap_or(2);
        }
    };
    match cli.run() {
        Ok(()) => 0,
        // The reader of our output went away (`propid sim | head`): not an error.
        Err(err)
            if err.chain().any(|e| {
                e.downcast_ref::<std::io::Error>()
                    .is_some_and(|e| e.kind() == std::io::ErrorKind::BrokenPipe)
            }) =>
        {
            0
        }
        Err(err) => {
            eprintln!("error: {err:#}");
            crate::exit_status_for(&err)
        }
    }
}

/// [`exit_status`] as the `ExitCode` a `main` returns.
pub fn run<I, T>(args: I) -> ExitCode
where
    I: IntoIterator<Item = T>,
    T: Into<OsString> + Clone,
{
    ExitCode::from(exit_status(args))
}
