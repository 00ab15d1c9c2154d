//! The scheduling priority of the threads that must keep up with a bus.
//!
//! ```text
//!  raise_thread_priority() ─► SCHED_RR 10 for the calling thread (Linux, when permitted:
//!                             root, CAP_SYS_NICE, or an RLIMIT_RTPRIO ≥ 10)
//!                          └─► otherwise unchanged, and why
//!  PriorityGuard dropped   ─► the thread's previous policy again
//! ```
//! On a loaded machine a normal thread waits in the run queue: measured here with four busy
//! loops beside `propid drive` and `propid sim-drive` on two cores, each process spent 0.3–0.6 s
//! of every second waiting for a CPU, the loop stalled for over a second and the run stopped
//! (benches/drive_load.sh, docs/TRANSPORTS.md). A real-time thread that sleeps until its bytes
//! arrive takes the CPU when they do. The policy is round-robin at a low real-time priority and
//! is not inherited by threads or processes the thread starts (`SCHED_RESET_ON_FORK`): only the
//! control loop and the serial reader run at it, and a thread that never sleeps could take at most
//! the kernel's real-time share (95 % of a CPU by default), not the machine.

use std::fmt;

/// The real-time priority asked for (1–99; low, above every normal thread).
pub const REALTIME_PRIORITY: i32 = 10;

/// What a thread runs at.
#[derive(Clone, Debug, PartialEq, Eq)]
pub enum ThreadPriority {
    /// A real-time policy.
    RealTime {
        /// The priority within it.
        priority: i32,
    },
    /// The normal, time-shared policy.
    Normal {
        /// Why it was not raised (the OS's refusal, or no support on this OS).
        why: String,
    },
}

impl ThreadPriority {
    /// True for a real-time policy.
    pub fn is_realtime(&self) -> bool {
        matches!(self, ThreadPriority::RealTime { .. })
    }
}

impl fmt::Display for ThreadPriority {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            ThreadPriority::RealTime { priority } => {
                write!(f, "real-time priority (round-robin, {priority})")
            }
            ThreadPriority::Normal { why } => write!(f, "normal priority ({why})"),
        }
    }
}

/// The calling thread's raised priority; its previous policy comes back when this is dropped.
pub struct PriorityGuard {
    obtained: ThreadPriority,
    /// Dropped on the thread it raised: not `Send`.
    _thread: std::marker::PhantomData<*const ()>,
    #[cfg(target_os = "linux")]
    previous: Option<(libc::c_int, libc::sched_param)>,
}

impl PriorityGuard {
    /// What the thread runs at now.
    pub fn obtained(&self) -> &ThreadPriority {
        &self.obtained
    }
}

/// Raises the calling thread to [`REALTIME_PRIORITY`] (round-robin) where the OS permits it.
#[cfg(target_os = "linux")]
pub fn raise_thread_priority() -> PriorityGuard {
    let mut previous = libc::sched_param { sched_priority: 0 };
    // SAFETY: pid 0 names the calling thread; `previous` is a valid, writable sched_param for
    // the duration of the call. Neither call keeps the pointer.
    let old_policy = unsafe { libc::sched_getscheduler(0) };
    let got = unsafe { libc::sched_getparam(0, &mut previous) };
    let wanted = libc::sched_param {
        sched_priority: REALTIME_PRIORITY,
    };
    // SAFETY: as above; `wanted` is a valid sched_param read during the call only.
    let set =
        unsafe { libc::sched_setscheduler(0, libc::SCHED_RR | libc::SCHED_RESET_ON_FORK, &wanted) };
    if set == 0 {
        PriorityGuard {
            obtained: ThreadPriority::RealTime {
                priority: REALTIME_PRIORITY,
            },
            previous: (old_policy >= 0 && got == 0).then_some((old_policy, previous)),
            _thread: std::marker::PhantomData,
        }
    } else {
        PriorityGuard {
            obtained: ThreadPriority::Normal {
                why: format!(
                    "no permission for a real-time one: {}",
                    std::io::Error::last_os_error()
                ),
            },
            previous: None,
            _thread: std::marker::PhantomData,
        }
    }
}

/// Raises the calling thread's priority where the OS permits it (not on this OS).
#[cfg(not(target_os = "linux"))]
pub fn raise_thread_priority() -> PriorityGuard {
    PriorityGuard {
        obtained: ThreadPriority::Normal {
            why: "real-time priority is only asked for on Linux".into(),
        },
        _thread: std::marker::PhantomData,
    }
}

impl Drop for PriorityGuard {
    fn drop(&mut self) {
        #[cfg(target_os = "linux")]
        if let Some((policy, param)) = self.previous.take() {
            // SAFETY: pid 0 is the calling thread (the guard is not Send, so it is dropped on the
            // thread that raised it); `param` is a valid sched_param read during the call only.
            unsafe {
                libc::sched_setscheduler(0, policy, &param);
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_raised_thread_gets_its_policy_back() {
        let before = current();
        {
            let g = raise_thread_priority();
            match g.obtained() {
                ThreadPriority::RealTime { priority } => {
                    assert_eq!(*priority, REALTIME_PRIORITY);
                    #[cfg(target_os = "linux")]
                    assert_eq!(current().0 & !libc::SCHED_RESET_ON_FORK, libc::SCHED_RR);
                }
                ThreadPriority::Normal { why } => assert!(!why.is_empty()),
            }
        }
        assert_eq!(current(), before);
    }

    #[cfg(target_os = "linux")]
    fn current() -> (libc::c_int, libc::c_int) {
        let mut p = libc::sched_param { sched_priority: 0 };
        // SAFETY: pid 0 is this thread; `p` is valid and writable during the call.
        let policy = unsafe {
            libc::sched_getparam(0, &mut p);
            libc::sched_getscheduler(0)
        };
        (policy, p.sched_priority)
    }

    #[cfg(not(target_os = "linux"))]
    fn current() -> (i32, i32) {
        (0, 0)
    }
}
