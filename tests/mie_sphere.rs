//! Single-sphere Lorenz–Mie against published values and physical identities.

mod common;

use common::{half_ulp_of_print, reference};
use nephele::mie::angular::AngleBasis;
use nephele::mie::batch::{weighted_intensity, Particle, WeightRow};
use nephele::mie::sphere::n_terms;
use nephele::mie::MieCoefficients;
use nephele::stats::gauss::gauss_legendre;
use num_complex::Complex64;
use proptest::prelude::*;

/// MIEV0 and the reference file write m = n − ik and conjugate amplitudes; ours are B&H's.
fn conj_pair(v: &serde_json::Value) -> Complex64 {
    Complex64::new(v[0].as_f64().unwrap(), -v[1].as_f64().unwrap())
}

/// Entries where the reference file disagrees with double-precision Mie codes beyond its own
/// digits: MIEV0 TESTMI's Re S2(140°) = 0.05669755, while both this code and miepython 3.3
/// (an independent implementation, checked in scripts/check_mie.py) give 0.0566968196 — the
/// imaginary part and S1 at the same angle agree to every digit. Held to 2e-5 relative.
const KNOWN_DISCREPANCIES: [(usize, &str); 1] = [(0, "s2_theta.re")];

fn assert_digits(name: &str, case: usize, got: f64, want: &serde_json::Value) {
    let want = want.as_f64().unwrap();
    let mut tol = half_ulp_of_print(want) * 1.0001;
    if KNOWN_DISCREPANCIES.contains(&(case, name)) {
        tol = 2e-5 * want.abs();
    }
    assert!(
        (got - want).abs() <= tol,
        "case {case} {name}: got {got:.10}, reference {want} (±{tol:e})"
    );
}

#[test]
fn every_reference_vector_to_the_digits_given() {
    let refs = reference("mie-vectors.json");
    let cases = refs["cases"].as_array().unwrap();
    assert!(cases.len() >= 9);
    for (i, c) in cases.iter().enumerate() {
        let m = Complex64::new(c["m"][0].as_f64().unwrap(), c["m"][1].as_f64().unwrap());
        let mut x = c["x"].as_f64().unwrap();
        if c["source"].as_str().unwrap().contains("Bohren") {
            // B&H's example is a sphere of radius 0.525 µm at λ = 0.6328 µm; the file rounds
            // its x = 2π r/λ = 5.2128197 to 5.21282, which moves Q_ext by 8e-7 — more than
            // the half-digit tolerance allows. Use the defining x.
            let exact = 2.0 * std::f64::consts::PI * 0.525 / 0.6328;
            assert!((exact - x).abs() < 5e-6);
            x = exact;
        }
        let coef = MieCoefficients::new(m, x);
        let e = coef.efficiencies();
        let checks = [
            ("qext", e.q_ext),
            ("qsca", e.q_sca),
            ("qback", e.q_back),
            ("g", e.g),
            ("g_qsca", e.g * e.q_sca),
        ];
        for (key, got) in checks {
            if !c[key].is_null() {
                assert_digits(key, i, got, &c[key]);
            }
        }
        let amp_checks = [
            ("s1_0", 0.0, 0),
            ("s1_180", 180.0, 0),
            ("s1_theta", f64::NAN, 0),
            ("s2_theta", f64::NAN, 1),
        ];
        for (key, deg, which) in amp_checks {
            if c[key].is_null() {
                continue;
            }
            let deg = if deg.is_nan() {
                c["theta_deg"].as_f64().unwrap()
            } else {
                deg
            };
            let (s1, s2) = coef.amplitudes(deg.to_radians().cos());
            let got = if which == 0 { s1 } else { s2 };
            let want = conj_pair(&c[key]);
            assert_digits(&format!("{key}.re"), i, got.re, &serde_json::json!(want.re));
            assert_digits(&format!("{key}.im"), i, got.im, &serde_json::json!(want.im));
        }
    }
}

#[test]
fn rayleigh_limit_at_tiny_x() {
    for (n, k) in [(1.333, 0.0), (1.5, 0.1), (1.0001, 0.0), (2.0, 1.0)] {
        let m = Complex64::new(n, k);
        let x = 1e-3;
        let e = MieCoefficients::new(m, x).efficiencies();
        let alpha = (m * m - 1.0) / (m * m + 2.0);
        let q_sca = 8.0 / 3.0 * x.powi(4) * alpha.norm_sqr();
        let q_abs = 4.0 * x * alpha.im;
        assert!(
            (e.q_sca / q_sca - 1.0).abs() < 1e-5,
            "m = {m}: Q_sca {} vs Rayleigh {q_sca}",
            e.q_sca
        );
        assert!(
            (e.q_ext - e.q_sca - q_abs).abs() <= 1e-5 * q_abs.max(e.q_sca),
            "m = {m}: Q_abs"
        );
        assert!(e.g.abs() < 1e-5, "m = {m}: g = {} should vanish", e.g);
    }
}

#[test]
fn large_spheres_are_stable() {
    for (n, k) in [
        (1.333, 0.0),
        (1.33, 1e-5),
        (1.5, 1.0),
        (1.0001, 0.0),
        (2.0, 0.0),
    ] {
        let e = MieCoefficients::new(Complex64::new(n, k), 2e4).efficiencies();
        assert!(
            e.q_ext.is_finite() && e.q_sca.is_finite() && e.g.is_finite(),
            "m = {n}+{k}i"
        );
        // Extinction paradox: Q_ext → 2 for x → ∞ (m − 1 not tiny).
        if n > 1.1 {
            assert!(
                (e.q_ext - 2.0).abs() < 0.02,
                "m = {n}+{k}i: Q_ext = {}",
                e.q_ext
            );
        }
        assert!(e.q_sca <= e.q_ext * (1.0 + 1e-12) && (-1.0..1.0).contains(&e.g));
    }
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(64))]

    /// Optical theorem: Q_ext = 4 Re S(0) / x².
    #[test]
    fn optical_theorem(n in 1.0001f64..2.0, k in prop_oneof![Just(0.0), 1e-6f64..1.0], lx in -3.0f64..4.3) {
        let x = 10f64.powf(lx);
        let coef = MieCoefficients::new(Complex64::new(n, k), x);
        let (s0, _) = coef.amplitudes(1.0);
        let q = coef.efficiencies().q_ext;
        prop_assert!((4.0 * s0.re / (x * x) - q).abs() <= 1e-10 * q.abs().max(1e-300), "x = {x}");
    }

    /// ∮ (|S1|² + |S2|²)/2 dΩ = k² C_sca = π x² Q_sca, and ∮ cos θ (…) = π x² Q_sca g.
    #[test]
    fn scattered_power_by_quadrature(n in 1.01f64..2.0, k in prop_oneof![Just(0.0), 1e-4f64..0.5], x in 0.01f64..60.0) {
        let coef = MieCoefficients::new(Complex64::new(n, k), x);
        let e = coef.efficiencies();
        let (mu, w) = gauss_legendre(2 * n_terms(x) + 20);
        let (mut total, mut first) = (0.0, 0.0);
        for (m, wi) in mu.iter().zip(&w) {
            let (s1, s2) = coef.amplitudes(*m);
            let i = 0.5 * (s1.norm_sqr() + s2.norm_sqr());
            total += 2.0 * std::f64::consts::PI * wi * i;
            first += 2.0 * std::f64::consts::PI * wi * i * m;
        }
        let want = std::f64::consts::PI * x * x * e.q_sca;
        prop_assert!((total / want - 1.0).abs() < 1e-9, "x = {x}: {total} vs {want}");
        prop_assert!((first / want - e.g).abs() < 1e-9, "x = {x}: g");
    }
}

#[test]
fn matrix_product_equals_direct_summation() {
    let particles: Vec<Particle> = [0.5, 3.0, 17.0, 80.0, 240.0, 241.5]
        .iter()
        .map(|&x| Particle {
            x,
            m: Complex64::new(1.333, 1e-3),
        })
        .collect();
    let deg: Vec<f64> = (0..=360).map(|i| i as f64 * 0.5).collect();
    let mu: Vec<f64> = deg.iter().map(|d: &f64| d.to_radians().cos()).collect();
    let basis = AngleBasis::new(&mu, n_terms(241.5));
    let n = particles.len();
    // Identity weights: one output row per sphere.
    let rows: Vec<WeightRow> = (0..n)
        .map(|i| WeightRow {
            start: i,
            weights: vec![1.0],
        })
        .collect();
    let (out, eff, _) = weighted_intensity(&particles, &rows, &basis, &|_| {});
    for (p, part) in particles.iter().enumerate() {
        let coef = MieCoefficients::new(part.m, part.x);
        assert_eq!(eff[p], coef.efficiencies());
        for (j, &m) in mu.iter().enumerate() {
            let (s1, s2) = coef.amplitudes(m);
            let direct = 0.5 * (s1.norm_sqr() + s2.norm_sqr());
            let got = out[p * mu.len() + j];
            assert!(
                (got - direct).abs() <= 1e-11 * direct.max(1e-300) + 1e-300,
                "x = {}, θ = {}°: {got} vs {direct}",
                part.x,
                deg[j]
            );
        }
    }
}

#[test]
fn continuous_through_the_zeros_of_psi() {
    // x = kπ makes ψ_0(x) = sin x vanish (and ψ_n vanish at the zeros of j_n); a ratio-based
    // ψ_n breaks there. The series must be continuous in x through these points.
    for k in [1.0, 5.0, 17.0, 1000.0] {
        let x = k * std::f64::consts::PI;
        for m in [Complex64::new(1.333, 0.0), Complex64::new(1.5, 0.01)] {
            let at = |x: f64| {
                let c = MieCoefficients::with_terms(m, x, n_terms(k * std::f64::consts::PI));
                (c.efficiencies(), c.amplitudes(1.0).0)
            };
            let (e0, s0) = at(x);
            let (e1, s1) = at(x * (1.0 + 1e-12));
            assert!(
                (e0.q_sca / e1.q_sca - 1.0).abs() < 1e-8,
                "x = {k}π, m = {m}: {} vs {}",
                e0.q_sca,
                e1.q_sca
            );
            assert!(
                (s0 - s1).norm() < 1e-8 * s1.norm(),
                "x = {k}π, m = {m}: S(0)"
            );
        }
    }
}
