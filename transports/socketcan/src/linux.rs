//! The SocketCAN transport itself (Linux only).

use std::io::ErrorKind;
use std::time::{Duration, SystemTime};

use propid_core::can::Frame;
use propid_transport::{BusState, CanTransport, Health, HostClock, OpenError, TransportError};
use socketcan::errors::{ControllerProblems, ErrorCause};
use socketcan::{
    frame::AsPtr, CanAnyFrame, CanDataFrame, CanError, CanFdFrame, CanFdSocket, CanFilter,
    EmbeddedFrame, ExtendedId, Frame as _, Socket, SocketOptions,
};

/// The SocketCAN flag marking an extended (29-bit) ID in filters.
const EFF_FLAG: u32 = 0x8000_0000;

/// A SocketCAN interface.
pub struct SocketCanTransport {
    socket: CanFdSocket,
    name: String,
    mtu: usize,
    health: Health,
}

impl SocketCanTransport {
    /// Opens interface `iface` (e.g. `can0`, `vcan0`) for frames up to `mtu` bytes (8 or 64).
    pub fn open(iface: &str, mtu: usize) -> Result<Self, TransportError> {
        let name = format!("socketcan:{iface}");
        let socket = CanFdSocket::open(iface).map_err(|e| TransportError::Open {
            device: name.clone(),
            why: match e.raw_os_error() {
                Some(libc::ENODEV | libc::ENXIO) => OpenError::NoSuchInterface {
                    name: iface.to_string(),
                },
                Some(libc::EAFNOSUPPORT | libc::EPROTONOSUPPORT) => OpenError::NoSocketCan,
                Some(libc::EPERM | libc::EACCES) => OpenError::CanPermission,
                _ => OpenError::Other(e.to_string()),
            },
        })?;
        Ok(Self::from_socket(socket, &name, mtu))
    }

    /// Wraps an open socket (tests use one end of a socket pair).
    pub fn from_socket(socket: CanFdSocket, name: &str, mtu: usize) -> Self {
        // Ask the kernel for arrival times; without them the host clock at read time is used.
        let _ = socket.set_recv_timestamp(true);
        // Controller state changes (warning, passive, bus-off, restart) as error frames.
        let _ = socket
            .set_error_filter(libc::CAN_ERR_CRTL | libc::CAN_ERR_BUSOFF | libc::CAN_ERR_RESTARTED);
        SocketCanTransport {
            socket,
            name: name.to_string(),
            mtu,
            health: Health::default(),
        }
    }

    /// Accepts only messages on `subjects` and service transfers addressed to `node_id`.
    pub fn filter_cyphal_ports(
        &self,
        subjects: &[u16],
        node_id: Option<u8>,
    ) -> Result<(), TransportError> {
        let mut filters: Vec<CanFilter> = subjects
            .iter()
            .map(|s| {
                CanFilter::new(
                    EFF_FLAG | (u32::from(*s) << 8),
                    EFF_FLAG | (1 << 25) | (0x1FFF << 8),
                )
            })
            .collect();
        if let Some(n) = node_id {
            filters.push(CanFilter::new(
                EFF_FLAG | (1 << 25) | (u32::from(n) << 7),
                EFF_FLAG | (1 << 25) | (0x7F << 7),
            ));
        }
        self.socket.set_filters(&filters).map_err(|e| self.io(e))
    }

    /// Writes one frame without waiting: `Ok(false)` when the kernel has no room (EAGAIN from a
    /// full socket buffer, ENOBUFS from a full device queue).
    fn write_now<F: AsPtr>(&self, frame: &F) -> Result<bool, TransportError> {
        // SAFETY: socketcan's frame constructors zero the whole `can_frame`/`canfd_frame`
        // before filling it, so every byte (padding included) is initialised — the same
        // argument the crate's own `write_frame` makes for this call.
        let bytes = unsafe { frame.as_bytes() };
        match self
            .socket
            .as_raw_socket()
            .send_with_flags(bytes, libc::MSG_DONTWAIT)
        {
            Ok(n) if n == bytes.len() => Ok(true),
            Ok(n) => Err(TransportError::Io {
                device: self.name.clone(),
                error: std::io::Error::other(format!(
                    "the kernel took {n} of a {}-byte CAN frame",
                    bytes.len()
                )),
            }),
            Err(e)
                if e.kind() == ErrorKind::WouldBlock || e.raw_os_error() == Some(libc::ENOBUFS) =>
            {
                Ok(false)
            }
            Err(e) => Err(self.io(e)),
        }
    }

    /// Takes a controller error frame into the health record.
    fn absorb_error(&mut self, error: &CanError) {
        for cause in error.causes() {
            match cause {
                ErrorCause::BusOff => self.health.bus_state = BusState::BusOff,
                ErrorCause::Restarted => self.health.bus_state = BusState::Active,
                ErrorCause::Controller(p) => {
                    self.health.bus_state = controller_state(*p, self.health.bus_state);
                    if p.intersects(ControllerProblems::RX_OVERFLOW) {
                        self.health.overruns += 1;
                    }
                }
                _ => continue,
            }
            self.health.status_reports += 1;
        }
    }

    fn io(&self, e: std::io::Error) -> TransportError {
        match e.kind() {
            ErrorKind::BrokenPipe | ErrorKind::NotConnected => {
                TransportError::Closed(self.name.clone())
            }
            _ if matches!(e.raw_os_error(), Some(libc::ENODEV | libc::ENXIO)) => {
                TransportError::Closed(self.name.clone())
            }
            _ => TransportError::Io {
                device: self.name.clone(),
                error: e,
            },
        }
    }
}

/// The state a `CAN_ERR_CRTL` report names (the kernel ORs RX and TX states together).
fn controller_state(p: ControllerProblems, before: BusState) -> BusState {
    if p.intersects(ControllerProblems::RX_PASSIVE | ControllerProblems::TX_PASSIVE) {
        BusState::Passive
    } else if p.intersects(ControllerProblems::RX_WARNING | ControllerProblems::TX_WARNING) {
        BusState::Warning
    } else if p.contains(ControllerProblems::ACTIVE) {
        BusState::Active
    } else {
        before
    }
}

impl CanTransport for SocketCanTransport {
    fn send(&mut self, frame: &Frame) -> Result<(), TransportError> {
        let id = ExtendedId::new(frame.id())
            .ok_or_else(|| TransportError::Unsupported("bad ID".into()))?;
        let data = frame.data();
        if data.len() > self.mtu {
            return Err(TransportError::Unsupported(format!(
                "{}: a {}-byte frame does not fit MTU {}",
                self.name,
                data.len(),
                self.mtu
            )));
        }
        let accepted = if data.len() <= 8 {
            let f = CanDataFrame::new(id, data)
                .ok_or_else(|| TransportError::Unsupported("frame".into()))?;
            self.write_now(&f)?
        } else {
            let f = CanFdFrame::new(id, data)
                .ok_or_else(|| TransportError::Unsupported("frame".into()))?;
            self.write_now(&f)?
        };
        if accepted {
            self.health.frames_sent += 1;
            Ok(())
        } else {
            self.health.would_block += 1;
            Err(TransportError::WouldBlock)
        }
    }

    fn flush(&mut self, _deadline: std::time::Instant) -> Result<bool, TransportError> {
        // A frame the kernel accepted is in its queue: nothing is held here.
        Ok(true)
    }

    fn receive(&mut self, timeout: Duration) -> Result<Option<Frame>, TransportError> {
        let deadline = std::time::Instant::now() + timeout;
        loop {
            let left = deadline.saturating_duration_since(std::time::Instant::now());
            if left.is_zero() {
                return Ok(None);
            }
            self.socket.set_read_timeout(left).map_err(|e| self.io(e))?;
            let (frame, stamps) = match self.socket.read_frame_with_timestamps() {
                Ok(x) => x,
                Err(e) if matches!(e.kind(), ErrorKind::WouldBlock | ErrorKind::TimedOut) => {
                    return Ok(None)
                }
                Err(e) if e.kind() == ErrorKind::Interrupted => continue,
                Err(e) => return Err(self.io(e)),
            };
            let now = HostClock::now();
            let age = stamps
                .socket
                .or(stamps.sw)
                .and_then(|t| SystemTime::now().duration_since(t).ok())
                .unwrap_or_default();
            let timestamp = if age < Duration::from_secs(10) {
                propid_core::time::Instant::from_micros(
                    now.as_micros().saturating_sub(age.as_micros() as u64),
                )
            } else {
                now
            };
            let (raw, data): (u32, Vec<u8>) = match frame {
                CanAnyFrame::Normal(f) if f.is_extended() => (f.id_word(), f.data().to_vec()),
                CanAnyFrame::Fd(f) if f.is_extended() => (f.id_word(), f.data().to_vec()),
                CanAnyFrame::Error(f) => {
                    self.absorb_error(&CanError::from(f));
                    continue;
                }
                // Standard IDs and remote frames are not Cyphal.
                _ => continue,
            };
            if let Some(f) = Frame::new(timestamp, raw & 0x1FFF_FFFF, &data) {
                self.health.frames_received += 1;
                return Ok(Some(f));
            }
        }
    }

    fn mtu(&self) -> usize {
        self.mtu
    }

    fn name(&self) -> String {
        self.name.clone()
    }

    fn health(&self) -> Health {
        self.health.clone()
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::os::fd::OwnedFd;
    use std::os::unix::net::UnixDatagram;

    fn pair() -> (SocketCanTransport, SocketCanTransport) {
        let (a, b) = UnixDatagram::pair().unwrap();
        let (a, b): (OwnedFd, OwnedFd) = (a.into(), b.into());
        (
            SocketCanTransport::from_socket(CanFdSocket::from(a), "pair:a", 64),
            SocketCanTransport::from_socket(CanFdSocket::from(b), "pair:b", 64),
        )
    }

    #[test]
    fn classic_and_fd_frames_cross_a_socket_pair() {
        let (mut a, mut b) = pair();
        let classic =
            Frame::new(propid_core::time::Instant::ZERO, 0x1060_642A, &[3, 0xE0]).unwrap();
        let fd = Frame::new(propid_core::time::Instant::ZERO, 0x0C64_D22A, &[7; 64]).unwrap();
        a.send(&classic).unwrap();
        a.send(&fd).unwrap();
        let x = b.receive(Duration::from_secs(1)).unwrap().unwrap();
        let y = b.receive(Duration::from_secs(1)).unwrap().unwrap();
        assert_eq!((x.id(), x.data()), (0x1060_642A, &[3u8, 0xE0][..]));
        assert_eq!((y.id(), y.data().len()), (0x0C64_D22A, 64));
        assert!(b.receive(Duration::from_millis(20)).unwrap().is_none());
    }

    #[test]
    fn a_full_socket_refuses_without_blocking_and_counts() {
        let (mut a, mut b) = pair();
        let f = Frame::new(propid_core::time::Instant::ZERO, 0x1060_642A, &[1; 8]).unwrap();
        let t0 = std::time::Instant::now();
        let mut accepted = 0u64;
        let err = loop {
            match a.send(&f) {
                Ok(()) => accepted += 1,
                Err(e) => break e,
            }
            assert!(accepted < 1_000_000, "the socket never filled");
        };
        assert!(err.is_would_block(), "{err}");
        assert!(t0.elapsed() < Duration::from_secs(1));
        assert_eq!(a.health().frames_sent, accepted);
        assert_eq!(a.health().would_block, 1);
        // Draining one frame makes room again.
        b.receive(Duration::from_secs(1)).unwrap().unwrap();
        a.send(&f).unwrap();
        assert!(a.flush(std::time::Instant::now()).unwrap());
    }

    #[test]
    fn controller_error_frames_set_the_bus_state() {
        let (a, mut b) = pair();
        let report = |bits: u32, ctrl: u8| {
            let mut data = [0u8; 8];
            data[1] = ctrl;
            let f = socketcan::CanErrorFrame::new_error(bits, &data).unwrap();
            a.socket.write_frame(&f).unwrap();
        };
        assert_eq!(b.health().bus_state, BusState::Unknown);
        report(libc::CAN_ERR_CRTL, libc::CAN_ERR_CRTL_TX_WARNING as u8);
        assert!(b.receive(Duration::from_millis(50)).unwrap().is_none());
        assert_eq!(b.health().bus_state, BusState::Warning);
        report(
            libc::CAN_ERR_CRTL,
            (libc::CAN_ERR_CRTL_TX_PASSIVE | libc::CAN_ERR_CRTL_RX_OVERFLOW) as u8,
        );
        assert!(b.receive(Duration::from_millis(50)).unwrap().is_none());
        assert_eq!(b.health().bus_state, BusState::Passive);
        assert_eq!(b.health().overruns, 1);
        report(libc::CAN_ERR_BUSOFF, 0);
        assert!(b.receive(Duration::from_millis(50)).unwrap().is_none());
        assert_eq!(b.health().bus_state, BusState::BusOff);
        report(libc::CAN_ERR_RESTARTED, 0);
        assert!(b.receive(Duration::from_millis(50)).unwrap().is_none());
        assert_eq!(b.health().bus_state, BusState::Active);
        assert_eq!(b.health().status_reports, 4);
    }

    #[test]
    fn a_missing_interface_is_a_clear_error() {
        let err = SocketCanTransport::open("nosuchcan7", 8)
            .err()
            .unwrap()
            .to_string();
        assert!(err.contains("socketcan:nosuchcan7"), "{err}");
    }
}
