//! Estimator cost: one `NormalEquations::update` (ns per sample) for 3 and 6 regressors in f32
//! and f64, and the cost of a solve and a merge for comparison.
//!
//! The update loop hides the samples from the optimiser once, as a slice (`black_box(&data)`),
//! not each sample: a `black_box` per sample sends every pointer and value through the stack
//! (five extra instructions, about 0.6 ns of a 4 ns update), which measures the bench loop,
//! not the estimator. The samples are still unknown to the compiler and each one is stored and
//! summed.

use criterion::{criterion_group, criterion_main, Criterion, Throughput};
use propid_core::estimate::{LoadBounds, LoadEstimator, NormalEquations};
use std::hint::black_box;

fn rows<const N: usize>(n: usize) -> Vec<([f64; N], f64)> {
    let mut s = 0x1234_5678u64;
    let mut next = move || {
        s = s
            .wrapping_mul(6364136223846793005)
            .wrapping_add(1442695040888963407);
        ((s >> 11) as f64) / ((1u64 << 53) as f64) - 0.5
    };
    (0..n)
        .map(|_| (core::array::from_fn(|_| next()), next()))
        .collect()
}

fn update<const N: usize>(c: &mut Criterion) {
    let data = rows::<N>(1024);
    let data32: Vec<([f32; N], f32)> = data
        .iter()
        .map(|(p, y)| (core::array::from_fn(|i| p[i] as f32), *y as f32))
        .collect();
    let mut g = c.benchmark_group(format!("estimator/update/N={N}"));
    g.throughput(Throughput::Elements(data.len() as u64));
    g.bench_function("f64", |b| {
        b.iter(|| {
            let mut ne = NormalEquations::<f64, N>::new();
            for (p, y) in black_box(&data) {
                ne.update(p, *y);
            }
            ne
        })
    });
    g.bench_function("f32", |b| {
        b.iter(|| {
            let mut ne = NormalEquations::<f32, N>::new();
            for (p, y) in black_box(&data32) {
                ne.update(p, *y);
            }
            ne
        })
    });
    g.bench_function("f32 with forgetting", |b| {
        b.iter(|| {
            let mut ne = NormalEquations::<f32, N>::with_forgetting(0.999);
            for (p, y) in black_box(&data32) {
                ne.update(p, *y);
            }
            ne
        })
    });
    g.finish();
}

fn solve(c: &mut Criterion) {
    let mut est = LoadEstimator::<f64>::new();
    let mut w = 500.0;
    for k in 0..2000 {
        let q = 0.05 + 0.04 * (k as f64 * 0.003).sin();
        let a = (q - 1.5e-8 * w * w) / 2e-5;
        est.update(q, w, a);
        w += a * 1e-3;
    }
    let mut g = c.benchmark_group("estimator/solve");
    g.bench_function("load fit with the seed's bounds (f64)", |b| {
        b.iter(|| black_box(&est).estimate(&LoadBounds::default()))
    });
    g.bench_function("unconstrained (f64)", |b| {
        b.iter(|| black_box(&est).estimate_unbounded())
    });
    g.bench_function("merge (f64, N=3)", |b| {
        b.iter(|| {
            let mut x = est;
            x.merge(black_box(&est));
            x
        })
    });
    g.finish();
}

fn benches(c: &mut Criterion) {
    update::<3>(c);
    update::<6>(c);
    solve(c);
}

criterion_group!(estimator, benches);
criterion_main!(estimator);
