//! The node's registers, its port list and its command service, in fixed memory.
//!
//! ```text
//!  uavcan.register.List request ──► Registry::list(index) ──► name (empty past the end)
//!  uavcan.register.Access request ─► Registry::access(req) ─► write (if mutable, converted as
//!                                                              PyCyphal converts) then read
//!                                                         └─► Node::take_register_change()
//!  uavcan.node.ExecuteCommand ─────► supported? SUCCESS + Node::take_command() : BAD_COMMAND
//!  every 10 s ─────────────────────► uavcan.node.port.List (publishers, subscribers, clients,
//!                                    servers, as the node's own tables say)
//! ```
//!
//! A [`Registry`] holds up to `N` registers: name, [`Value`], mutable and persistent flags
//! (about 530 bytes each: a name of up to 255 bytes and a value of up to 258). It answers
//! `List` by index and `Access` exactly as PyCyphal's register server does (checked against the
//! golden `assign` vectors from PyCyphal 1.27.1):
//!
//! - an empty value only reads; a nonexistent register reads as empty with both flags clear;
//! - a read-only register ignores writes and returns its unchanged value;
//! - a write keeps the register's type and dimension ([`convert`]): text to text (string ↔
//!   unstructured), numbers to numbers (the written array cut or zero-padded to the register's
//!   length; to `bit` as `x != 0`; to reals by IEEE cast, overflowing to ±∞; to integers by
//!   rounding half to even, refused when out of range, NaN or ∞; a `bit` source cannot be
//!   written into an integer register); text ↔ numbers is refused. A refused write leaves the
//!   register unchanged and its value is returned. (Where PyCyphal's conversion raises an
//!   exception, its server sends no answer at all; propid answers with the unchanged value, as
//!   the specification prescribes.)
//! - a register given limits ([`Registry::set_limits`]) also refuses a write that would put an
//!   element outside them (propid's own rule; PyCyphal's registry has none).
//!
//! Nothing here stores anything: persistence is the owner's business. The node reports each
//! accepted write through [`Node::take_register_change`] and each accepted command through
//! [`Node::take_command`]; the owner saves, restarts or resets and the node never does I/O.

use core::time::Duration;

use super::{Node, NodeError, SERVICE_DEADLINE};
use crate::can::{Port, Priority, Subscription, TransferHeader, TransferKind};
use crate::can::{ServiceId, SubjectId};
use crate::dsdl::{
    AccessRequest, AccessResponse, BitArray, DataType, ExecuteCommandRequest,
    ExecuteCommandResponse, ListRequest, ListResponse, Name, PortList, ServiceIdList,
    SubjectIdList, Value, ACCESS_SERVICE_ID, EXECUTE_COMMAND_SERVICE_ID, GET_INFO_SERVICE_ID,
    LIST_SERVICE_ID,
};
use crate::time::Instant;

/// One register.
#[derive(Clone, Debug, PartialEq)]
pub struct Register {
    /// Its name.
    pub name: Name,
    /// Its value (never [`Value::Empty`]).
    pub value: Value,
    /// Writable over the bus.
    pub mutable: bool,
    /// Kept across restarts (by the owner).
    pub persistent: bool,
}

/// Why a register could not be added or set.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum RegisterError {
    /// All `N` slots are taken.
    Full,
    /// Empty, or longer than 255 bytes.
    InvalidName,
    /// A register of that name exists.
    Duplicate,
    /// Registers cannot hold the empty value.
    EmptyValue,
    /// No register of that name.
    NotFound,
    /// The value cannot be converted to the register's type.
    TypeMismatch,
    /// The node could not subscribe to the register services (no free port slot).
    NoPortSlot,
}

impl core::fmt::Display for RegisterError {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        f.write_str(match self {
            RegisterError::Full => "no free register slot",
            RegisterError::InvalidName => "register names are 1 to 255 bytes",
            RegisterError::Duplicate => "a register of that name exists",
            RegisterError::EmptyValue => "a register cannot hold the empty value",
            RegisterError::NotFound => "no such register",
            RegisterError::TypeMismatch => "the value cannot be converted to the register's type",
            RegisterError::NoPortSlot => "no free port slot for the register services",
        })
    }
}

/// Up to `N` registers, in the order they were added (the `List` index).
#[derive(Clone, Debug)]
pub struct Registry<const N: usize> {
    registers: heapless::Vec<Register, N>,
    written: [bool; N],
    /// Per register: the closed range every element of a written numeric value must lie in.
    limits: [Option<(f64, f64)>; N],
}

impl<const N: usize> Default for Registry<N> {
    fn default() -> Self {
        Registry::new()
    }
}

impl<const N: usize> Registry<N> {
    /// No registers.
    pub fn new() -> Self {
        Registry {
            registers: heapless::Vec::new(),
            written: [false; N],
            limits: [None; N],
        }
    }

    /// Adds a register; returns its index.
    pub fn add(
        &mut self,
        name: &str,
        value: Value,
        mutable: bool,
        persistent: bool,
    ) -> Result<usize, RegisterError> {
        let name = Name::new(name)
            .filter(|n| !n.is_empty())
            .ok_or(RegisterError::InvalidName)?;
        if value.is_empty() {
            return Err(RegisterError::EmptyValue);
        }
        if self.registers.iter().any(|r| r.name == name) {
            return Err(RegisterError::Duplicate);
        }
        self.registers
            .push(Register {
                name,
                value,
                mutable,
                persistent,
            })
            .map_err(|_| RegisterError::Full)?;
        Ok(self.registers.len() - 1)
    }

    /// Number of registers.
    pub fn len(&self) -> usize {
        self.registers.len()
    }

    /// True if there are none.
    pub fn is_empty(&self) -> bool {
        self.registers.is_empty()
    }

    /// The registers in `List` order.
    pub fn iter(&self) -> impl Iterator<Item = &Register> {
        self.registers.iter()
    }

    /// The register at `index`.
    pub fn by_index(&self, index: usize) -> Option<&Register> {
        self.registers.get(index)
    }

    /// The index of the register named `name`.
    pub fn index_of(&self, name: &str) -> Option<usize> {
        self.registers
            .iter()
            .position(|r| r.name.name == name.as_bytes())
    }

    /// The register named `name`.
    pub fn get(&self, name: &str) -> Option<&Register> {
        self.index_of(name).map(|i| &self.registers[i])
    }

    /// Sets a register from the application side (mutability does not apply; the type is kept
    /// by [`convert`]). Not reported as a change.
    pub fn set(&mut self, name: &str, value: &Value) -> Result<(), RegisterError> {
        let i = self.index_of(name).ok_or(RegisterError::NotFound)?;
        let r = &mut self.registers[i];
        r.value = convert(&r.value, value).ok_or(RegisterError::TypeMismatch)?;
        Ok(())
    }

    /// Sets a register from text (an environment variable, a flag, a line of a register file),
    /// as [`parse_value`] reads it.
    pub fn set_text(&mut self, name: &str, text: &str) -> Result<(), RegisterError> {
        let i = self.index_of(name).ok_or(RegisterError::NotFound)?;
        let r = &mut self.registers[i];
        r.value = parse_value(&r.value, text).ok_or(RegisterError::TypeMismatch)?;
        Ok(())
    }

    /// Refuses writes over the bus (`Access`) that would put an element of register `name`
    /// outside `min..=max` (or make it NaN): the register keeps its value and the answer carries
    /// it, as for any refused write. The owner's own [`Registry::set`] is not limited. For
    /// registers whose owner can only use some values (an interval that must be positive).
    pub fn set_limits(&mut self, name: &str, min: f64, max: f64) -> Result<(), RegisterError> {
        let i = self.index_of(name).ok_or(RegisterError::NotFound)?;
        self.limits[i] = Some((min, max));
        Ok(())
    }

    /// `uavcan.register.List`: the name at `index`, empty past the end.
    pub fn list(&self, request: &ListRequest) -> ListResponse {
        ListResponse {
            name: self
                .registers
                .get(usize::from(request.index))
                .map(|r| r.name.clone())
                .unwrap_or_default(),
        }
    }

    /// `uavcan.register.Access`: write (if the value is not empty and the register mutable and
    /// the value converts), then read. An accepted write is remembered for
    /// [`Registry::take_written`]. The timestamp is 0 (unknown), as PyCyphal sends.
    pub fn access(&mut self, request: &AccessRequest) -> AccessResponse {
        let Some(i) = self.registers.iter().position(|r| r.name == request.name) else {
            return AccessResponse::default();
        };
        let limits = self.limits[i];
        let r = &mut self.registers[i];
        if r.mutable && !request.value.is_empty() {
            if let Some(v) = convert(&r.value, &request.value) {
                let within = |(min, max): (f64, f64)| {
                    (0..v.len()).all(|k| v.float_at(k).is_none_or(|x| x >= min && x <= max))
                };
                if limits.is_none_or(within) {
                    r.value = v;
                    self.written[i] = true;
                }
            }
        }
        AccessResponse {
            timestamp_us: 0,
            mutable: r.mutable,
            persistent: r.persistent,
            value: r.value.clone(),
        }
    }

    /// The index of a register written over the bus since the last call (lowest first).
    pub fn take_written(&mut self) -> Option<usize> {
        let i = self.written.iter().position(|w| *w)?;
        self.written[i] = false;
        Some(i)
    }
}

/// One array element, widened without loss.
#[derive(Clone, Copy)]
enum Elem {
    Bool(bool),
    Int(i128),
    Float(f64),
}

/// Element `i` of a numeric value; past its end, a zero of its kind (numpy's `resize` pads so).
fn elem(v: &Value, i: usize) -> Elem {
    fn at<T: Copy + Default>(s: &[T], i: usize) -> T {
        s.get(i).copied().unwrap_or_default()
    }
    match v {
        Value::Bit(b) => Elem::Bool(b.get(i)),
        Value::Integer64(s) => Elem::Int(at(s, i).into()),
        Value::Integer32(s) => Elem::Int(at(s, i).into()),
        Value::Integer16(s) => Elem::Int(at(s, i).into()),
        Value::Integer8(s) => Elem::Int(at(s, i).into()),
        Value::Natural64(s) => Elem::Int(at(s, i).into()),
        Value::Natural32(s) => Elem::Int(at(s, i).into()),
        Value::Natural16(s) => Elem::Int(at(s, i).into()),
        Value::Natural8(s) | Value::String(s) | Value::Unstructured(s) => {
            Elem::Int(at(s, i).into())
        }
        Value::Real64(s) => Elem::Float(at(s, i)),
        Value::Real32(s) => Elem::Float(at(s, i).into()),
        Value::Real16(s) => Elem::Float(s.get(i).map_or(0.0, |x| x.to_f64())),
        Value::Empty => Elem::Int(0),
    }
}

fn to_f64(e: Elem) -> f64 {
    match e {
        Elem::Bool(b) => f64::from(u8::from(b)),
        Elem::Int(x) => x as f64,
        Elem::Float(x) => x,
    }
}

fn to_f32(e: Elem) -> f32 {
    match e {
        Elem::Bool(b) => f32::from(u8::from(b)),
        // One rounding, as numpy's integer → float32 cast.
        Elem::Int(x) => x as f32,
        Elem::Float(x) => x as f32,
    }
}

/// Python's `round()` (half to even) into `[min, max]`; `None` for bits, NaN, ∞ or out of range.
fn to_int(e: Elem, min: i128, max: i128) -> Option<i128> {
    let x = match e {
        Elem::Bool(_) => return None,
        Elem::Int(x) => x,
        Elem::Float(x) => {
            let r = libm::rint(x); // half to even, as Python's round()
            if !r.is_finite() || r.abs() > 1e30 {
                return None;
            }
            r as i128
        }
    };
    (min..=max).contains(&x).then_some(x)
}

/// Converts `from` to the type and dimension of `to`, as PyCyphal's `ValueProxy.assign` does
/// (see the module documentation); `None` where PyCyphal refuses or raises.
pub fn convert(to: &Value, from: &Value) -> Option<Value> {
    if to.is_empty() || from.is_empty() {
        return Some(to.clone());
    }
    match (to, from) {
        (Value::String(_), Value::String(s) | Value::Unstructured(s)) => {
            return Some(Value::String(s.clone()))
        }
        (Value::Unstructured(_), Value::String(s) | Value::Unstructured(s)) => {
            return Some(Value::Unstructured(s.clone()))
        }
        _ if !to.is_numeric() || !from.is_numeric() => return None,
        _ => {}
    }
    let n = to.len();
    macro_rules! ints {
        ($variant:ident, $t:ty) => {{
            let mut out = heapless::Vec::new();
            for i in 0..n {
                let x = to_int(elem(from, i), <$t>::MIN.into(), <$t>::MAX.into())?;
                // Cannot fail: n is the register's own length; x is in range.
                let _ = out.push(x as $t);
            }
            Value::$variant(out)
        }};
    }
    Some(match to {
        Value::Bit(_) => {
            let mut out = BitArray::new();
            for i in 0..n {
                let nonzero = match elem(from, i) {
                    Elem::Bool(b) => b,
                    Elem::Int(x) => x != 0,
                    Elem::Float(x) => x != 0.0,
                };
                let _ = out.push(nonzero);
            }
            Value::Bit(out)
        }
        Value::Real64(_) => Value::Real64((0..n).map(|i| to_f64(elem(from, i))).collect()),
        Value::Real32(_) => Value::Real32((0..n).map(|i| to_f32(elem(from, i))).collect()),
        Value::Real16(_) => Value::Real16(
            (0..n)
                .map(|i| half::f16::from_f64(to_f64(elem(from, i))))
                .collect(),
        ),
        Value::Integer64(_) => ints!(Integer64, i64),
        Value::Integer32(_) => ints!(Integer32, i32),
        Value::Integer16(_) => ints!(Integer16, i16),
        Value::Integer8(_) => ints!(Integer8, i8),
        Value::Natural64(_) => ints!(Natural64, u64),
        Value::Natural32(_) => ints!(Natural32, u32),
        Value::Natural16(_) => ints!(Natural16, u16),
        Value::Natural8(_) => ints!(Natural8, u8),
        Value::Empty | Value::String(_) | Value::Unstructured(_) => return None,
    })
}

/// The value of a register given as text, the way the specification maps registers to
/// environment variables and PyCyphal's `ValueProxy.assign_environment_variable` reads them:
/// text into a string or unstructured register as is; into a numeric register as
/// space-separated decimals (all integers: an `integer64` array, else a `real64` one, at most 32),
/// then [`convert`]ed to the register's type. No tokens leave the value unchanged. `None` where
/// PyCyphal raises (a token that is not a number, a value out of range).
pub fn parse_value(template: &Value, text: &str) -> Option<Value> {
    if !template.is_numeric() {
        let bytes = heapless::Vec::from_slice(text.as_bytes()).ok()?;
        return convert(template, &Value::String(bytes));
    }
    let mut ints: heapless::Vec<i64, 32> = heapless::Vec::new();
    let mut floats: heapless::Vec<f64, 32> = heapless::Vec::new();
    let mut all_ints = true;
    for token in text.split_whitespace() {
        let (i, f) = match token.parse::<i64>() {
            Ok(i) => (i, i as f64),
            Err(_) => {
                all_ints = false;
                (0, token.parse::<f64>().ok()?)
            }
        };
        ints.push(i).ok()?;
        floats.push(f).ok()?;
    }
    let source = if ints.is_empty() {
        Value::Empty
    } else if all_ints {
        Value::Integer64(ints)
    } else {
        Value::Real64(floats)
    };
    convert(template, &source)
}

/// A command accepted over `uavcan.node.ExecuteCommand`, for the owner to carry out.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct Command {
    /// `ExecuteCommandRequest::COMMAND_*` or a vendor command.
    pub command: u16,
    /// Its parameter.
    pub parameter: heapless::Vec<u8, 255>,
    /// The node that asked.
    pub client: u8,
}

/// How many accepted commands wait for [`Node::take_command`]; more are answered `BAD_STATE`.
const PENDING_COMMANDS: usize = 4;

/// The node's register, command and port-list state.
pub(super) struct Services<const N: usize> {
    pub(super) registry: Registry<N>,
    serving_registers: bool,
    commands: heapless::Vec<u16, 8>,
    pending: heapless::Deque<Command, PENDING_COMMANDS>,
    port_list_next: Option<Instant>,
    port_list_tid: u8,
    pub(super) port_lists: u64,
}

impl<const N: usize> Services<N> {
    pub(super) fn new() -> Self {
        Services {
            registry: Registry::new(),
            serving_registers: false,
            commands: heapless::Vec::new(),
            pending: heapless::Deque::new(),
            port_list_next: None,
            port_list_tid: 0,
            port_lists: 0,
        }
    }

    pub(super) fn port_list_due(&self) -> Option<Instant> {
        self.port_list_next
    }
}

/// The largest request the node serves itself (`Access`: a 255-byte name and a 258-byte value).
pub(super) const SERVED_REQUEST_MAX: usize = AccessRequest::MAX_SIZE_BYTES;

/// The services the node answers itself.
pub(super) fn is_served(service_id: ServiceId) -> bool {
    matches!(
        service_id.get(),
        GET_INFO_SERVICE_ID | ACCESS_SERVICE_ID | LIST_SERVICE_ID | EXECUTE_COMMAND_SERVICE_ID
    )
}

impl<
        const PORTS: usize,
        const SESSIONS: usize,
        const EXTENT: usize,
        const QUEUE: usize,
        const REGISTERS: usize,
    > Node<PORTS, SESSIONS, EXTENT, QUEUE, REGISTERS>
{
    fn subscribe_request(&mut self, service_id: u16, extent: usize) -> Result<(), NodeError> {
        self.rx
            .subscribe(Subscription {
                port: Port::Request(ServiceId::from_const(service_id)),
                extent,
                transfer_id_timeout: crate::can::DEFAULT_TRANSFER_ID_TIMEOUT,
            })
            .map_err(|_| NodeError::TooManyPorts)
    }

    /// Adds a register and, with the first one, starts serving `uavcan.register.List` and
    /// `uavcan.register.Access` (two port slots). A node whose `EXTENT` is under 515 bytes
    /// still serves them, but refuses writes whose request was cut by its buffer.
    pub fn add_register(
        &mut self,
        name: &str,
        value: Value,
        mutable: bool,
        persistent: bool,
    ) -> Result<usize, RegisterError> {
        if !self.services.serving_registers {
            self.subscribe_request(LIST_SERVICE_ID, ListRequest::EXTENT_BYTES)
                .and_then(|_| self.subscribe_request(ACCESS_SERVICE_ID, SERVED_REQUEST_MAX))
                .map_err(|_| RegisterError::NoPortSlot)?;
            self.services.serving_registers = true;
        }
        self.services.registry.add(name, value, mutable, persistent)
    }

    /// Adds the standard registers the specification recommends for every node:
    /// `uavcan.node.id` (`natural16[1]`, this node's ID) and `uavcan.node.description`
    /// (`string`, empty), both mutable and persistent. The node keeps its ID until the owner
    /// restarts it with the new one.
    pub fn add_standard_registers(&mut self) -> Result<(), RegisterError> {
        let id = Value::natural16(&[u16::from(self.config.node_id.get())]).unwrap_or_default();
        self.add_register("uavcan.node.id", id, true, true)?;
        self.add_register(
            "uavcan.node.description",
            Value::String(heapless::Vec::new()),
            true,
            true,
        )?;
        Ok(())
    }

    /// The registers.
    pub fn registers(&self) -> &Registry<REGISTERS> {
        &self.services.registry
    }

    /// The registers, for the owner to set values ([`Registry::set`]).
    pub fn registers_mut(&mut self) -> &mut Registry<REGISTERS> {
        &mut self.services.registry
    }

    /// The index of a register written over the bus since the last call, if any: the owner
    /// reads its new value with [`Node::registers`] and applies (and, if persistent, stores) it.
    #[must_use]
    pub fn take_register_change(&mut self) -> Option<usize> {
        self.services.registry.take_written()
    }

    /// Answers `uavcan.node.ExecuteCommand` (one port slot): the commands in `supported` get
    /// `STATUS_SUCCESS` and are handed to the owner through [`Node::take_command`]; any other
    /// gets `STATUS_BAD_COMMAND`. At most 8 commands.
    pub fn serve_commands(&mut self, supported: &[u16]) -> Result<(), NodeError> {
        self.subscribe_request(
            EXECUTE_COMMAND_SERVICE_ID,
            ExecuteCommandRequest::EXTENT_BYTES,
        )?;
        self.services.commands =
            heapless::Vec::from_slice(&supported[..supported.len().min(8)]).unwrap_or_default();
        Ok(())
    }

    /// A command accepted over the bus, oldest first.
    #[must_use]
    pub fn take_command(&mut self) -> Option<Command> {
        self.services.pending.pop_front()
    }

    /// Publishes `uavcan.node.port.List.1.0` now and then every 10 s (the specification's
    /// `MAX_PUBLICATION_PERIOD`), at priority OPTIONAL. Its sparse form takes 146 bytes plus 2
    /// per subject-ID: 22 or more Classic CAN frames, which must fit the `QUEUE`.
    pub fn enable_port_list(&mut self, now: Instant) {
        self.services.port_list_next = Some(now);
    }

    /// The ports this node uses: subjects it published or subscribes to (Heartbeat and, when
    /// enabled, port.List included), services it called, services it answers.
    pub fn port_list(&self) -> PortList {
        let mut publishers: heapless::Vec<u16, 255> = heapless::Vec::new();
        let mut subscribers: heapless::Vec<u16, 255> = heapless::Vec::new();
        let mut clients = ServiceIdList::default();
        let mut servers = ServiceIdList::default();
        let _ = publishers.push(crate::dsdl::Heartbeat::FIXED_SUBJECT_ID);
        if self.services.port_list_next.is_some() {
            let _ = publishers.push(PortList::FIXED_SUBJECT_ID);
        }
        for &(service, port) in self.transfer_ids.keys() {
            if service {
                clients.insert(port);
            } else if !publishers.contains(&port) {
                let _ = publishers.push(port);
            }
        }
        for s in self.rx.subscriptions() {
            match s.port {
                Port::Subject(id) => {
                    let _ = subscribers.push(id.get());
                }
                Port::Request(id) => servers.insert(id.get()),
                Port::Response(id) => clients.insert(id.get()),
            }
        }
        publishers.sort_unstable();
        subscribers.sort_unstable();
        PortList {
            publishers: SubjectIdList::SparseList(publishers),
            subscribers: SubjectIdList::SparseList(subscribers),
            clients,
            servers,
        }
    }

    /// Publishes port.List when it is due (called from `poll_transmit`).
    pub(super) fn poll_port_list(&mut self, now: Instant) {
        let Some(due) = self.services.port_list_next else {
            return;
        };
        if now < due {
            return;
        }
        let list = self.port_list();
        let mut buf = [0u8; PortList::MAX_SIZE_BYTES];
        let n = list.serialize(&mut buf);
        let header = TransferHeader {
            priority: Priority::OPTIONAL,
            kind: TransferKind::Message {
                subject_id: SubjectId::from_const(PortList::FIXED_SUBJECT_ID),
            },
            source: Some(self.config.node_id),
            transfer_id: self.services.port_list_tid,
        };
        self.services.port_list_tid = (self.services.port_list_tid + 1) % 32;
        if self
            .enqueue(&header, &buf[..n], now, now + SERVICE_DEADLINE)
            .is_ok()
        {
            self.services.port_lists += 1;
        }
        let period = Duration::from_secs(PortList::MAX_PUBLICATION_PERIOD_S);
        let mut next = due + period;
        if next <= now {
            next = now + period;
        }
        self.services.port_list_next = Some(next);
    }

    fn respond(&mut self, now: Instant, request: &TransferHeader, service_id: u16, payload: &[u8]) {
        let Some(client) = request.source else {
            return;
        };
        let header = TransferHeader {
            priority: request.priority,
            kind: TransferKind::Response {
                service_id: ServiceId::from_const(service_id),
                destination: client,
            },
            source: Some(self.config.node_id),
            transfer_id: request.transfer_id,
        };
        let _ = self.enqueue(&header, payload, now, now + SERVICE_DEADLINE);
    }

    /// Answers a request to a service the node serves itself (see [`is_served`]).
    pub(super) fn serve(&mut self, now: Instant, header: &TransferHeader, payload: &[u8]) {
        let TransferKind::Request { service_id, .. } = header.kind else {
            return;
        };
        let Some(client) = header.source else {
            return;
        };
        let service_id = service_id.get();
        match service_id {
            GET_INFO_SERVICE_ID => {
                self.answer_get_info(now, client, header.transfer_id, header.priority)
            }
            LIST_SERVICE_ID => {
                let Ok(request) = ListRequest::deserialize(payload) else {
                    return;
                };
                let response = self.services.registry.list(&request);
                let mut buf = [0u8; ListResponse::MAX_SIZE_BYTES];
                let n = response.serialize(&mut buf);
                self.respond(now, header, service_id, &buf[..n]);
            }
            ACCESS_SERVICE_ID => {
                let Ok(mut request) = AccessRequest::deserialize(payload) else {
                    return;
                };
                // A request cut by this node's receive buffer would write zero-extended
                // garbage: read only.
                let mut whole = [0u8; AccessRequest::MAX_SIZE_BYTES];
                if payload.len() >= EXTENT.min(SERVED_REQUEST_MAX)
                    && request.serialize(&mut whole) > payload.len()
                {
                    request.value = Value::Empty;
                }
                let response = self.services.registry.access(&request);
                let mut buf = [0u8; AccessResponse::MAX_SIZE_BYTES];
                let n = response.serialize(&mut buf);
                self.respond(now, header, service_id, &buf[..n]);
            }
            EXECUTE_COMMAND_SERVICE_ID => {
                let Ok(request) = ExecuteCommandRequest::deserialize(payload) else {
                    return;
                };
                let status = if !self.services.commands.contains(&request.command) {
                    ExecuteCommandResponse::STATUS_BAD_COMMAND
                } else if self
                    .services
                    .pending
                    .push_back(Command {
                        command: request.command,
                        parameter: request.parameter,
                        client: client.get(),
                    })
                    .is_err()
                {
                    ExecuteCommandResponse::STATUS_BAD_STATE
                } else {
                    ExecuteCommandResponse::STATUS_SUCCESS
                };
                let mut buf = [0u8; ExecuteCommandResponse::MAX_SIZE_BYTES];
                let n = ExecuteCommandResponse::status(status).serialize(&mut buf);
                self.respond(now, header, service_id, &buf[..n]);
            }
            _ => {}
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn writes_keep_the_type() {
        let u16v = Value::natural16(&[42]).unwrap();
        let w = Value::real64(&[2.5]).unwrap();
        assert_eq!(convert(&u16v, &w), Value::natural16(&[2]));
        assert_eq!(convert(&u16v, &Value::real64(&[-1.0]).unwrap()), None);
        assert_eq!(convert(&u16v, &Value::string("7").unwrap()), None);
        assert_eq!(
            convert(&u16v, &Value::natural16(&[1, 2]).unwrap()),
            Value::natural16(&[1])
        );
        let mut r: Registry<2> = Registry::new();
        r.add("a.b", u16v.clone(), false, true).unwrap();
        assert_eq!(
            r.add("a.b", u16v.clone(), true, true),
            Err(RegisterError::Duplicate)
        );
        let resp = r.access(&AccessRequest {
            name: Name::new("a.b").unwrap(),
            value: Value::natural16(&[7]).unwrap(),
        });
        assert_eq!(resp.value, u16v);
        assert!(!resp.mutable && resp.persistent);
        assert_eq!(r.take_written(), None);
    }

    #[test]
    fn limited_registers_refuse_writes_out_of_range() {
        let mut r: Registry<1> = Registry::new();
        let v = Value::real32(&[0.005]).unwrap();
        r.add("mns.pub_interval_min", v.clone(), true, true)
            .unwrap();
        r.set_limits("mns.pub_interval_min", 1e-4, 1.0).unwrap();
        let write = |r: &mut Registry<1>, x: f64| {
            r.access(&AccessRequest {
                name: Name::new("mns.pub_interval_min").unwrap(),
                value: Value::real64(&[x]).unwrap(),
            })
            .value
        };
        for bad in [0.0, -1.0, 2.0, f64::NAN] {
            assert_eq!(write(&mut r, bad), v, "{bad}");
        }
        assert_eq!(r.take_written(), None);
        assert_eq!(write(&mut r, 0.02), Value::real32(&[0.02]).unwrap());
        assert_eq!(r.take_written(), Some(0));
    }
}
