//! Henyey–Greenstein (1941).
//!
//!   p(μ) = (1 − g²) / (4π (1 + g² − 2gμ)^{3/2}),  ⟨μ⟩ = g.
//!
//! Sampling by inverting the CDF F(μ) = (1 − g)(1 + μ) / (v (1 + g + v)), v = √(1 + g² − 2gμ),
//! written without the 1/g of the textbook form so that it stays exact as g → 0 (and in f32):
//! with μ₀ = 2ξ − 1,
//!   μ = [μ₀ + (g/2)(3 + μ₀²) + g² μ₀ + (g³/2)(μ₀² − 1)] / (1 + g μ₀)².

use super::{inv_four_pi, PhaseFunction};
use crate::real::Real;

/// Henyey–Greenstein with asymmetry g ∈ (−1, 1).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct HenyeyGreenstein<F> {
    /// Asymmetry parameter, ⟨μ⟩.
    pub g: F,
}

impl<F: Real> HenyeyGreenstein<F> {
    /// HG with asymmetry `g`, |g| < 1 (not checked: |g| ≥ 1 is not a distribution).
    pub fn new(g: F) -> Self {
        Self { g }
    }

    /// The CDF F(μ) = ∫_{−1}^{μ} 2π p dμ′.
    pub fn cdf(&self, mu: F) -> F {
        let g = self.g;
        let one = F::of(1.0);
        let v = (one + g * g - F::of(2.0) * g * mu).sqrt();
        (one - g) * (one + mu) / (v * (one + g + v))
    }
}

impl<F: Real> PhaseFunction<F> for HenyeyGreenstein<F> {
    #[inline]
    fn eval(&self, mu: F) -> F {
        let g = self.g;
        let one = F::of(1.0);
        let d = one + g * g - F::of(2.0) * g * mu;
        inv_four_pi::<F>() * (one - g * g) / (d * d.sqrt())
    }

    #[inline]
    fn sample_mu(&self, xi: F) -> F {
        let g = self.g;
        let (one, half) = (F::of(1.0), F::of(0.5));
        let m0 = F::of(2.0) * xi - one;
        let s = one + g * m0;
        let num = m0
            + half * g * (F::of(3.0) + m0 * m0)
            + g * g * m0
            + half * g * g * g * (m0 * m0 - one);
        (num / (s * s)).clamp_to(-one, one)
    }

    fn mean_cosine(&self) -> Option<F> {
        Some(self.g)
    }
}
