//! Schlick's approximation (Blasi, Le Saëc & Schlick 1993):
//!   p(μ) = (1 − k²) / (4π (1 − kμ)²),
//!   ⟨μ⟩ = 1/k − (1 − k²)/(2k²) ln((1 + k)/(1 − k))  (→ 2k/3 as k → 0),
//! sampled by μ = (2ξ + k − 1)/(2kξ − k + 1), the exact inverse CDF.

use super::{inv_four_pi, Cosine, PhaseFunction};
use crate::real::{Math, Real};

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
        self.pdf_cosine(Cosine::from_mu(mu))
    }

    /// With 1 − kμ = (1 − k) + k(1 − μ) on the forward side.
    #[inline]
    fn pdf_cosine(&self, c: Cosine<F>) -> F {
        let (k, one) = (self.k, F::of(1.0));
        let d = if c.mu > F::of(0.0) {
            (one - k) + k * c.one_minus_mu
        } else {
            one - k * c.mu
        };
        inv_four_pi::<F>() * (one - k) * (one + k) / (d * d)
    }

    /// μ = (2ξ + k − 1)/(2kξ − k + 1) and 1 − μ = 2(1 − k)(1 − ξ)/(2kξ − k + 1).
    #[inline]
    fn sample_cosine(&self, xi: F) -> Cosine<F> {
        let (k, one, two) = (self.k, F::of(1.0), F::of(2.0));
        let den = two * k * xi - k + one;
        let mu = ((two * xi + k - one) / den).clamp_to(-one, one);
        if mu > F::of(0.0) {
            Cosine::from_one_minus_mu(
                (two * (one - k) * (one - xi) / den).clamp_to(F::of(0.0), one),
            )
        } else {
            Cosine::from_mu(mu)
        }
    }

    fn mean_cosine(&self) -> Option<F> {
        let k = self.k.f64();
        let m = if k.abs() < 1e-3 {
            2.0 * k / 3.0 + 2.0 * k * k * k / 15.0
        } else {
            1.0 / k - (1.0 - k * k) / (2.0 * k * k) * Math::ln((1.0 + k) / (1.0 - k))
        };
        Some(F::of(m))
    }
}
