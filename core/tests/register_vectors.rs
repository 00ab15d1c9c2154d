//! PyCyphal's golden vectors for the register API, port.List and ExecuteCommand
//! (`tests/data/register_payloads.json`, made by `tools/vectors/gen_registers.py`), both ways:
//! encode cases must give PyCyphal's bytes and decode back to what PyCyphal decodes; decode cases
//! must be accepted or refused as PyCyphal does and re-encode to PyCyphal's bytes. The `assign`
//! and `env` cases (what a register write or an environment variable leaves in the register) are
//! checked in `register_server.rs`.

use propid_core::dsdl::{
    AccessRequest, AccessResponse, DataType, ExecuteCommandRequest, ExecuteCommandResponse,
    ListRequest, ListResponse, Name, PortList, ServiceIdList, SubjectIdList, Value,
};
use serde_json::Value as Json;

mod common;
use common::register_json::value_of;

fn name_of(j: &Json) -> Name {
    Name {
        name: heapless::Vec::from_slice(&hex::decode(j.as_str().unwrap()).unwrap()).unwrap(),
    }
}

fn subject_list_of(j: &Json) -> SubjectIdList {
    let obj = j.as_object().unwrap();
    if let Some(m) = obj.get("mask") {
        let mut mask = [0u8; 1024];
        mask.copy_from_slice(&hex::decode(m.as_str().unwrap()).unwrap());
        SubjectIdList::Mask(mask)
    } else if let Some(l) = obj.get("sparse_list") {
        SubjectIdList::SparseList(heapless::Vec::from_iter(
            l.as_array()
                .unwrap()
                .iter()
                .map(|x| x.as_u64().unwrap() as u16),
        ))
    } else {
        assert!(obj.contains_key("total"));
        SubjectIdList::Total
    }
}

fn service_list_of(j: &Json) -> ServiceIdList {
    let mut mask = [0u8; 64];
    mask.copy_from_slice(&hex::decode(j.as_str().unwrap()).unwrap());
    ServiceIdList { mask }
}

/// A decoded value of any of the types, compared through its serialization.
#[derive(Debug)]
#[allow(clippy::large_enum_variant)] // test-only value holder
enum Decoded {
    Value(Value),
    Name(Name),
    AccessRequest(AccessRequest),
    AccessResponse(AccessResponse),
    ListRequest(ListRequest),
    ListResponse(ListResponse),
    PortList(Box<PortList>),
    ExecuteCommandRequest(ExecuteCommandRequest),
    ExecuteCommandResponse(ExecuteCommandResponse),
}

fn from_fields(ty: &str, f: &Json) -> Decoded {
    match ty {
        "uavcan.register.Value.1.0" => Decoded::Value(value_of(f)),
        "uavcan.register.Name.1.0" => Decoded::Name(name_of(&f["name"])),
        "uavcan.register.Access.1.0.Request" => Decoded::AccessRequest(AccessRequest {
            name: name_of(&f["name"]),
            value: value_of(&f["value"]),
        }),
        "uavcan.register.Access.1.0.Response" => Decoded::AccessResponse(AccessResponse {
            timestamp_us: f["timestamp"].as_u64().unwrap(),
            mutable: f["mutable"].as_bool().unwrap(),
            persistent: f["persistent"].as_bool().unwrap(),
            value: value_of(&f["value"]),
        }),
        "uavcan.register.List.1.0.Request" => Decoded::ListRequest(ListRequest {
            index: f["index"].as_u64().unwrap() as u16,
        }),
        "uavcan.register.List.1.0.Response" => Decoded::ListResponse(ListResponse {
            name: name_of(&f["name"]),
        }),
        "uavcan.node.port.List.1.0" => Decoded::PortList(Box::new(PortList {
            publishers: subject_list_of(&f["publishers"]),
            subscribers: subject_list_of(&f["subscribers"]),
            clients: service_list_of(&f["clients"]),
            servers: service_list_of(&f["servers"]),
        })),
        "uavcan.node.ExecuteCommand.1.3.Request" => {
            Decoded::ExecuteCommandRequest(ExecuteCommandRequest {
                command: f["command"].as_u64().unwrap() as u16,
                parameter: heapless::Vec::from_slice(
                    &hex::decode(f["parameter"].as_str().unwrap()).unwrap(),
                )
                .unwrap(),
            })
        }
        "uavcan.node.ExecuteCommand.1.3.Response" => {
            Decoded::ExecuteCommandResponse(ExecuteCommandResponse {
                status: f["status"].as_u64().unwrap() as u8,
                output: heapless::Vec::from_slice(
                    &hex::decode(f["output"].as_str().unwrap()).unwrap(),
                )
                .unwrap(),
            })
        }
        other => panic!("unknown type {other}"),
    }
}

fn decode(ty: &str, p: &[u8]) -> Option<Decoded> {
    Some(match ty {
        "uavcan.register.Value.1.0" => Decoded::Value(Value::deserialize(p).ok()?),
        "uavcan.register.Name.1.0" => Decoded::Name(Name::deserialize(p).ok()?),
        "uavcan.register.Access.1.0.Request" => {
            Decoded::AccessRequest(AccessRequest::deserialize(p).ok()?)
        }
        "uavcan.register.Access.1.0.Response" => {
            Decoded::AccessResponse(AccessResponse::deserialize(p).ok()?)
        }
        "uavcan.register.List.1.0.Request" => {
            Decoded::ListRequest(ListRequest::deserialize(p).ok()?)
        }
        "uavcan.register.List.1.0.Response" => {
            Decoded::ListResponse(ListResponse::deserialize(p).ok()?)
        }
        "uavcan.node.port.List.1.0" => Decoded::PortList(Box::new(PortList::deserialize(p).ok()?)),
        "uavcan.node.ExecuteCommand.1.3.Request" => {
            Decoded::ExecuteCommandRequest(ExecuteCommandRequest::deserialize(p).ok()?)
        }
        "uavcan.node.ExecuteCommand.1.3.Response" => {
            Decoded::ExecuteCommandResponse(ExecuteCommandResponse::deserialize(p).ok()?)
        }
        other => panic!("unknown type {other}"),
    })
}

fn encode(d: &Decoded) -> Vec<u8> {
    let mut buf = vec![0u8; 4096];
    let n = match d {
        Decoded::Value(v) => v.serialize(&mut buf),
        Decoded::Name(v) => v.serialize(&mut buf),
        Decoded::AccessRequest(v) => v.serialize(&mut buf),
        Decoded::AccessResponse(v) => v.serialize(&mut buf),
        Decoded::ListRequest(v) => v.serialize(&mut buf),
        Decoded::ListResponse(v) => v.serialize(&mut buf),
        Decoded::PortList(v) => v.serialize(&mut buf),
        Decoded::ExecuteCommandRequest(v) => v.serialize(&mut buf),
        Decoded::ExecuteCommandResponse(v) => v.serialize(&mut buf),
    };
    buf.truncate(n);
    buf
}

/// Two decoded values are the same if they serialize to the same bytes (exact for floats, NaN
/// payloads included) and are the same type.
fn equal(a: &Decoded, b: &Decoded) -> bool {
    core::mem::discriminant(a) == core::mem::discriminant(b) && encode(a) == encode(b)
}

#[test]
fn every_register_vector_passes_both_ways() {
    let doc: Json =
        serde_json::from_str(include_str!("data/register_payloads.json")).expect("vector file");
    let cases = doc["cases"].as_array().unwrap();
    let mut per_type = std::collections::BTreeMap::<String, usize>::new();
    let mut failures = Vec::new();
    let mut checked = 0;
    for case in cases {
        let kind = case["kind"].as_str().unwrap();
        if kind == "assign" || kind == "env" {
            continue;
        }
        checked += 1;
        let ty = case["type"].as_str().unwrap();
        let name = case["name"].as_str().unwrap();
        let payload = hex::decode(case["payload_hex"].as_str().unwrap()).unwrap();
        let ok = match kind {
            "encode" => {
                let value = from_fields(ty, &case["fields"]);
                let got = encode(&value);
                if got != payload {
                    failures.push(format!(
                        "{name}: encode gave {} want {}",
                        hex::encode(&got),
                        hex::encode(&payload)
                    ));
                }
                let expected = from_fields(ty, &case["decoded"]);
                got == payload && decode(ty, &payload).is_some_and(|d| equal(&d, &expected))
            }
            "decode" => match &case["decoded"] {
                Json::Null => decode(ty, &payload).is_none(),
                expected => {
                    let expected = from_fields(ty, expected);
                    let reencoded = hex::decode(case["reencoded_hex"].as_str().unwrap()).unwrap();
                    decode(ty, &payload)
                        .is_some_and(|d| equal(&d, &expected) && encode(&d) == reencoded)
                }
            },
            other => panic!("unknown kind {other}"),
        };
        if ok {
            *per_type.entry(ty.to_string()).or_default() += 1;
        } else {
            failures.push(format!("{name} ({ty}) failed"));
        }
    }
    assert!(failures.is_empty(), "failures:\n{}", failures.join("\n"));
    // The declared sizes agree with the codecs'.
    let types = doc["types"].as_object().unwrap();
    let max = |t: &str| types[t]["max_size_bytes"].as_u64().unwrap() as usize;
    assert_eq!(max("uavcan.register.Value.1.0"), Value::MAX_SIZE_BYTES);
    assert_eq!(
        max("uavcan.register.Access.1.0.Request"),
        AccessRequest::MAX_SIZE_BYTES
    );
    assert_eq!(
        max("uavcan.register.Access.1.0.Response"),
        AccessResponse::MAX_SIZE_BYTES
    );
    // Sealed, but its delimited members may grow to their extents: 8466 bytes a receiver must
    // accept, of which today's definitions use at most 2194.
    assert_eq!(max("uavcan.node.port.List.1.0"), PortList::EXTENT_BYTES);
    assert_eq!(
        max("uavcan.node.ExecuteCommand.1.3.Request"),
        ExecuteCommandRequest::MAX_SIZE_BYTES
    );
    assert_eq!(
        types["uavcan.node.ExecuteCommand.1.3.Request"]["extent_bytes"],
        ExecuteCommandRequest::EXTENT_BYTES
    );
    let total: usize = per_type.values().sum();
    let mut report = String::new();
    for (ty, n) in &per_type {
        report += &format!("register vectors: {ty}: {n} cases passed\n");
    }
    report += &format!("register vectors: {total} of {checked} encode/decode cases passed\n");
    std::io::Write::write_all(&mut std::io::stderr(), report.as_bytes()).unwrap();
    assert!(failures.is_empty(), "failures:\n{}", failures.join("\n"));
    assert_eq!(total, checked);
    assert_eq!(checked, 115, "the vector file has 115 encode/decode cases");
}
