//! # propid-drive-proto: the identification run on a bus, as state machines
//!
//! The seed's driver is a PyCyphal node that engages a Telega, plays a ratiometric torque pattern
//! and records the drive's dynamics feedback. [`drive::Drive`] is that node; [`sim_drive::SimDrive`]
//! is its counterpart, a simulated Telega that runs a [`plant::Plant`] behind the same Cyphal
//! ports, so the whole run can be tested without hardware; [`telega::Client`] discovers drives
//! and reads, writes and stores their registers.
//!
//! All three are Sans-IO state machines in the style of the core's `Node` and quinn-proto: they
//! read no clock, touch no device, write no file and depend on nothing but `propid-core`. Time
//! and frames go in, frames and events come out ([`Machine`]):
//!
//! ```text
//!  handle_frame(now, &Frame) ─► Node ─► DoF3rdTs ─► DriveEvent::Row (the caller writes + flushes it)
//!                                   └─► Heartbeat of the drive (uptime went down ⇒ it rebooted: stop)
//!  poll_transmit(now) ◄─ Node's TxQueue ◄─ Readiness ENGAGED + Vector31 setpoint every period
//!  handle_blocked(now, frame)   the link refused a frame (WouldBlock): kept, re-offered until its
//!                               deadline, then dropped and counted
//!  poll_timeout()               when to call again (the next setpoint, heartbeat or retry)
//!  poll_event()                 phases, rows, progress, the stop and its report
//!  handle_fault(now, reason)    signal, transport fault, bus-off, output error ⇒ the stop sequence
//!  every feedback sample        the limits (crate::limits); one that trips ⇒ the stop sequence
//!  stop sequence: purge the queue ─► STANDBY + zero setpoint first, re-sent STOP_REPEATS times
//!                 within STOP_WINDOW ─► Stopped(StopReport)
//! ```
//!
//! The modules, each importing only those above it:
//!
//! ```text
//!  settings     the machines' settings as types (SetpointPeriod, SetpointRange, MaxSpeed, …): out
//!               of range cannot be built, so no machine validates its configuration
//!  excitation   the pattern behind a trait (Schedule: the seed's timing registers)
//!  plant        the simulated load behind a trait (TorqueScaled: a motor wired the other way)
//!  node         HostNode, HostRegistry: the Cyphal node the machines are built on
//!  feedback_loss  lost feedback counted from transfer-IDs and the drive's timestamps
//!  limits       the limits that stop a runaway rotor: soft start, maximum speed, speed watchdog
//!  machine      Machine (the Sans-IO contract) and StopReason
//!  registers    register names, types and defaults; serving them; Telega's prerequisites
//!  drive, sim_drive, telega    the three machines (each maps its configuration onto registers)
//!  virtual_link two machines on a modelled CAN link in virtual time
//! ```
//! [`virtual_link`] runs two machines against each other in virtual time, so the seed's 200 s
//! run is a deterministic test of well under a second. The real-time loop, the runners that write
//! files, register files and the live view live in `propid-drive-host`.
//!
//! The library never prints: progress reaches the caller as events.
#![deny(missing_docs)]

pub mod drive;
pub mod excitation;
pub mod feedback_loss;
pub mod limits;
pub mod machine;
pub mod node;
pub mod plant;
pub mod registers;
pub mod settings;
pub mod sim_drive;
pub mod telega;
pub mod virtual_link;

pub use machine::{Machine, StopReason};
pub use node::{HostNode, HostRegistry, HOST_REGISTERS};
