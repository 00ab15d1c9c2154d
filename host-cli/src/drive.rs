//! `propid drive` (not yet implemented).

/// Arguments of `propid drive`.
#[derive(clap::Args, Debug)]
pub struct Args {}

/// Runs `propid drive`.
pub fn run(_args: Args) -> anyhow::Result<()> {
    anyhow::bail!("propid drive is not implemented yet")
}
