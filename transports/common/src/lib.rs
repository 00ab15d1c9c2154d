//! # propid-transport
//!
//! The one trait the host tools use to reach a CAN bus, whichever adapter is behind it, and the
//! PyCyphal way of naming one.
//!
//! ```text
//!  "slcan:/dev/ttyACM0@115200" ─┐
//!  "socketcan:can0"            ─┴─► IfaceSpec::parse ─► (host-cli's bus::open) ─► Box<dyn CanTransport>
//!  CanTransport::receive(timeout) ─► propid_core::can::Frame (timestamped on the HostClock)
//!  CanTransport::send(&Frame)     ─► Ok (accepted whole) | Err(WouldBlock) (not taken, nothing written)
//!  CanTransport::flush(deadline)  ─► did every accepted byte leave?   (the stop sequence)
//!  CanTransport::health()         ─► counters and the adapter's bus state
//! ```
//! Frames are `propid_core::can::Frame`, which implements `embedded_can::Frame`. Every received
//! frame carries a timestamp on the [`HostClock`] — one monotonic clock per process, so the
//! drive loop, the transports and the core all count microseconds from the same epoch.
//!
//! ## Sending never blocks the control loop
//! A link can be congested: a slow reader on the other end of a serial port, a busy bus, a full
//! kernel queue. [`CanTransport::send`] never waits for it. It either accepts the frame whole —
//! it will reach the link in full, though its last bytes may still sit in the transport until a
//! later call (SLCAN keeps the tail of a partly written line and completes it before anything
//! else, so the wire never carries half a frame followed by another) — or refuses it with
//! [`TransportError::WouldBlock`], having written nothing of it. A refusal is counted in
//! [`Health::would_block`]; the caller decides whether to retry, supersede or drop the frame.
//! [`CanTransport::flush`] pushes out what was accepted, retrying until a deadline, and says
//! whether everything left; [`CanTransport::send_by`] does both for one frame, for the stop
//! sequence (STANDBY and a zero setpoint) that must go out within a bound.
#![deny(missing_docs)]

pub mod priority;

use std::fmt;
use std::sync::mpsc;
use std::sync::OnceLock;
use std::time::Duration;

pub use propid_core::can::Frame;
use propid_core::time::Instant;

/// Why a transport operation failed. Each displays as one sentence naming the device, with the
/// operating system's words once (never again as a "source": a message chain would repeat them).
#[derive(Debug, thiserror::Error)]
pub enum TransportError {
    /// The device could not be opened; the reason says what fixes it.
    #[error("{device}: {why}")]
    Open {
        /// Interface or device name, as given (`slcan:/dev/ttyACM0`, `socketcan:can0`).
        device: String,
        /// Why, typed.
        why: OpenError,
    },
    /// The device failed while in use.
    #[error("{device}: {error}")]
    Io {
        /// Interface or device name.
        device: String,
        /// The operating system's error.
        error: std::io::Error,
    },
    /// The device went away (adapter unplugged, peer closed): the transport is unusable.
    #[error("{0}: device disappeared (adapter unplugged or the other end closed)")]
    Closed(String),
    /// The link cannot take a frame now (congestion); nothing of the frame was written. Not a
    /// failure: counted in [`Health::would_block`], retry later or drop the frame.
    #[error("the link cannot take a frame now (congested); nothing was written")]
    WouldBlock,
    /// The adapter refused a command it must accept (SLCAN BELL), e.g. the bit rate or the
    /// open command.
    #[error("{device}: the adapter refused the command `{command}`")]
    Refused {
        /// Interface name.
        device: String,
        /// The refused command, without its line end.
        command: String,
    },
    /// The request cannot be served by this transport (e.g. CAN FD over SLCAN).
    #[error("{0}")]
    Unsupported(String),
}

/// The operating systems whose device names a hint gives.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Os {
    /// Linux: `/dev/ttyACM0`, groups and udev rules.
    Linux,
    /// macOS: `/dev/cu.usbmodem…`.
    MacOs,
    /// Windows: `COM3`.
    Windows,
}

impl Os {
    /// The one this program runs on (another Unix gets the Linux words).
    pub const fn this() -> Os {
        if cfg!(target_os = "macos") {
            Os::MacOs
        } else if cfg!(windows) {
            Os::Windows
        } else {
            Os::Linux
        }
    }
}

/// Why a device could not be opened, typed, so each displays with the step that fixes it.
#[derive(Clone, Debug, PartialEq, Eq)]
pub enum OpenError {
    /// A serial device that does not exist (adapter not plugged in, a typo).
    NoSerialDevice(Os),
    /// Not allowed to open the serial device.
    SerialPermission {
        /// Where the program runs.
        os: Os,
        /// The device path.
        path: String,
    },
    /// The path exists but is not a serial port (a regular file, a directory).
    NotASerialPort,
    /// Another program holds the port.
    Busy(Os),
    /// No such SocketCAN interface.
    NoSuchInterface {
        /// The interface name.
        name: String,
    },
    /// The kernel has no SocketCAN.
    NoSocketCan,
    /// Not allowed to open the SocketCAN interface.
    CanPermission,
    /// Anything else, in the operating system's words.
    Other(String),
}

impl fmt::Display for OpenError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            OpenError::NoSerialDevice(os) => {
                write!(f, "no such device. Is the adapter plugged in? ")?;
                match os {
                    Os::Linux => write!(
                        f,
                        "A Zubax Babel appears as /dev/ttyACM0 or similar: `ls /dev/ttyACM* /dev/serial/by-id/`"
                    ),
                    Os::MacOs => write!(
                        f,
                        "On macOS it appears as /dev/cu.usbmodem… : `ls /dev/cu.usbmodem*`"
                    ),
                    Os::Windows => write!(
                        f,
                        "On Windows it appears as a COM port (Device Manager → Ports): give slcan:COM3, for example"
                    ),
                }
            }
            OpenError::SerialPermission { os, path } => {
                write!(f, "permission denied. ")?;
                match os {
                    Os::Linux => write!(
                        f,
                        "Add your user to the group that owns the port (`ls -l {path}` names it: `sudo usermod -aG dialout $USER` on Debian and Ubuntu, `uucp` on Arch and Fedora), then log in again; or install a udev rule that opens the adapter to your user, e.g. /etc/udev/rules.d/50-can-adapter.rules with `SUBSYSTEM==\"tty\", ATTRS{{idVendor}}==\"VID\", MODE=\"0660\", TAG+=\"uaccess\"` (VID from `lsusb`), then `sudo udevadm control --reload` and plug it in again"
                    ),
                    Os::MacOs => write!(
                        f,
                        "Use the /dev/cu.* device rather than /dev/tty.*, and check `ls -l {path}`"
                    ),
                    Os::Windows => write!(
                        f,
                        "Another program may hold the port: close it (a terminal, another propid) and try again"
                    ),
                }
            }
            OpenError::NotASerialPort => write!(
                f,
                "not a serial port (a regular file or a directory); give the adapter's device, such as /dev/ttyACM0, /dev/cu.usbmodem… or COM3"
            ),
            OpenError::Busy(Os::Windows) => write!(
                f,
                "no such port, or another program holds it: check Device Manager → Ports and close other programs using it"
            ),
            OpenError::Busy(_) => write!(
                f,
                "the port is in use by another program; close it (a terminal, another propid) and try again"
            ),
            OpenError::NoSuchInterface { name } => write!(
                f,
                "no such CAN interface. List them with `ip link show`; bring one up with `sudo ip link set {name} up type can bitrate 1000000` (a USB-CAN adapter must be plugged in)"
            ),
            OpenError::NoSocketCan => write!(
                f,
                "this kernel has no SocketCAN (`sudo modprobe can_raw`), or use an SLCAN adapter: slcan:DEVICE"
            ),
            OpenError::CanPermission => write!(
                f,
                "permission denied opening a CAN socket (run with CAP_NET_RAW, or ask an administrator)"
            ),
            OpenError::Other(why) => write!(f, "{why}"),
        }
    }
}

/// An interface specification that cannot be understood.
#[derive(Clone, Debug, PartialEq, Eq, thiserror::Error)]
pub enum SpecError {
    /// No `slcan:` or `socketcan:` before the device.
    #[error("no transport prefix")]
    NoPrefix,
    /// A prefix with nothing after it.
    #[error("no device given")]
    NoDevice,
    /// A prefix propid does not know.
    #[error("unknown transport `{0}`")]
    UnknownTransport(String),
    /// `@BAUD` that is not a number.
    #[error("the baud rate `{0}` is not a number")]
    BadBaud(String),
}

/// A bit rate setting that is not one or two integers.
#[derive(Clone, Debug, PartialEq, Eq, thiserror::Error)]
#[error("bit rate `{0}` is not one or two integers (arbitration [data], bit/s)")]
pub struct BitrateError(pub String);

impl TransportError {
    /// Whether this is the congestion outcome of a send, not a failure.
    pub fn is_would_block(&self) -> bool {
        matches!(self, TransportError::WouldBlock)
    }
}

/// The CAN controller's error state, as the adapter or kernel last reported it.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, PartialOrd, Ord)]
pub enum BusState {
    /// No report yet (or the transport cannot tell).
    #[default]
    Unknown,
    /// Error-active: normal operation.
    Active,
    /// An error counter passed the warning level (96).
    Warning,
    /// An error counter passed 127: the controller may no longer flag errors actively.
    Passive,
    /// The transmit error counter passed 255: the controller is off the bus and sends nothing.
    BusOff,
}

/// What a transport has done and seen since it was opened. Counters only grow.
#[derive(Clone, Debug, Default, PartialEq, Eq)]
pub struct Health {
    /// Frames accepted by [`CanTransport::send`].
    pub frames_sent: u64,
    /// Frames delivered by [`CanTransport::receive`].
    pub frames_received: u64,
    /// Sends refused with [`TransportError::WouldBlock`].
    pub would_block: u64,
    /// Lines the adapter refused (SLCAN BELL).
    pub refused: u64,
    /// The last line the adapter refused (`T1060642A2…`, `S8`), as far as replies can be matched
    /// to requests.
    pub last_refused: Option<String>,
    /// Input skipped because it could not be understood.
    pub garbage: u64,
    /// The controller's state from the last status report.
    pub bus_state: BusState,
    /// The raw status flags of the last report, where the adapter gives flags (SLCAN `F`).
    pub status_flags: Option<u8>,
    /// Status reports received.
    pub status_reports: u64,
    /// Reports of frames lost in the adapter or the kernel (receive overrun).
    pub overruns: u64,
    /// Times the adapter's timestamps disagreed with the host clock and were re-anchored.
    pub timestamp_resyncs: u64,
}

/// A CAN bus as the host tools see it. See the crate documentation for the sending contract.
pub trait CanTransport: Send {
    /// Offers one frame without waiting: `Ok(())` when it was accepted whole (it will reach the
    /// link in full; its tail may leave during a later call), `Err(WouldBlock)` when the link
    /// cannot take it now (nothing of it was written; counted in [`Health::would_block`]).
    fn send(&mut self, frame: &Frame) -> Result<(), TransportError>;
    /// Pushes out the accepted bytes still held in the transport, retrying until `deadline`:
    /// `Ok(true)` when nothing is left, `Ok(false)` when the deadline passed first.
    fn flush(&mut self, deadline: std::time::Instant) -> Result<bool, TransportError>;
    /// Waits up to `timeout` for a frame; `Ok(None)` on timeout. Also moves pending output along,
    /// so a caller that only receives still completes an accepted frame.
    fn receive(&mut self, timeout: Duration) -> Result<Option<Frame>, TransportError>;
    /// Largest data length per frame (8 or 64).
    fn mtu(&self) -> usize;
    /// A short description for logs (`slcan:/dev/ttyACM0`).
    fn name(&self) -> String;
    /// Counters and the bus state so far.
    fn health(&self) -> Health;

    /// Sends `frame`, retrying while the link is congested, then flushes, all before
    /// `deadline`: `Ok(true)` when the frame left completely, `Ok(false)` when the deadline came
    /// first (the frame was then either never accepted or is still partly queued). For the stop
    /// sequence, which must not wait forever and must know whether it got through.
    fn send_by(
        &mut self,
        frame: &Frame,
        deadline: std::time::Instant,
    ) -> Result<bool, TransportError> {
        loop {
            match self.send(frame) {
                Ok(()) => return self.flush(deadline),
                Err(TransportError::WouldBlock) => {
                    let now = std::time::Instant::now();
                    if now >= deadline {
                        return Ok(false);
                    }
                    // Let the link drain what it holds, then offer again.
                    let step = (deadline - now).min(RETRY_STEP);
                    if self.flush(now + step)? {
                        std::thread::sleep(step);
                    }
                }
                Err(e) => return Err(e),
            }
        }
    }
}

/// How long [`CanTransport::send_by`] lets a congested link drain between offers.
const RETRY_STEP: Duration = Duration::from_micros(200);

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
    /// The form it takes: `socketcan:IFACE` or `slcan:DEVICE[@BAUD]`.
    pub const SYNTAX: &'static str = "socketcan:IFACE or slcan:DEVICE[@BAUD]";

    /// Parses one interface (PyCyphal allows several separated by spaces; propid uses the first).
    pub fn parse(text: &str) -> Result<IfaceSpec, SpecError> {
        let first = text.split_whitespace().next().unwrap_or("");
        let (kind, rest) = first.split_once(':').ok_or(SpecError::NoPrefix)?;
        match kind {
            "socketcan" if !rest.is_empty() => Ok(IfaceSpec::SocketCan {
                name: rest.to_string(),
            }),
            "slcan" if !rest.is_empty() => {
                let (path, baud) = match rest.rsplit_once('@') {
                    Some((p, b)) => (p, b.parse().map_err(|_| SpecError::BadBaud(b.to_string()))?),
                    None => (rest, 115_200),
                };
                Ok(IfaceSpec::Slcan {
                    path: path.to_string(),
                    baud,
                })
            }
            "socketcan" | "slcan" => Err(SpecError::NoDevice),
            other => Err(SpecError::UnknownTransport(other.to_string())),
        }
    }
}

/// Parses PyCyphal's `UAVCAN__CAN__BITRATE` ("1000000" or "1000000 4000000": arbitration and
/// data bit rates).
pub fn parse_bitrate(text: &str) -> Result<(u32, u32), BitrateError> {
    let v: Vec<u32> = text
        .split_whitespace()
        .map(|x| x.parse())
        .collect::<Result<_, _>>()
        .map_err(|_| BitrateError(text.to_string()))?;
    match v.as_slice() {
        [a] => Ok((*a, *a)),
        [a, d] => Ok((*a, *d)),
        _ => Err(BitrateError(text.to_string())),
    }
}

/// One end of an in-memory bus (tests, and a loopback for tools): frames sent on one end are
/// received on the other, timestamped on arrival. With a capacity, each direction holds at most
/// that many frames in flight, and a send beyond it is refused with `WouldBlock` until the other
/// end receives: congestion that tests can create deterministically.
pub struct MemoryBus {
    tx: MemorySender,
    rx: mpsc::Receiver<Frame>,
    mtu: usize,
    health: Health,
}

enum MemorySender {
    Unbounded(mpsc::Sender<Frame>),
    Bounded(mpsc::SyncSender<Frame>),
}

impl MemoryBus {
    /// Two connected ends with no limit on frames in flight.
    pub fn pair(mtu: usize) -> (MemoryBus, MemoryBus) {
        let (a_tx, b_rx) = mpsc::channel();
        let (b_tx, a_rx) = mpsc::channel();
        (
            Self::end(MemorySender::Unbounded(a_tx), a_rx, mtu),
            Self::end(MemorySender::Unbounded(b_tx), b_rx, mtu),
        )
    }

    /// Two connected ends, each direction holding at most `capacity` frames (at least 1) that
    /// the other end has not received yet.
    pub fn pair_with_capacity(mtu: usize, capacity: usize) -> (MemoryBus, MemoryBus) {
        let (a_tx, b_rx) = mpsc::sync_channel(capacity.max(1));
        let (b_tx, a_rx) = mpsc::sync_channel(capacity.max(1));
        (
            Self::end(MemorySender::Bounded(a_tx), a_rx, mtu),
            Self::end(MemorySender::Bounded(b_tx), b_rx, mtu),
        )
    }

    fn end(tx: MemorySender, rx: mpsc::Receiver<Frame>, mtu: usize) -> MemoryBus {
        MemoryBus {
            tx,
            rx,
            mtu,
            health: Health {
                bus_state: BusState::Active,
                ..Health::default()
            },
        }
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
        let closed = || TransportError::Closed("memory bus".into());
        match &self.tx {
            MemorySender::Unbounded(tx) => tx.send(frame.clone()).map_err(|_| closed())?,
            MemorySender::Bounded(tx) => match tx.try_send(frame.clone()) {
                Ok(()) => {}
                Err(mpsc::TrySendError::Full(_)) => {
                    self.health.would_block += 1;
                    return Err(TransportError::WouldBlock);
                }
                Err(mpsc::TrySendError::Disconnected(_)) => return Err(closed()),
            },
        }
        self.health.frames_sent += 1;
        Ok(())
    }

    fn flush(&mut self, _deadline: std::time::Instant) -> Result<bool, TransportError> {
        // An accepted frame is already on the bus.
        Ok(true)
    }

    fn receive(&mut self, timeout: Duration) -> Result<Option<Frame>, TransportError> {
        match self.rx.recv_timeout(timeout) {
            Ok(mut f) => {
                f.timestamp = HostClock::now();
                self.health.frames_received += 1;
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

    fn health(&self) -> Health {
        self.health.clone()
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
    fn open_errors_say_what_fixes_them_on_each_os() {
        let device = |why| {
            TransportError::Open {
                device: "slcan:/dev/ttyX".into(),
                why,
            }
            .to_string()
        };
        let missing = device(OpenError::NoSerialDevice(Os::Linux));
        assert!(missing.starts_with("slcan:/dev/ttyX: no such device."));
        assert!(missing.contains("ls /dev/ttyACM*"), "{missing}");
        assert!(device(OpenError::NoSerialDevice(Os::MacOs)).contains("/dev/cu.usbmodem*"));
        assert!(device(OpenError::NoSerialDevice(Os::Windows)).contains("COM3"));
        let denied = |os| {
            device(OpenError::SerialPermission {
                os,
                path: "/dev/ttyX".into(),
            })
        };
        let linux = denied(Os::Linux);
        for want in [
            "dialout",
            "uucp",
            "udev rule",
            "ls -l /dev/ttyX",
            "log in again",
        ] {
            assert!(linux.contains(want), "{want}: {linux}");
        }
        assert!(denied(Os::MacOs).contains("/dev/cu."));
        assert!(denied(Os::Windows).contains("Another program"));
        let can = TransportError::Open {
            device: "socketcan:can9".into(),
            why: OpenError::NoSuchInterface {
                name: "can9".into(),
            },
        }
        .to_string();
        assert_eq!(can.matches("ip link").count(), 2, "{can}");
        assert!(can.contains("sudo ip link set can9 up"), "{can}");
        // The OS's words appear once: an Io error is not also its own source.
        let io = TransportError::Io {
            device: "slcan:/dev/ttyX".into(),
            error: std::io::Error::other("Input/output error"),
        };
        assert!(std::error::Error::source(&io).is_none());
        assert_eq!(io.to_string(), "slcan:/dev/ttyX: Input/output error");
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

    #[test]
    fn a_full_memory_bus_refuses_without_blocking_and_counts() {
        let (mut a, mut b) = MemoryBus::pair_with_capacity(8, 2);
        let f = |k: u8| Frame::new(Instant::ZERO, 0x1060_642A, &[k]).unwrap();
        a.send(&f(1)).unwrap();
        a.send(&f(2)).unwrap();
        let t0 = std::time::Instant::now();
        assert!(a.send(&f(3)).unwrap_err().is_would_block());
        assert!(a.send(&f(3)).unwrap_err().is_would_block());
        // Refusing is immediate: congestion never stalls the caller.
        assert!(t0.elapsed() < Duration::from_millis(50));
        let h = a.health();
        assert_eq!((h.frames_sent, h.would_block), (2, 2));
        // The other end drains one: room for exactly one more.
        assert_eq!(b.receive(Duration::ZERO).unwrap().unwrap().data(), &[1]);
        a.send(&f(3)).unwrap();
        assert!(a.send(&f(4)).is_err());
        // send_by gives up at its deadline and says so; succeeds once there is room.
        let deadline = std::time::Instant::now() + Duration::from_millis(5);
        assert!(!a.send_by(&f(4), deadline).unwrap());
        assert!(std::time::Instant::now() >= deadline);
        b.receive(Duration::ZERO).unwrap().unwrap();
        let deadline = std::time::Instant::now() + Duration::from_millis(5);
        assert!(a.send_by(&f(4), deadline).unwrap());
        let got: Vec<u8> = std::iter::from_fn(|| b.receive(Duration::ZERO).unwrap())
            .map(|f| f.data()[0])
            .collect();
        assert_eq!(got, [3, 4]);
        assert_eq!(b.health().frames_received, 4);
    }
}
