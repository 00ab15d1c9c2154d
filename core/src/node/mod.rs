//! A Sans-IO Cyphal node: time and frames in, frames out, in fixed memory.
//!
//! ```text
//!  handle_frame(now, frame) ──► Reassembler ──► GetInfo request? → response queued
//!                                           └─► Event::Message / Event::Response to the caller
//!  publish(now, subject, payload) / request(now, service, server, payload)
//!        ──► FrameSplitter ──► transmit queue (deadlines) ──► poll_transmit(now) → Frame
//!  poll_timeout() → when to come back (the next heartbeat)
//! ```
//! The node publishes `uavcan.node.Heartbeat.1.0` once a second (uptime, health, mode) and
//! answers `uavcan.node.GetInfo.1.0` requests addressed to it with its name and version. Every
//! other port is the caller's: subjects and services are given at run time. Capacities are const
//! parameters: `PORTS` subscriptions, `SESSIONS` receive sessions, `EXTENT` bytes per received
//! transfer, `QUEUE` frames waiting to be sent. Nothing here reads a clock or touches a device, so
//! two nodes can be driven through a simulated link with a virtual clock (see `tests/node_link.rs`).
//!
//! Opt-in, in `registry.rs`: `REGISTERS` registers served over `uavcan.register.List`/`Access`
//! ([`Node::add_register`]; writes reported by [`Node::take_register_change`]),
//! `uavcan.node.ExecuteCommand` ([`Node::serve_commands`], [`Node::take_command`]) and
//! `uavcan.node.port.List` every 10 s ([`Node::enable_port_list`]). To accept every Access request
//! whole, `EXTENT` must be ≥ 515 bytes (see `tests/register_server.rs`).

use core::time::Duration;

mod registry;
pub use registry::{convert, parse_value, Command, Register, RegisterError, Registry};

use crate::can::{
    Frame, FrameSplitter, Mtu, Port, Priority, Reassembler, RxStats, Subscription, TransferHeader,
    TransferKind, TxError, DEFAULT_TRANSFER_ID_TIMEOUT,
};
use crate::dsdl::{DataType, GetInfoResponse, Heartbeat, Version, GET_INFO_SERVICE_ID};
use crate::time::Instant;

/// Who the node is.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct NodeConfig {
    /// Node-ID, 0..=127.
    pub node_id: u8,
    /// Name reported by GetInfo (reverse-domain style), at most 50 bytes.
    pub name: heapless::Vec<u8, 50>,
    /// Software version reported by GetInfo.
    pub software_version: Version,
    /// Unique ID reported by GetInfo.
    pub unique_id: [u8; 16],
    /// Classic CAN or CAN FD.
    pub mtu: Mtu,
}

impl NodeConfig {
    /// A configuration with the given ID and name (truncated to 50 bytes), version 0.1.
    pub fn new(node_id: u8, name: &str, mtu: Mtu) -> Self {
        let bytes = name.as_bytes();
        NodeConfig {
            node_id,
            name: heapless::Vec::from_slice(&bytes[..bytes.len().min(50)]).unwrap_or_default(),
            software_version: Version { major: 0, minor: 1 },
            unique_id: [node_id; 16],
            mtu,
        }
    }
}

/// Something the caller should know about.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Event<'a> {
    /// A message on a subscribed subject.
    Message {
        /// Subject-ID.
        subject_id: u16,
        /// Publisher (`None`: anonymous).
        source: Option<u8>,
        /// Transfer-ID.
        transfer_id: u8,
        /// Priority.
        priority: Priority,
        /// Time of its first frame.
        timestamp: Instant,
        /// Payload (DSDL-serialised).
        payload: &'a [u8],
    },
    /// A response to a request this node made.
    Response {
        /// Service-ID.
        service_id: u16,
        /// Server node-ID.
        source: u8,
        /// Transfer-ID (that of the request).
        transfer_id: u8,
        /// Time of its first frame.
        timestamp: Instant,
        /// Payload.
        payload: &'a [u8],
    },
}

/// Why a port could not be set up.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum NodeError {
    /// All subscription slots are taken.
    TooManyPorts,
    /// A port-ID out of range.
    InvalidPort,
}

/// Counters.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct NodeStats {
    /// Receive-side counters.
    pub rx: RxStats,
    /// Frames dropped because they waited past their deadline.
    pub tx_expired: u64,
    /// Transfers refused because the queue was full.
    pub tx_queue_full: u64,
    /// Heartbeats published.
    pub heartbeats: u64,
    /// GetInfo requests answered.
    pub get_info_answered: u64,
}

/// Deadline of heartbeat and GetInfo frames.
const SERVICE_DEADLINE: Duration = Duration::from_millis(1000);

/// A Cyphal node. See the module documentation; `REGISTERS` register slots (about 530 bytes
/// each; none by default) are served as [`registry`](Node::add_register) describes.
pub struct Node<
    const PORTS: usize,
    const SESSIONS: usize,
    const EXTENT: usize,
    const QUEUE: usize,
    const REGISTERS: usize = 0,
> {
    config: NodeConfig,
    started: Instant,
    next_heartbeat: Instant,
    health: u8,
    mode: u8,
    vendor_status: u8,
    rx: Reassembler<PORTS, SESSIONS, EXTENT>,
    queue: heapless::Deque<(Frame, Instant), QUEUE>,
    transfer_ids: heapless::LinearMap<(bool, u16), u8, PORTS>,
    heartbeat_tid: u8,
    stats: NodeStats,
    /// The latest time the caller gave.
    now: Instant,
    /// Registers, commands, port list.
    services: registry::Services<REGISTERS>,
}

impl<
        const PORTS: usize,
        const SESSIONS: usize,
        const EXTENT: usize,
        const QUEUE: usize,
        const REGISTERS: usize,
    > Node<PORTS, SESSIONS, EXTENT, QUEUE, REGISTERS>
{
    /// A node that starts now: its first heartbeat is due immediately.
    pub fn new(config: NodeConfig, now: Instant) -> Self {
        let mut rx = Reassembler::new(Some(config.node_id));
        // GetInfo requests are empty; a slot for them always exists when PORTS ≥ 1.
        let _ = rx.subscribe(Subscription {
            port: Port::Request(GET_INFO_SERVICE_ID),
            extent: 0,
            transfer_id_timeout: DEFAULT_TRANSFER_ID_TIMEOUT,
        });
        Node {
            config,
            started: now,
            next_heartbeat: now,
            health: Heartbeat::HEALTH_NOMINAL,
            mode: Heartbeat::MODE_OPERATIONAL,
            vendor_status: 0,
            rx,
            queue: heapless::Deque::new(),
            transfer_ids: heapless::LinearMap::new(),
            heartbeat_tid: 0,
            stats: NodeStats::default(),
            now,
            services: registry::Services::new(),
        }
    }

    /// The node's configuration.
    pub fn config(&self) -> &NodeConfig {
        &self.config
    }

    /// Sets what the heartbeat reports.
    pub fn set_status(&mut self, health: u8, mode: u8, vendor_status: u8) {
        self.health = health;
        self.mode = mode;
        self.vendor_status = vendor_status;
    }

    /// Counters so far.
    pub fn stats(&self) -> NodeStats {
        NodeStats {
            rx: self.rx.stats(),
            ..self.stats
        }
    }

    /// Receives messages on `subject_id`, keeping up to `extent` payload bytes.
    pub fn subscribe_message(&mut self, subject_id: u16, extent: usize) -> Result<(), NodeError> {
        if subject_id > 8191 {
            return Err(NodeError::InvalidPort);
        }
        self.rx
            .subscribe(Subscription {
                port: Port::Subject(subject_id),
                extent,
                transfer_id_timeout: DEFAULT_TRANSFER_ID_TIMEOUT,
            })
            .map_err(|_| NodeError::TooManyPorts)
    }

    fn next_transfer_id(&mut self, service: bool, port: u16) -> Result<u8, TxError> {
        if let Some(t) = self.transfer_ids.get_mut(&(service, port)) {
            let tid = *t;
            *t = (tid + 1) % 32;
            return Ok(tid);
        }
        self.transfer_ids
            .insert((service, port), 1)
            .map_err(|_| TxError::QueueFull)?;
        Ok(0)
    }

    fn enqueue(
        &mut self,
        header: &TransferHeader,
        payload: &[u8],
        now: Instant,
        deadline: Instant,
    ) -> Result<(), TxError> {
        let frames = FrameSplitter::new(header, payload, self.config.mtu, now)?;
        if self.queue.capacity() - self.queue.len() < frames.frame_count() {
            self.stats.tx_queue_full += 1;
            return Err(TxError::QueueFull);
        }
        for f in frames {
            // Room was checked above.
            let _ = self.queue.push_back((f, deadline));
        }
        Ok(())
    }

    /// Publishes `payload` on `subject_id`; its frames are dropped if not sent within `timeout`.
    pub fn publish(
        &mut self,
        now: Instant,
        subject_id: u16,
        priority: Priority,
        payload: &[u8],
        timeout: Duration,
    ) -> Result<(), TxError> {
        if subject_id > 8191 {
            return Err(TxError::InvalidHeader);
        }
        let transfer_id = self.next_transfer_id(false, subject_id)?;
        let header = TransferHeader {
            priority,
            kind: TransferKind::Message { subject_id },
            source: Some(self.config.node_id),
            transfer_id,
        };
        self.enqueue(&header, payload, now, now + timeout)
    }

    /// Serialises and publishes a DSDL message (payload up to 512 bytes).
    pub fn publish_message<T: DataType>(
        &mut self,
        now: Instant,
        subject_id: u16,
        priority: Priority,
        message: &T,
        timeout: Duration,
    ) -> Result<(), TxError> {
        let mut buf = [0u8; 512];
        let n = message.serialize(&mut buf[..T::MAX_SIZE_BYTES.min(512)]);
        self.publish(now, subject_id, priority, &buf[..n], timeout)
    }

    /// Sends a service request to `server`; the response arrives as [`Event::Response`].
    /// Returns the request's transfer-ID.
    pub fn request(
        &mut self,
        now: Instant,
        service_id: u16,
        server: u8,
        payload: &[u8],
        response_extent: usize,
        timeout: Duration,
    ) -> Result<u8, TxError> {
        if service_id > 511 || server > 127 {
            return Err(TxError::InvalidHeader);
        }
        self.rx
            .subscribe(Subscription {
                port: Port::Response(service_id),
                extent: response_extent,
                transfer_id_timeout: DEFAULT_TRANSFER_ID_TIMEOUT,
            })
            .map_err(|_| TxError::QueueFull)?;
        let transfer_id = self.next_transfer_id(true, service_id)?;
        let header = TransferHeader {
            priority: Priority::NOMINAL,
            kind: TransferKind::Request {
                service_id,
                destination: server,
            },
            source: Some(self.config.node_id),
            transfer_id,
        };
        self.enqueue(&header, payload, now, now + timeout)?;
        Ok(transfer_id)
    }

    /// Takes one received frame.
    pub fn handle_frame<'s>(&'s mut self, now: Instant, frame: &'s Frame) -> Option<Event<'s>> {
        self.now = self.now.max(now);
        let served = crate::can::CanId::parse(frame.id()).is_some_and(|id| {
            matches!(id.kind, TransferKind::Request { service_id, .. } if registry::is_served(service_id))
        });
        if served {
            // GetInfo, and the register and command services when enabled: answered here.
            let transfer = self.rx.accept(frame).ok()??;
            let header = transfer.header;
            let mut buf = [0u8; registry::SERVED_REQUEST_MAX];
            let n = transfer.payload.len().min(buf.len());
            buf[..n].copy_from_slice(&transfer.payload[..n]);
            self.serve(now, &header, &buf[..n]);
            return None;
        }
        let transfer = self.rx.accept(frame).ok()??;
        let header = transfer.header;
        let (timestamp, payload) = (transfer.timestamp, transfer.payload);
        match header.kind {
            TransferKind::Message { subject_id } => Some(Event::Message {
                subject_id,
                source: header.source,
                transfer_id: header.transfer_id,
                priority: header.priority,
                timestamp,
                payload,
            }),
            TransferKind::Response { service_id, .. } => Some(Event::Response {
                service_id,
                source: header.source?,
                transfer_id: header.transfer_id,
                timestamp,
                payload,
            }),
            TransferKind::Request { .. } => None,
        }
    }

    fn answer_get_info(&mut self, now: Instant, client: u8, transfer_id: u8, priority: Priority) {
        let info = GetInfoResponse {
            protocol_version: Version { major: 1, minor: 0 },
            hardware_version: Version { major: 0, minor: 0 },
            software_version: self.config.software_version,
            software_vcs_revision_id: 0,
            unique_id: self.config.unique_id,
            name: self.config.name.clone(),
            software_image_crc: None,
            certificate_of_authenticity: heapless::Vec::new(),
        };
        let mut buf = [0u8; GetInfoResponse::MAX_SIZE_BYTES];
        let n = info.serialize(&mut buf);
        let header = TransferHeader {
            priority,
            kind: TransferKind::Response {
                service_id: GET_INFO_SERVICE_ID,
                destination: client,
            },
            source: Some(self.config.node_id),
            transfer_id,
        };
        if self
            .enqueue(&header, &buf[..n], now, now + SERVICE_DEADLINE)
            .is_ok()
        {
            self.stats.get_info_answered += 1;
        }
    }

    /// The next frame to send, if any is due. Publishes the heartbeat when it is time.
    pub fn poll_transmit(&mut self, now: Instant) -> Option<Frame> {
        self.now = self.now.max(now);
        if now >= self.next_heartbeat {
            let uptime = now.saturating_duration_since(self.started).as_secs();
            let hb = Heartbeat {
                uptime: u32::try_from(uptime).unwrap_or(u32::MAX),
                health: self.health,
                mode: self.mode,
                vendor_specific_status_code: self.vendor_status,
            };
            let mut buf = [0u8; 7];
            hb.serialize(&mut buf);
            let header = TransferHeader {
                priority: Priority::NOMINAL,
                kind: TransferKind::Message {
                    subject_id: Heartbeat::FIXED_SUBJECT_ID,
                },
                source: Some(self.config.node_id),
                transfer_id: self.heartbeat_tid,
            };
            self.heartbeat_tid = (self.heartbeat_tid + 1) % 32;
            if self
                .enqueue(&header, &buf, now, now + SERVICE_DEADLINE)
                .is_ok()
            {
                self.stats.heartbeats += 1;
            }
            // Keep the 1 Hz grid; after a long pause, resume from now.
            self.next_heartbeat = self.next_heartbeat + Duration::from_secs(1);
            if self.next_heartbeat <= now {
                self.next_heartbeat = now + Duration::from_secs(1);
            }
        }
        self.poll_port_list(now);
        while let Some((mut frame, deadline)) = self.queue.pop_front() {
            if now > deadline {
                self.stats.tx_expired += 1;
                continue;
            }
            frame.timestamp = now;
            return Some(frame);
        }
        None
    }

    /// When to call [`Node::poll_transmit`] next: now if frames are waiting, else at the next
    /// heartbeat.
    pub fn poll_timeout(&self) -> Option<Instant> {
        if self.queue.is_empty() {
            let port_list = self.services.port_list_due();
            Some(port_list.map_or(self.next_heartbeat, |t| t.min(self.next_heartbeat)))
        } else {
            Some(self.now)
        }
    }
}
