//! Ctrl-C and termination as a flag the drive loops poll, so they can command STANDBY before
//! the command returns. The handlers live as long as the returned guard: a command run
//! in-process (`propid::run` from Python, or twice in one test) leaves none behind.

use std::sync::atomic::AtomicBool;
use std::sync::Arc;

use anyhow::Context;
use signal_hook::SigId;

/// The installed handlers; dropping it removes them.
#[must_use = "the handlers are removed when the guard is dropped"]
pub struct Handlers(Vec<SigId>);

impl Drop for Handlers {
    fn drop(&mut self) {
        for id in self.0.drain(..) {
            signal_hook::low_level::unregister(id);
        }
    }
}

/// Raises `stop` on SIGINT or SIGTERM until the guard is dropped.
pub fn install(stop: &Arc<AtomicBool>) -> anyhow::Result<Handlers> {
    let mut ids = Handlers(Vec::new());
    for signal in [signal_hook::consts::SIGINT, signal_hook::consts::SIGTERM] {
        let id = signal_hook::flag::register(signal, Arc::clone(stop))
            .context("installing signal handlers")?;
        ids.0.push(id);
    }
    Ok(ids)
}
