//! `propid sim` (not yet implemented).

/// Arguments of `propid sim`.
#[derive(clap::Args, Debug)]
pub struct Args {}

/// Runs `propid sim`.
pub fn run(_args: Args) -> anyhow::Result<()> {
    anyhow::bail!("propid sim is not implemented yet")
}
