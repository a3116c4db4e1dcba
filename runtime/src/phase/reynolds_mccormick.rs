//! Reynolds–McCormick (1980), the Gegenbauer-kernel phase function:
//!   p(μ) = α g (1 − g²)^{2α} / (π [(1 + g)^{2α} − (1 − g)^{2α}] (1 + g² − 2gμ)^{α + 1}),
//! α > 0 (α = 1/2 is HG). With d = 1 + g² − 2gμ the CDF inverts in closed form:
//!   d^{−α} = (1 − ξ)(1 + g)^{−2α} + ξ (1 − g)^{−2α},  μ = (1 + g² − d)/(2g),
//!   1 − μ = (d − (1 − g)²)/(2g),
//! evaluated in f64 (the 1/(2g) cancels for small g; below |g| = 1e-4 the first-order
//! expansion p ≈ (1 + 2(α + 1)gμ)/(4π) is used instead). Mean cosine, with u± = (1 ± g)²:
//!   ⟨μ⟩ = K/(4g²) [(1 + g²)(u₋^{−α} − u₊^{−α})/α − (u₊^{1−α} − u₋^{1−α})/(1 − α)],
//!   K = 2α g (1 − g²)^{2α}/((1 + g)^{2α} − (1 − g)^{2α})  (ln(u₊/u₋) for the last term at α = 1).

use super::{Cosine, PhaseFunction};
use crate::real::{Math, Real};

/// Reynolds–McCormick with |g| < 1 and α > 0.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ReynoldsMcCormick<F> {
    /// Shape g.
    pub g: F,
    /// Exponent α.
    pub alpha: F,
    /// α g (1 − g²)^{2α} / (π [(1 + g)^{2α} − (1 − g)^{2α}]), sr⁻¹.
    norm: F,
}

fn pow(x: f64, y: f64) -> f64 {
    Math::exp(y * Math::ln(x))
}

/// Below this |g| the first-order expansion in g is used.
const SMALL_G: f64 = 1e-4;

impl<F: Real> ReynoldsMcCormick<F> {
    /// RM(g, α).
    pub fn new(g: F, alpha: F) -> Self {
        let (gd, a) = (g.f64(), alpha.f64());
        let norm = if Math::abs(gd) < SMALL_G {
            0.25 / core::f64::consts::PI
        } else {
            a * gd * pow(1.0 - gd * gd, 2.0 * a)
                / (core::f64::consts::PI * (pow(1.0 + gd, 2.0 * a) - pow(1.0 - gd, 2.0 * a)))
        };
        Self {
            g,
            alpha,
            norm: F::of(norm),
        }
    }
}

impl<F: Real> PhaseFunction<F> for ReynoldsMcCormick<F> {
    fn eval(&self, mu: F) -> F {
        self.pdf_cosine(Cosine::from_mu(mu))
    }

    fn pdf_cosine(&self, c: Cosine<F>) -> F {
        let (g, a, one) = (self.g, self.alpha, F::of(1.0));
        if Math::abs(g.f64()) < SMALL_G {
            return self.norm * (one + F::of(2.0) * (a + one) * g * c.mu);
        }
        let d = if c.mu > F::of(0.0) {
            (one - g) * (one - g) + F::of(2.0) * g * c.one_minus_mu
        } else {
            one + g * g - F::of(2.0) * g * c.mu
        };
        self.norm * (-(a + one) * d.ln()).exp()
    }

    fn sample_cosine(&self, xi: F) -> Cosine<F> {
        let (g, a, xi) = (self.g.f64(), self.alpha.f64(), xi.f64());
        if Math::abs(g) < SMALL_G {
            let m0 = 2.0 * xi - 1.0;
            return Cosine::from_mu(F::of(m0 + (a + 1.0) * g * (1.0 - m0 * m0)));
        }
        let s = (1.0 - xi) * pow(1.0 + g, -2.0 * a) + xi * pow(1.0 - g, -2.0 * a);
        let d = pow(s, -1.0 / a);
        let mu = ((1.0 + g * g - d) / (2.0 * g)).clamp(-1.0, 1.0);
        let omm = ((d - (1.0 - g) * (1.0 - g)) / (2.0 * g)).clamp(0.0, 2.0);
        Cosine {
            mu: F::of(mu),
            one_minus_mu: F::of(if mu > 0.0 { omm } else { 1.0 - mu }),
        }
    }

    fn mean_cosine(&self) -> Option<F> {
        let (g, a) = (self.g.f64(), self.alpha.f64());
        if Math::abs(g) < 1e-3 {
            return Some(F::of(2.0 * (a + 1.0) * g / 3.0));
        }
        let (up, um) = ((1.0 + g) * (1.0 + g), (1.0 - g) * (1.0 - g));
        let k = 2.0 * a * g * pow(1.0 - g * g, 2.0 * a)
            / (pow(1.0 + g, 2.0 * a) - pow(1.0 - g, 2.0 * a));
        let first = (1.0 + g * g) * (pow(um, -a) - pow(up, -a)) / a;
        let second = if Math::abs(1.0 - a) < 1e-9 {
            Math::ln(up / um)
        } else {
            (pow(up, 1.0 - a) - pow(um, 1.0 - a)) / (1.0 - a)
        };
        Some(F::of(k / (4.0 * g * g) * (first - second)))
    }
}
