//! `propid import` (not yet implemented).

/// The importers.
#[derive(clap::Subcommand, Debug)]
pub enum Command {}

/// Runs an importer.
pub fn run(command: Command) -> anyhow::Result<()> {
    match command {}
}
