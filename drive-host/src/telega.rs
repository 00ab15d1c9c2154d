//! A register client on a real bus: [`propid_drive_proto::telega::Client`] run in real time,
//! one op per call (what `propid telega` and `propid drive --from-telega` use).

use std::sync::atomic::AtomicBool;
use std::time::Duration;

use propid_core::can::{Mtu, NodeId};
use propid_core::dsdl::{GetInfoResponse, Value};
use propid_drive_proto::telega::{Client, ClientEvent, Op, RemoteRegister, CHECKED_REGISTERS};
use propid_transport::CanTransport;

use crate::realtime::{run_realtime, Clock};

/// A [`Client`] on a [`CanTransport`] in real time: each call runs one op to its end.
pub struct BlockingClient<'a> {
    client: Client,
    transport: &'a mut dyn CanTransport,
    clock: &'a dyn Clock,
}

impl<'a> BlockingClient<'a> {
    /// A client node `node_id` on `transport`.
    pub fn new(
        transport: &'a mut dyn CanTransport,
        clock: &'a dyn Clock,
        node_id: NodeId,
        mtu: Mtu,
    ) -> Self {
        BlockingClient {
            client: Client::new(node_id, mtu, clock.now()),
            transport,
            clock,
        }
    }

    /// Runs `op`; its event (a transport failure is an error, its sentence).
    pub fn run(&mut self, op: Op) -> Result<ClientEvent, String> {
        self.client.push(op);
        let stop = AtomicBool::new(false);
        let mut got = None;
        run_realtime(
            &mut self.client,
            self.transport,
            self.clock,
            &stop,
            &mut |e| {
                got = Some(e);
                Ok(())
            },
        );
        match got {
            Some(ClientEvent::Failed(reason)) => Err(reason.to_string()),
            Some(e) => Ok(e),
            None => Err("the client ended without an answer".into()),
        }
    }

    /// Listens for heartbeats for `d`; the node-IDs heard.
    pub fn discover(&mut self, d: Duration) -> Result<Vec<NodeId>, String> {
        match self.run(Op::Listen(d))? {
            ClientEvent::Heard(v) => Ok(v),
            _ => Ok(self.client.heard()),
        }
    }

    /// GetInfo of `server` (`None`: no answer).
    pub fn get_info(&mut self, server: NodeId) -> Result<Option<GetInfoResponse>, String> {
        Ok(match self.run(Op::GetInfo(server))? {
            ClientEvent::Info(_, i) => i,
            _ => None,
        })
    }

    /// The register names of `server` (`None`: it does not answer List).
    pub fn list(&mut self, server: NodeId) -> Result<Option<Vec<String>>, String> {
        Ok(match self.run(Op::List(server))? {
            ClientEvent::Names(_, n) => n,
            _ => None,
        })
    }

    /// Reads (`Value::Empty`) or writes a register; what the drive then holds (`None`: no answer).
    pub fn access(
        &mut self,
        server: NodeId,
        name: &str,
        value: Value,
    ) -> Result<Option<RemoteRegister>, String> {
        Ok(match self.run(Op::Access(server, name.into(), value))? {
            ClientEvent::Register(_, r) => r,
            _ => None,
        })
    }

    /// Sends a command; its status (`None`: no answer).
    pub fn execute(&mut self, server: NodeId, command: u16) -> Result<Option<u8>, String> {
        Ok(match self.run(Op::Execute(server, command))? {
            ClientEvent::Executed(_, _, s) => s,
            _ => None,
        })
    }

    /// Reads the [`CHECKED_REGISTERS`] of `server` (those it lacks are left out).
    pub fn read_checked(&mut self, server: NodeId) -> Result<Vec<(String, Value)>, String> {
        self.read(server, &CHECKED_REGISTERS)
    }

    /// Reads `names` from `server` (those it lacks are left out). A server that does not answer
    /// the first read is not asked again (a node without registers costs one timeout, not one
    /// per name).
    pub fn read(&mut self, server: NodeId, names: &[&str]) -> Result<Vec<(String, Value)>, String> {
        let mut out = Vec::new();
        for (i, name) in names.iter().enumerate() {
            match self.access(server, name, Value::Empty)? {
                Some(r) if !r.value.is_empty() => out.push((name.to_string(), r.value)),
                Some(_) => {}
                None if i == 0 => break,
                None => {}
            }
        }
        Ok(out)
    }
}
