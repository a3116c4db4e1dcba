//! The walk's lateral bookkeeping in an unbounded medium: a pencil beam along ẑ, n flights of
//! Exp(1) mean free paths joined by the walk's own scattering step. Whatever the phase function,
//! the direction cosines after i scatterings obey E[ω_i·ω_j] = g^|j−i| and, for i ≤ j,
//! E[(ω_i·ẑ)(ω_j·ẑ)] = g^(j−i) (1 + 2 g₂^i)/3 (g = ⟨P₁⟩, g₂ = ⟨P₂⟩ of the phase function), so the
//! position r = Σ s_i ω_i at the n-th scattering has
//!
//!   E[r_z]    = Σ_i g^i,
//!   E[|r|²]   = Σ_i 2 + 2 Σ_{i<j} g^(j−i),
//!   E[r_z²]   = Σ_i 2 c_i + 2 Σ_{i<j} g^(j−i) c_i,   c_i = (1 + 2 g₂^i)/3,
//!   E[|r_⊥|²] = E[|r|²] − E[r_z²]                    (E[s] = 1, E[s²] = 2).
//!
//! Tested for HG (g₂ = g²) and for the 10 µm Mie table, whose g and g₂ are integrated here from
//! the table itself, against the walk's `free_path` and `scatter` (the same functions the slab
//! walk runs; its plane tallies are tested against closed forms in tests/slab.rs).

use nephele::mie::polydisperse::{CONVERGED_DEFAULT, DEFAULT_WAVELENGTHS};
use nephele::mie::MieJob;
use nephele::slab::walk::{batch_rng, free_path, scatter};
use nephele_runtime::phase::{HenyeyGreenstein, TabulatedTable};
use nephele_runtime::PhaseFunction;

const ORDERS: usize = 12;

/// E[r_z], E[|r|²], E[|r_⊥|²] after n = 1..=ORDERS flights.
fn expected(g: f64, g2: f64) -> Vec<[f64; 3]> {
    (1..=ORDERS)
        .map(|n| {
            let c = |i: usize| (1.0 + 2.0 * g2.powi(i as i32)) / 3.0;
            let (mut rz, mut r2, mut z2) = (0.0, 0.0, 0.0);
            for i in 0..n {
                rz += g.powi(i as i32);
                r2 += 2.0;
                z2 += 2.0 * c(i);
                for j in i + 1..n {
                    let gij = g.powi((j - i) as i32);
                    r2 += 2.0 * gij;
                    z2 += 2.0 * gij * c(i);
                }
            }
            [rz, r2, r2 - z2]
        })
        .collect()
}

/// The walk's estimates: per n, the means and standard errors of r_z, |r|², |r_⊥|².
fn simulate(phase: &(dyn PhaseFunction<f64> + Sync), photons: u64) -> Vec<[(f64, f64); 3]> {
    let mut rng = batch_rng(7, 0, 0);
    let mut sum = vec![[0.0f64; 3]; ORDERS];
    let mut sum2 = vec![[0.0f64; 3]; ORDERS];
    for _ in 0..photons {
        let (mut pos, mut dir) = ([0.0f64; 3], [0.0, 0.0, 1.0]);
        for n in 0..ORDERS {
            let s = free_path(&mut rng);
            for i in 0..3 {
                pos[i] += s * dir[i];
            }
            dir = scatter(phase, dir, &mut rng);
            let perp = pos[0] * pos[0] + pos[1] * pos[1];
            let v = [pos[2], perp + pos[2] * pos[2], perp];
            for q in 0..3 {
                sum[n][q] += v[q];
                sum2[n][q] += v[q] * v[q];
            }
        }
    }
    let n = photons as f64;
    (0..ORDERS)
        .map(|k| {
            std::array::from_fn(|q| {
                let m = sum[k][q] / n;
                (m, ((sum2[k][q] / n - m * m) / (n - 1.0)).sqrt())
            })
        })
        .collect()
}

/// Every moment at every order within 4 standard errors, and the worst |z| reported.
fn check(name: &str, phase: &(dyn PhaseFunction<f64> + Sync), g: f64, g2: f64) {
    let want = expected(g, g2);
    let got = simulate(phase, 400_000);
    let mut worst = 0.0f64;
    for n in 0..ORDERS {
        for q in 0..3 {
            let (m, se) = got[n][q];
            if se == 0.0 {
                // |r_⊥|² after the first flight, along the beam: exactly 0.
                assert!(
                    m == 0.0 && want[n][q].abs() < 1e-12,
                    "{name}: n = 1, moment {q}"
                );
                continue;
            }
            let z = (m - want[n][q]) / se;
            worst = worst.max(z.abs());
            assert!(
                z.abs() < 4.0,
                "{name}: after {} scatterings moment {q}: walk {m} ± {se}, exact {}",
                n + 1,
                want[n][q]
            );
        }
    }
    let last = ORDERS - 1;
    println!(
        "{name}: g = {g:.5}, g2 = {g2:.5}; after {ORDERS} scatterings <|r_perp|^2> = {:.4} ± {:.4} (exact {:.4}); worst |z| over {} moments {worst:.2}",
        got[last][2].0, got[last][2].1, want[last][2], 3 * ORDERS
    );
}

#[test]
fn pencil_beam_moments_hg() {
    for g in [0.0, 0.5, 0.9] {
        check(&format!("HG {g}"), &HenyeyGreenstein::new(g), g, g * g);
    }
}

/// ⟨P₁⟩ and ⟨P₂⟩ of the density f(θ) = 2π p(θ) sin θ taken piecewise linear between the nodes
/// (the density the tabulated sampler draws from), by 4-point Gauss–Legendre per interval.
fn table_moments(theta_deg: &[f64], phase: &[f64]) -> (f64, f64) {
    let x = [
        -0.861136311594053,
        -0.339981043584856,
        0.339981043584856,
        0.861136311594053,
    ];
    let w = [
        0.347854845137454,
        0.652145154862546,
        0.652145154862546,
        0.347854845137454,
    ];
    let (mut m0, mut m1, mut m2) = (0.0, 0.0, 0.0);
    for i in 0..theta_deg.len() - 1 {
        let (a, b) = (theta_deg[i].to_radians(), theta_deg[i + 1].to_radians());
        let (fa, fb) = (phase[i] * a.sin(), phase[i + 1] * b.sin());
        for k in 0..4 {
            let u = 0.5 * (x[k] + 1.0);
            let th = a + u * (b - a);
            let f = (fa + u * (fb - fa)) * 0.5 * (b - a) * w[k];
            let mu = th.cos();
            m0 += f;
            m1 += f * mu;
            m2 += f * 0.5 * (3.0 * mu * mu - 1.0);
        }
    }
    (m1 / m0, m2 / m0)
}

#[test]
fn pencil_beam_moments_mie() {
    let job = MieJob::paper(10.0, CONVERGED_DEFAULT, DEFAULT_WAVELENGTHS);
    let tables = job.compute(&|_, _| {}).unwrap().0;
    let t = &tables[0];
    let table = TabulatedTable::<f64>::from_phase(&t.theta_deg, &t.phase).unwrap();
    let (g, g2) = table_moments(&t.theta_deg, &t.phase);
    check("Mie 10 um", &table.view(), g, g2);
}
