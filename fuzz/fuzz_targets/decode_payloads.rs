//! Fuzz every DSDL decoder: any bytes must decode without panicking (only GetInfo may refuse),
//! and whatever decodes must survive encode → decode unchanged.
#![no_main]

use libfuzzer_sys::fuzz_target;
use propid_core::dsdl::{
    DataType, DoF3rdTs, GetInfoRequest, GetInfoResponse, Heartbeat, Readiness, Vector31,
};

fn round_trip<T: DataType + PartialEq + core::fmt::Debug>(
    bytes: &[u8],
    same: impl Fn(&T, &T) -> bool,
) {
    if let Ok(v) = T::deserialize(bytes) {
        let mut buf = [0u8; 512];
        let n = v.serialize(&mut buf);
        assert!(n <= T::MAX_SIZE_BYTES);
        let again = T::deserialize(&buf[..n]).expect("re-encoded payload must decode");
        assert!(same(&v, &again), "{v:?} != {again:?}");
    }
}

fn bits_equal(a: &[f32], b: &[f32]) -> bool {
    a.iter().zip(b).all(|(x, y)| x.to_bits() == y.to_bits())
}

fuzz_target!(|bytes: &[u8]| {
    round_trip::<Readiness>(bytes, |a, b| a == b);
    round_trip::<Heartbeat>(bytes, |a, b| a == b);
    round_trip::<GetInfoRequest>(bytes, |a, b| a == b);
    round_trip::<GetInfoResponse>(bytes, |a, b| a == b);
    round_trip::<Vector31>(bytes, |a, b| bits_equal(&a.value, &b.value));
    round_trip::<DoF3rdTs>(bytes, |a, b| {
        let (p, q) = (&a.value, &b.value);
        a.timestamp == b.timestamp
            && bits_equal(
                &[
                    p.kinematics.base.position,
                    p.kinematics.base.velocity,
                    p.kinematics.acceleration,
                    p.force,
                ],
                &[
                    q.kinematics.base.position,
                    q.kinematics.base.velocity,
                    q.kinematics.acceleration,
                    q.force,
                ],
            )
    });
});
