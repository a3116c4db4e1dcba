//! Chi-square goodness-of-fit test of a direction sampler against its pdf on the sphere, in
//! the style of Mitsuba 3's `chi2.py`.
//!
//! The sphere is cut into `n_mu` bins in cos θ × `n_phi` bins in φ around +z. Samples are
//! histogrammed; the expected count of a cell is N ∫∫ pdf dΩ, integrated by adaptive Simpson
//! in μ and composite Simpson in φ (`sub` panels per cell). Cells expecting fewer than 5 samples are pooled
//! into one; the statistic Σ (O − E)²/E has (cells − 1) degrees of freedom. A test passes when
//! its p-value exceeds the Šidák-corrected significance 1 − (1 − α)^{1/m} for m tests.

use crate::adaptive_simpson;
use rand::{Rng, SeedableRng};
use rand_xoshiro::Xoshiro256PlusPlus;
use statrs::distribution::{ChiSquared, ContinuousCDF};
use std::f64::consts::PI;

/// How a chi-square test is run.
#[derive(Clone, Copy, Debug)]
pub struct Chi2Config {
    /// Bins in cos θ.
    pub n_mu: usize,
    /// Bins in φ.
    pub n_phi: usize,
    /// Number of samples.
    pub samples: usize,
    /// Simpson panels per cell in φ for the expected counts (even).
    pub sub: usize,
    /// Seed of the sample stream.
    pub seed: u64,
}

impl Default for Chi2Config {
    fn default() -> Self {
        Self {
            n_mu: 100,
            n_phi: 50,
            samples: 1_000_000,
            sub: 8,
            seed: 0x5eed,
        }
    }
}

/// Outcome of one test.
#[derive(Clone, Copy, Debug)]
pub struct Chi2Result {
    /// Σ (O − E)²/E over the kept (and the pooled) cells.
    pub statistic: f64,
    /// Degrees of freedom.
    pub dof: usize,
    /// P(χ² ≥ statistic).
    pub p_value: f64,
    /// Cells pooled because they expected fewer than 5 samples.
    pub pooled: usize,
    /// Samples that fell outside the sphere (not unit length, or NaN).
    pub invalid: usize,
}

impl Chi2Result {
    /// Whether the test passes at significance `alpha` corrected for `tests` tests (Šidák).
    pub fn passes(&self, alpha: f64, tests: usize) -> bool {
        self.invalid == 0 && self.p_value > sidak(alpha, tests)
    }
}

/// The per-test significance that keeps the family-wise rate at `alpha` over `tests` tests.
pub fn sidak(alpha: f64, tests: usize) -> f64 {
    1.0 - (1.0 - alpha).powf(1.0 / tests.max(1) as f64)
}

/// Tests `sample(ξ1, ξ2) → unit direction` against `pdf(direction)` (per steradian).
pub fn chi2_sphere(
    cfg: &Chi2Config,
    sample: impl Fn(f64, f64) -> [f64; 3],
    pdf: impl Fn([f64; 3]) -> f64,
) -> Chi2Result {
    let (n_mu, n_phi) = (cfg.n_mu, cfg.n_phi);
    let mut observed = vec![0u64; n_mu * n_phi];
    let mut rng = Xoshiro256PlusPlus::seed_from_u64(cfg.seed);
    let mut invalid = 0;
    for _ in 0..cfg.samples {
        let d = sample(rng.random::<f64>(), rng.random::<f64>());
        let len2 = d[0] * d[0] + d[1] * d[1] + d[2] * d[2];
        if !((len2 - 1.0).abs() < 1e-4) {
            invalid += 1;
            continue;
        }
        observed[cell(d, n_mu, n_phi)] += 1;
    }
    let expected = expected_counts(cfg, &pdf);
    let (statistic, dof, pooled) = statistic(&observed, &expected);
    let p_value = if dof == 0 {
        1.0
    } else {
        1.0 - ChiSquared::new(dof as f64).expect("dof > 0").cdf(statistic)
    };
    Chi2Result {
        statistic,
        dof,
        p_value,
        pooled,
        invalid,
    }
}

/// Index of the (μ, φ) cell of a unit direction.
fn cell(d: [f64; 3], n_mu: usize, n_phi: usize) -> usize {
    let mu = d[2].clamp(-1.0, 1.0);
    let phi = d[1].atan2(d[0]).rem_euclid(2.0 * PI);
    let i = (((mu + 1.0) * 0.5 * n_mu as f64) as usize).min(n_mu - 1);
    let j = ((phi / (2.0 * PI) * n_phi as f64) as usize).min(n_phi - 1);
    i * n_phi + j
}

/// N ∫∫ pdf dΩ per cell: composite Simpson in φ (`sub` panels) inside adaptive Simpson in μ,
/// so that a forward peak narrower than a μ-bin (HG with g = 0.99) is still integrated exactly.
fn expected_counts(cfg: &Chi2Config, pdf: &impl Fn([f64; 3]) -> f64) -> Vec<f64> {
    let (n_mu, n_phi, s) = (cfg.n_mu, cfg.n_phi, cfg.sub.max(2) & !1);
    let simpson_w = |k: usize| {
        if k == 0 || k == s {
            1.0
        } else if k % 2 == 1 {
            4.0
        } else {
            2.0
        }
    };
    let (dmu, dphi) = (2.0 / n_mu as f64, 2.0 * PI / n_phi as f64);
    let mut out = vec![0.0; n_mu * n_phi];
    for i in 0..n_mu {
        for j in 0..n_phi {
            let over_phi = |mu: f64| {
                let sin = (1.0 - mu * mu).max(0.0).sqrt();
                let sum: f64 = (0..=s)
                    .map(|b| {
                        let phi = dphi * (j as f64 + b as f64 / s as f64);
                        simpson_w(b) * pdf([sin * phi.cos(), sin * phi.sin(), mu])
                    })
                    .sum();
                sum * dphi / (3.0 * s as f64)
            };
            let (a, b) = (-1.0 + dmu * i as f64, -1.0 + dmu * (i + 1) as f64);
            out[i * n_phi + j] = adaptive_simpson(&over_phi, a, b, 1e-10) * cfg.samples as f64;
        }
    }
    out
}

/// Pearson's statistic with the cells expecting < 5 pooled into one; (χ², dof, pooled cells).
fn statistic(observed: &[u64], expected: &[f64]) -> (f64, usize, usize) {
    let (mut chi2, mut kept, mut pooled) = (0.0, 0usize, 0usize);
    let (mut pool_o, mut pool_e) = (0.0, 0.0);
    for (&o, &e) in observed.iter().zip(expected) {
        let o = o as f64;
        if e < 5.0 {
            pool_o += o;
            pool_e += e;
            pooled += 1;
        } else {
            chi2 += (o - e) * (o - e) / e;
            kept += 1;
        }
    }
    if pool_e > 0.0 {
        chi2 += (pool_o - pool_e) * (pool_o - pool_e) / pool_e.max(5.0);
        kept += 1;
    }
    (chi2, kept.saturating_sub(1), pooled)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn uniform_sphere(x1: f64, x2: f64) -> [f64; 3] {
        let mu = 2.0 * x1 - 1.0;
        let s = (1.0 - mu * mu).sqrt();
        [s * (2.0 * PI * x2).cos(), s * (2.0 * PI * x2).sin(), mu]
    }

    #[test]
    fn accepts_a_correct_sampler_and_rejects_a_wrong_pdf() {
        let cfg = Chi2Config::default();
        let ok = chi2_sphere(&cfg, uniform_sphere, |_| 0.25 / PI);
        assert!(ok.passes(0.01, 1), "{ok:?}");
        // A pdf slightly tilted forward (⟨μ⟩ = 0.02) must be caught with 1e6 samples.
        let wrong = chi2_sphere(&cfg, uniform_sphere, |d| 0.25 / PI * (1.0 + 0.06 * d[2]));
        assert!(!wrong.passes(0.01, 1), "{wrong:?}");
    }
}
