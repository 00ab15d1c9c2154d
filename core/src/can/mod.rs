//! Cyphal/CAN: frames, the CAN ID layout, the tail byte, transmit framing and reassembly.
//!
//! A [`Frame`] is one CAN frame (29-bit ID, up to 64 data bytes) with the time it was received or
//! is due. It implements [`embedded_can::Frame`], so it moves between this crate, the transports
//! and any HAL without conversion glue.

mod frame;

pub use frame::{Frame, MAX_DATA_LEN};
