//! Finding drives on the bus and reading and writing their registers: what `propid telega` and
//! `propid drive --from-telega` use.
//!
//! ```text
//!  Client (a Machine, Sans-IO): a queue of Ops, one at a time, each ending in one ClientEvent
//!    Op::Listen(d)       heartbeats for d ─────────────────► Heard(node-IDs)
//!    Op::GetInfo(n)      uavcan.node.GetInfo ──────────────► Info
//!    Op::List(n)         uavcan.register.List 0, 1, … until an empty name ─► Names
//!    Op::Access(n, r, v) uavcan.register.Access (empty v: read) ─► Register (what the drive holds)
//!    Op::Execute(n, c)   uavcan.node.ExecuteCommand ───────► Executed(status)
//!  each request: one retry after CALL_TIMEOUT, then answered with None
//!  is_stopped() ⇔ idle (no op left): virtual_link and run_realtime run it until then
//!  the host runs the same Client on a CanTransport in real time, one op per call
//! ```
//! The client is a core `Node` (node-ID, heartbeats, GetInfo answered) like the drive itself: no
//! second protocol implementation. Register values are converted by the server (Access
//! semantics); what comes back is what the drive holds.

use std::collections::VecDeque;
use std::time::Duration;

use propid_core::can::{Frame, Mtu, NodeId, ServiceId, SubjectId};
use propid_core::dsdl::{
    AccessRequest, AccessResponse, DataType, ExecuteCommandRequest, ExecuteCommandResponse,
    GetInfoRequest, GetInfoResponse, Heartbeat, ListRequest, ListResponse, Name, Value,
    ACCESS_SERVICE_ID, EXECUTE_COMMAND_SERVICE_ID, GET_INFO_SERVICE_ID, LIST_SERVICE_ID,
};
use propid_core::node::{Event, NodeConfig};
use propid_core::time::Instant;

use crate::machine::{Machine, StopReason};
use crate::node::HostNode;
use crate::registers::{LOCAL_TIMESTAMP, PUB_INTERVAL_MIN, TELEGA_FEEDBACK_ID};

/// How long a request waits for its answer before its one retry.
pub const CALL_TIMEOUT: Duration = Duration::from_millis(1000);

/// The registers [`crate::registers::check_prerequisites`] looks at.
pub const CHECKED_REGISTERS: [&str; 3] = [PUB_INTERVAL_MIN, LOCAL_TIMESTAMP, TELEGA_FEEDBACK_ID];

/// A register as a drive reported it.
#[derive(Clone, Debug, PartialEq)]
pub struct RemoteRegister {
    /// Name.
    pub name: String,
    /// Value (empty: the drive has no such register).
    pub value: Value,
    /// Writable.
    pub mutable: bool,
    /// Kept across restarts.
    pub persistent: bool,
}

/// One thing for the [`Client`] to do.
// A handful are queued at a time; boxing the value would only add an allocation.
#[allow(clippy::large_enum_variant)]
#[derive(Clone, Debug, PartialEq)]
pub enum Op {
    /// Listen for heartbeats this long.
    Listen(Duration),
    /// Ask a node for its GetInfo.
    GetInfo(NodeId),
    /// List a node's register names.
    List(NodeId),
    /// Read (empty value) or write a register.
    Access(NodeId, String, Value),
    /// Send a command.
    Execute(NodeId, u16),
}

/// What one [`Op`] came to.
#[allow(clippy::large_enum_variant)]
#[derive(Clone, Debug, PartialEq)]
pub enum ClientEvent {
    /// The nodes heard so far (sorted), after [`Op::Listen`].
    Heard(Vec<NodeId>),
    /// GetInfo's answer (`None`: none).
    Info(NodeId, Option<GetInfoResponse>),
    /// The register names (`None`: no answer to the first List request).
    Names(NodeId, Option<Vec<String>>),
    /// The register after the access (`None`: no answer).
    Register(NodeId, Option<RemoteRegister>),
    /// The command's status (`None`: no answer).
    Executed(NodeId, u16, Option<u8>),
    /// The transport failed; the ops left were dropped.
    Failed(StopReason),
}

struct Pending {
    server: NodeId,
    service: ServiceId,
    transfer_id: u8,
    deadline: Instant,
    retried: bool,
    payload: Vec<u8>,
    extent: usize,
}

/// A Cyphal client node for configuring drives. See the module documentation.
pub struct Client {
    node: HostNode,
    ops: VecDeque<Op>,
    current: Option<Op>,
    pending: Option<Pending>,
    listen_until: Option<Instant>,
    names: Vec<String>,
    heard: Vec<NodeId>,
    last_now: Instant,
    events: VecDeque<ClientEvent>,
    held: Option<Frame>,
}

impl Client {
    /// A client node with `node_id` (MTU 8 or 64) starting now.
    pub fn new(node_id: NodeId, mtu: Mtu, now: Instant) -> Self {
        let mut node = HostNode::new(NodeConfig::new(node_id, "org.propid.telega", mtu), now);
        // A fresh node with 8 port slots: cannot fail.
        let _ = node.subscribe_message(
            SubjectId::from_const(Heartbeat::FIXED_SUBJECT_ID),
            Heartbeat::EXTENT_BYTES,
        );
        Client {
            node,
            ops: VecDeque::new(),
            current: None,
            pending: None,
            listen_until: None,
            names: Vec::new(),
            heard: Vec::new(),
            last_now: now,
            events: VecDeque::new(),
            held: None,
        }
    }

    /// Queues an op; it starts at the next call.
    pub fn push(&mut self, op: Op) {
        self.ops.push_back(op);
    }

    /// The nodes whose heartbeat was heard so far, sorted.
    pub fn heard(&self) -> Vec<NodeId> {
        let mut v = self.heard.clone();
        v.sort_unstable();
        v
    }

    fn send(
        &mut self,
        now: Instant,
        server: NodeId,
        service: u16,
        payload: Vec<u8>,
        extent: usize,
    ) {
        let service = ServiceId::from_const(service);
        match self
            .node
            .request(now, service, server, &payload, extent, CALL_TIMEOUT)
        {
            Ok(transfer_id) => {
                self.pending = Some(Pending {
                    server,
                    service,
                    transfer_id,
                    deadline: now + CALL_TIMEOUT,
                    retried: false,
                    payload,
                    extent,
                })
            }
            // The queue is full or the ports are taken: the op ends unanswered.
            Err(_) => self.answer(now, None),
        }
    }

    fn request<T: DataType>(
        &mut self,
        now: Instant,
        server: NodeId,
        service: u16,
        req: &T,
        extent: usize,
    ) {
        let mut buf = vec![0u8; T::MAX_SIZE_BYTES];
        let n = req.serialize(&mut buf);
        buf.truncate(n);
        self.send(now, server, service, buf, extent);
    }

    /// Starts the next op if none is under way.
    fn start(&mut self, now: Instant) {
        while self.current.is_none() {
            let Some(op) = self.ops.pop_front() else {
                return;
            };
            self.current = Some(op.clone());
            match op {
                Op::Listen(d) => self.listen_until = Some(now + d),
                Op::GetInfo(n) => self.request(
                    now,
                    n,
                    GET_INFO_SERVICE_ID,
                    &GetInfoRequest,
                    GetInfoResponse::EXTENT_BYTES,
                ),
                Op::List(n) => {
                    self.names.clear();
                    self.request(
                        now,
                        n,
                        LIST_SERVICE_ID,
                        &ListRequest { index: 0 },
                        ListResponse::EXTENT_BYTES,
                    )
                }
                Op::Access(n, name, value) => match Name::new(&name) {
                    Some(name) => self.request(
                        now,
                        n,
                        ACCESS_SERVICE_ID,
                        &AccessRequest { name, value },
                        AccessResponse::EXTENT_BYTES,
                    ),
                    None => self.answer(now, None),
                },
                Op::Execute(n, command) => self.request(
                    now,
                    n,
                    EXECUTE_COMMAND_SERVICE_ID,
                    &ExecuteCommandRequest {
                        command,
                        parameter: Default::default(),
                    },
                    ExecuteCommandResponse::EXTENT_BYTES,
                ),
            }
        }
    }

    /// The current op got its answer (`None`: none came).
    fn answer(&mut self, now: Instant, payload: Option<&[u8]>) {
        self.pending = None;
        let Some(op) = self.current.take() else {
            return;
        };
        let event = match op {
            Op::Listen(_) => ClientEvent::Heard(self.heard()),
            Op::GetInfo(n) => ClientEvent::Info(
                n,
                payload.and_then(|p| GetInfoResponse::deserialize(p).ok()),
            ),
            Op::List(n) => {
                let name = payload.and_then(|p| ListResponse::deserialize(p).ok());
                match name {
                    Some(r) if !r.name.is_empty() && self.names.len() < usize::from(u16::MAX) => {
                        self.names
                            .push(String::from_utf8_lossy(&r.name.name).into_owned());
                        let index = self.names.len() as u16;
                        self.current = Some(Op::List(n));
                        self.request(
                            now,
                            n,
                            LIST_SERVICE_ID,
                            &ListRequest { index },
                            ListResponse::EXTENT_BYTES,
                        );
                        return;
                    }
                    Some(_) => ClientEvent::Names(n, Some(std::mem::take(&mut self.names))),
                    // No answer: what was listed so far, if anything.
                    None if self.names.is_empty() => ClientEvent::Names(n, None),
                    None => ClientEvent::Names(n, Some(std::mem::take(&mut self.names))),
                }
            }
            Op::Access(n, name, _) => ClientEvent::Register(
                n,
                payload
                    .and_then(|p| AccessResponse::deserialize(p).ok())
                    .map(|r| RemoteRegister {
                        name,
                        value: r.value,
                        mutable: r.mutable,
                        persistent: r.persistent,
                    }),
            ),
            Op::Execute(n, c) => ClientEvent::Executed(
                n,
                c,
                payload
                    .and_then(|p| ExecuteCommandResponse::deserialize(p).ok())
                    .map(|r| r.status),
            ),
        };
        self.events.push_back(event);
    }

    fn advance(&mut self, now: Instant) {
        self.last_now = self.last_now.max(now);
        if self.listen_until.is_some_and(|t| now >= t) {
            self.listen_until = None;
            self.answer(now, None);
        }
        if let Some(p) = &self.pending {
            if now >= p.deadline {
                if p.retried {
                    self.answer(now, None);
                } else {
                    let (server, service, payload, extent) =
                        (p.server, p.service.get(), p.payload.clone(), p.extent);
                    self.send(now, server, service, payload, extent);
                    if let Some(p) = self.pending.as_mut() {
                        p.retried = true;
                    }
                }
            }
        }
        self.start(now);
    }

    /// Takes one received frame.
    pub fn handle_frame(&mut self, now: Instant, frame: &Frame) {
        self.advance(now);
        let mut answer = None;
        let mut heard = None;
        match self.node.handle_frame(now, frame) {
            Some(Event::Message {
                subject_id,
                source: Some(src),
                ..
            }) if subject_id.get() == Heartbeat::FIXED_SUBJECT_ID => heard = Some(src),
            Some(Event::Response {
                service_id,
                source,
                transfer_id,
                payload,
                ..
            }) => {
                if let Some(p) = &self.pending {
                    if p.service == service_id && p.server == source && p.transfer_id == transfer_id
                    {
                        answer = Some(payload.to_vec());
                    }
                }
            }
            _ => {}
        }
        if let Some(src) = heard {
            if !self.heard.contains(&src) {
                self.heard.push(src);
            }
        }
        if let Some(p) = answer {
            self.answer(now, Some(&p));
            self.start(now);
        }
    }

    /// The next frame to send, if one is due.
    #[must_use]
    pub fn poll_transmit(&mut self, now: Instant) -> Option<Frame> {
        self.advance(now);
        self.held.take().or_else(|| self.node.poll_transmit(now))
    }

    /// When to call again.
    #[must_use]
    pub fn poll_timeout(&self) -> Option<Instant> {
        let mut t = self.node.poll_timeout();
        let mut min = |x: Instant| t = Some(t.map_or(x, |t: Instant| t.min(x)));
        if self.held.is_some() {
            min(self.last_now + Duration::from_millis(1));
        }
        if let Some(l) = self.listen_until {
            min(l);
        }
        if let Some(p) = &self.pending {
            min(p.deadline);
        }
        if self.current.is_none() && !self.ops.is_empty() {
            min(self.last_now);
        }
        t
    }

    /// The next event.
    #[must_use]
    pub fn poll_event(&mut self) -> Option<ClientEvent> {
        self.events.pop_front()
    }

    /// True when no op is left and nothing waits to be sent.
    pub fn is_idle(&self) -> bool {
        self.current.is_none()
            && self.ops.is_empty()
            && self.held.is_none()
            && self.node.is_transmit_queue_empty()
    }
}

impl Machine for Client {
    type Event = ClientEvent;
    fn handle_frame(&mut self, now: Instant, frame: &Frame) {
        Client::handle_frame(self, now, frame)
    }
    fn poll_transmit(&mut self, now: Instant) -> Option<Frame> {
        Client::poll_transmit(self, now)
    }
    fn handle_blocked(&mut self, _now: Instant, frame: Frame) {
        self.held = Some(frame);
    }
    fn poll_timeout(&self) -> Option<Instant> {
        Client::poll_timeout(self)
    }
    fn poll_event(&mut self) -> Option<ClientEvent> {
        Client::poll_event(self)
    }
    fn handle_fault(&mut self, _now: Instant, reason: StopReason) {
        self.ops.clear();
        self.current = None;
        self.pending = None;
        self.listen_until = None;
        self.held = None;
        let _ = self.node.purge_transmit();
        self.events.push_back(ClientEvent::Failed(reason));
    }
    fn is_stopped(&self) -> bool {
        self.is_idle()
    }
}
