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
