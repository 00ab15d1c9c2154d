//! # propid-drive: the identification run on a bus
//!
//! The seed's driver is a PyCyphal node that engages a Telega, plays a ratiometric torque pattern
//! and records the drive's dynamics feedback. [`drive`] is that node; [`sim_drive`] is its
//! counterpart, a simulated Telega that runs `propid_science::stand::Stand` behind the same
//! Cyphal ports, so the whole run can be tested without hardware.
//!
//! ```text
//!  DriveConfig (validated once) ─► drive loop:
//!    every setpoint period: Readiness ENGAGED + Vector31 setpoint ─► Node ─► CanTransport
//!    CanTransport ─► Node::handle_frame ─► DoF3rdTs ─► tsv::Row (flushed) [+ running fit]
//!  every stop (end, error, signal, lost feedback): STANDBY + zero setpoint before returning
//! ```
//! The library never prints: progress reaches the caller as [`drive::DriveEvent`]s.
#![deny(missing_docs)]

pub mod drive;
pub mod registers;
pub mod sim_drive;
pub mod telega;

use propid_core::node::Node;

/// The node type of the host tools: 16 ports, 16 sessions, 515-byte transfers (a whole
/// `uavcan.register.Access` request), 256 queued frames, 32 registers.
pub type HostNode = Node<16, 16, 515, 256, { registers::HOST_REGISTERS }>;
