//! The C ABI's cost beside the Rust call it wraps, in one run: T of all groups and T, c, σ of
//! all groups at 4096 fixed random points (the shipped tables). `cargo bench -p nephele-c`.

use criterion::{criterion_group, Criterion};
use nephele_c::*;
use nephele_runtime::embedded::mie_10um;
use nephele_runtime::transport::{SlabPoint, Transport};
use std::hint::black_box;

fn points() -> Vec<NepheleSlabPoint> {
    let mut rng = nephele_stats::XorShift64::new(0x9E3779B97F4A7C15);
    let mut r = || rng.unit_f32();
    (0..4096)
        .map(|_| {
            let t = 0.5 * 256f32.powf(r());
            NepheleSlabPoint {
                thickness: t,
                mu_l: 0.125 + 0.875 * r(),
                depth: t * r(),
                mu_v: 2.0 * r() - 1.0,
                psi_v: std::f32::consts::PI * r(),
            }
        })
        .collect()
}

fn slab(p: &NepheleSlabPoint) -> SlabPoint<f32> {
    SlabPoint {
        thickness: p.thickness,
        mu_l: p.mu_l,
        depth: p.depth,
        mu_v: p.mu_v,
        psi_v: p.psi_v,
    }
}

fn bench(c: &mut Criterion) {
    let pts = points();
    let rust: Vec<SlabPoint<f32>> = pts.iter().map(slab).collect();
    let tab = mie_10um();
    let mut handle = std::ptr::null_mut();
    assert_eq!(
        unsafe { nephele_tables_embedded(&mut handle) },
        NepheleStatus::Ok
    );
    let mut group = c.benchmark_group("c_abi_4096_points");
    group.bench_function("T all groups, Rust", |b| {
        let mut out = [0.0f32; 8];
        b.iter(|| {
            for p in &rust {
                tab.transport_all(black_box(p), &mut out);
            }
            out[0]
        })
    });
    group.bench_function("T all groups, C ABI", |b| {
        let mut out = [0.0f32; 8];
        b.iter(|| {
            for p in &pts {
                unsafe { nephele_transport_all(handle, black_box(p), out.as_mut_ptr(), 8) };
            }
            out[0]
        })
    });
    group.bench_function("T c sigma all groups, Rust", |b| {
        let mut out = [Transport::default(); 8];
        b.iter(|| {
            for p in &rust {
                tab.evaluate_all(black_box(p), &mut out);
            }
            out[0].t
        })
    });
    group.bench_function("T c sigma all groups, C ABI", |b| {
        let mut out = [NepheleTransport::default(); 8];
        b.iter(|| {
            for p in &pts {
                unsafe { nephele_evaluate_all(handle, black_box(p), out.as_mut_ptr(), 8) };
            }
            out[0].t
        })
    });
    group.finish();
    unsafe { nephele_tables_free(handle) };
}

criterion_group! {
    name = benches;
    config = Criterion::default().sample_size(30);
    targets = bench
}
/// The ratio the target speaks of, measured so the machine's drift cancels: the Rust call and
/// the C ABI call alternated round by round (T of all groups at the 4096 points, 40 rounds),
/// best round of each and the median of the per-round ratios.
fn alternating_ratio() {
    let pts = points();
    let rust: Vec<SlabPoint<f32>> = pts.iter().map(slab).collect();
    let tab = mie_10um();
    let mut handle = std::ptr::null_mut();
    assert_eq!(
        unsafe { nephele_tables_embedded(&mut handle) },
        NepheleStatus::Ok
    );
    let mut out = [0.0f32; 8];
    let (mut best, mut ratios) = ([f64::INFINITY; 2], Vec::new());
    for _ in 0..40 {
        let start = std::time::Instant::now();
        for p in &rust {
            tab.transport_all(black_box(p), &mut out);
        }
        let a = start.elapsed().as_secs_f64();
        let start = std::time::Instant::now();
        for p in &pts {
            unsafe { nephele_transport_all(handle, black_box(p), out.as_mut_ptr(), 8) };
        }
        let b = start.elapsed().as_secs_f64();
        best = [best[0].min(a), best[1].min(b)];
        ratios.push(b / a);
    }
    ratios.sort_by(f64::total_cmp);
    println!(
        "T of all groups, 4096 points, alternating ×40: Rust best {:.3} ms, C ABI best {:.3} ms \
         (C ABI / Rust: best {:.3}, median of rounds {:.3})",
        1e3 * best[0],
        1e3 * best[1],
        best[1] / best[0],
        ratios[ratios.len() / 2]
    );
    unsafe { nephele_tables_free(handle) };
}

fn main() {
    benches();
    alternating_ratio();
    Criterion::default().configure_from_args().final_summary();
}
