//! # propid-slcan
//!
//! SLCAN as spoken by the Zubax Babel.
#![deny(missing_docs)]
