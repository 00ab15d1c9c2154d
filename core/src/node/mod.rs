//! A Sans-IO Cyphal node: time and frames in, frames out, in fixed memory.
//!
//! ```text
//!  handle_frame(now, frame) ──► Reassembler ──► GetInfo request? → response queued
//!                                           └─► Event::Message / Event::Response to the caller
//!  publish(now, subject, payload) / request(now, service, server, payload)
//!        ──► FrameSplitter ──► TxQueue (priority, deadlines, supersede) ──► poll_transmit(now) → Frame
//!  poll_timeout() → when to come back: now while frames wait, else the next heartbeat
//! ```
//! The node publishes `uavcan.node.Heartbeat.1.0` once a second (uptime, health, mode) and
//! answers `uavcan.node.GetInfo.1.0` requests addressed to it with its name and version. Every
//! other port is the caller's: subjects and services are given at run time. Capacities are const
//! parameters: `PORTS` subscriptions, `SESSIONS` receive sessions, `EXTENT` bytes per received
//! transfer, `QUEUE` frames waiting to be sent. Nothing here reads a clock or touches a device, so
//! two nodes can be driven through a simulated link with a virtual clock (see `tests/node_link.rs`).
//!
//! Frames leave through a [`TxQueue`]: in Cyphal priority order, each before its deadline or
//! never, a newer message superseding an unsent one on the same subject, a full queue refusing
//! (counted) rather than blocking. [`Node::purge_transmit`] empties it, so a stop sequence can put
//! its last commands first in line.
//!
//! Opt-in, in `registry.rs`: `REGISTERS` registers served over `uavcan.register.List`/`Access`
//! ([`Node::add_register`]; writes reported by [`Node::take_register_change`]),
//! `uavcan.node.ExecuteCommand` ([`Node::serve_commands`], [`Node::take_command`]) and
//! `uavcan.node.port.List` every 10 s ([`Node::enable_port_list`]). To accept every Access request
//! whole, `EXTENT` must be ≥ 515 bytes (see `tests/register_server.rs`).

use core::time::Duration;

mod registry;
mod status;
mod tx_queue;

pub use registry::{convert, parse_value, Command, Register, RegisterError, Registry};
pub use status::{Health, Mode};
pub use tx_queue::{TxQueue, TxStats};

use crate::can::{
    CanId, Frame, Mtu, NodeId, Port, Priority, Reassembler, RxStats, ServiceId, SubjectId,
    Subscription, TailByte, TransferHeader, TransferKind, TxError, DEFAULT_TRANSFER_ID_TIMEOUT,
};
use crate::dsdl::{DataType, GetInfoResponse, Heartbeat, Version};

/// `uavcan.node.Heartbeat.1.0`'s fixed subject.
const HEARTBEAT_SUBJECT: SubjectId = SubjectId::from_const(Heartbeat::FIXED_SUBJECT_ID);
/// `uavcan.node.GetInfo.1.0`'s fixed service.
const GET_INFO_SERVICE: ServiceId = ServiceId::from_const(crate::dsdl::GET_INFO_SERVICE_ID);
use crate::time::Instant;

/// Who the node is.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct NodeConfig {
    /// Node-ID.
    pub node_id: NodeId,
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
    pub fn new(node_id: NodeId, name: &str, mtu: Mtu) -> Self {
        let bytes = name.as_bytes();
        NodeConfig {
            node_id,
            name: heapless::Vec::from_slice(&bytes[..bytes.len().min(50)]).unwrap_or_default(),
            software_version: Version { major: 0, minor: 1 },
            unique_id: [node_id.get(); 16],
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
        subject_id: SubjectId,
        /// Publisher (`None`: anonymous).
        source: Option<NodeId>,
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
        service_id: ServiceId,
        /// Server node-ID.
        source: NodeId,
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
}

/// Counters.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct NodeStats {
    /// Receive-side counters.
    pub rx: RxStats,
    /// Transmit-side counters: sent, expired, superseded, displaced, refused, purged.
    pub tx: TxStats,
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
    health: Health,
    mode: Mode,
    vendor_status: u8,
    rx: Reassembler<PORTS, SESSIONS, EXTENT>,
    queue: TxQueue<QUEUE>,
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
            port: Port::Request(GET_INFO_SERVICE),
            extent: 0,
            transfer_id_timeout: DEFAULT_TRANSFER_ID_TIMEOUT,
        });
        Node {
            config,
            started: now,
            next_heartbeat: now,
            health: Health::Nominal,
            mode: Mode::Operational,
            vendor_status: 0,
            rx,
            queue: TxQueue::new(),
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

    /// Sets what the heartbeats report from the next one on (a node starts `Nominal`,
    /// `Operational`, vendor status 0).
    pub fn set_status(&mut self, health: Health, mode: Mode, vendor_status: u8) {
        self.health = health;
        self.mode = mode;
        self.vendor_status = vendor_status;
    }

    /// What the heartbeats report: health, mode, vendor status.
    pub fn status(&self) -> (Health, Mode, u8) {
        (self.health, self.mode, self.vendor_status)
    }

    /// Counters so far.
    pub fn stats(&self) -> NodeStats {
        NodeStats {
            rx: self.rx.stats(),
            tx: self.queue.stats(),
            ..self.stats
        }
    }

    /// Frames waiting to be sent.
    pub fn transmit_queue_len(&self) -> usize {
        self.queue.len()
    }

    /// True if no frame is waiting to be sent.
    pub fn is_transmit_queue_empty(&self) -> bool {
        self.queue.is_empty()
    }

    /// Frames of messages on `subject_id` waiting to be sent.
    pub fn pending_frames(&self, subject_id: SubjectId) -> usize {
        self.queue.pending_frames(subject_id)
    }

    /// Drops every frame waiting to be sent, the rest of a transfer in progress included
    /// (counted in [`TxStats::purged`]); returns how many. A stop sequence calls this, then
    /// publishes its last commands, which are then first in line.
    pub fn purge_transmit(&mut self) -> usize {
        self.queue.purge()
    }

    /// Receives messages on `subject_id`, keeping up to `extent` payload bytes.
    pub fn subscribe_message(
        &mut self,
        subject_id: SubjectId,
        extent: usize,
    ) -> Result<(), NodeError> {
        self.rx
            .subscribe(Subscription {
                port: Port::Subject(subject_id),
                extent,
                transfer_id_timeout: DEFAULT_TRANSFER_ID_TIMEOUT,
            })
            .map_err(|_| NodeError::TooManyPorts)
    }

    /// The transfer-ID counter of a port, made when it has none yet (refused when the table of
    /// counters is full).
    fn transfer_id_counter(&mut self, service: bool, port: u16) -> Result<&mut u8, TxError> {
        let key = (service, port);
        if !self.transfer_ids.contains_key(&key) {
            self.transfer_ids
                .insert(key, 0)
                .map_err(|_| TxError::TooManyPorts)?;
        }
        self.transfer_ids.get_mut(&key).ok_or(TxError::TooManyPorts)
    }

    fn next_transfer_id(&mut self, service: bool, port: u16) -> Result<u8, TxError> {
        Ok(take_transfer_id(self.transfer_id_counter(service, port)?))
    }

    /// The transfer-ID the next message on `subject_id` will leave with, making room for its
    /// counter if it has none yet. The ID is given for good only as the transfer's first frame
    /// leaves ([`TxQueue::pop_assigning`]): one that never leaves takes none.
    fn provisional_transfer_id(&mut self, subject_id: SubjectId) -> Result<u8, TxError> {
        self.transfer_id_counter(false, subject_id.get())
            .map(|t| *t)
    }

    fn enqueue(
        &mut self,
        header: &TransferHeader,
        payload: &[u8],
        now: Instant,
        deadline: Instant,
    ) -> Result<(), TxError> {
        self.now = self.now.max(now);
        self.queue
            .push(now, header, payload, self.config.mtu, deadline)
    }

    /// Publishes `payload` on `subject_id`; its frames are dropped if not sent within `timeout`.
    /// It supersedes a queued transfer on the same subject none of whose frames has left yet.
    /// A full queue refuses it with [`TxError::QueueFull`] (counted in [`TxStats::refused`]).
    /// Its transfer-ID is the subject's next as its first frame leaves, so the transfers a
    /// receiver sees are numbered without gaps whatever was superseded, expired or purged.
    pub fn publish(
        &mut self,
        now: Instant,
        subject_id: SubjectId,
        priority: Priority,
        payload: &[u8],
        timeout: Duration,
    ) -> Result<(), TxError> {
        let transfer_id = self.provisional_transfer_id(subject_id)?;
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
        subject_id: SubjectId,
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
        service_id: ServiceId,
        server: NodeId,
        payload: &[u8],
        response_extent: usize,
        timeout: Duration,
    ) -> Result<u8, TxError> {
        self.rx
            .subscribe(Subscription {
                port: Port::Response(service_id),
                extent: response_extent,
                transfer_id_timeout: DEFAULT_TRANSFER_ID_TIMEOUT,
            })
            .map_err(|_| TxError::TooManyPorts)?;
        let transfer_id = self.next_transfer_id(true, service_id.get())?;
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

    fn answer_get_info(
        &mut self,
        now: Instant,
        client: NodeId,
        transfer_id: u8,
        priority: Priority,
    ) {
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
                service_id: GET_INFO_SERVICE,
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

    /// The next frame to send, if any is due. Publishes the heartbeat when it is time. Frames
    /// leave in priority order; one whose deadline has passed is dropped (counted), never returned.
    #[must_use]
    pub fn poll_transmit(&mut self, now: Instant) -> Option<Frame> {
        self.now = self.now.max(now);
        if now >= self.next_heartbeat {
            let uptime = now.saturating_duration_since(self.started).as_secs();
            let hb = Heartbeat {
                uptime: u32::try_from(uptime).unwrap_or(u32::MAX),
                health: self.health as u8,
                mode: self.mode as u8,
                vendor_specific_status_code: self.vendor_status,
            };
            let mut buf = [0u8; 7];
            hb.serialize(&mut buf);
            let header = TransferHeader {
                priority: Priority::NOMINAL,
                kind: TransferKind::Message {
                    subject_id: HEARTBEAT_SUBJECT,
                },
                source: Some(self.config.node_id),
                transfer_id: self.heartbeat_tid,
            };
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
        let (counters, heartbeat_tid) = (&mut self.transfer_ids, &mut self.heartbeat_tid);
        self.queue.pop_assigning(now, &mut |subject| {
            // Every queued message's subject has a counter: `publish` made room for it.
            message_counter(counters, heartbeat_tid, subject).map_or(0, take_transfer_id)
        })
    }

    /// Takes back a frame [`Node::poll_transmit`] gave out that never reached the bus (the link
    /// refused it until it went stale). If it began a message transfer, the rest of that
    /// transfer is dropped (counted as expired) and its transfer-ID given back, so the next
    /// transfer on the subject takes it: the IDs a receiver sees stay without gaps however long
    /// the link refused. Any other frame is only forgotten.
    pub fn unsent(&mut self, frame: &Frame) {
        let Some(&tail) = frame.data().last() else {
            return;
        };
        let tail = TailByte::parse(tail);
        let Some(CanId {
            kind: TransferKind::Message { subject_id },
            ..
        }) = CanId::parse(frame.id())
        else {
            return;
        };
        if !tail.start {
            return;
        }
        if !tail.end {
            self.queue.drop_in_progress();
        }
        let counter = message_counter(&mut self.transfer_ids, &mut self.heartbeat_tid, subject_id);
        if let Some(t) = counter.filter(|t| **t == (tail.transfer_id + 1) % 32) {
            *t = tail.transfer_id;
        }
    }

    /// When to call [`Node::poll_transmit`] next: the latest time given if frames are waiting
    /// (one is ready, or an expired one is to be dropped), else the next heartbeat.
    #[must_use]
    pub fn poll_timeout(&self) -> Option<Instant> {
        if self.queue.is_empty() {
            let port_list = self.services.port_list_due();
            Some(port_list.map_or(self.next_heartbeat, |t| t.min(self.next_heartbeat)))
        } else {
            Some(self.now)
        }
    }
}

/// The counter a message on `subject` takes its transfer-ID from: the heartbeat's own, or the
/// subject's in `counters` (`None` when it has none).
fn message_counter<'a, const PORTS: usize>(
    counters: &'a mut heapless::LinearMap<(bool, u16), u8, PORTS>,
    heartbeat_tid: &'a mut u8,
    subject: SubjectId,
) -> Option<&'a mut u8> {
    if subject == HEARTBEAT_SUBJECT {
        Some(heartbeat_tid)
    } else {
        counters.get_mut(&(false, subject.get()))
    }
}

/// The counter's transfer-ID, which it then advances (modulo 32).
fn take_transfer_id(counter: &mut u8) -> u8 {
    let tid = *counter;
    *counter = (tid + 1) % 32;
    tid
}
