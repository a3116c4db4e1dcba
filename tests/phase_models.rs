//! Every phase model: normalisation, mean cosine, inverse CDF and sample/pdf consistency, at
//! ordinary and extreme parameters, checked by adaptive quadrature of p (not of our CDFs).

use nephele::stats::adaptive_simpson;
use nephele_runtime::frame::dot;
use nephele_runtime::phase::{
    Draine, HenyeyGreenstein, Rayleigh, ReynoldsMcCormick, Schlick, TwoTermHg, VonMisesFisher, Xlf,
};
use nephele_runtime::presets::{jendersie_deon, nephele_refit};
use nephele_runtime::PhaseFunction;
use std::f64::consts::PI;

/// ∫_{a}^{b} 2π p(μ) μ^k dμ.
fn moment(p: &dyn PhaseFunction<f64>, a: f64, b: f64, k: i32) -> f64 {
    adaptive_simpson(&|mu| 2.0 * PI * p.eval(mu) * mu.powi(k), a, b, 1e-11)
}

fn models() -> Vec<(String, Box<dyn PhaseFunction<f64>>)> {
    let mut v: Vec<(String, Box<dyn PhaseFunction<f64>>)> = Vec::new();
    for g in [-0.99, -0.5, -1e-5, 0.0, 1e-4, 0.3, 0.85, 0.99] {
        v.push((format!("HG g={g}"), Box::new(HenyeyGreenstein::new(g))));
    }
    for (g, a) in [
        (0.0, 1.0),
        (1e-5, 250.0),
        (5e-4, 250.0),
        (0.02, 250.0),
        (0.3, 0.5),
        (0.6, 20.0),
        (-0.7, 3.0),
        (0.99, 250.0),
        (-0.99, 250.0),
        (0.5, 0.0),
    ] {
        v.push((format!("Draine g={g} a={a}"), Box::new(Draine::new(g, a))));
    }
    v.push((
        "Cornette-Shanks g=0.8".into(),
        Box::new(Draine::cornette_shanks(0.8)),
    ));
    v.push(("Rayleigh".into(), Box::new(Rayleigh)));
    for g in [-0.47, -0.1, 0.09, 1e-6, 0.2, 0.476955] {
        v.push((format!("XLF g={g}"), Box::new(Xlf::new(g).unwrap())));
    }
    for (g, a) in [
        (0.5, 0.5),
        (0.8, 1.0),
        (-0.6, 2.5),
        (0.3, 0.1),
        (5e-5, 1.5),
        (0.95, 0.3),
    ] {
        v.push((
            format!("Reynolds-McCormick g={g} a={a}"),
            Box::new(ReynoldsMcCormick::new(g, a)),
        ));
    }
    for k in [-0.9, -1e-4, 0.0, 0.5, 0.95] {
        v.push((format!("Schlick k={k}"), Box::new(Schlick::new(k))));
    }
    for kappa in [0.0, 1e-5, 0.5, 10.0, 1000.0] {
        v.push((
            format!("vMF kappa={kappa}"),
            Box::new(VonMisesFisher::new(kappa)),
        ));
    }
    v.push((
        "two-term HG".into(),
        Box::new(TwoTermHg::two_term(0.9, -0.4, 0.7)),
    ));
    for d in [0.05, 0.5, 3.0, 10.0, 50.0] {
        let p = jendersie_deon(d);
        v.push((format!("HG+Draine d={d}"), Box::new(p.phase::<f64>())));
    }
    v
}

#[test]
fn normalised_to_1e_6() {
    for (name, p) in models() {
        let total = moment(p.as_ref(), -1.0, 1.0, 0);
        assert!((total - 1.0).abs() < 1e-6, "{name}: ∮ p dΩ = {total}");
    }
}

#[test]
fn mean_cosine_matches_quadrature() {
    for (name, p) in models() {
        let want = moment(p.as_ref(), -1.0, 1.0, 1);
        let got = p.mean_cosine().expect("closed form");
        assert!(
            (got - want).abs() < 1e-8,
            "{name}: ⟨μ⟩ = {got}, quadrature {want}"
        );
    }
}

#[test]
fn single_lobe_samplers_invert_the_cdf() {
    // F(sample_mu(ξ)) = ξ, with F by quadrature of p.
    for (name, p) in models()
        .into_iter()
        .filter(|(n, _)| !n.starts_with("two") && !n.starts_with("HG+"))
    {
        for i in 0..=40 {
            let xi = i as f64 / 40.0;
            let mu = p.sample_mu(xi);
            assert!((-1.0..=1.0).contains(&mu), "{name}: μ = {mu}");
            let f = moment(p.as_ref(), -1.0, mu, 0);
            assert!((f - xi).abs() < 2e-7, "{name}: F(sample(ξ = {xi})) = {f}");
        }
    }
}

#[test]
fn sample_pdf_is_the_pdf_of_the_returned_direction() {
    let wi = [0.48, -0.6, 0.64];
    for (name, p) in models() {
        for (x1, x2) in [(0.1, 0.7), (0.5, 0.2), (0.93, 0.55), (0.999, 0.01)] {
            let (wo, pdf) = p.sample(x1, x2, wi);
            let len = dot(wo, wo).sqrt();
            assert!((len - 1.0).abs() < 1e-12, "{name}: |wo| = {len}");
            let mu = dot(wi, wo);
            assert!(
                (pdf / p.pdf(mu) - 1.0).abs() < 1e-6,
                "{name}: pdf {pdf} vs pdf(μ) {}",
                p.pdf(mu)
            );
        }
    }
}

#[test]
fn draine_f32_samples_have_cdf_error_below_1e_5() {
    // Dense grid over the fits' range: g ∈ [−0.99, 0.99], α ∈ [0, 250], ξ ∈ [0, 1]; the CDF of
    // the f32 sample is evaluated exactly (f64 quadrature of p). Inside a strong peak an f32 μ
    // cannot do better than the CDF's change over one f32 ulp of μ (6e-8 near |μ| = 1 is 3e-4 of
    // CDF at |g| = 0.99): the error allowed is 1e-5 plus that representation limit, and the
    // sample must be the exact root rounded (within one ulp).
    let mut worst = (0.0f64, 0.0, 0.0, 0.0);
    for gi in 0..=22 {
        let g = -0.99 + 1.98 * gi as f64 / 22.0;
        let g = if gi == 11 { 1e-6 } else { g };
        for a in [0.0, 0.5, 1.0, 5.0, 30.0, 100.0, 250.0] {
            let p32 = Draine::<f32>::new(g as f32, a as f32);
            let p64 = Draine::<f64>::new((g as f32) as f64, (a as f32) as f64);
            for i in 0..=50 {
                let xi = i as f64 / 50.0;
                let mu32 = p32.sample_mu(xi as f32);
                let mu = mu32 as f64;
                let ulp = (f32::from_bits(mu32.to_bits() + 1) - mu32).abs() as f64;
                let limit = 2.0 * PI * p64.eval(mu) * ulp;
                let exact = p64.sample_mu((xi as f32) as f64);
                assert!(
                    (exact - mu).abs() <= 1.01 * ulp,
                    "g = {g}, α = {a}, ξ = {xi}: {mu} vs exact {exact}"
                );
                let err = ((moment(&p64, -1.0, mu, 0) - xi).abs() - limit).max(0.0);
                if err > worst.0 {
                    worst = (err, g, a, xi);
                }
            }
        }
    }
    assert!(
        worst.0 <= 1e-5,
        "worst CDF error {:.2e} at g = {}, α = {}, ξ = {}",
        worst.0,
        worst.1,
        worst.2,
        worst.3
    );
    println!(
        "worst f32 Draine CDF error {:.2e} at g = {}, α = {}, ξ = {}",
        worst.0, worst.1, worst.2, worst.3
    );
}

#[test]
fn xlf_is_non_negative_up_to_its_limit_and_refused_beyond() {
    use nephele_runtime::phase::XLF_G_MAX;
    for g in [XLF_G_MAX, -XLF_G_MAX] {
        let p = Xlf::new(g).unwrap();
        let min = (0..=2000)
            .map(|i| p.eval(-1.0 + i as f64 / 1000.0))
            .fold(f64::INFINITY, f64::min);
        assert!((0.0..1e-4).contains(&min), "g = {g}: min p = {min}");
    }
    assert!(Xlf::new(0.48).is_none() && Xlf::new(-0.9).is_none() && Xlf::new(f64::NAN).is_none());
    // The published form is not normalised: ∮ p̃ dΩ ≠ 1 (1.07 at g = 0.3).
    let g: f64 = 0.3;
    let raw = |mu: f64| {
        (1.5 * (1.0 - g * g) / (2.0 + g * g) * (1.0 + mu * mu) / (1.0 + g * g - 2.0 * g * mu)
            + g * mu)
            / (4.0 * PI)
    };
    let total = adaptive_simpson(&|mu| 2.0 * PI * raw(mu), -1.0, 1.0, 1e-12);
    assert!((total - 1.0).abs() > 0.01, "{total}");
}

#[test]
fn preset_matches_the_paper_and_jumps_where_documented() {
    // Paper eqs. 4–7 at d = 10 µm, evaluated by hand from the published constants.
    let p = jendersie_deon(10.0);
    let d: f64 = 10.0;
    assert_eq!(
        nephele_runtime::phase::HgDraine::<f64>::from_diameter(10.0),
        p.phase::<f64>()
    );
    assert!((p.g_hg - (-0.0990567 / (d - 1.67154)).exp()).abs() < 1e-15);
    assert!((p.alpha - (3.62489 - 8.29288 / (d + 5.52825)).exp()).abs() < 1e-12);
    let documented = [
        (5.0, 0.96904, 0.97068, 18.071, 17.068),
        (1.5, 0.83849, 0.88565, 250.0, 9.278),
        (0.1, 0.13800, 0.10383, 250.0, 250.0),
    ];
    for (edge, g_below, g_above, a_below, a_above) in documented {
        let below = jendersie_deon(edge * (1.0 - 1e-9));
        let above = jendersie_deon(edge * (1.0 + 1e-9));
        assert!(
            (below.g_hg - g_below).abs() < 1e-5 && (above.g_hg - g_above).abs() < 1e-5,
            "{edge} µm g_HG"
        );
        assert!(
            (below.alpha - a_below).abs() < 1e-3 && (above.alpha - a_above).abs() < 1e-3,
            "{edge} µm α"
        );
    }
    for (edge, what) in [(5.0, "5 µm"), (1.5, "1.5 µm"), (0.1, "0.1 µm")] {
        let below = jendersie_deon(edge * (1.0 - 1e-9));
        let above = jendersie_deon(edge * (1.0 + 1e-9));
        println!("{what}: below {below:?}\n        above {above:?}");
        // The branches are separate fits: they do not meet (the module docs tabulate the jumps).
        assert!(below != above);
    }
}

#[test]
fn refit_preset_stays_inside_the_fit_bounds_and_near_the_paper_above_5_um() {
    let mut d = 0.01;
    while d < 200.0 {
        let p = nephele_refit(d);
        let ok = p.g_hg.abs() < 1.0
            && p.g_d.abs() < 1.0
            && (0.0..=250.0).contains(&p.alpha)
            && (0.0..=1.0).contains(&p.w_d);
        assert!(ok, "d = {d}: {p:?}");
        if (5.0..=50.0).contains(&d) {
            // Two fits of the same Mie setup with the same forms: within the agreement spec 30
            // expects of a reproduction (0.02 in g_HG, g_D, w_D; 20 % in α).
            let q = jendersie_deon(d);
            let dg = [p.g_hg - q.g_hg, p.g_d - q.g_d, p.w_d - q.w_d];
            assert!(dg.iter().all(|x| x.abs() <= 0.02), "d = {d}: {dg:?}");
            assert!(
                (p.alpha / q.alpha - 1.0).abs() <= 0.2,
                "d = {d}: α {} vs {}",
                p.alpha,
                q.alpha
            );
        }
        d *= 1.01;
    }
    // Below 0.1 µm the refit is the paper's Rayleigh-limit branch.
    assert_eq!(nephele_refit(0.05), jendersie_deon(0.05));
    for edge in [0.1, 1.5, 5.0] {
        let (below, above) = (
            nephele_refit(edge * (1.0 - 1e-9)),
            nephele_refit(edge * (1.0 + 1e-9)),
        );
        println!("{edge} µm: below {below:?}\n        above {above:?}");
    }
}

/// What f32 (C, WGSL, a renderer) gives up against f64 (Python, the toolchain), model by model
/// at the parameters the Python module is used with: the largest relative difference of p over
/// 2001 cosines and the largest difference of the sampled cosine over 2001 ξ, both from the
/// same (f32-representable) parameters. docs/integration.md quotes the printed figures.
#[test]
fn f32_follows_f64_within_a_few_ulps_of_the_cosine() {
    use nephele_runtime::phase::HgDraine;
    fn both<P32: PhaseFunction<f32>, P64: PhaseFunction<f64>>(
        name: &str,
        a: P32,
        b: P64,
    ) -> (f64, f64) {
        let (mut eval, mut sample) = (0.0f64, 0.0f64);
        for i in 0..=2000 {
            let x = i as f64 / 2000.0;
            let mu = (2.0 * x - 1.0) as f32;
            let (p32, p64) = (a.eval(mu) as f64, b.eval(mu as f64));
            eval = eval.max((p32 / p64 - 1.0).abs());
            let xi = (x.min(1.0 - 1e-7)) as f32;
            sample = sample.max((a.sample_mu(xi) as f64 - b.sample_mu(xi as f64)).abs());
        }
        eprintln!("{name}: p within {eval:.1e} (relative), sampled cosine within {sample:.1e}");
        (eval, sample)
    }
    let r = [
        both(
            "HG g=0.85",
            HenyeyGreenstein::new(0.85f32),
            HenyeyGreenstein::new(0.85f32 as f64),
        ),
        both(
            "Draine g=0.5 a=1",
            Draine::new(0.5f32, 1.0),
            Draine::new(0.5, 1.0),
        ),
        both(
            "Schlick k=0.6",
            Schlick::new(0.6f32),
            Schlick::new(0.6f32 as f64),
        ),
        both(
            "vMF kappa=8",
            VonMisesFisher::new(8.0f32),
            VonMisesFisher::new(8.0),
        ),
        both("Rayleigh", Rayleigh, Rayleigh),
        both(
            "two-term HG",
            TwoTermHg::two_term(0.9f32, -0.3, 0.8),
            TwoTermHg::two_term(0.9f32 as f64, -0.3f32 as f64, 0.8f32 as f64),
        ),
        both(
            "HG+Draine d=10 um",
            HgDraine::<f32>::from_diameter(10.0),
            HgDraine::<f64>::from_diameter(10.0),
        ),
    ];
    for (eval, sample) in r {
        // f32 carries 6e-8 relative; p's steepest parts (HG at g = 0.85 near μ = 1) amplify
        // an ulp of μ by |d ln p / d ln μ| ≲ 40, and the samplers invert a CDF in f32.
        assert!(eval < 1e-5, "{eval}");
        assert!(sample < 2e-5, "{sample}");
    }
}
