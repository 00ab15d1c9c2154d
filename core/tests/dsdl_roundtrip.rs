//! Property tests: decode(encode(x)) == x for every type, and decoding never panics.

use propid_core::dsdl::{
    DataType, DoF3rdTs, GetInfoResponse, Heartbeat, Readiness, Timestamp, Vector31, Version,
};
use proptest::prelude::*;

proptest! {
    #[test]
    fn dof3rdts_round_trips(us in 0u64..(1 << 53), p: f32, v: f32, a: f32, f: f32) {
        let mut m = DoF3rdTs { timestamp: Timestamp { microsecond: us }, ..Default::default() };
        m.value.kinematics.base.position = p;
        m.value.kinematics.base.velocity = v;
        m.value.kinematics.acceleration = a;
        m.value.force = f;
        let mut buf = [0u8; 23];
        m.serialize(&mut buf);
        let back = DoF3rdTs::deserialize(&buf).unwrap();
        prop_assert_eq!(back.timestamp, m.timestamp);
        prop_assert_eq!(back.value.force.to_bits(), f.to_bits());
        prop_assert_eq!(back.value.kinematics.base.velocity.to_bits(), v.to_bits());
    }

    #[test]
    fn vector31_round_trips_through_float16(values in proptest::array::uniform31(-70000f32..70000f32)) {
        let m = Vector31 { value: values };
        let mut buf = [0u8; 62];
        m.serialize(&mut buf);
        let back = Vector31::deserialize(&buf).unwrap();
        for (x, y) in values.iter().zip(back.value) {
            let want = half::f16::from_f32(x.clamp(-65504.0, 65504.0)).to_f32();
            prop_assert_eq!(y, want);
        }
        // Encoding the decoded value again is the identity on the wire.
        let mut again = [0u8; 62];
        back.serialize(&mut again);
        prop_assert_eq!(buf, again);
    }

    #[test]
    fn heartbeat_and_readiness_round_trip(uptime: u32, health in 0u8..4, mode in 0u8..8, vssc: u8, r in 0u8..4) {
        let hb = Heartbeat { uptime, health, mode, vendor_specific_status_code: vssc };
        let mut buf = [0u8; 7];
        hb.serialize(&mut buf);
        prop_assert_eq!(Heartbeat::deserialize(&buf).unwrap(), hb);
        let mut b1 = [0u8; 1];
        Readiness { value: r }.serialize(&mut b1);
        prop_assert_eq!(Readiness::deserialize(&b1).unwrap().value, r);
    }

    #[test]
    fn get_info_round_trips(name in proptest::collection::vec(any::<u8>(), 0..=50),
                            cert in proptest::collection::vec(any::<u8>(), 0..=222),
                            crc: Option<u64>, rev: u64, major: u8) {
        let m = GetInfoResponse {
            software_version: Version { major, minor: 1 },
            software_vcs_revision_id: rev,
            name: heapless::Vec::from_slice(&name).unwrap(),
            software_image_crc: crc,
            certificate_of_authenticity: heapless::Vec::from_slice(&cert).unwrap(),
            ..Default::default()
        };
        let mut buf = [0u8; 313];
        let n = m.serialize(&mut buf);
        prop_assert_eq!(GetInfoResponse::deserialize(&buf[..n]).unwrap(), m);
    }

    #[test]
    fn decoders_accept_any_bytes_without_panicking(bytes in proptest::collection::vec(any::<u8>(), 0..400)) {
        let _ = Readiness::deserialize(&bytes).unwrap();
        let _ = Vector31::deserialize(&bytes).unwrap();
        let _ = DoF3rdTs::deserialize(&bytes).unwrap();
        let _ = Heartbeat::deserialize(&bytes).unwrap();
        if let Ok(m) = GetInfoResponse::deserialize(&bytes) {
            let mut buf = [0u8; 313];
            let n = m.serialize(&mut buf);
            prop_assert_eq!(GetInfoResponse::deserialize(&buf[..n]).unwrap(), m);
        }
    }
}
