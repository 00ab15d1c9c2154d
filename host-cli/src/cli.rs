//! The `propid` command line as a library function: [`run`] parses the arguments, runs the
//! subcommand and turns its outcome into the exit status. The binary's `main` is one call to it,
//! and the Python package runs the same function in-process (its signal handlers are installed
//! by the commands that drive, for as long as they drive, never by `main`).

use std::ffi::OsString;
use std::process::ExitCode;

use clap::{Parser, Subcommand};

use crate::cmd;

/// Identify the dynamics of a propeller or fan on a Zubax Telega drive over Cyphal/CAN.
#[derive(Parser)]
#[command(name = "propid", version, about, long_about = None)]
pub struct Cli {
    /// The subcommand.
    #[command(subcommand)]
    pub command: Command,
}

/// The subcommands.
// Parsed once per process; the arguments' sizes do not matter.
#[allow(clippy::large_enum_variant)]
#[derive(Subcommand)]
pub enum Command {
    /// Drive a Telega over Cyphal/CAN with the identification pattern and record its feedback as TSV.
    Drive(cmd::drive::Args),
    /// Fit inertia and drag (m, c1, c2) to a recorded TSV, like the seed regressor but exact.
    Fit(cmd::fit::Args),
    /// Simulate a test stand and write the TSV `drive` would have recorded.
    Sim(cmd::sim::Args),
    /// Find what the fitted model gets wrong, name the cause, extend the model and measure the gain.
    Diagnose(cmd::diagnose::Args),
    /// Convert measured logs from other test stands into propid's TSV.
    #[command(subcommand)]
    Import(cmd::import::Command),
    /// Run a simulated Telega as a Cyphal node on a CAN interface.
    SimDrive(cmd::sim_drive::Args),
    /// Reassemble a candump log and write the feedback subject as TSV.
    Replay(cmd::replay::Args),
    /// Design the excitation from a prior: the most precise J and c2 within the setpoint range.
    Plan(cmd::plan::Args),
    /// Write one self-contained HTML report of a recording: fit, diagnosis, interactive plots.
    Report(cmd::report::Args),
    /// Propeller and motor from a stand's log: C_T and C_Q over speed, thrust per watt, figure of
    /// merit, Kv, resistance, no-load current, efficiency.
    Propulsion(cmd::propulsion::Args),
    /// Size the drivetrain: speed, torque, power, current, DC link and battery for a thrust.
    Size(cmd::size::Args),
    /// Find Telega drives on the bus, check their registers for identification, fix and store them.
    Telega(cmd::telega::Args),
    /// Run the whole pipeline on a simulated stand over a virtual SLCAN bus; no hardware needed.
    Demo(cmd::demo::Args),
}

impl Cli {
    /// Runs the parsed command.
    pub fn run(self) -> anyhow::Result<()> {
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

/// Runs the command line `args` (the program's name first, as `std::env::args_os` gives them)
/// as `main` does and returns the exit status: help and usage errors as clap prints them (0 or
/// 2), a command's error on stderr as `error: …` with [`crate::exit_status_for`]'s status (1
/// failed, 2 bad input, 3 cannot judge), 130 after an interruption (said already).
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
        // Said already (the drive's stop line); the shell's convention for SIGINT.
        Err(err) if err.downcast_ref::<crate::Interrupted>().is_some() => 130,
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

#[cfg(test)]
mod tests {
    use super::*;
    use crate::settings::{Fields, Names};
    use propid_drive_proto::registers::environment_name;

    /// Every setting of every command, by its names.
    fn settings_of(args: &[&str]) -> Vec<Names> {
        let mut names = Vec::new();
        let mut visit = |fields: &mut dyn Fields| fields.visit(&mut |n, _| names.push(n));
        match Cli::try_parse_from(args).unwrap().command {
            Command::Drive(mut a) => visit(&mut a),
            Command::SimDrive(mut a) => visit(&mut a),
            Command::Telega(mut a) => visit(&mut a),
            Command::Plan(mut a) => visit(&mut a),
            Command::Demo(mut a) => visit(&mut a),
            _ => unreachable!("a command without settings"),
        }
        names
    }

    #[test]
    fn a_registers_variable_is_its_name_as_pycyphal_maps_it_and_flags_are_unique() {
        for args in [
            &["propid", "drive"][..],
            &["propid", "sim-drive"],
            &["propid", "telega"],
            &["propid", "plan", "--max-torque", "1"],
            &["propid", "demo"],
        ] {
            let names = settings_of(args);
            assert!(!names.is_empty(), "{args:?}");
            for n in &names {
                if let (Some(r), Some(e)) = (n.register, n.env) {
                    assert_eq!(environment_name(r), e, "{args:?}: {n:?}");
                }
                // The flag reaches its own slot: a flag given is set where its names say.
                if let Some(flag) = n.flag {
                    let mut given = args.to_vec();
                    let long = format!("--{flag}");
                    given.extend([long.as_str(), "x"]);
                    let mut set = Vec::new();
                    let mut record = |fields: &mut dyn Fields| {
                        fields.visit(&mut |m, slot| {
                            if slot.is_set() {
                                set.push(m)
                            }
                        })
                    };
                    match Cli::try_parse_from(&given).unwrap().command {
                        Command::Drive(mut a) => record(&mut a),
                        Command::SimDrive(mut a) => record(&mut a),
                        Command::Telega(mut a) => record(&mut a),
                        Command::Plan(mut a) => record(&mut a),
                        Command::Demo(mut a) => record(&mut a),
                        _ => unreachable!(),
                    }
                    assert_eq!(set, [*n], "{given:?}");
                }
            }
            let mut flags: Vec<_> = names.iter().filter_map(|n| n.flag).collect();
            flags.sort();
            let count = flags.len();
            flags.dedup();
            assert_eq!(flags.len(), count, "{args:?}: a flag named twice");
        }
    }
}
