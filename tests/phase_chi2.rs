//! Chi-square goodness-of-fit of every runtime phase model's sampler against its own pdf, on
//! the sphere (Mitsuba 3 chi2.py style: 10⁶ samples, 100 cos θ × 50 φ cells, pooled below 5
//! expected, significance 0.01 with Šidák correction over all tests), f64 and f32 samplers.

use nephele::stats::chi2::{chi2_sphere, Chi2Config};
use nephele_runtime::phase::{
    Draine, HenyeyGreenstein, Rayleigh, ReynoldsMcCormick, Schlick, TwoTermHg, VonMisesFisher, Xlf,
};
use nephele_runtime::presets::jendersie_deon;
use nephele_runtime::PhaseFunction;

fn cases() -> Vec<(
    String,
    Box<dyn PhaseFunction<f64> + Sync>,
    Box<dyn PhaseFunction<f32> + Sync>,
)> {
    let mut v: Vec<(
        String,
        Box<dyn PhaseFunction<f64> + Sync>,
        Box<dyn PhaseFunction<f32> + Sync>,
    )> = Vec::new();
    for g in [-0.99, 1e-6, 0.5, 0.99] {
        v.push((
            format!("HG g={g}"),
            Box::new(HenyeyGreenstein::new(g)),
            Box::new(HenyeyGreenstein::new(g as f32)),
        ));
    }
    for (g, a) in [
        (0.7, 3.0),
        (1e-6, 250.0),
        (0.3, 250.0),
        (-0.99, 250.0),
        (0.99, 1.0),
    ] {
        v.push((
            format!("Draine g={g} a={a}"),
            Box::new(Draine::new(g, a)),
            Box::new(Draine::new(g as f32, a as f32)),
        ));
    }
    v.push(("Rayleigh".into(), Box::new(Rayleigh), Box::new(Rayleigh)));
    for g in [-0.3, 0.05, 0.47] {
        v.push((
            format!("XLF g={g}"),
            Box::new(Xlf::new(g).unwrap()),
            Box::new(Xlf::new(g as f32).unwrap()),
        ));
    }
    for (g, a) in [(0.8, 1.0), (-0.6, 2.5), (0.97, 0.3)] {
        v.push((
            format!("Reynolds-McCormick g={g} a={a}"),
            Box::new(ReynoldsMcCormick::new(g, a)),
            Box::new(ReynoldsMcCormick::new(g as f32, a as f32)),
        ));
    }
    for k in [-0.8, 0.95] {
        v.push((
            format!("Schlick k={k}"),
            Box::new(Schlick::new(k)),
            Box::new(Schlick::new(k as f32)),
        ));
    }
    for kappa in [1e-5, 5.0, 500.0] {
        v.push((
            format!("vMF kappa={kappa}"),
            Box::new(VonMisesFisher::new(kappa)),
            Box::new(VonMisesFisher::new(kappa as f32)),
        ));
    }
    v.push((
        "two-term HG".into(),
        Box::new(TwoTermHg::two_term(0.9, -0.4, 0.7)),
        Box::new(TwoTermHg::two_term(0.9f32, -0.4, 0.7)),
    ));
    for d in [0.05, 1.0, 10.0, 50.0] {
        let p = jendersie_deon(d);
        v.push((
            format!("HG+Draine d={d}"),
            Box::new(p.phase::<f64>()),
            Box::new(p.phase::<f32>()),
        ));
    }
    v
}

#[test]
fn every_sampler_passes_chi_square() {
    use rayon::prelude::*;
    let cases = cases();
    let tests = 2 * cases.len();
    let cfg = Chi2Config::default();
    let wi64 = [0.0, 0.0, 1.0];
    let wi32 = [0.0f32, 0.0, 1.0];
    let failures: Vec<String> = cases
        .par_iter()
        .flat_map(|(name, p64, p32)| {
            let pdf = |d: [f64; 3]| p64.pdf(d[2]);
            let r64 = chi2_sphere(&cfg, |a, b| p64.sample(a, b, wi64).0, pdf);
            let r32 = chi2_sphere(
                &cfg,
                |a, b| p32.sample(a as f32, b as f32, wi32).0.map(f64::from),
                pdf,
            );
            [("f64", r64), ("f32", r32)]
                .into_iter()
                .filter(|(_, r)| !r.passes(0.01, tests))
                .map(|(prec, r)| format!("{name} ({prec}): {r:?}"))
                .collect::<Vec<_>>()
        })
        .collect();
    assert!(
        failures.is_empty(),
        "{} of {tests} tests failed:\n{}",
        failures.len(),
        failures.join("\n")
    );
}

/// One direction for every single-lobe sampler (docs/conventions.md, Sampling tables): ξ = 0
/// gives the backward μ = −1 and μ never decreases with ξ. Mixtures pick a lobe with ξ instead.
#[test]
fn single_lobe_samplers_run_from_back_to_forward() {
    for (name, p64, p32) in cases() {
        if name.starts_with("two-term") || name.starts_with("HG+Draine") {
            continue;
        }
        let mu64: Vec<f64> = (0..=4096)
            .map(|k| p64.sample_mu(k as f64 / 4096.0))
            .collect();
        let mu32: Vec<f32> = (0..=4096)
            .map(|k| p32.sample_mu(k as f32 / 4096.0))
            .collect();
        assert!(
            mu64[0] < -0.999 && mu64[4096] > 0.999,
            "{name}: {} → {}",
            mu64[0],
            mu64[4096]
        );
        assert!(
            mu64.windows(2).all(|w| w[1] >= w[0] - 1e-12),
            "{name} (f64) decreases"
        );
        assert!(
            mu32.windows(2).all(|w| w[1] >= w[0] - 1e-6),
            "{name} (f32) decreases"
        );
    }
}
