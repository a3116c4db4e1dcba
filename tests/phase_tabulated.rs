//! The tabulated phase function built from stage-1 Mie tables: normalisation, agreement with
//! the table at its nodes, and chi-square of its sampler (f64 and f32) at 10 and 50 µm, where
//! the forward peak is narrower than f32's resolution in μ.

use nephele::mie::{MieJob, PhaseTable, SizeRule};
use nephele::stats::adaptive_simpson;
use nephele::stats::chi2::{chi2_sphere, Chi2Config};
use nephele_runtime::phase::{Cosine, TabulatedTable};
use nephele_runtime::PhaseFunction;
use std::f64::consts::PI;

fn mie(d: f64) -> PhaseTable {
    let job = MieJob::paper(d, SizeRule::Product { sizes: 41 }, 16);
    job.compute(&|_, _| {}).unwrap().0.remove(0)
}

/// The cosine of a unit direction around +z, with 1 − μ = (x² + y²)/(1 + z) exact near +z.
fn cosine_of(d: [f64; 3]) -> Cosine<f64> {
    if d[2] > 0.0 {
        Cosine {
            mu: d[2],
            one_minus_mu: (d[0] * d[0] + d[1] * d[1]) / (1.0 + d[2]),
        }
    } else {
        Cosine::from_mu(d[2])
    }
}

#[test]
fn tabulated_mie_tables_are_normalised_exact_at_nodes_and_sample_correctly() {
    for d in [10.0, 50.0] {
        let t = mie(d);
        let table = TabulatedTable::<f64>::from_phase(&t.theta_deg, &t.phase).unwrap();
        let p = table.view();
        // ∮ p dΩ = ∫ 2π p sin θ dθ, by quadrature in θ (each linear piece integrates exactly).
        let at = |th: f64| Cosine {
            mu: th.cos(),
            one_minus_mu: 2.0 * (0.5 * th).sin().powi(2),
        };
        let total: f64 = t
            .theta_deg
            .windows(2)
            .map(|w| {
                let (a, b) = (w[0].to_radians(), w[1].to_radians());
                adaptive_simpson(
                    &|th| 2.0 * PI * p.pdf_cosine(at(th)) * th.sin(),
                    a,
                    b,
                    1e-14,
                )
            })
            .sum();
        assert!((total - 1.0).abs() < 1e-9, "d = {d}: ∮ p dΩ = {total}");
        // At the nodes the table is the Mie phase function up to its quadrature normalisation.
        for i in (1..t.theta_deg.len() - 1).step_by(50) {
            let got = p.pdf_cosine(at(t.theta_deg[i].to_radians())) * t.quadrature_norm;
            assert!(
                (got / t.phase[i] - 1.0).abs() < 1e-9,
                "d = {d}, θ = {}",
                t.theta_deg[i]
            );
        }
        // Chi-square of the samplers against the f64 pdf.
        let t32 = TabulatedTable::<f32>::from_phase(&t.theta_deg, &t.phase).unwrap();
        let p32 = t32.view();
        let cfg = Chi2Config::default();
        let pdf = |dir: [f64; 3]| p.pdf_cosine(cosine_of(dir));
        let r64 = chi2_sphere(&cfg, |a, b| p.sample(a, b, [0.0, 0.0, 1.0]).0, pdf);
        let r32 = chi2_sphere(
            &cfg,
            |a, b| {
                p32.sample(a as f32, b as f32, [0.0f32, 0.0, 1.0])
                    .0
                    .map(f64::from)
            },
            pdf,
        );
        assert!(
            r64.passes(0.01, 4) && r32.passes(0.01, 4),
            "d = {d}: f64 {r64:?}, f32 {r32:?}"
        );
        // The pdf returned with a sample is the pdf of the returned direction.
        for (x1, x2) in [(0.05, 0.3), (0.5, 0.9), (0.97, 0.1)] {
            let (dir, pdf_s) = p.sample(x1, x2, [0.0, 0.0, 1.0]);
            assert!((pdf_s / pdf(dir) - 1.0).abs() < 1e-6, "d = {d}: ξ = {x1}");
        }
    }
}

/// Like every single-lobe model, the table samples μ = −1 at ξ = 0 and μ grows with ξ (its CDF
/// runs in θ, forward first; docs/conventions.md, Sampling tables).
#[test]
fn the_tabulated_sampler_runs_from_back_to_forward() {
    let t = mie(10.0);
    let table = TabulatedTable::<f64>::from_phase(&t.theta_deg, &t.phase).unwrap();
    let p = table.view();
    let mu: Vec<f64> = (0..=4096).map(|k| p.sample_mu(k as f64 / 4096.0)).collect();
    assert!(
        mu[0] < -0.999 && mu[4096] > 0.999,
        "{} → {}",
        mu[0],
        mu[4096]
    );
    assert!(mu.windows(2).all(|w| w[1] >= w[0]), "decreases");
}

#[test]
fn bad_tables_are_refused() {
    use nephele_runtime::phase::TableError;
    assert_eq!(
        TabulatedTable::<f32>::from_phase(&[0.0, 90.0], &[1.0, 1.0]).unwrap_err(),
        TableError::Angles
    );
    assert_eq!(
        TabulatedTable::<f32>::from_phase(&[0.0, 180.0], &[1.0]).unwrap_err(),
        TableError::Shape
    );
    assert_eq!(
        TabulatedTable::<f32>::from_phase(&[0.0, 180.0], &[1.0, f64::NAN]).unwrap_err(),
        TableError::Values
    );
    assert!(TabulatedTable::<f32>::from_phase(&[0.0, 90.0, 180.0], &[1.0, 1.0, 1.0]).is_ok());
}
