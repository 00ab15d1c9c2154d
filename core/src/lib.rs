//! # propid-core
//!
//! The part of propid that runs everywhere: on a laptop behind a USB-CAN adapter and inside
//! motor-controller firmware on a Cortex-M4F. It is `#![no_std]`, never allocates, never reads a
//! clock and never touches a device. The caller owns the loop: it passes the current time and the
//! received frames in, and takes frames to send out. That is what makes every protocol test
//! deterministic and lets the same estimator run on both sides.
//!
//! ## How data flows
//!
//! ```text
//!  CAN frame (+ timestamp) ─► can::Reassembler ─► transfer payload ─► dsdl::*::deserialize ─► Sample
//!                                                                                          │
//!  node::Node: handle_frame(now, frame) / poll_transmit(now) / poll_timeout()              ▼
//!                                                                           estimate::NormalEquations
//! ```
//!
//! - [`time`]: the caller's clock as a plain value ([`time::Instant`]).
//! - [`dsdl`]: bit-exact codecs for the handful of DSDL types propid speaks.
//! - [`can`]: Cyphal/CAN framing (transmit) and reassembly (receive), Classic CAN and CAN FD.
//! - [`node`]: a Sans-IO Cyphal node: heartbeat, GetInfo, the configured publishers and subscribers.
//! - [`estimate`]: fixed-memory incremental least squares for the load's inertia and drag.
//! - [`plant`]: the load model (inertia, drag, friction) the simulator and the firmware demo share.
//! - [`sample`]: the [`sample::Sample`] every producer makes and every consumer takes.
#![no_std]
#![deny(missing_docs)]
#![forbid(unsafe_code)]

pub mod can;
pub mod dsdl;
pub mod estimate;
pub mod node;
pub mod plant;
pub mod sample;
pub mod time;
