//! Finding drives on the bus and reading and writing their registers: what `propid telega` and
//! `drive`'s pre-flight check use.
//!
//! ```text
//!  listen (heartbeats, ~1 s) ─► node-IDs ─► GetInfo ─► name
//!  uavcan.register.List (index 0, 1, … until empty) ─► names
//!  uavcan.register.Access (empty value: read; a value: write, then read back) ─► values
//!  uavcan.node.ExecuteCommand (STORE_PERSISTENT_STATES) ─► status
//! ```
//! A [`Client`] is a [`HostNode`] of its own on the transport; each call sends one request and
//! waits (at most a timeout, one retry) for the answer, answering heartbeats and GetInfo itself
//! meanwhile. Register values are converted by the drive (Access semantics); what comes back is
//! what the drive holds.

use std::time::Duration;

use propid_core::can::Mtu;
use propid_core::dsdl::{
    AccessRequest, AccessResponse, DataType, ExecuteCommandRequest, ExecuteCommandResponse,
    GetInfoResponse, Heartbeat, ListRequest, ListResponse, Name, Value, ACCESS_SERVICE_ID,
    EXECUTE_COMMAND_SERVICE_ID, GET_INFO_SERVICE_ID, LIST_SERVICE_ID,
};
use propid_core::node::{Event, NodeConfig};
use propid_core::time::Instant;
use propid_transport::{CanTransport, HostClock};

use crate::HostNode;

/// How long a call waits for its answer before one retry.
pub const CALL_TIMEOUT: Duration = Duration::from_millis(1000);

/// A register as a drive reported it.
#[derive(Clone, Debug, PartialEq)]
pub struct RemoteRegister {
    /// Name.
    pub name: String,
    /// Value.
    pub value: Value,
    /// Writable.
    pub mutable: bool,
    /// Kept across restarts.
    pub persistent: bool,
}

/// A Cyphal client node for configuring drives.
pub struct Client<'a> {
    node: HostNode,
    transport: &'a mut dyn CanTransport,
    heard: Vec<u8>,
}

impl<'a> Client<'a> {
    /// A client with node-ID `node_id` on `transport` (MTU 8 or 64).
    pub fn new(transport: &'a mut dyn CanTransport, node_id: u8, mtu: usize) -> Self {
        let mtu = if mtu == 64 { Mtu::Fd } else { Mtu::Classic };
        let mut node = HostNode::new(
            NodeConfig::new(node_id, "org.propid.telega", mtu),
            HostClock::now(),
        );
        let _ = node.subscribe_message(Heartbeat::FIXED_SUBJECT_ID, Heartbeat::EXTENT_BYTES);
        Client {
            node,
            transport,
            heard: Vec::new(),
        }
    }

    /// Sends what is due and takes frames until `until`, or until `want` returns a value.
    fn pump<T>(
        &mut self,
        until: Instant,
        mut want: impl FnMut(&Event<'_>) -> Option<T>,
    ) -> Result<Option<T>, String> {
        loop {
            let now = HostClock::now();
            while let Some(f) = self.node.poll_transmit(now) {
                // Configuration traffic may wait for a congested link, briefly.
                let deadline = std::time::Instant::now() + Duration::from_millis(500);
                if !self
                    .transport
                    .send_by(&f, deadline)
                    .map_err(|e| e.to_string())?
                {
                    return Err("the bus did not take a frame within 0.5 s".into());
                }
            }
            if now >= until {
                return Ok(None);
            }
            let wait = until
                .saturating_duration_since(now)
                .min(Duration::from_millis(20));
            let Some(frame) = self.transport.receive(wait).map_err(|e| e.to_string())? else {
                continue;
            };
            let Some(event) = self.node.handle_frame(HostClock::now(), &frame) else {
                continue;
            };
            if let Event::Message {
                subject_id: Heartbeat::FIXED_SUBJECT_ID,
                source: Some(src),
                ..
            } = event
            {
                if !self.heard.contains(&src) {
                    self.heard.push(src);
                }
            }
            if let Some(v) = want(&event) {
                return Ok(Some(v));
            }
        }
    }

    /// Listens for heartbeats for `listen`; returns the node-IDs heard (sorted).
    pub fn discover(&mut self, listen: Duration) -> Result<Vec<u8>, String> {
        let until = HostClock::now() + listen;
        self.pump(until, |_| None::<()>)?;
        let mut ids = self.heard.clone();
        ids.sort_unstable();
        Ok(ids)
    }

    /// One request to `server`; the response payload, or `None` after a timeout and one retry.
    pub fn call<T: DataType>(
        &mut self,
        server: u8,
        service_id: u16,
        request: &T,
        response_extent: usize,
    ) -> Result<Option<Vec<u8>>, String> {
        let mut buf = vec![0u8; T::MAX_SIZE_BYTES];
        let n = request.serialize(&mut buf);
        for _ in 0..2 {
            let now = HostClock::now();
            let tid = self
                .node
                .request(
                    now,
                    service_id,
                    server,
                    &buf[..n],
                    response_extent,
                    CALL_TIMEOUT,
                )
                .map_err(|e| format!("cannot send the request: {e:?}"))?;
            let got = self.pump(now + CALL_TIMEOUT, |e| match e {
                Event::Response {
                    service_id: s,
                    source,
                    transfer_id,
                    payload,
                    ..
                } if *s == service_id && *source == server && *transfer_id == tid => {
                    Some(payload.to_vec())
                }
                _ => None,
            })?;
            if got.is_some() {
                return Ok(got);
            }
        }
        Ok(None)
    }

    /// `uavcan.node.GetInfo`.
    pub fn get_info(&mut self, server: u8) -> Result<Option<GetInfoResponse>, String> {
        let p = self.call(
            server,
            GET_INFO_SERVICE_ID,
            &propid_core::dsdl::GetInfoRequest,
            448,
        )?;
        Ok(p.and_then(|p| GetInfoResponse::deserialize(&p).ok()))
    }

    /// `uavcan.register.Access`: writes `value` (unless empty) and returns what the drive then
    /// holds (`None`: no answer; an empty value: no such register).
    pub fn access(
        &mut self,
        server: u8,
        name: &str,
        value: Value,
    ) -> Result<Option<AccessResponse>, String> {
        let name = Name::new(name).ok_or_else(|| format!("register name too long: {name}"))?;
        let p = self.call(
            server,
            ACCESS_SERVICE_ID,
            &AccessRequest { name, value },
            AccessResponse::EXTENT_BYTES,
        )?;
        Ok(p.and_then(|p| AccessResponse::deserialize(&p).ok()))
    }

    /// Every register name, by `uavcan.register.List` (`None`: the node does not answer List).
    pub fn list(&mut self, server: u8) -> Result<Option<Vec<String>>, String> {
        let mut names = Vec::new();
        for index in 0..=u16::MAX {
            let Some(p) = self.call(
                server,
                LIST_SERVICE_ID,
                &ListRequest { index },
                ListResponse::EXTENT_BYTES,
            )?
            else {
                return Ok((index > 0).then_some(names));
            };
            let Ok(r) = ListResponse::deserialize(&p) else {
                break;
            };
            if r.name.is_empty() {
                break;
            }
            names.push(String::from_utf8_lossy(&r.name.name).into_owned());
        }
        Ok(Some(names))
    }

    /// Every register with its value (List, then Access for each).
    pub fn read_all(&mut self, server: u8) -> Result<Option<Vec<RemoteRegister>>, String> {
        let Some(names) = self.list(server)? else {
            return Ok(None);
        };
        let mut out = Vec::new();
        for name in names {
            if let Some(r) = self.access(server, &name, Value::Empty)? {
                out.push(RemoteRegister {
                    name,
                    value: r.value,
                    mutable: r.mutable,
                    persistent: r.persistent,
                });
            }
        }
        Ok(Some(out))
    }

    /// `uavcan.node.ExecuteCommand`; the status (`None`: no answer).
    pub fn execute(&mut self, server: u8, command: u16) -> Result<Option<u8>, String> {
        let request = ExecuteCommandRequest {
            command,
            parameter: heapless::Vec::new(),
        };
        let p = self.call(
            server,
            EXECUTE_COMMAND_SERVICE_ID,
            &request,
            ExecuteCommandResponse::EXTENT_BYTES,
        )?;
        Ok(p.and_then(|p| ExecuteCommandResponse::deserialize(&p).ok())
            .map(|r| r.status))
    }

    /// Counts the messages on `subject_id` over `d` and returns them with their timestamps
    /// (µs, as the publisher stamped them: DoF3rdTs's first 7 bytes).
    pub fn sample_subject(&mut self, subject_id: u16, d: Duration) -> Result<Vec<u64>, String> {
        self.node
            .subscribe_message(subject_id, 64)
            .map_err(|e| format!("cannot subscribe: {e:?}"))?;
        let until = HostClock::now() + d;
        let mut stamps = Vec::new();
        self.pump(until, |e| {
            if let Event::Message {
                subject_id: s,
                payload,
                ..
            } = e
            {
                if *s == subject_id {
                    let mut b = [0u8; 8];
                    for (o, i) in b.iter_mut().zip(payload.iter().take(7)) {
                        *o = *i;
                    }
                    stamps.push(u64::from_le_bytes(b));
                }
            }
            None::<()>
        })?;
        Ok(stamps)
    }

    /// Keeps the node alive (heartbeats) for `d`.
    pub fn idle(&mut self, d: Duration) -> Result<(), String> {
        let until = HostClock::now() + d;
        self.pump(until, |_| None::<()>).map(|_| ())
    }
}

/// The registers [`crate::registers::check_prerequisites`] looks at.
pub const CHECKED_REGISTERS: [&str; 3] = [
    "mns.pub_interval_min",
    "mns.local_timestamp",
    "uavcan.pub.dynamics.id",
];

/// Reads the checked registers of `server` (missing ones are left out).
pub fn read_checked(client: &mut Client<'_>, server: u8) -> Result<Vec<(String, Value)>, String> {
    let mut out = Vec::new();
    for name in CHECKED_REGISTERS {
        if let Some(r) = client.access(server, name, Value::Empty)? {
            if !r.value.is_empty() {
                out.push((name.to_string(), r.value));
            }
        }
    }
    Ok(out)
}
