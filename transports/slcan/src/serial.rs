//! SLCAN over a serial port.
//!
//! A reader thread drains the port as soon as bytes arrive and stamps each read on the host
//! clock, into a bounded queue the caller's loop empties when it gets to it: a loop busy with a
//! row, or descheduled on a loaded machine, leaves the bytes waiting in the process, not in the
//! kernel's few kilobytes of terminal buffer (a pseudo-terminal holds about 16 KiB; behind a USB
//! adapter, a full buffer stops the reads and the adapter drops frames). A received frame's
//! timestamp is the time of the read that brought it (or the adapter's, mapped onto the host
//! clock), not the time the loop looked.
//!
//! Writes never wait for the adapter: the port is non-blocking (Unix: `O_NONBLOCK` on the file
//! descriptor) or has a 1 ms write timeout (Windows), a line the port takes only in part keeps
//! its tail in `tail`, and that tail goes out before any other byte. Replies (`\r`, `z`, BELL)
//! come back in the order the lines went out, so each is matched to the oldest line still
//! awaiting one; that is how a BELL names the command it refuses.

use std::collections::VecDeque;
use std::io::{ErrorKind, Write};
use std::sync::atomic::{AtomicBool, AtomicU64, Ordering};
use std::sync::mpsc::{Receiver, RecvTimeoutError, SyncSender, TrySendError};
use std::sync::Arc;
use std::thread::JoinHandle;
use std::time::Duration;

use propid_core::can::Frame;
use propid_core::time::Instant;
use propid_transport::{BusState, CanTransport, Health, HostClock, OpenError, Os, TransportError};

use crate::codec::{
    bitrate_command, encode_frame, open_command, raw_bitrate_command, AdapterClock, Decoder, Event,
};

/// How long one write may wait for room. Zero on Unix, where the port is non-blocking;
/// Windows' serial timeouts treat zero as "forever", so 1 ms there.
const WRITE_WAIT: Duration = if cfg!(unix) {
    Duration::ZERO
} else {
    Duration::from_millis(1)
};
/// How long the set-up commands may take to leave.
const COMMAND_DEADLINE: Duration = Duration::from_millis(500);
/// How long `configure` waits for the adapter's replies. A peer that never replies (another
/// host on a pseudo-terminal) costs this once; a Babel replies within a millisecond.
const REPLY_WAIT: Duration = Duration::from_millis(100);
/// Lines remembered while awaiting a reply; a peer that never replies must not grow it.
const AWAITING_MAX: usize = 256;
/// How often the adapter's status flags are asked for (`F`).
const STATUS_INTERVAL: Duration = Duration::from_secs(1);
/// Reads the reader thread has made and the caller's loop has not taken yet, at most (about
/// 30 s of a 500 Hz drive's feedback, one message per read); when full, the reader waits and the
/// kernel buffers again.
const READ_QUEUE: usize = 16_384;
/// The largest single read.
const READ_CHUNK: usize = 4096;
/// How long one wait of the reader thread lasts (how soon it sees that the transport is gone).
const READ_SLICE: Duration = Duration::from_millis(20);

/// One read of the reader thread.
enum ReadResult {
    /// Bytes, and the host time they were read at.
    Bytes(Instant, Vec<u8>),
    /// The port failed: end of file (`None`) or an error; the thread has ended.
    Failed(Option<std::io::Error>),
}

/// What the reader thread counts.
#[derive(Default)]
struct ReaderCounters {
    reads: AtomicU64,
    bytes: AtomicU64,
    /// Reads that filled the whole buffer (more was waiting in the kernel).
    full_reads: AtomicU64,
    /// Times the queue was full and the reader had to wait for the caller.
    queue_full: AtomicU64,
    /// The reader runs at a real-time priority.
    realtime: AtomicBool,
}

/// The reader thread and the queue it fills.
struct Reader {
    queue: Option<Receiver<ReadResult>>,
    stop: Arc<AtomicBool>,
    counters: Arc<ReaderCounters>,
    thread: Option<JoinHandle<()>>,
}

impl Reader {
    fn start(mut port: Box<dyn serialport::SerialPort>, name: &str) -> std::io::Result<Reader> {
        // Unix: the clone's timeout is its own (a poll before each read). Windows' timeouts
        // belong to the handle, which the writer sets; the reader takes whatever it has.
        if cfg!(unix) {
            port.set_timeout(READ_SLICE)?;
        }
        let (tx, rx) = std::sync::mpsc::sync_channel(READ_QUEUE);
        let stop = Arc::new(AtomicBool::new(false));
        let counters = Arc::new(ReaderCounters::default());
        let thread = {
            let (stop, counters) = (Arc::clone(&stop), Arc::clone(&counters));
            std::thread::Builder::new()
                .name(format!("slcan reader {name}"))
                .spawn(move || read_loop(port.as_mut(), &tx, &stop, &counters))?
        };
        Ok(Reader {
            queue: Some(rx),
            stop,
            counters,
            thread: Some(thread),
        })
    }
}

impl Drop for Reader {
    fn drop(&mut self) {
        self.stop.store(true, Ordering::Relaxed);
        // A reader waiting on a full queue wakes up with an error once the queue is gone.
        self.queue.take();
        if let Some(t) = self.thread.take() {
            let _ = t.join();
        }
    }
}

/// The reader thread: reads until the port fails or the transport is dropped.
fn read_loop(
    port: &mut dyn serialport::SerialPort,
    tx: &SyncSender<ReadResult>,
    stop: &AtomicBool,
    counters: &ReaderCounters,
) {
    // Bytes that wait in the kernel are lost once its buffer is full: this thread takes the CPU
    // as soon as they arrive, where permitted.
    let priority = propid_transport::priority::raise_thread_priority();
    counters
        .realtime
        .store(priority.obtained().is_realtime(), Ordering::Relaxed);
    let mut buf = vec![0u8; READ_CHUNK];
    while !stop.load(Ordering::Relaxed) {
        let read = match port.read(&mut buf) {
            Ok(0) => ReadResult::Failed(None),
            Ok(n) => {
                let now = HostClock::now();
                counters.reads.fetch_add(1, Ordering::Relaxed);
                counters.bytes.fetch_add(n as u64, Ordering::Relaxed);
                if n == buf.len() {
                    counters.full_reads.fetch_add(1, Ordering::Relaxed);
                }
                ReadResult::Bytes(now, buf[..n].to_vec())
            }
            Err(e)
                if matches!(
                    e.kind(),
                    ErrorKind::TimedOut | ErrorKind::WouldBlock | ErrorKind::Interrupted
                ) =>
            {
                continue
            }
            Err(e) => ReadResult::Failed(Some(e)),
        };
        let failed = matches!(read, ReadResult::Failed(_));
        let sent = match tx.try_send(read) {
            Err(TrySendError::Full(read)) => {
                counters.queue_full.fetch_add(1, Ordering::Relaxed);
                tx.send(read).is_ok()
            }
            other => other.is_ok(),
        };
        if failed || !sent {
            return;
        }
    }
}

/// What the reader thread of an [`SlcanTransport`] has done.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct ReaderStats {
    /// Reads that returned bytes.
    pub reads: u64,
    /// Bytes read.
    pub bytes: u64,
    /// Reads that filled the whole buffer: more was waiting in the kernel.
    pub full_reads: u64,
    /// Times the queue to the caller was full and the reader waited (the kernel buffered).
    pub queue_full: u64,
    /// The reader thread runs at a real-time priority.
    pub realtime: bool,
}

/// An SLCAN adapter on a serial port (or one end of a pseudo-terminal pair).
pub struct SlcanTransport {
    /// The port, for writing (the reader thread reads a clone of it).
    port: Box<dyn serialport::SerialPort>,
    reader: Reader,
    name: String,
    decoder: Decoder,
    pending: VecDeque<Frame>,
    events: Vec<Event>,
    clock: AdapterClock,
    /// Bytes of accepted lines the port has not taken yet; they leave before anything else.
    tail: Vec<u8>,
    /// Lines sent and not yet answered, oldest first (without `\r`).
    awaiting: VecDeque<String>,
    /// Lines refused since the last `configure` began.
    refused_recent: Vec<String>,
    health: Health,
    status_interval: Option<Duration>,
    next_status: std::time::Instant,
    /// Set once the device has disappeared: every later call fails the same way.
    gone: bool,
}

/// Why `path` could not be opened as a serial port, typed so the message says what fixes it.
fn open_error(path: &str, e: &serialport::Error) -> OpenError {
    use serialport::ErrorKind as K;
    let os = Os::this();
    match e.kind() {
        K::Io(ErrorKind::NotFound) => OpenError::NoSerialDevice(os),
        K::Io(ErrorKind::PermissionDenied) => OpenError::SerialPermission {
            os,
            path: path.to_string(),
        },
        K::NoDevice => OpenError::Busy(os),
        // A path that exists but is no terminal (ENOTTY on a regular file, EISDIR, …).
        _ if std::fs::metadata(path).is_ok_and(|m| !is_device(&m)) => OpenError::NotASerialPort,
        _ => OpenError::Other(e.description.clone()),
    }
}

/// Whether a file is a device (a character device on Unix; anything that opens on Windows).
fn is_device(m: &std::fs::Metadata) -> bool {
    #[cfg(unix)]
    {
        use std::os::unix::fs::FileTypeExt;
        m.file_type().is_char_device()
    }
    #[cfg(not(unix))]
    {
        !m.is_file() && !m.is_dir()
    }
}

impl SlcanTransport {
    /// Opens `path` at `baud` (non-blocking) and configures the adapter for `bitrate` with
    /// timestamps on.
    pub fn open(path: &str, baud: u32, bitrate: u32) -> Result<Self, TransportError> {
        let port = serialport::new(path, baud)
            .timeout(Duration::from_millis(10))
            .open_native()
            .map_err(|e| TransportError::Open {
                device: format!("slcan:{path}"),
                why: open_error(path, &e),
            })?;
        #[cfg(unix)]
        let mut t = Self::from_tty(port, path)?;
        #[cfg(not(unix))]
        let mut t = Self::from_port(Box::new(port), path)?;
        t.configure(bitrate)?;
        Ok(t)
    }

    /// Wraps an open terminal (a pty end in tests and the demo) without configuring it, and
    /// makes its file descriptor non-blocking so that no write can stall the caller.
    #[cfg(unix)]
    pub fn from_tty(port: serialport::TTYPort, name: &str) -> Result<Self, TransportError> {
        use std::os::fd::{AsRawFd, BorrowedFd};
        // SAFETY: `port` owns this descriptor and outlives the borrow, which ends with the two
        // fcntl calls below; nothing closes it meanwhile.
        let fd = unsafe { BorrowedFd::borrow_raw(port.as_raw_fd()) };
        let flags = rustix::fs::fcntl_getfl(fd)
            .and_then(|f| rustix::fs::fcntl_setfl(fd, f | rustix::fs::OFlags::NONBLOCK));
        if let Err(e) = flags {
            return Err(TransportError::Io {
                device: format!("slcan:{name}"),
                error: std::io::Error::from(e),
            });
        }
        Self::from_port(Box::new(port), name)
    }

    /// Wraps an already open port without configuring it, and starts its reader thread (on a
    /// clone of the port). On Unix prefer [`Self::from_tty`]: a port left blocking can stall a
    /// write until a whole line fits.
    pub fn from_port(
        port: Box<dyn serialport::SerialPort>,
        name: &str,
    ) -> Result<Self, TransportError> {
        let name = format!("slcan:{name}");
        let io = |error| TransportError::Io {
            device: name.clone(),
            error,
        };
        let clone = port
            .try_clone()
            .map_err(|e| io(std::io::Error::other(e.to_string())))?;
        let reader = Reader::start(clone, &name).map_err(io)?;
        Ok(SlcanTransport {
            port,
            reader,
            name,
            decoder: Decoder::new(),
            pending: VecDeque::new(),
            events: Vec::new(),
            clock: AdapterClock::new(),
            tail: Vec::new(),
            awaiting: VecDeque::new(),
            refused_recent: Vec::new(),
            health: Health::default(),
            status_interval: Some(STATUS_INTERVAL),
            next_status: std::time::Instant::now() + STATUS_INTERVAL,
            gone: false,
        })
    }

    /// How often to ask the adapter for its status flags (`F`); `None` never asks (a status
    /// is then only known when the adapter volunteers it). A refusal triggers a poll at once.
    pub fn set_status_interval(&mut self, every: Option<Duration>) {
        self.status_interval = every;
        self.next_status = std::time::Instant::now() + every.unwrap_or(Duration::ZERO);
    }

    /// Sends the set-up commands for a rate without an `S` code: close, `sXXYY` with the raw bus
    /// timing registers, timestamps on, open (or listen only).
    pub fn configure_raw(
        &mut self,
        btr0: u8,
        btr1: u8,
        listen_only: bool,
    ) -> Result<(), TransportError> {
        let rate = raw_bitrate_command(btr0, btr1);
        self.run_commands(&["C\r", &rate, "Z1\r", open_command(listen_only)])
    }

    /// Sends the set-up commands: close, bit rate, timestamps on, open. Waits briefly for the
    /// replies: a refused bit rate or open is [`TransportError::Refused`]; a refused close (the
    /// channel was closed already) or timestamp command is only counted. A peer that does not
    /// reply at all is accepted.
    pub fn configure(&mut self, bitrate: u32) -> Result<(), TransportError> {
        let rate = bitrate_command(bitrate).ok_or_else(|| {
            TransportError::Unsupported(format!(
                "{}: no SLCAN bit-rate code for {bitrate} bit/s (use 10k, 20k, 50k, 100k, 125k, 250k, 500k, 800k or 1M, or raw bus timing registers with SlcanTransport::configure_raw)",
                self.name
            ))
        })?;
        self.run_commands(&["C\r", rate, "Z1\r", "O\r"])
    }

    fn run_commands(&mut self, commands: &[&str]) -> Result<(), TransportError> {
        self.check_gone()?;
        self.refused_recent.clear();
        let deadline = std::time::Instant::now() + COMMAND_DEADLINE;
        for cmd in commands {
            self.enqueue_line(cmd.as_bytes());
            if !self.flush(deadline)? {
                return Err(TransportError::Io {
                    device: self.name.clone(),
                    error: std::io::Error::new(
                        ErrorKind::TimedOut,
                        format!(
                            "the adapter did not take the command `{}` within {} ms",
                            cmd.trim_end(),
                            COMMAND_DEADLINE.as_millis()
                        ),
                    ),
                });
            }
        }
        // Wait for the replies (or for a peer that gives none).
        let until = std::time::Instant::now() + REPLY_WAIT;
        let is_setup = |l: &String| commands.iter().any(|c| c.trim_end() == l);
        while self.awaiting.iter().any(is_setup) {
            let left = until.saturating_duration_since(std::time::Instant::now());
            if left.is_zero() {
                break;
            }
            self.read_once(left.min(Duration::from_millis(5)))?;
        }
        let fatal = self
            .refused_recent
            .iter()
            .find(|c| commands.iter().any(|k| k.trim_end() == c.as_str()))
            .filter(|c| !c.starts_with('C') && !c.starts_with('Z'));
        match fatal {
            Some(command) => Err(TransportError::Refused {
                device: self.name.clone(),
                command: command.clone(),
            }),
            None => Ok(()),
        }
    }

    /// Lines skipped as garbage.
    pub fn garbage_count(&self) -> u64 {
        self.decoder.garbage_count()
    }

    fn check_gone(&self) -> Result<(), TransportError> {
        if self.gone {
            Err(TransportError::Closed(self.name.clone()))
        } else {
            Ok(())
        }
    }

    /// Queues a whole line behind whatever is pending and remembers it awaits a reply.
    fn enqueue_line(&mut self, line: &[u8]) {
        self.tail.extend_from_slice(line);
        self.expect_reply(line);
    }

    fn expect_reply(&mut self, line: &[u8]) {
        if self.awaiting.len() == AWAITING_MAX {
            self.awaiting.pop_front();
        }
        let text = String::from_utf8_lossy(line);
        self.awaiting
            .push_back(text.trim_end_matches('\r').to_string());
    }

    /// One write that does not wait: the bytes the port took (0 when it took none).
    fn write_some(&mut self, bytes: &[u8]) -> Result<usize, TransportError> {
        let _ = self.port.set_timeout(WRITE_WAIT);
        match self.port.write(bytes) {
            Ok(n) => Ok(n),
            Err(e)
                if matches!(
                    e.kind(),
                    ErrorKind::WouldBlock | ErrorKind::TimedOut | ErrorKind::Interrupted
                ) =>
            {
                Ok(0)
            }
            Err(e) => Err(self.io_error(e)),
        }
    }

    /// Writes as much of the pending tail as the port takes now; `true` when none is left.
    fn push_tail(&mut self) -> Result<bool, TransportError> {
        while !self.tail.is_empty() {
            let tail = std::mem::take(&mut self.tail);
            let n = self.write_some(&tail);
            self.tail = tail;
            match n? {
                0 => return Ok(false),
                n => {
                    self.tail.drain(..n);
                }
            }
        }
        Ok(true)
    }

    /// Offers a whole line: `false` (nothing written) when the port takes none of it now.
    fn offer(&mut self, line: &[u8]) -> Result<bool, TransportError> {
        if !self.push_tail()? {
            return Ok(false);
        }
        let n = self.write_some(line)?;
        if n == 0 {
            return Ok(false);
        }
        self.tail.extend_from_slice(&line[n..]);
        self.expect_reply(line);
        Ok(true)
    }

    /// Asks for the status flags when a poll is due and the line is free.
    fn poll_status(&mut self) -> Result<(), TransportError> {
        let Some(every) = self.status_interval else {
            return Ok(());
        };
        let now = std::time::Instant::now();
        if now >= self.next_status && self.offer(b"F\r")? {
            self.next_status = now + every;
        }
        Ok(())
    }

    /// Takes what the reader thread read, waiting up to `wait` for the first read; frames go to
    /// `pending`, replies to the counters.
    fn read_once(&mut self, wait: Duration) -> Result<(), TransportError> {
        let Some(queue) = self.reader.queue.as_ref() else {
            return Err(self.disappeared());
        };
        let mut next = match queue.recv_timeout(wait) {
            Ok(read) => Some(read),
            Err(RecvTimeoutError::Timeout) => return Ok(()),
            Err(RecvTimeoutError::Disconnected) => Some(ReadResult::Failed(None)),
        };
        // Everything already read, without waiting again.
        while let Some(read) = next.take() {
            match read {
                ReadResult::Bytes(at, bytes) => {
                    self.decoder.push(&bytes, &mut self.events);
                    self.absorb(at);
                }
                ReadResult::Failed(None) => return Err(self.disappeared()),
                ReadResult::Failed(Some(e)) => return Err(self.io_error(e)),
            }
            next = self.reader.queue.as_ref().and_then(|q| q.try_recv().ok());
        }
        Ok(())
    }

    /// What the reader thread has done so far: reads, bytes, reads that filled its buffer
    /// (more was waiting in the kernel), and times its queue was full.
    pub fn reader_counters(&self) -> ReaderStats {
        let c = &self.reader.counters;
        ReaderStats {
            reads: c.reads.load(Ordering::Relaxed),
            bytes: c.bytes.load(Ordering::Relaxed),
            full_reads: c.full_reads.load(Ordering::Relaxed),
            queue_full: c.queue_full.load(Ordering::Relaxed),
            realtime: c.realtime.load(Ordering::Relaxed),
        }
    }

    fn disappeared(&mut self) -> TransportError {
        self.gone = true;
        TransportError::Closed(self.name.clone())
    }

    /// What a failed read or write means. A pseudo-terminal whose other side closed, or a USB
    /// CDC port whose adapter was unplugged, reports a hang-up (which `serialport` gives as
    /// BrokenPipe) or EIO/ENXIO/ENODEV; `serialport` keeps only the text of the last three.
    fn io_error(&mut self, e: std::io::Error) -> TransportError {
        let text = e.to_string();
        let gone_text = ["I/O error", "No such device", "Input/output error"];
        let gone = matches!(
            e.kind(),
            ErrorKind::BrokenPipe
                | ErrorKind::NotConnected
                | ErrorKind::UnexpectedEof
                | ErrorKind::ConnectionReset
                | ErrorKind::ConnectionAborted
        ) || matches!(e.raw_os_error(), Some(5 | 6 | 19))
            || gone_text.iter().any(|t| text.contains(t));
        if gone {
            return self.disappeared();
        }
        TransportError::Io {
            device: self.name.clone(),
            error: e,
        }
    }

    fn absorb(&mut self, now: Instant) {
        for event in std::mem::take(&mut self.events) {
            match event {
                Event::Frame {
                    id,
                    extended: true,
                    data,
                    remote: false,
                    adapter_ms,
                } => {
                    let timestamp = match adapter_ms {
                        Some(ms) => Instant::from_micros(self.clock.map(ms, now.as_micros())),
                        None => now,
                    };
                    if let Some(f) = Frame::new(timestamp, id, &data) {
                        self.pending.push_back(f);
                    }
                }
                Event::Status(flags) => {
                    self.health.status_reports += 1;
                    self.health.status_flags = Some(flags.0);
                    self.health.bus_state = flags.bus_state();
                    if flags.overrun() {
                        self.health.overruns += 1;
                    }
                    // `F` is answered by its report, not by an empty line.
                    if self.awaiting.front().is_some_and(|l| l == "F") {
                        self.awaiting.pop_front();
                    }
                }
                Event::Ack | Event::TransmitAck => {
                    self.awaiting.pop_front();
                }
                Event::Nack => {
                    let line = self
                        .awaiting
                        .pop_front()
                        .unwrap_or_else(|| "(no command awaiting a reply)".into());
                    self.health.refused += 1;
                    self.health.last_refused = Some(line.clone());
                    self.refused_recent.push(line);
                    // Find out why: a refused frame usually means bus-off or a full queue.
                    self.next_status = std::time::Instant::now();
                }
                // Standard-ID and remote frames are not Cyphal; info needs no action.
                _ => {}
            }
        }
        self.health.timestamp_resyncs = self.clock.resyncs();
    }
}

impl CanTransport for SlcanTransport {
    fn send(&mut self, frame: &Frame) -> Result<(), TransportError> {
        self.check_gone()?;
        let line = encode_frame(frame.id(), frame.data()).ok_or_else(|| {
            TransportError::Unsupported(format!(
                "{}: SLCAN carries Classic CAN only; a {}-byte (CAN FD) frame cannot be sent (set UAVCAN__CAN__MTU=8)",
                self.name,
                frame.data().len()
            ))
        })?;
        let accepted = self.offer(line.as_bytes())?;
        // After the frame, so that a poll never takes the room the frame could have had.
        self.poll_status()?;
        if accepted {
            self.health.frames_sent += 1;
            Ok(())
        } else {
            self.health.would_block += 1;
            Err(TransportError::WouldBlock)
        }
    }

    fn flush(&mut self, deadline: std::time::Instant) -> Result<bool, TransportError> {
        self.check_gone()?;
        loop {
            if self.push_tail()? {
                return Ok(true);
            }
            let left = deadline.saturating_duration_since(std::time::Instant::now());
            if left.is_zero() {
                return Ok(false);
            }
            // Keep reading while waiting: a peer blocked on writing to us may be the one that
            // is not draining our output.
            self.read_once(left.min(Duration::from_millis(1)))?;
        }
    }

    fn receive(&mut self, timeout: Duration) -> Result<Option<Frame>, TransportError> {
        self.check_gone()?;
        let deadline = std::time::Instant::now() + timeout;
        loop {
            if let Some(f) = self.pending.pop_front() {
                self.health.frames_received += 1;
                return Ok(Some(f));
            }
            let tail_left = !self.push_tail()?;
            self.poll_status()?;
            let left = deadline.saturating_duration_since(std::time::Instant::now());
            // With output pending, wake up often to move it along.
            let step = if tail_left {
                Duration::from_millis(1)
            } else {
                Duration::from_millis(50)
            };
            self.read_once(left.min(step))?;
            if left.is_zero() && self.pending.is_empty() {
                return Ok(None);
            }
        }
    }

    fn mtu(&self) -> usize {
        8
    }

    fn name(&self) -> String {
        self.name.clone()
    }

    fn health(&self) -> Health {
        Health {
            garbage: self.decoder.garbage_count(),
            bus_state: if self.health.status_reports == 0 {
                BusState::Unknown
            } else {
                self.health.bus_state
            },
            ..self.health.clone()
        }
    }
}
