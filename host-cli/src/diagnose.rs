//! `propid diagnose` (not yet implemented).

/// Arguments of `propid diagnose`.
#[derive(clap::Args, Debug)]
pub struct Args {}

/// Runs `propid diagnose`.
pub fn run(_args: Args) -> anyhow::Result<()> {
    anyhow::bail!("propid diagnose is not implemented yet")
}
