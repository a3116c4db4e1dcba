//! The evaluators under whichever math backend the build selected (std, `libm`, or the built-in
//! `soft_math` of a bare `--no-default-features` build; CI runs this file under all three):
//! results are compared with formulas evaluated by the test harness's own `std`.

use nephele_runtime::phase::{Draine, HenyeyGreenstein};
use nephele_runtime::PhaseFunction;

#[test]
fn hg_eval_matches_the_formula() {
    for g in [-0.99, -0.5, 0.0, 0.3, 0.9, 0.99] {
        let p = HenyeyGreenstein::<f64>::new(g);
        for i in 0..=100 {
            let mu = -1.0 + 2.0 * i as f64 / 100.0;
            let want = (1.0 - g * g)
                / (4.0 * std::f64::consts::PI)
                / (1.0 + g * g - 2.0 * g * mu).powf(1.5);
            let got = p.eval(mu);
            // At g = −0.99, μ = −1 the base 1 + g² − 2gμ = (1 − |g|)² = 1e-4 is formed by
            // cancellation: 1e-16 / 1e-4 relative, whichever way it is computed.
            assert!(
                (got / want - 1.0).abs() < 1e-11,
                "g = {g}, μ = {mu}: {got} vs {want}"
            );
        }
    }
}

#[test]
fn draine_samples_invert_the_cdf() {
    for (g, alpha) in [
        (0.9, 0.0),
        (0.6, 1.0),
        (0.05, 250.0),
        (-0.5, 30.0),
        (0.99, 100.0),
    ] {
        let p64 = Draine::<f64>::new(g, alpha);
        let p32 = Draine::<f32>::new(g as f32, alpha as f32);
        let q64 = Draine::<f64>::new((g as f32) as f64, (alpha as f32) as f64);
        for i in 1..100 {
            let xi = i as f64 / 100.0;
            let mu = p64.sample_mu(xi);
            // The f64 sampler (one Newton step after a Hermite guess) is good to ~1e-10; allow
            // 1e-9 plus what a few ulp of μ move the CDF inside a strong peak.
            let tol = 1e-9 + 2.0 * std::f64::consts::PI * p64.eval(mu) * 4.0 * f64::EPSILON;
            let err = (p64.cdf(mu) - xi).abs();
            assert!(
                err < tol,
                "g = {g}, α = {alpha}, ξ = {xi}: {err:e} > {tol:e}"
            );
            let mu32 = p32.sample_mu(xi as f32);
            let ulp = (f32::from_bits(mu32.to_bits() + 1) - mu32).abs() as f64;
            let exact = q64.sample_mu((xi as f32) as f64);
            assert!(
                (mu32 as f64 - exact).abs() <= 1.01 * ulp,
                "f32 {mu32} vs {exact}"
            );
        }
    }
}

#[test]
fn sampled_directions_are_unit_and_carry_the_sampled_cosine() {
    let p = HenyeyGreenstein::<f32>::new(0.8);
    let wi = [0.0f32, 0.6, 0.8];
    for i in 0..1000 {
        let (x1, x2) = (
            (i as f32 + 0.5) / 1000.0,
            ((i * 7919) % 1000) as f32 / 1000.0,
        );
        let (wo, pdf) = p.sample(x1, x2, wi);
        let norm = (wo[0] * wo[0] + wo[1] * wo[1] + wo[2] * wo[2]).sqrt();
        assert!((norm - 1.0).abs() < 1e-6, "|wo| = {norm}");
        let mu = wo[0] * wi[0] + wo[1] * wi[1] + wo[2] * wi[2];
        assert!(
            (pdf / p.eval(mu) - 1.0).abs() < 1e-4,
            "pdf {pdf} vs p(μ) {}",
            p.eval(mu)
        );
    }
}
