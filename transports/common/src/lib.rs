//! # propid-transport
//!
//! The one trait the host tools use to reach a CAN bus, whichever adapter is behind it, and the
//! PyCyphal way of naming one.
//!
//! ```text
//!  "slcan:/dev/ttyACM0@115200" ─┐
//!  "socketcan:can0"            ─┴─► IfaceSpec::parse ─► (host-cli's bus::open) ─► Box<dyn CanTransport>
//!  CanTransport::receive(timeout) ─► propid_core::can::Frame (timestamped on the HostClock)
//!  CanTransport::send(&Frame)
//! ```
//! Frames are `propid_core::can::Frame`, which implements `embedded_can::Frame`. Every received
//! frame carries a timestamp on the [`HostClock`] — one monotonic clock per process, so the
//! drive loop, the transports and the core all count microseconds from the same epoch.
#![deny(missing_docs)]

use std::sync::mpsc;
use std::sync::OnceLock;
use std::time::Duration;

pub use propid_core::can::Frame;
use propid_core::time::Instant;

/// Why a transport operation failed.
#[derive(Debug, thiserror::Error)]
pub enum TransportError {
    /// The device or file could not be used.
    #[error("{device}: {source}")]
    Io {
        /// Interface or device name.
        device: String,
        /// The underlying error.
        #[source]
        source: std::io::Error,
    },
    /// The device went away (adapter unplugged, peer closed).
    #[error("{0}: the interface is gone (adapter unplugged or peer closed)")]
    Closed(String),
    /// The request cannot be served by this transport (e.g. CAN FD over SLCAN).
    #[error("{0}")]
    Unsupported(String),
    /// An interface specification could not be understood.
    #[error("{0}")]
    BadSpec(String),
}

/// A CAN bus as the host tools see it.
pub trait CanTransport: Send {
    /// Sends one frame (blocking until the driver took it).
    fn send(&mut self, frame: &Frame) -> Result<(), TransportError>;
    /// Waits up to `timeout` for a frame; `Ok(None)` on timeout.
    fn receive(&mut self, timeout: Duration) -> Result<Option<Frame>, TransportError>;
    /// Largest data length per frame (8 or 64).
    fn mtu(&self) -> usize;
    /// A short description for logs (`slcan:/dev/ttyACM0`).
    fn name(&self) -> String;
}

/// The process's monotonic clock, as `propid_core::time::Instant` (µs since the first use).
pub struct HostClock;

impl HostClock {
    fn epoch() -> std::time::Instant {
        static EPOCH: OnceLock<std::time::Instant> = OnceLock::new();
        *EPOCH.get_or_init(std::time::Instant::now)
    }

    /// Now.
    pub fn now() -> Instant {
        Instant::from_micros(Self::epoch().elapsed().as_micros() as u64)
    }

    /// A `std` instant on the same clock.
    pub fn to_std(t: Instant) -> std::time::Instant {
        Self::epoch() + Duration::from_micros(t.as_micros())
    }
}

/// An interface, as PyCyphal's `UAVCAN__CAN__IFACE` names it.
#[derive(Clone, Debug, PartialEq, Eq)]
pub enum IfaceSpec {
    /// A Linux SocketCAN interface (`socketcan:can0`).
    SocketCan {
        /// Interface name.
        name: String,
    },
    /// An SLCAN adapter on a serial port (`slcan:/dev/ttyACM0@115200`).
    Slcan {
        /// Serial device path.
        path: String,
        /// Serial baud rate (irrelevant for USB CDC adapters such as the Babel).
        baud: u32,
    },
}

impl IfaceSpec {
    /// Parses one interface (PyCyphal allows several separated by spaces; propid uses the first).
    pub fn parse(text: &str) -> Result<IfaceSpec, TransportError> {
        let first = text.split_whitespace().next().unwrap_or("");
        let bad = |why: &str| {
            TransportError::BadSpec(format!(
                "interface `{text}`: {why} (expected `socketcan:IFACE` or `slcan:DEVICE[@BAUD]`)"
            ))
        };
        let (kind, rest) = first
            .split_once(':')
            .ok_or_else(|| bad("no transport prefix"))?;
        match kind {
            "socketcan" if !rest.is_empty() => Ok(IfaceSpec::SocketCan {
                name: rest.to_string(),
            }),
            "slcan" if !rest.is_empty() => {
                let (path, baud) = match rest.rsplit_once('@') {
                    Some((p, b)) => (
                        p,
                        b.parse()
                            .map_err(|_| bad("the baud rate is not a number"))?,
                    ),
                    None => (rest, 115_200),
                };
                Ok(IfaceSpec::Slcan {
                    path: path.to_string(),
                    baud,
                })
            }
            "socketcan" | "slcan" => Err(bad("no device given")),
            other => Err(bad(&format!("unknown transport `{other}`"))),
        }
    }
}

/// Parses PyCyphal's `UAVCAN__CAN__BITRATE` ("1000000" or "1000000 4000000": arbitration and
/// data bit rates).
pub fn parse_bitrate(text: &str) -> Result<(u32, u32), TransportError> {
    let v: Vec<u32> = text
        .split_whitespace()
        .map(|x| x.parse())
        .collect::<Result<_, _>>()
        .map_err(|_| {
            TransportError::BadSpec(format!("bit rate `{text}` is not one or two integers"))
        })?;
    match v.as_slice() {
        [a] => Ok((*a, *a)),
        [a, d] => Ok((*a, *d)),
        _ => Err(TransportError::BadSpec(format!(
            "bit rate `{text}` is not one or two integers"
        ))),
    }
}

/// One end of an in-memory bus (tests, and a loopback for tools): frames sent on one end are
/// received on the other, timestamped on arrival.
pub struct MemoryBus {
    tx: mpsc::Sender<Frame>,
    rx: mpsc::Receiver<Frame>,
    mtu: usize,
}

impl MemoryBus {
    /// Two connected ends.
    pub fn pair(mtu: usize) -> (MemoryBus, MemoryBus) {
        let (a_tx, b_rx) = mpsc::channel();
        let (b_tx, a_rx) = mpsc::channel();
        (
            MemoryBus {
                tx: a_tx,
                rx: a_rx,
                mtu,
            },
            MemoryBus {
                tx: b_tx,
                rx: b_rx,
                mtu,
            },
        )
    }
}

impl CanTransport for MemoryBus {
    fn send(&mut self, frame: &Frame) -> Result<(), TransportError> {
        if frame.data().len() > self.mtu {
            return Err(TransportError::Unsupported(format!(
                "a {}-byte frame does not fit MTU {}",
                frame.data().len(),
                self.mtu
            )));
        }
        self.tx
            .send(frame.clone())
            .map_err(|_| TransportError::Closed("memory bus".into()))
    }

    fn receive(&mut self, timeout: Duration) -> Result<Option<Frame>, TransportError> {
        match self.rx.recv_timeout(timeout) {
            Ok(mut f) => {
                f.timestamp = HostClock::now();
                Ok(Some(f))
            }
            Err(mpsc::RecvTimeoutError::Timeout) => Ok(None),
            Err(mpsc::RecvTimeoutError::Disconnected) => {
                Err(TransportError::Closed("memory bus".into()))
            }
        }
    }

    fn mtu(&self) -> usize {
        self.mtu
    }

    fn name(&self) -> String {
        "memory".into()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn iface_specs() {
        assert_eq!(
            IfaceSpec::parse("slcan:/dev/ttyACM0@115200").unwrap(),
            IfaceSpec::Slcan {
                path: "/dev/ttyACM0".into(),
                baud: 115_200
            }
        );
        assert_eq!(
            IfaceSpec::parse("socketcan:vcan0 slcan:/x").unwrap(),
            IfaceSpec::SocketCan {
                name: "vcan0".into()
            }
        );
        assert!(IfaceSpec::parse("can0")
            .unwrap_err()
            .to_string()
            .contains("no transport prefix"));
        assert!(IfaceSpec::parse("udp:1.2.3.4")
            .unwrap_err()
            .to_string()
            .contains("unknown transport `udp`"));
        assert!(IfaceSpec::parse("slcan:/x@fast").is_err());
        assert_eq!(
            parse_bitrate("1000000 1000000").unwrap(),
            (1_000_000, 1_000_000)
        );
        assert_eq!(parse_bitrate("500000").unwrap(), (500_000, 500_000));
        assert!(parse_bitrate("1M").is_err());
    }

    #[test]
    fn memory_bus_delivers_and_timestamps() {
        let (mut a, mut b) = MemoryBus::pair(8);
        let f = Frame::new(Instant::ZERO, 0x1060_642A, &[3, 0xE0]).unwrap();
        a.send(&f).unwrap();
        let got = b.receive(Duration::from_millis(100)).unwrap().unwrap();
        assert_eq!(got.data(), f.data());
        assert!(b.receive(Duration::from_millis(1)).unwrap().is_none());
        assert!(a
            .send(&Frame::new(Instant::ZERO, 1, &[0; 12]).unwrap())
            .is_err());
        drop(a);
        assert!(matches!(
            b.receive(Duration::from_millis(1)),
            Err(TransportError::Closed(_))
        ));
    }
}
