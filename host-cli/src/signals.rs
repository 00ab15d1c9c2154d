//! Ctrl-C and termination as a flag the drive loops poll, so they can command STANDBY before
//! the process exits.

use std::sync::atomic::AtomicBool;
use std::sync::Arc;

use anyhow::Context;

/// Raises `stop` on SIGINT or SIGTERM.
pub fn install(stop: &Arc<AtomicBool>) -> anyhow::Result<()> {
    for signal in [signal_hook::consts::SIGINT, signal_hook::consts::SIGTERM] {
        signal_hook::flag::register(signal, Arc::clone(stop))
            .context("installing signal handlers")?;
    }
    Ok(())
}
