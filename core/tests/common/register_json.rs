//! The register vectors' JSON value notation (see `tools/vectors/gen_registers.py`).

use propid_core::dsdl::{BitArray, DataType, Value};
use serde_json::Value as Json;

/// Parses the generator's JSON value notation (see the generator's docstring).
pub fn value_of(j: &Json) -> Value {
    let obj = j.as_object().expect("value object");
    let (kind, items) = obj
        .iter()
        .find(|(k, _)| k.as_str() != "approx")
        .expect("a member");
    let list = || items.as_array().expect("array").iter();
    let hex_bytes = || hex::decode(items.as_str().expect("hex")).unwrap();
    let ints = || list().map(|x| x.as_i64().expect("int"));
    let bits = |w: usize| {
        list().map(move |x| {
            let s = x.as_str().expect("hex bits");
            assert_eq!(s.len(), w);
            u64::from_str_radix(s, 16).unwrap()
        })
    };
    macro_rules! vec_of {
        ($it:expr) => {
            heapless::Vec::from_iter($it)
        };
    }
    match kind.as_str() {
        "empty" => Value::Empty,
        "string" => Value::String(heapless::Vec::from_slice(&hex_bytes()).unwrap()),
        "unstructured" => Value::Unstructured(heapless::Vec::from_slice(&hex_bytes()).unwrap()),
        "bit" => Value::Bit(
            BitArray::from_bools(&list().map(|b| b.as_bool().unwrap()).collect::<Vec<bool>>())
                .unwrap(),
        ),
        "integer8" => Value::Integer8(vec_of!(ints().map(|x| x as i8))),
        "integer16" => Value::Integer16(vec_of!(ints().map(|x| x as i16))),
        "integer32" => Value::Integer32(vec_of!(ints().map(|x| x as i32))),
        "integer64" => Value::Integer64(vec_of!(ints())),
        "natural8" => Value::Natural8(vec_of!(list().map(|x| x.as_u64().unwrap() as u8))),
        "natural16" => Value::Natural16(vec_of!(list().map(|x| x.as_u64().unwrap() as u16))),
        "natural32" => Value::Natural32(vec_of!(list().map(|x| x.as_u64().unwrap() as u32))),
        "natural64" => Value::Natural64(vec_of!(list().map(|x| x.as_u64().unwrap()))),
        "real16" => Value::Real16(vec_of!(bits(4).map(|b| half::f16::from_bits(b as u16)))),
        "real32" => Value::Real32(vec_of!(bits(8).map(|b| f32::from_bits(b as u32)))),
        "real64" => Value::Real64(vec_of!(bits(16).map(f64::from_bits))),
        other => panic!("unknown value member {other}"),
    }
}

/// Values equal bit for bit (NaN payloads included): compare their serializations.
#[allow(dead_code)] // used by one of the two test binaries
pub fn same_value(a: &Value, b: &Value) -> bool {
    let (mut x, mut y) = ([0u8; 259], [0u8; 259]);
    let (n, m) = (a.serialize(&mut x), b.serialize(&mut y));
    x[..n] == y[..m]
}
