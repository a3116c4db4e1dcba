//! von Mises–Fisher on the sphere:
//!   p(μ) = κ e^{κμ} / (4π sinh κ) = κ e^{κ(μ − 1)} / (2π (1 − e^{−2κ})),
//!   ⟨μ⟩ = coth κ − 1/κ  (→ κ/3 as κ → 0),
//! sampled by μ = 1 + ln(ξ + (1 − ξ) e^{−2κ})/κ (Wenzel 1994 / Jakob 2012).

use super::{inv_four_pi, PhaseFunction};
use crate::real::Real;

/// von Mises–Fisher lobe with concentration κ ≥ 0 around the forward direction.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct VonMisesFisher<F> {
    /// Concentration κ (0 is isotropic).
    pub kappa: F,
}

impl<F: Real> VonMisesFisher<F> {
    /// vMF with concentration `kappa` ≥ 0.
    pub fn new(kappa: F) -> Self {
        Self { kappa }
    }
}

impl<F: Real> PhaseFunction<F> for VonMisesFisher<F> {
    #[inline]
    fn eval(&self, mu: F) -> F {
        let k = self.kappa;
        if k < F::of(1e-4) {
            return inv_four_pi::<F>() * (F::of(1.0) + k * mu);
        }
        let one = F::of(1.0);
        k * (k * (mu - one)).exp() / (F::of(2.0) * F::PI * (one - (F::of(-2.0) * k).exp()))
    }

    #[inline]
    fn sample_mu(&self, xi: F) -> F {
        let k = self.kappa;
        let one = F::of(1.0);
        if k < F::of(1e-4) {
            // First order in κ: F(μ) = (1 + μ)/2 + κ(μ² − 1)/4, inverted around μ₀ = 2ξ − 1.
            let m0 = F::of(2.0) * xi - one;
            return m0 + F::of(0.5) * k * (one - m0 * m0);
        }
        let e = (F::of(-2.0) * k).exp();
        (one + (xi + (one - xi) * e).ln() / k).clamp_to(-one, one)
    }

    fn mean_cosine(&self) -> Option<F> {
        let k = self.kappa.f64();
        let m = if k < 1e-3 {
            k / 3.0 - k * k * k / 45.0
        } else {
            let e = Real::exp(-2.0 * k);
            (1.0 + e) / (1.0 - e) - 1.0 / k
        };
        Some(F::of(m))
    }
}
