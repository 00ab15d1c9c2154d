//! # propid-socketcan
//!
//! Linux SocketCAN (Classic and FD) as a `propid_transport::CanTransport`.
//!
//! ```text
//!  kernel CAN socket ─► read_frame_with_timestamp (SO_TIMESTAMP) ─► Frame on the HostClock
//!  Frame ─► CanDataFrame (≤ 8 bytes) or CanFdFrame ─► write_frame
//! ```
//! Receive timestamps come from the kernel (`SO_TIMESTAMP`, wall clock) and are mapped onto the
//! process's monotonic `propid_transport::HostClock` by their age; when the kernel gives none, the host clock at
//! read time is used. An acceptance filter limits the socket to the Cyphal ports in use.
//!
//! SocketCAN exists only on Linux: elsewhere this crate is empty ([`AVAILABLE`] is false) and
//! callers offer SLCAN instead.
#![deny(missing_docs)]

/// Whether SocketCAN exists on the target this crate was built for (Linux only).
pub const AVAILABLE: bool = cfg!(target_os = "linux");

#[cfg(target_os = "linux")]
mod linux;
#[cfg(target_os = "linux")]
pub use linux::SocketCanTransport;
