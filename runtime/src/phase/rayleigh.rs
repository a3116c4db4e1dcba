//! Rayleigh: p(μ) = 3(1 + μ²)/(16π), ⟨μ⟩ = 0.
//!
//! CDF F(μ) = (μ³ + 3μ + 4)/8; F = ξ is the depressed cubic μ³ + 3μ + (4 − 8ξ) = 0, whose one
//! real root is μ = u − 1/u with u = ∛(4ξ − 2 + √((4ξ − 2)² + 1)) (Cardano).

use super::{inv_four_pi, Cosine, PhaseFunction};
use crate::real::Real;

/// The Rayleigh phase function (unpolarised).
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct Rayleigh;

impl<F: Real> PhaseFunction<F> for Rayleigh {
    #[inline]
    fn eval(&self, mu: F) -> F {
        F::of(0.75) * inv_four_pi::<F>() * (F::of(1.0) + mu * mu)
    }

    #[inline]
    fn sample_cosine(&self, xi: F) -> Cosine<F> {
        Cosine::from_mu(self.rayleigh_mu(xi))
    }

    fn mean_cosine(&self) -> Option<F> {
        Some(F::of(0.0))
    }
}

impl Rayleigh {
    /// The Cardano root.
    #[inline]
    fn rayleigh_mu<F: Real>(&self, xi: F) -> F {
        let q = F::of(4.0) * xi - F::of(2.0);
        // For q < 0 use the mirror root: u(−q) = 1/u(q), avoiding the cancellation in q + √….
        let r = (q * q + F::of(1.0)).sqrt();
        let u = if q >= F::of(0.0) {
            (q + r).cbrt()
        } else {
            F::of(1.0) / (r - q).cbrt()
        };
        (u - F::of(1.0) / u).clamp_to(F::of(-1.0), F::of(1.0))
    }
}
