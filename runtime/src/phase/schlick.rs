//! Schlick's approximation (Blasi, Le Saëc & Schlick 1993):
//!   p(μ) = (1 − k²) / (4π (1 − kμ)²),
//!   ⟨μ⟩ = 1/k − (1 − k²)/(2k²) ln((1 + k)/(1 − k))  (→ 2k/3 as k → 0),
//! sampled by μ = (2ξ + k − 1)/(2kξ − k + 1), the exact inverse CDF.

use super::{inv_four_pi, PhaseFunction};
use crate::real::Real;

/// Schlick's phase function with k ∈ (−1, 1).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Schlick<F> {
    /// Shape parameter k (k > 0 forward).
    pub k: F,
}

impl<F: Real> Schlick<F> {
    /// Schlick with parameter `k`.
    pub fn new(k: F) -> Self {
        Self { k }
    }
}

impl<F: Real> PhaseFunction<F> for Schlick<F> {
    #[inline]
    fn eval(&self, mu: F) -> F {
        let d = F::of(1.0) - self.k * mu;
        inv_four_pi::<F>() * (F::of(1.0) - self.k * self.k) / (d * d)
    }

    #[inline]
    fn sample_mu(&self, xi: F) -> F {
        let (k, one, two) = (self.k, F::of(1.0), F::of(2.0));
        ((two * xi + k - one) / (two * k * xi - k + one)).clamp_to(-one, one)
    }

    fn mean_cosine(&self) -> Option<F> {
        let k = self.k.f64();
        let m = if k.abs() < 1e-3 {
            2.0 * k / 3.0 + 2.0 * k * k * k / 15.0
        } else {
            1.0 / k - (1.0 - k * k) / (2.0 * k * k) * Real::ln((1.0 + k) / (1.0 - k))
        };
        Some(F::of(m))
    }
}
