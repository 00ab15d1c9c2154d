//! SLCAN over a serial port.

use std::io::{ErrorKind, Read, Write};
use std::time::Duration;

use propid_core::can::Frame;
use propid_core::time::Instant;
use propid_transport::{CanTransport, HostClock, TransportError};

use crate::codec::{
    bitrate_command, encode_frame, open_command, raw_bitrate_command, Decoder, Event,
    TimestampUnwrapper,
};

/// How long a write may wait for room in the adapter's buffer before the adapter counts as stuck.
const WRITE_TIMEOUT: Duration = Duration::from_millis(500);

/// An SLCAN adapter on a serial port (or one end of a pseudo-terminal pair).
pub struct SlcanTransport {
    port: Box<dyn serialport::SerialPort>,
    name: String,
    decoder: Decoder,
    pending: std::collections::VecDeque<Frame>,
    events: Vec<Event>,
    unwrapper: TimestampUnwrapper,
    /// Host time of the first adapter timestamp, to map adapter time onto the host clock.
    adapter_epoch: Option<(u64, Instant)>,
    /// Status events seen (overrun, error-passive, bus-off).
    pub status_events: u64,
    /// Commands the adapter refused.
    pub nacks: u64,
}

impl SlcanTransport {
    /// Opens `path` at `baud` and configures the adapter for `bitrate` with timestamps on.
    pub fn open(path: &str, baud: u32, bitrate: u32) -> Result<Self, TransportError> {
        let port = serialport::new(path, baud)
            .timeout(Duration::from_millis(10))
            .open()
            .map_err(|e| TransportError::Io {
                device: path.to_string(),
                source: std::io::Error::other(e.to_string()),
            })?;
        let mut t = Self::from_port(port, path);
        t.configure(bitrate)?;
        Ok(t)
    }

    /// Wraps an already open port (a pty end in tests and the demo) without configuring it.
    pub fn from_port(port: Box<dyn serialport::SerialPort>, name: &str) -> Self {
        SlcanTransport {
            port,
            name: format!("slcan:{name}"),
            decoder: Decoder::new(),
            pending: Default::default(),
            events: Vec::new(),
            unwrapper: TimestampUnwrapper::default(),
            adapter_epoch: None,
            status_events: 0,
            nacks: 0,
        }
    }

    /// Sends the set-up commands for a rate without an `S` code: close, `sXXYY` with the raw bus
    /// timing registers, timestamps on, open (or listen only).
    pub fn configure_raw(
        &mut self,
        btr0: u8,
        btr1: u8,
        listen_only: bool,
    ) -> Result<(), TransportError> {
        for cmd in [
            "C\r".to_string(),
            raw_bitrate_command(btr0, btr1),
            "Z1\r".into(),
            open_command(listen_only).into(),
        ] {
            self.write(cmd.as_bytes())?;
        }
        Ok(())
    }

    /// Sends the set-up commands: close, bit rate, timestamps on, open.
    pub fn configure(&mut self, bitrate: u32) -> Result<(), TransportError> {
        let rate = match bitrate_command(bitrate) {
            Some(cmd) => cmd.to_string(),
            None => {
                return Err(TransportError::Unsupported(format!(
                    "{}: no SLCAN bit-rate code for {bitrate} bit/s (use 10k, 20k, 50k, 100k, 125k, 250k, 500k, 800k or 1M, or raw bus timing registers with SlcanTransport::configure_raw)",
                    self.name
                )))
            }
        };
        for cmd in ["C\r", &rate, "Z1\r", "O\r"] {
            self.write(cmd.as_bytes())?;
        }
        Ok(())
    }

    /// Lines skipped as garbage.
    pub fn garbage_count(&self) -> u64 {
        self.decoder.garbage_count()
    }

    fn write(&mut self, bytes: &[u8]) -> Result<(), TransportError> {
        // The port's timeout is shortened while receiving; a write may wait for the adapter
        // (or the peer on a pseudo-terminal) to drain its buffer, up to WRITE_TIMEOUT.
        let _ = self.port.set_timeout(WRITE_TIMEOUT);
        self.port.write_all(bytes).map_err(|e| self.io_error(e))?;
        Ok(())
    }

    /// EIO (5) is what reading a pseudo-terminal or a USB CDC port gives when the other side is
    /// gone.
    fn io_error(&self, e: std::io::Error) -> TransportError {
        match e.kind() {
            _ if e.raw_os_error() == Some(5) => TransportError::Closed(self.name.clone()),
            ErrorKind::BrokenPipe | ErrorKind::NotConnected | ErrorKind::UnexpectedEof => {
                TransportError::Closed(self.name.clone())
            }
            _ => TransportError::Io {
                device: self.name.clone(),
                source: e,
            },
        }
    }

    fn absorb(&mut self, now: Instant) {
        for event in self.events.drain(..) {
            match event {
                Event::Frame {
                    id,
                    extended: true,
                    data,
                    remote: false,
                    adapter_ms,
                } => {
                    let timestamp = match adapter_ms {
                        Some(ms) => {
                            let ms = self.unwrapper.unwrap(ms);
                            let (ms0, host0) = *self.adapter_epoch.get_or_insert((ms, now));
                            host0 + Duration::from_millis(ms - ms0)
                        }
                        None => now,
                    };
                    if let Some(f) = Frame::new(timestamp, id, &data) {
                        self.pending.push_back(f);
                    }
                }
                Event::Status(_) => self.status_events += 1,
                Event::Nack => self.nacks += 1,
                // Standard-ID and remote frames are not Cyphal; acks and info need no action.
                _ => {}
            }
        }
    }
}

impl CanTransport for SlcanTransport {
    fn send(&mut self, frame: &Frame) -> Result<(), TransportError> {
        let line = encode_frame(frame.id(), frame.data()).ok_or_else(|| {
            TransportError::Unsupported(format!(
                "{}: SLCAN carries Classic CAN only; a {}-byte (CAN FD) frame cannot be sent (set UAVCAN__CAN__MTU=8)",
                self.name,
                frame.data().len()
            ))
        })?;
        self.write(line.as_bytes())
    }

    fn receive(&mut self, timeout: Duration) -> Result<Option<Frame>, TransportError> {
        let deadline = std::time::Instant::now() + timeout;
        let mut buf = [0u8; 1024];
        loop {
            if let Some(f) = self.pending.pop_front() {
                return Ok(Some(f));
            }
            let left = deadline.saturating_duration_since(std::time::Instant::now());
            if left.is_zero() {
                return Ok(None);
            }
            let _ = self.port.set_timeout(left.min(Duration::from_millis(50)));
            match self.port.read(&mut buf) {
                Ok(0) => return Err(TransportError::Closed(self.name.clone())),
                Ok(n) => {
                    let now = HostClock::now();
                    self.decoder.push(&buf[..n], &mut self.events);
                    self.absorb(now);
                }
                Err(e) if e.kind() == ErrorKind::TimedOut || e.kind() == ErrorKind::WouldBlock => {}
                Err(e) if e.kind() == ErrorKind::Interrupted => {}
                Err(e) => return Err(self.io_error(e)),
            }
        }
    }

    fn mtu(&self) -> usize {
        8
    }

    fn name(&self) -> String {
        self.name.clone()
    }
}
