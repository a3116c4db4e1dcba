//! Mie benchmarks (criterion): one sphere's coefficients, and the product-rule job of
//! issue 2 (d = 5 µm, σ = 0.25, 41 sizes × 31 wavelengths, 2251 angles). The comparison
//! against miepython lives in scripts/bench_mie.py (same machine, same run).

use criterion::{criterion_group, criterion_main, Criterion};
use nephele::mie::{MieCoefficients, MieJob, SizeRule};
use num_complex::Complex64;
use std::hint::black_box;

fn coefficients(c: &mut Criterion) {
    for x in [10.0, 100.0, 1000.0] {
        c.bench_function(&format!("coefficients x={x}"), |b| {
            b.iter(|| MieCoefficients::new(Complex64::new(1.333, 0.0), black_box(x)).efficiencies())
        });
    }
}

fn product_rule_job(c: &mut Criterion) {
    let job = MieJob::paper(5.0, SizeRule::Product { sizes: 41 }, 31);
    let mut group = c.benchmark_group("polydisperse");
    group.sample_size(10);
    group.bench_function("d=5 product 41x31, 2251 angles", |b| {
        b.iter(|| job.compute(&|_, _| {}).unwrap())
    });
    group.finish();
}

criterion_group!(benches, coefficients, product_rule_job);
criterion_main!(benches);
