//! Every case of PyCyphal's golden payload vectors (`tests/data/payloads.json`), both ways.

use propid_core::dsdl::{
    DataType, DoF2ndKinematics, DoF3rdDynamics, DoF3rdKinematics, DoF3rdTs, GetInfoRequest,
    GetInfoResponse, Heartbeat, Readiness, Timestamp, Vector31, Version,
};
use serde_json::Value;

fn f32_of(v: &Value) -> f32 {
    match v {
        Value::String(s) => match s.as_str() {
            "nan" => f32::NAN,
            "inf" => f32::INFINITY,
            "-inf" => f32::NEG_INFINITY,
            other => panic!("bad float string {other}"),
        },
        // Inputs are exactly representable as f32 (vectors README).
        v => v.as_f64().expect("float") as f32,
    }
}

fn u64_of(v: &Value) -> u64 {
    v.as_u64().expect("integer")
}

fn bytes_of(v: &Value) -> Vec<u8> {
    v.as_array()
        .expect("byte list")
        .iter()
        .map(|b| u64_of(b) as u8)
        .collect()
}

fn same_f32(a: f32, b: f32) -> bool {
    (a.is_nan() && b.is_nan()) || a.to_bits() == b.to_bits()
}

fn version_of(v: &Value) -> Version {
    Version {
        major: u64_of(&v["major"]) as u8,
        minor: u64_of(&v["minor"]) as u8,
    }
}

/// A decoded value in a comparable form.
#[derive(Debug)]
#[allow(clippy::large_enum_variant)] // test-only value holder
enum Decoded {
    Readiness(Readiness),
    Vector31(Vector31),
    DoF3rdTs(DoF3rdTs),
    Heartbeat(Heartbeat),
    GetInfoRequest(GetInfoRequest),
    GetInfoResponse(GetInfoResponse),
}

fn from_fields(ty: &str, f: &Value) -> Decoded {
    match ty {
        "zubax.service.Readiness.1.0" => Decoded::Readiness(Readiness {
            value: u64_of(&f["value"]) as u8,
        }),
        "zubax.primitive.real16.Vector31.1.0" => {
            let arr = f["value"].as_array().unwrap();
            assert_eq!(arr.len(), 31);
            let mut value = [0f32; 31];
            for (o, v) in value.iter_mut().zip(arr) {
                *o = f32_of(v);
            }
            Decoded::Vector31(Vector31 { value })
        }
        "zubax.physics.dynamics.DoF3rdTs.1.0" => {
            let k = &f["value"]["kinematics"];
            Decoded::DoF3rdTs(DoF3rdTs {
                timestamp: Timestamp {
                    microsecond: u64_of(&f["timestamp"]["microsecond"]),
                },
                value: DoF3rdDynamics {
                    kinematics: DoF3rdKinematics {
                        base: DoF2ndKinematics {
                            position: f32_of(&k["base"]["position"]),
                            velocity: f32_of(&k["base"]["velocity"]),
                        },
                        acceleration: f32_of(&k["acceleration"]),
                    },
                    force: f32_of(&f["value"]["force"]),
                },
            })
        }
        "uavcan.node.Heartbeat.1.0" => Decoded::Heartbeat(Heartbeat {
            uptime: u64_of(&f["uptime"]) as u32,
            health: u64_of(&f["health"]["value"]) as u8,
            mode: u64_of(&f["mode"]["value"]) as u8,
            vendor_specific_status_code: u64_of(&f["vendor_specific_status_code"]) as u8,
        }),
        "uavcan.node.GetInfo.1.0.Request" => Decoded::GetInfoRequest(GetInfoRequest),
        "uavcan.node.GetInfo.1.0.Response" => {
            let crc = bytes_u64s(&f["software_image_crc"]);
            assert!(crc.len() <= 1);
            let mut unique_id = [0u8; 16];
            unique_id.copy_from_slice(&bytes_of(&f["unique_id"]));
            Decoded::GetInfoResponse(GetInfoResponse {
                protocol_version: version_of(&f["protocol_version"]),
                hardware_version: version_of(&f["hardware_version"]),
                software_version: version_of(&f["software_version"]),
                software_vcs_revision_id: u64_of(&f["software_vcs_revision_id"]),
                unique_id,
                name: heapless::Vec::from_slice(&bytes_of(&f["name"])).unwrap(),
                software_image_crc: crc.first().copied(),
                certificate_of_authenticity: heapless::Vec::from_slice(&bytes_of(
                    &f["certificate_of_authenticity"],
                ))
                .unwrap(),
            })
        }
        other => panic!("unknown type {other}"),
    }
}

fn bytes_u64s(v: &Value) -> Vec<u64> {
    v.as_array().unwrap().iter().map(u64_of).collect()
}

fn decode(ty: &str, payload: &[u8]) -> Option<Decoded> {
    Some(match ty {
        "zubax.service.Readiness.1.0" => Decoded::Readiness(Readiness::deserialize(payload).ok()?),
        "zubax.primitive.real16.Vector31.1.0" => {
            Decoded::Vector31(Vector31::deserialize(payload).ok()?)
        }
        "zubax.physics.dynamics.DoF3rdTs.1.0" => {
            Decoded::DoF3rdTs(DoF3rdTs::deserialize(payload).ok()?)
        }
        "uavcan.node.Heartbeat.1.0" => Decoded::Heartbeat(Heartbeat::deserialize(payload).ok()?),
        "uavcan.node.GetInfo.1.0.Request" => {
            Decoded::GetInfoRequest(GetInfoRequest::deserialize(payload).ok()?)
        }
        "uavcan.node.GetInfo.1.0.Response" => {
            Decoded::GetInfoResponse(GetInfoResponse::deserialize(payload).ok()?)
        }
        other => panic!("unknown type {other}"),
    })
}

fn encode(d: &Decoded) -> Vec<u8> {
    let mut buf = [0u8; 512];
    let n = match d {
        Decoded::Readiness(v) => v.serialize(&mut buf),
        Decoded::Vector31(v) => v.serialize(&mut buf),
        Decoded::DoF3rdTs(v) => v.serialize(&mut buf),
        Decoded::Heartbeat(v) => v.serialize(&mut buf),
        Decoded::GetInfoRequest(v) => v.serialize(&mut buf),
        Decoded::GetInfoResponse(v) => v.serialize(&mut buf),
    };
    buf[..n].to_vec()
}

fn equal(a: &Decoded, b: &Decoded) -> bool {
    match (a, b) {
        (Decoded::Vector31(x), Decoded::Vector31(y)) => {
            x.value.iter().zip(&y.value).all(|(p, q)| same_f32(*p, *q))
        }
        (Decoded::DoF3rdTs(x), Decoded::DoF3rdTs(y)) => {
            let (p, q) = (&x.value, &y.value);
            x.timestamp == y.timestamp
                && same_f32(p.kinematics.base.position, q.kinematics.base.position)
                && same_f32(p.kinematics.base.velocity, q.kinematics.base.velocity)
                && same_f32(p.kinematics.acceleration, q.kinematics.acceleration)
                && same_f32(p.force, q.force)
        }
        (Decoded::Readiness(x), Decoded::Readiness(y)) => x == y,
        (Decoded::Heartbeat(x), Decoded::Heartbeat(y)) => x == y,
        (Decoded::GetInfoRequest(x), Decoded::GetInfoRequest(y)) => x == y,
        (Decoded::GetInfoResponse(x), Decoded::GetInfoResponse(y)) => x == y,
        _ => false,
    }
}

#[test]
fn every_payload_vector_passes_both_ways() {
    let text = include_str!("data/payloads.json");
    let doc: Value = serde_json::from_str(text).unwrap();
    let cases = doc["cases"].as_array().unwrap();
    let mut per_type = std::collections::BTreeMap::<String, usize>::new();
    let mut failures = Vec::new();
    for case in cases {
        let ty = case["type"].as_str().unwrap();
        let name = case["name"].as_str().unwrap();
        let payload = hex::decode(case["payload_hex"].as_str().unwrap()).unwrap();
        let ok = match case["kind"].as_str().unwrap() {
            "encode" => {
                let value = from_fields(ty, &case["fields"]);
                // Where PyCyphal overflows float16 to inf, the spec saturates.
                let want = case
                    .get("saturating_rne_payload_hex")
                    .and_then(Value::as_str)
                    .map(|h| hex::decode(h).unwrap())
                    .unwrap_or_else(|| payload.clone());
                let got = encode(&value);
                let enc_ok = got == want;
                let expected = from_fields(ty, &case["decoded"]);
                let dec_ok = decode(ty, &payload).is_some_and(|d| equal(&d, &expected));
                if !enc_ok {
                    failures.push(format!(
                        "{name}: encode gave {} want {}",
                        hex::encode(&got),
                        hex::encode(&want)
                    ));
                }
                enc_ok && dec_ok
            }
            "decode" => match &case["decoded"] {
                Value::Null => decode(ty, &payload).is_none(),
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
    let total: usize = per_type.values().sum();
    // Written to the stderr handle directly so the count shows even when libtest captures output.
    let mut report = String::new();
    for (ty, n) in &per_type {
        report += &format!("dsdl vectors: {ty}: {n} cases passed\n");
    }
    report += &format!("dsdl vectors: {total} of {} cases passed\n", cases.len());
    std::io::Write::write_all(&mut std::io::stderr(), report.as_bytes()).unwrap();
    assert!(failures.is_empty(), "failures:\n{}", failures.join("\n"));
    assert_eq!(total, cases.len());
    assert_eq!(total, 74, "the vector file has 74 cases");
}
