//! `propid demo` (not yet implemented).

/// Arguments of `propid demo`.
#[derive(clap::Args, Debug)]
pub struct Args {}

/// Runs `propid demo`.
pub fn run(_args: Args) -> anyhow::Result<()> {
    anyhow::bail!("propid demo is not implemented yet")
}
