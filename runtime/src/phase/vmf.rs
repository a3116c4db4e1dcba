//! von Mises–Fisher on the sphere:
//!   p(μ) = κ e^{κμ} / (4π sinh κ) = κ e^{κ(μ − 1)} / (2π (1 − e^{−2κ})),
//!   ⟨μ⟩ = coth κ − 1/κ  (→ κ/3 as κ → 0),
//! sampled by μ = 1 + ln(ξ + (1 − ξ) e^{−2κ})/κ (Wenzel 1994 / Jakob 2012).

use super::{inv_four_pi, Cosine, PhaseFunction};
use crate::real::{Math, Real};

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
        self.pdf_cosine(Cosine::from_mu(mu))
    }

    #[inline]
    fn pdf_cosine(&self, c: Cosine<F>) -> F {
        let k = self.kappa;
        if k < F::of(1e-4) {
            return inv_four_pi::<F>() * (F::of(1.0) + k * c.mu);
        }
        k * (-k * c.one_minus_mu).exp()
            / (F::of(2.0) * F::PI * (F::of(1.0) - (F::of(-2.0) * k).exp()))
    }

    /// 1 − μ = −ln(ξ + (1 − ξ) e^{−2κ})/κ, exact near the peak.
    #[inline]
    fn sample_cosine(&self, xi: F) -> Cosine<F> {
        let k = self.kappa;
        let one = F::of(1.0);
        if k < F::of(1e-4) {
            // First order in κ: F(μ) = (1 + μ)/2 + κ(μ² − 1)/4, inverted around μ₀ = 2ξ − 1.
            let m0 = F::of(2.0) * xi - one;
            return Cosine::from_mu(m0 + F::of(0.5) * k * (one - m0 * m0));
        }
        let e = (F::of(-2.0) * k).exp();
        let omm = -(xi + (one - xi) * e).ln() / k;
        Cosine::from_one_minus_mu(omm.clamp_to(F::of(0.0), F::of(2.0)))
    }

    fn mean_cosine(&self) -> Option<F> {
        let k = self.kappa.f64();
        let m = if k < 1e-3 {
            k / 3.0 - k * k * k / 45.0
        } else {
            let e = Math::exp(-2.0 * k);
            (1.0 + e) / (1.0 - e) - 1.0 / k
        };
        Some(F::of(m))
    }
}
