//! `propid replay` (not yet implemented).

/// Arguments of `propid replay`.
#[derive(clap::Args, Debug)]
pub struct Args {}

/// Runs `propid replay`.
pub fn run(_args: Args) -> anyhow::Result<()> {
    anyhow::bail!("propid replay is not implemented yet")
}
