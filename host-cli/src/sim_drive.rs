//! `propid sim-drive` (not yet implemented).

/// Arguments of `propid sim-drive`.
#[derive(clap::Args, Debug)]
pub struct Args {}

/// Runs `propid sim-drive`.
pub fn run(_args: Args) -> anyhow::Result<()> {
    anyhow::bail!("propid sim-drive is not implemented yet")
}
