//! The SocketCAN transport itself (Linux only).

use std::io::ErrorKind;
use std::time::{Duration, SystemTime};

use propid_core::can::Frame;
use propid_transport::{CanTransport, HostClock, TransportError};
use socketcan::{
    CanAnyFrame, CanDataFrame, CanFdFrame, CanFdSocket, CanFilter, EmbeddedFrame, ExtendedId,
    Frame as _, Socket, SocketOptions,
};

/// The SocketCAN flag marking an extended (29-bit) ID in filters.
const EFF_FLAG: u32 = 0x8000_0000;

/// A SocketCAN interface.
pub struct SocketCanTransport {
    socket: CanFdSocket,
    name: String,
    mtu: usize,
}

impl SocketCanTransport {
    /// Opens interface `iface` (e.g. `can0`, `vcan0`) for frames up to `mtu` bytes (8 or 64).
    pub fn open(iface: &str, mtu: usize) -> Result<Self, TransportError> {
        let name = format!("socketcan:{iface}");
        let socket = CanFdSocket::open(iface).map_err(|e| TransportError::Io {
            device: name.clone(),
            source: std::io::Error::new(
                e.kind(),
                format!("cannot open the CAN interface ({e}); does it exist and is it up? (`ip link show {iface}`)"),
            ),
        })?;
        Ok(Self::from_socket(socket, &name, mtu))
    }

    /// Wraps an open socket (tests use one end of a socket pair).
    pub fn from_socket(socket: CanFdSocket, name: &str, mtu: usize) -> Self {
        // Ask the kernel for arrival times; without them the host clock at read time is used.
        let _ = socket.set_recv_timestamp(true);
        SocketCanTransport {
            socket,
            name: name.to_string(),
            mtu,
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

    fn io(&self, e: std::io::Error) -> TransportError {
        match e.kind() {
            ErrorKind::BrokenPipe | ErrorKind::NotConnected => {
                TransportError::Closed(self.name.clone())
            }
            _ if e.raw_os_error() == Some(19) => TransportError::Closed(self.name.clone()), // ENODEV
            _ => TransportError::Io {
                device: self.name.clone(),
                source: e,
            },
        }
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
        let result = if data.len() <= 8 {
            let f = CanDataFrame::new(id, data)
                .ok_or_else(|| TransportError::Unsupported("frame".into()))?;
            self.socket.write_frame(&f)
        } else {
            let f = CanFdFrame::new(id, data)
                .ok_or_else(|| TransportError::Unsupported("frame".into()))?;
            self.socket.write_frame(&f)
        };
        result.map_err(|e| self.io(e))
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
                // Standard IDs, remote and error frames are not Cyphal.
                _ => continue,
            };
            if let Some(f) = Frame::new(timestamp, raw & 0x1FFF_FFFF, &data) {
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
    fn a_missing_interface_is_a_clear_error() {
        let err = SocketCanTransport::open("nosuchcan7", 8)
            .err()
            .unwrap()
            .to_string();
        assert!(err.contains("socketcan:nosuchcan7"), "{err}");
    }
}
