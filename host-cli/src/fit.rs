//! `propid fit` (not yet implemented).

/// Arguments of `propid fit`.
#[derive(clap::Args, Debug)]
pub struct Args {}

/// Runs `propid fit`.
pub fn run(_args: Args) -> anyhow::Result<()> {
    anyhow::bail!("propid fit is not implemented yet")
}
