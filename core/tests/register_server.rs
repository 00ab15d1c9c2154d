//! The node's register server, port list and command service: the write conversions against
//! PyCyphal's register server (the `assign` vectors), then a client node and a server node on a
//! simulated link with a virtual clock doing List, Access (read, write, read-only refusal,
//! conversion), port.List and ExecuteCommand.

use core::time::Duration;

use propid_core::can::{Frame, Mtu, NodeId, ServiceId, SubjectId};
use propid_core::dsdl::{
    AccessRequest, AccessResponse, DataType, ExecuteCommandRequest, ExecuteCommandResponse,
    ListRequest, ListResponse, Name, PortList, Value, ACCESS_SERVICE_ID,
    EXECUTE_COMMAND_SERVICE_ID, LIST_SERVICE_ID,
};
use propid_core::node::{parse_value, Event, Node, NodeConfig, Registry};
use propid_core::time::Instant;
use serde_json::Value as Json;

mod common;

fn nid(n: u8) -> NodeId {
    NodeId::try_from(n).unwrap()
}
fn sub(n: u16) -> SubjectId {
    SubjectId::try_from(n).unwrap()
}
fn svc(n: u16) -> ServiceId {
    ServiceId::try_from(n).unwrap()
}
use common::register_json::{same_value, value_of};

#[test]
fn writes_convert_as_pycyphal_register_server_does() {
    let doc: Json =
        serde_json::from_str(include_str!("data/register_payloads.json")).expect("vector file");
    let mut failures = Vec::new();
    let (mut n, mut refused) = (0, 0);
    for case in doc["cases"].as_array().unwrap() {
        if case["kind"] != "assign" {
            continue;
        }
        n += 1;
        let initial = value_of(&case["register"]);
        let mutable = case["mutable"].as_bool().unwrap();
        let mut reg: Registry<1> = Registry::new();
        reg.add("r.x", initial.clone(), mutable, true).unwrap();
        let response = reg.access(&AccessRequest {
            name: Name::new("r.x").unwrap(),
            value: value_of(&case["write"]),
        });
        let want = match &case["result"] {
            Json::Null => {
                refused += 1;
                initial.clone()
            }
            r => value_of(r),
        };
        let written = reg.take_written().is_some();
        let should_write =
            mutable && !case["result"].is_null() && case["write"].get("empty").is_none();
        if !same_value(&response.value, &want)
            || response.mutable != mutable
            || written != should_write
        {
            failures.push(format!(
                "{}: got {:?} want {:?}",
                case["name"].as_str().unwrap(),
                response.value,
                want
            ));
        }
    }
    std::io::Write::write_all(
        &mut std::io::stderr(),
        format!(
            "register writes: {} of {n} assign cases as PyCyphal ({refused} where PyCyphal refuses or raises)\n",
            n - failures.len()
        )
        .as_bytes(),
    )
    .unwrap();
    assert!(failures.is_empty(), "{}", failures.join("\n"));
    assert_eq!(n, 560);
}

#[test]
fn environment_text_reads_as_pycyphal_reads_it() {
    let doc: Json =
        serde_json::from_str(include_str!("data/register_payloads.json")).expect("vector file");
    let mut failures = Vec::new();
    let mut n = 0;
    for case in doc["cases"].as_array().unwrap() {
        if case["kind"] != "env" {
            continue;
        }
        n += 1;
        let template = value_of(&case["register"]);
        let got = parse_value(&template, case["text"].as_str().unwrap());
        let ok = match (&case["result"], &got) {
            (Json::Null, None) => true,
            (Json::Null, Some(_)) | (_, None) => false,
            (want, Some(got)) => same_value(got, &value_of(want)),
        };
        if !ok {
            failures.push(format!("{}: got {got:?}", case["name"].as_str().unwrap()));
        }
    }
    std::io::Write::write_all(
        &mut std::io::stderr(),
        format!(
            "register text: {} of {n} env cases as PyCyphal\n",
            n - failures.len()
        )
        .as_bytes(),
    )
    .unwrap();
    assert!(failures.is_empty(), "{}", failures.join("\n"));
    assert_eq!(n, 272);
}

type Client = Node<6, 8, 512, 64>;
type Server = Node<8, 8, 515, 128, 8>;

struct Link {
    now: Instant,
    client: Client,
    server: Server,
    /// Responses and messages the client received: (port, payload).
    got: Vec<(u16, Vec<u8>)>,
}

impl Link {
    fn new(mtu: Mtu) -> Link {
        let now = Instant::from_millis(5000);
        let mut client = Client::new(NodeConfig::new(nid(100), "org.test.client", mtu), now);
        client
            .subscribe_message(sub(PortList::FIXED_SUBJECT_ID), PortList::EXTENT_BYTES)
            .unwrap();
        let mut server = Server::new(NodeConfig::new(nid(10), "org.propid.drive", mtu), now);
        server.add_standard_registers().unwrap();
        server
            .add_register(
                "setpoint_rat_lo_hi",
                Value::real64(&[0.1, 0.9]).unwrap(),
                true,
                true,
            )
            .unwrap();
        server
            .add_register(
                "uavcan.pub.sp_rat.id",
                Value::natural16(&[24]).unwrap(),
                true,
                true,
            )
            .unwrap();
        server
            .add_register(
                "uavcan.pub.sp_rat.type",
                Value::string("zubax.primitive.real16.Vector31.1.0").unwrap(),
                false,
                true,
            )
            .unwrap();
        server.subscribe_message(sub(110), 23).unwrap();
        server
            .serve_commands(&[
                ExecuteCommandRequest::COMMAND_RESTART,
                ExecuteCommandRequest::COMMAND_STORE_PERSISTENT_STATES,
                ExecuteCommandRequest::COMMAND_FACTORY_RESET,
            ])
            .unwrap();
        server.enable_port_list(now);
        Link {
            now,
            client,
            server,
            got: Vec::new(),
        }
    }

    /// Runs `ms` milliseconds of virtual time in 1 ms steps.
    fn run(&mut self, ms: u64) {
        for _ in 0..ms {
            self.now = self.now + Duration::from_millis(1);
            let now = self.now;
            let mut to_server: Vec<Frame> = Vec::new();
            while let Some(f) = self.client.poll_transmit(now) {
                to_server.push(f);
            }
            let mut to_client: Vec<Frame> = Vec::new();
            while let Some(f) = self.server.poll_transmit(now) {
                to_client.push(f);
            }
            for f in &to_server {
                let _ = self.server.handle_frame(now, f);
            }
            for f in &to_client {
                match self.client.handle_frame(now, f) {
                    Some(Event::Response {
                        service_id,
                        source,
                        payload,
                        ..
                    }) if source == nid(10) => self.got.push((service_id.get(), payload.to_vec())),
                    Some(Event::Message {
                        subject_id,
                        payload,
                        ..
                    }) if subject_id == sub(PortList::FIXED_SUBJECT_ID) => self
                        .got
                        .push((PortList::FIXED_SUBJECT_ID, payload.to_vec())),
                    _ => {}
                }
            }
        }
    }

    /// Sends a request and returns the response payload.
    fn call<T: DataType>(&mut self, service: u16, request: &T, extent: usize) -> Vec<u8> {
        let mut buf = vec![0u8; T::MAX_SIZE_BYTES];
        let n = request.serialize(&mut buf);
        self.got.retain(|(p, _)| *p != service);
        self.client
            .request(
                self.now,
                svc(service),
                nid(10),
                &buf[..n],
                extent,
                Duration::from_secs(1),
            )
            .unwrap();
        self.run(20);
        let pos = self
            .got
            .iter()
            .position(|(p, _)| *p == service)
            .expect("a response");
        self.got.remove(pos).1
    }

    fn access(&mut self, name: &str, value: Value) -> AccessResponse {
        let request = AccessRequest {
            name: Name::new(name).unwrap(),
            value,
        };
        let p = self.call(ACCESS_SERVICE_ID, &request, AccessResponse::EXTENT_BYTES);
        AccessResponse::deserialize(&p).unwrap()
    }
}

#[test]
fn list_access_port_list_and_commands_between_two_nodes() {
    for mtu in [Mtu::Classic, Mtu::Fd] {
        let mut link = Link::new(mtu);
        // List: every name in order, then the empty name.
        let mut names = Vec::new();
        for index in 0.. {
            let p = link.call(
                LIST_SERVICE_ID,
                &ListRequest { index },
                ListResponse::EXTENT_BYTES,
            );
            let name = ListResponse::deserialize(&p).unwrap().name;
            if name.is_empty() {
                break;
            }
            names.push(name.as_str().unwrap().to_string());
        }
        assert_eq!(
            names,
            [
                "uavcan.node.id",
                "uavcan.node.description",
                "setpoint_rat_lo_hi",
                "uavcan.pub.sp_rat.id",
                "uavcan.pub.sp_rat.type"
            ],
            "{mtu:?}"
        );

        // Read.
        let r = link.access("setpoint_rat_lo_hi", Value::Empty);
        assert_eq!(r.value, Value::real64(&[0.1, 0.9]).unwrap());
        assert!(r.mutable && r.persistent);
        let r = link.access("uavcan.node.id", Value::Empty);
        assert_eq!(r.value, Value::natural16(&[10]).unwrap());

        // Write of the same type; the owner sees it.
        let r = link.access("setpoint_rat_lo_hi", Value::real64(&[0.2, 0.7]).unwrap());
        assert_eq!(r.value, Value::real64(&[0.2, 0.7]).unwrap());
        assert_eq!(link.server.take_register_change(), Some(2));
        assert_eq!(link.server.take_register_change(), None);

        // Write of another type: converted (real32 → natural16, rounded half to even).
        let r = link.access("uavcan.pub.sp_rat.id", Value::real32(&[100.5]).unwrap());
        assert_eq!(r.value, Value::natural16(&[100]).unwrap());
        assert_eq!(link.server.take_register_change(), Some(3));
        // Not convertible: unchanged, not reported.
        let r = link.access("uavcan.pub.sp_rat.id", Value::string("7").unwrap());
        assert_eq!(r.value, Value::natural16(&[100]).unwrap());
        assert_eq!(link.server.take_register_change(), None);

        // Read-only: refused, the unchanged value returned.
        let r = link.access("uavcan.pub.sp_rat.type", Value::string("x").unwrap());
        assert_eq!(
            r.value,
            Value::string("zubax.primitive.real16.Vector31.1.0").unwrap()
        );
        assert!(!r.mutable && r.persistent);
        assert_eq!(link.server.take_register_change(), None);

        // Nonexistent: empty, flags clear.
        let r = link.access("no.such", Value::natural16(&[1]).unwrap());
        assert_eq!(r, AccessResponse::default());

        // ExecuteCommand: supported → SUCCESS and handed to the owner; others → BAD_COMMAND.
        let exec = |link: &mut Link, command: u16| {
            let p = link.call(
                EXECUTE_COMMAND_SERVICE_ID,
                &ExecuteCommandRequest {
                    command,
                    parameter: heapless::Vec::new(),
                },
                ExecuteCommandResponse::EXTENT_BYTES,
            );
            ExecuteCommandResponse::deserialize(&p).unwrap().status
        };
        assert_eq!(
            exec(
                &mut link,
                ExecuteCommandRequest::COMMAND_STORE_PERSISTENT_STATES
            ),
            ExecuteCommandResponse::STATUS_SUCCESS
        );
        let c = link.server.take_command().unwrap();
        assert_eq!(
            (c.command, c.client),
            (ExecuteCommandRequest::COMMAND_STORE_PERSISTENT_STATES, 100)
        );
        assert_eq!(
            exec(&mut link, ExecuteCommandRequest::COMMAND_POWER_OFF),
            ExecuteCommandResponse::STATUS_BAD_COMMAND
        );
        assert_eq!(
            exec(&mut link, 1234),
            ExecuteCommandResponse::STATUS_BAD_COMMAND
        );
        assert!(link.server.take_command().is_none());

        // port.List: published at once, then every 10 s; it names the node's ports.
        link.run(25_000);
        let lists: Vec<PortList> = link
            .got
            .iter()
            .filter(|(p, _)| *p == PortList::FIXED_SUBJECT_ID)
            .map(|(_, p)| PortList::deserialize(p).unwrap())
            .collect();
        // At 0 s (before the calls above), 10 s and 20 s of virtual time.
        assert_eq!(lists.len(), 3, "{mtu:?}");
        let last = lists.last().unwrap();
        for s in [7509, 7510] {
            assert!(last.publishers.contains(s));
        }
        assert!(last.subscribers.contains(110));
        assert!(!last.subscribers.contains(24));
        for s in [384, 385, 430, 435] {
            assert!(last.servers.contains(s), "server {s}");
        }
        assert!(!last.servers.contains(434));
        assert_eq!(last.clients.mask, [0u8; 64]);
        assert_eq!(link.server.stats().tx.expired, 0);
    }
}

#[test]
fn a_node_without_registers_serves_none() {
    let now = Instant::from_millis(0);
    let mut client = Client::new(NodeConfig::new(nid(1), "c", Mtu::Classic), now);
    let mut plain = Client::new(NodeConfig::new(nid(2), "p", Mtu::Classic), now);
    let mut buf = [0u8; 2];
    let n = ListRequest { index: 0 }.serialize(&mut buf);
    client
        .request(
            now,
            svc(LIST_SERVICE_ID),
            nid(2),
            &buf[..n],
            256,
            Duration::from_secs(1),
        )
        .unwrap();
    let mut answered = false;
    for ms in 0..100 {
        let t = now + Duration::from_millis(ms);
        while let Some(f) = client.poll_transmit(t) {
            let _ = plain.handle_frame(t, &f);
        }
        while let Some(f) = plain.poll_transmit(t) {
            answered |= matches!(client.handle_frame(t, &f), Some(Event::Response { .. }));
        }
    }
    assert!(!answered);
    assert!(plain.port_list().servers.contains(430));
    assert!(!plain.port_list().servers.contains(385));
}
