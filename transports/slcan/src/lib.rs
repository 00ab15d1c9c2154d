//! # propid-slcan
//!
//! SLCAN (the Lawicel ASCII protocol) as the Zubax Babel speaks it: a Sans-IO codec and a
//! serial-port transport.
//!
//! ```text
//!  serial bytes ─► Decoder::push ─► Event::Frame { id, data, adapter_ms } ─► AdapterClock ─► Frame
//!                                   Event::Ack / Nack / Status / Version / Garbage
//!  Frame ─► encode_frame ─► "T1060642A203E0\r" ─► serial port
//! ```
//! - [`codec`]: bytes in, events out; frames and commands in, bytes out. No I/O.
//! - [`SlcanTransport`]: opens a serial port (`serialport`, no libudev), configures the adapter
//!   (`C`, `S8` or a raw bit rate, `Z1` timestamps, `O`) and implements
//!   `propid_transport::CanTransport`: writes never wait (a non-blocking port; the tail of a
//!   partly written line goes out first on the next call), BELL replies are matched to the line
//!   they refuse, the adapter's status flags are polled (`F`, every second and after a refusal)
//!   into `health()`, and a vanished device is `TransportError::Closed` naming the port.
#![deny(missing_docs)]

pub mod codec;
mod serial;

pub use codec::{
    bitrate_command, encode_frame, open_command, raw_bitrate_command, AdapterClock, Decoder, Event,
    StatusFlags, TimestampUnwrapper,
};
pub use serial::{ReaderStats, SlcanTransport};
