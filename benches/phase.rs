//! Phase-model benchmarks (criterion): eval and sample of every runtime model, f32 and f64,
//! static dispatch, 1024 calls per iteration (divide the reported time by 1024 for ns per call).
//! The side-by-side comparison with benches/baselines/phase_ref.c is scripts/bench_phase.sh.

use criterion::{criterion_group, criterion_main, Criterion, Throughput};
use nephele_runtime::phase::{
    Draine, HenyeyGreenstein, Rayleigh, ReynoldsMcCormick, Schlick, TabulatedTable, TwoTermHg,
    VonMisesFisher, Xlf,
};
use nephele_runtime::presets::jendersie_deon;
use nephele_runtime::{PhaseFunction, Real};
use std::hint::black_box;

const N: usize = 1024;

fn inputs<F: Real>() -> Vec<F> {
    (0..N).map(|i| F::of((i as f64 + 0.5) / N as f64)).collect()
}

fn bench_model<F: Real, P: PhaseFunction<F>>(c: &mut Criterion, name: &str, p: &P) {
    let xi = inputs::<F>();
    let mu: Vec<F> = xi.iter().map(|&x| F::of(2.0) * x - F::of(1.0)).collect();
    let mut group = c.benchmark_group(name);
    group.throughput(Throughput::Elements(N as u64));
    group.bench_function("eval", |b| {
        b.iter(|| mu.iter().fold(F::of(0.0), |a, &m| a + p.eval(black_box(m))))
    });
    group.bench_function("sample", |b| {
        b.iter(|| {
            xi.iter()
                .fold(F::of(0.0), |a, &x| a + p.sample_mu(black_box(x)))
        })
    });
    group.finish();
}

fn models<F: Real>(c: &mut Criterion, prec: &str) {
    let blend = jendersie_deon(20.0);
    bench_model(
        c,
        &format!("{prec}/hg"),
        &HenyeyGreenstein::new(F::of(0.85)),
    );
    bench_model(
        c,
        &format!("{prec}/draine"),
        &Draine::new(F::of(blend.g_d), F::of(blend.alpha)),
    );
    bench_model(
        c,
        &format!("{prec}/draine-g0.02-a250"),
        &Draine::new(F::of(0.02), F::of(250.0)),
    );
    bench_model(c, &format!("{prec}/hg-draine-20um"), &blend.phase::<F>());
    bench_model::<F, _>(c, &format!("{prec}/rayleigh"), &Rayleigh);
    bench_model(c, &format!("{prec}/schlick"), &Schlick::new(F::of(0.8)));
    bench_model(c, &format!("{prec}/vmf"), &VonMisesFisher::new(F::of(20.0)));
    bench_model(
        c,
        &format!("{prec}/two-term-hg"),
        &TwoTermHg::two_term(F::of(0.9), F::of(-0.3), F::of(0.8)),
    );
    bench_model(
        c,
        &format!("{prec}/reynolds-mccormick"),
        &ReynoldsMcCormick::new(F::of(0.8), F::of(1.5)),
    );
    bench_model(
        c,
        &format!("{prec}/xlf"),
        &Xlf::new(F::of(0.3)).expect("valid g"),
    );
}

fn all(c: &mut Criterion) {
    models::<f32>(c, "f32");
    models::<f64>(c, "f64");
    // The 50 µm Mie table of `nephele mie` (product rule 41 × 16: the peak is what matters here).
    let job = nephele::mie::MieJob::paper(50.0, nephele::mie::SizeRule::Product { sizes: 41 }, 16);
    let mie = job.compute(&|_, _| {}).expect("Mie table").0.remove(0);
    let table = TabulatedTable::<f32>::from_phase(&mie.theta_deg, &mie.phase).expect("valid table");
    bench_model(c, "f32/tabulated-mie-50um", &table.view());
}

criterion_group!(benches, all);
criterion_main!(benches);
