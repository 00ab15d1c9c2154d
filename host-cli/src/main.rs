//! The `propid` command: a thin argument parser over the `propid` library.

use std::process::ExitCode;

use clap::{Parser, Subcommand};

/// Identify the dynamics of a propeller or fan on a Zubax Telega drive over Cyphal/CAN.
#[derive(Parser)]
#[command(name = "propid", version, about, long_about = None)]
struct Cli {
    #[command(subcommand)]
    command: Command,
}

#[derive(Subcommand)]
enum Command {
    /// Drive a Telega over Cyphal/CAN with the identification pattern and record its feedback as TSV.
    Drive(propid::cmd::drive::Args),
    /// Fit inertia and drag (m, c1, c2) to a recorded TSV, like the seed regressor but exact.
    Fit(propid::cmd::fit::Args),
    /// Simulate a test stand and write the TSV `drive` would have recorded.
    Sim(propid::cmd::sim::Args),
    /// Find what the fitted model gets wrong, name the cause, extend the model and measure the gain.
    Diagnose(propid::cmd::diagnose::Args),
    /// Convert measured logs from other test stands into propid's TSV.
    #[command(subcommand)]
    Import(propid::cmd::import::Command),
    /// Run a simulated Telega as a Cyphal node on a CAN interface.
    SimDrive(propid::cmd::sim_drive::Args),
    /// Reassemble a candump log and write the feedback subject as TSV.
    Replay(propid::cmd::replay::Args),
    /// Design the excitation from a prior: the most precise J and c2 within the setpoint range.
    Plan(propid::cmd::plan::Args),
    /// Write one self-contained HTML report of a recording: fit, diagnosis, interactive plots.
    Report(propid::cmd::report::Args),
    /// Propeller and motor from a stand's log: C_T and C_Q over speed, thrust per watt, figure of
    /// merit, Kv, resistance, no-load current, efficiency.
    Propulsion(propid::cmd::propulsion::Args),
    /// Size the drivetrain: speed, torque, power, current, DC link and battery for a thrust.
    Size(propid::cmd::size::Args),
    /// Find Telega drives on the bus, check their registers for identification, fix and store them.
    Telega(propid::cmd::telega::Args),
    /// Run the whole pipeline on a simulated stand over a virtual SLCAN bus; no hardware needed.
    Demo(propid::cmd::demo::Args),
}

fn main() -> ExitCode {
    let cli = Cli::parse();
    let result = match cli.command {
        Command::Drive(a) => propid::cmd::drive::run(a),
        Command::Fit(a) => propid::cmd::fit::run(a),
        Command::Sim(a) => propid::cmd::sim::run(a),
        Command::Diagnose(a) => propid::cmd::diagnose::run(a),
        Command::Import(c) => propid::cmd::import::run(c),
        Command::SimDrive(a) => propid::cmd::sim_drive::run(a),
        Command::Replay(a) => propid::cmd::replay::run(a),
        Command::Plan(a) => propid::cmd::plan::run(a),
        Command::Report(a) => propid::cmd::report::run(a),
        Command::Demo(a) => propid::cmd::demo::run(a),
        Command::Telega(a) => propid::cmd::telega::run(a),
        Command::Propulsion(a) => propid::cmd::propulsion::run(a),
        Command::Size(a) => propid::cmd::size::run(a),
    };
    match result {
        Ok(()) => ExitCode::SUCCESS,
        // The reader of our output went away (`propid sim | head`): not an error.
        Err(err)
            if err.chain().any(|e| {
                e.downcast_ref::<std::io::Error>()
                    .is_some_and(|e| e.kind() == std::io::ErrorKind::BrokenPipe)
            }) =>
        {
            ExitCode::SUCCESS
        }
        Err(err) => {
            eprintln!("error: {err:#}");
            ExitCode::from(propid::exit_status_for(&err))
        }
    }
}
