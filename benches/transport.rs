//! The compressed tables at one point (nephele-runtime, f32, one core), on 4096 fixed random
//! points over the whole domain (t = 0.5 … 128 mfp log-uniform, any depth, μ_V ∈ [−1, 1],
//! ψ_V ∈ [0, π], μ_L ∈ [0.1, 1]): T of every group, T of one group, T, c and σ of every group
//! and of one, and order 1 — each timed per point, for the shipped tables (with the halo near
//! the beam) and the same without the halo. Targets: T of all 8 groups ≤ 1 µs, one ≤ 0.3 µs,
//! T + c + σ of all ≤ 2.5 µs.
//!
//! `cargo bench --bench transport`

use criterion::{criterion_group, criterion_main, Criterion, Throughput};
use nephele::compress::ship::without_halo;
use nephele_runtime::embedded::MIE_10UM;
use nephele_runtime::transport::{SlabPoint, Transport, TransportTables};
use nephele_stats::XorShift32;
use std::hint::black_box;

fn points() -> Vec<SlabPoint<f32>> {
    let mut rng = XorShift32::new(12345);
    let mut next = || rng.unit_f32();
    (0..4096)
        .map(|_| {
            let t = 0.5 * 256f32.powf(next());
            SlabPoint {
                depth: next() * t,
                thickness: t,
                mu_v: 2.0 * next() - 1.0,
                psi_v: std::f32::consts::PI * next(),
                mu_l: 0.1 + 0.9 * next(),
            }
        })
        .collect()
}

fn bench(c: &mut Criterion) {
    let points = points();
    let bare = without_halo(MIE_10UM).expect("the tables without their halo");
    for (layout, bytes) in [("shipped", MIE_10UM), ("no_halo", &bare[..])] {
        let tab = TransportTables::from_bytes(bytes).expect("valid tables");
        let mut group = c.benchmark_group(format!("transport_{layout}"));
        group.throughput(Throughput::Elements(points.len() as u64));
        group.bench_function("T all groups", |b| {
            b.iter(|| {
                let mut s = 0.0f32;
                for p in &points {
                    let mut all = [0.0f32; 8];
                    tab.transport_all(p, &mut all);
                    s += all.iter().sum::<f32>();
                }
                black_box(s)
            })
        });
        group.bench_function("T one group", |b| {
            b.iter(|| points.iter().map(|p| tab.transport(3, p)).sum::<f32>())
        });
        group.bench_function("T c sigma all groups", |b| {
            b.iter(|| {
                let mut s = 0.0f32;
                for p in &points {
                    let mut all = [Transport::default(); 8];
                    tab.evaluate_all(p, &mut all);
                    s += all.iter().map(|v| v.t + v.sigma).sum::<f32>();
                }
                black_box(s)
            })
        });
        group.bench_function("T c sigma one group", |b| {
            b.iter(|| points.iter().map(|p| tab.evaluate(3, p).sigma).sum::<f32>())
        });
        group.bench_function("order 1", |b| {
            b.iter(|| points.iter().map(|p| tab.order1(p)).sum::<f32>())
        });
        group.finish();
    }
}

criterion_group!(benches, bench);
criterion_main!(benches);
