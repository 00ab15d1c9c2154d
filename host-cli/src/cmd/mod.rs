//! One module per subcommand: its clap arguments and the `run` that calls the libraries.

pub mod demo;
pub mod diagnose;
pub mod drive;
pub mod fit;
pub mod import;
pub mod plan;
pub mod propulsion;
pub mod replay;
pub mod report;
pub mod sim;
pub mod sim_drive;
pub mod size;
pub mod stand_instruments;
pub mod telega;

/// How the recording's columns are read, for every command that fits (`fit`, `diagnose`,
/// `report`): the answers to the plausibility gate's findings.
#[derive(clap::Args, Debug, Clone, Copy)]
pub struct ReadingArgs {
    /// The force column's sign is reversed (the torque works against the acceleration it
    /// causes): read it negated.
    #[arg(long)]
    pub flip_torque: bool,
    /// The velocity column's unit: rad/s (propid's), rpm, rev/s or deg/s; it is converted to
    /// rad/s before anything is fitted (the acceleration stays in rad/s²).
    #[arg(long, value_parser = propid_science::plausibility::SpeedUnit::parse, default_value = "rad/s")]
    pub velocity_unit: propid_science::plausibility::SpeedUnit,
}

impl ReadingArgs {
    /// The reading these flags ask for.
    pub fn reading(&self) -> propid_science::plausibility::Reading {
        propid_science::plausibility::Reading {
            flip_torque: self.flip_torque,
            velocity_unit: self.velocity_unit,
        }
    }
}
