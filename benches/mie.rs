//! Mie benchmarks (criterion): one sphere's coefficients, the product-rule job
//! (d = 5 µm, σ = 0.25, 41 sizes × 31 wavelengths, 2251 angles), and the matrix product at
//! its shapes through the GEMM nephele uses (the `gemm` crate, faer's kernels) against
//! matrixmultiply (the earlier GEMM), both dispatching to the CPU's SIMD level at run
//! time: which one a build should take, measured in one run on the machine at hand
//! (docs/mie.md). The comparison
//! against miepython and numpy's DGEMM lives in scripts/bench_mie.py (same machine, same run).

use criterion::{criterion_group, criterion_main, Criterion, Throughput};
use nephele::mie::batch::{gemm_strided, Gemm};
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

/// The SIMD level the GEMMs can dispatch to on this CPU.
fn simd_level() -> &'static str {
    #[cfg(target_arch = "x86_64")]
    {
        if is_x86_feature_detected!("avx512f") {
            return "x86-64-v4 (AVX-512F)";
        }
        if is_x86_feature_detected!("avx2") && is_x86_feature_detected!("fma") {
            return "x86-64-v3 (AVX2, FMA)";
        }
        "x86-64 (SSE2)"
    }
    #[cfg(not(target_arch = "x86_64"))]
    "not x86-64"
}

/// C (m × n) = A (m × k) B (k × n), the block product of `mie::batch` (m = 2 × its `BLOCK`
/// spheres, re and im rows; k Mie orders: 40 ≈ d = 5 µm at 700 nm, 170 ≈ 20 µm at 400 nm, 500
/// the size tail; n = 128, the panel of angles the job multiplies, or all 2251 angles);
/// throughput in flops (2 m k n per product).
fn gemm_shapes(c: &mut Criterion) {
    eprintln!("CPU SIMD level: {}", simd_level());
    let m = 2 * nephele::mie::batch::BLOCK;
    let shapes = [128usize, 2251]
        .into_iter()
        .flat_map(|n| [40usize, 170, 500].map(|k| (k, n)));
    for (k, n) in shapes {
        let a: Vec<f64> = (0..m * k)
            .map(|i| ((i * 7919) % 1000) as f64 / 1e3)
            .collect();
        let b: Vec<f64> = (0..k * n)
            .map(|i| ((i * 104729) % 1000) as f64 / 1e3)
            .collect();
        let mut out = vec![0.0; m * n];
        let mut group = c.benchmark_group(format!("gemm {m}x{k}x{n}"));
        group.throughput(Throughput::Elements(2 * (m * k * n) as u64));
        for (name, which) in [
            ("matrixmultiply", Gemm::MatrixMultiply),
            ("gemm crate", Gemm::Faer),
        ] {
            group.bench_function(name, |bench| {
                bench.iter(|| gemm_strided(which, m, k, n, &a, &b, n, &mut out))
            });
        }
        group.finish();
    }
}

criterion_group!(benches, coefficients, product_rule_job, gemm_shapes);
criterion_main!(benches);
