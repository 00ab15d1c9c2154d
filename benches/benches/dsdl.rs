//! DSDL encode and decode cost of each type propid speaks (ns per message).

use criterion::{criterion_group, criterion_main, Criterion};
use propid_core::dsdl::{DataType, DoF3rdTs, GetInfoResponse, Heartbeat, Readiness, Vector31};
use std::hint::black_box;

fn bench_type<T: DataType>(c: &mut Criterion, name: &str, value: T) {
    let mut group = c.benchmark_group(format!("dsdl/{name}"));
    let mut buf = [0u8; 512];
    group.bench_function("encode", |b| {
        b.iter(|| black_box(&value).serialize(black_box(&mut buf)))
    });
    let n = value.serialize(&mut buf);
    let payload = buf[..n].to_vec();
    group.bench_function("decode", |b| {
        b.iter(|| T::deserialize(black_box(&payload)).ok())
    });
    group.finish();
}

fn dsdl(c: &mut Criterion) {
    bench_type(
        c,
        "Readiness",
        Readiness {
            value: Readiness::ENGAGED,
        },
    );
    let mut v = Vector31::splat(0.5);
    v.value[3] = -1234.5;
    bench_type(c, "Vector31", v);
    let mut fb = DoF3rdTs::default();
    fb.timestamp.microsecond = 123_456_789;
    fb.value.kinematics.base.velocity = 812.5;
    fb.value.force = 0.031;
    bench_type(c, "DoF3rdTs", fb);
    bench_type(
        c,
        "Heartbeat",
        Heartbeat {
            uptime: 3600,
            ..Default::default()
        },
    );
    let mut info = GetInfoResponse::default();
    info.name.extend_from_slice(b"org.propid.drive").unwrap();
    bench_type(c, "GetInfoResponse", info);
}

criterion_group!(benches, dsdl);
criterion_main!(benches);
