//! Fuzz the register API, port.List and ExecuteCommand decoders and the register server: any
//! bytes must decode (or be refused) without panicking, whatever decodes must re-encode to bytes
//! that decode to the same bytes again, and an Access request built from the bytes must leave
//! every register with its type and dimension.
#![no_main]

use libfuzzer_sys::fuzz_target;
use propid_core::dsdl::{
    AccessRequest, AccessResponse, DataType, ExecuteCommandRequest, ExecuteCommandResponse,
    ListRequest, ListResponse, Name, PortList, Value,
};
use propid_core::node::{convert, Registry};

/// decode → encode → decode → encode gives the same bytes twice.
fn round_trip<T: DataType>(bytes: &[u8]) -> Option<T> {
    let v = T::deserialize(bytes).ok()?;
    let mut a = vec![0u8; T::MAX_SIZE_BYTES];
    let n = v.serialize(&mut a);
    assert!(n <= T::MAX_SIZE_BYTES);
    let again = T::deserialize(&a[..n]).expect("a re-encoded payload must decode");
    let mut b = vec![0u8; T::MAX_SIZE_BYTES];
    let m = again.serialize(&mut b);
    assert_eq!(a[..n], b[..m]);
    Some(v)
}

fuzz_target!(|bytes: &[u8]| {
    let value = round_trip::<Value>(bytes);
    round_trip::<Name>(bytes);
    round_trip::<AccessResponse>(bytes);
    round_trip::<ListRequest>(bytes);
    round_trip::<ListResponse>(bytes);
    round_trip::<PortList>(bytes);
    round_trip::<ExecuteCommandRequest>(bytes);
    round_trip::<ExecuteCommandResponse>(bytes);
    let Some(request) = round_trip::<AccessRequest>(bytes) else {
        return;
    };
    // The register server: every type of register, written with whatever the bytes hold.
    let mut registry: Registry<6> = Registry::new();
    let kinds = [
        Value::natural16(&[42]).unwrap(),
        Value::real64(&[0.1, 0.9]).unwrap(),
        Value::string("abc").unwrap(),
        Value::bit(&[true, false, true]).unwrap(),
        Value::deserialize(&[7, 2, 0, 0xFF, 2]).unwrap(), // integer8 [-1, 2]
        Value::real16(&[1.5]).unwrap(),
    ];
    let name = request.name.as_str().unwrap_or("x").to_string();
    for (i, v) in kinds.iter().enumerate() {
        let n = if i == 0 { name.clone() } else { format!("r{i}") };
        let _ = registry.add(&n, v.clone(), true, false);
    }
    let response = registry.access(&request);
    // Only when the request named that register (a non-UTF-8 name was replaced by "x").
    if let Some(r) = registry.get(&name).filter(|_| request.name.as_str() == Some(&name)) {
        assert_eq!(r.value.tag(), response.value.tag());
        assert_eq!(r.value.tag(), kinds[0].tag());
        assert_eq!(r.value.len(), kinds[0].len());
    }
    if let Some(from) = value {
        for to in &kinds {
            if let Some(c) = convert(to, &from) {
                // Text keeps its type but not its length (the specification exempts it).
                assert_eq!(c.tag(), to.tag());
                if to.is_numeric() {
                    assert_eq!(c.len(), to.len());
                }
            }
        }
    }
});
