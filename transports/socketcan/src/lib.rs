//! # propid-socketcan
//!
//! Linux SocketCAN transport.
#![deny(missing_docs)]
