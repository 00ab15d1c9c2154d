//! # propid-transport
//!
//! The one trait the host tools use to reach a CAN bus, whichever adapter is behind it.
#![deny(missing_docs)]
