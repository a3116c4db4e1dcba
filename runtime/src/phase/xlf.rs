//! Xiao-Lei Fan's phase function (XLF), **normalised**. As published,
//!   p̃(μ) = (1/4π) [ (3/2) (1 − g²)/(2 + g²) (1 + μ²)/(1 + g² − 2gμ) + gμ ]
//! does not integrate to one over the sphere (∮ p̃ dΩ = A I(g)/2 with A = (3/2)(1 − g²)/(2 + g²),
//! I(g) = ∫ (1 + μ²)/(1 + g² − 2gμ) dμ over [−1, 1]; 1.07 at g = 0.3), so here
//!   p(μ) = [A (1 + μ²)/(a − bμ) + gμ] / (2π A I(g)),  a = 1 + g², b = 2g.
//! It is a distribution only while p ≥ 0 everywhere, i.e. |g| ≤ 0.476955 (where the backward
//! value A·2/(1 + |g|)² falls to |g|: 0.4769553); `Xlf::new` refuses larger |g|.
//!
//! Integrals: for |g| ≥ 0.1 the closed form
//!   J(μ) = ∫_{−1}^{μ} (1 + t²)/(a − bt) dt
//!        = −(μ² − 1)/(2b) − a(μ + 1)/b² − (1 + a²/b²) ln((a − bμ)/(a + b))/b,
//! and below, where its 1/g³ terms cancel, the exact series in r = b/a < 0.2
//!   ∫_{−1}^{μ} tⁿ (1 + t²)/(a − bt) dt = (1/a) Σ_k r^k ∫_{−1}^{μ} (t^{n+k} + t^{n+k+2}) dt.
//! Sampling inverts the CDF by bracketed Newton in f64, as for Draine; the mean cosine is
//! ⟨μ⟩ = [A K(g) + 2g/3] / (A I(g)) with K = ∫ μ(1 + μ²)/(a − bμ) dμ.

use super::{invert_cdf, Cosine, PhaseFunction};
use crate::real::{Math, Real};

/// Largest |g| for which the normalised XLF stays non-negative.
pub const XLF_G_MAX: f64 = 0.476955;

/// The normalised XLF phase function, |g| ≤ [`XLF_G_MAX`].
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Xlf<F> {
    /// Parameter g (not the mean cosine).
    pub g: F,
    /// 2π A I(g).
    norm: F,
}

/// ∫_{−1}^{μ} tⁿ (1 + t²)/(a − bt) dt for n = 0, 1 (see the module notes).
fn series(g: f64, mu: f64, n: u32) -> f64 {
    if Math::abs(g) >= 0.1 {
        let (a, b) = (1.0 + g * g, 2.0 * g);
        let j0 = -(mu * mu - 1.0) / (2.0 * b)
            - a * (mu + 1.0) / (b * b)
            - (1.0 + a * a / (b * b)) * Math::ln((a - b * mu) / (a + b)) / b;
        return if n == 0 {
            j0
        } else {
            (a * j0 - (mu + 1.0) - (mu * mu * mu + 1.0) / 3.0) / b
        };
    }
    let a = 1.0 + g * g;
    let r = 2.0 * g / a;
    let prim = |j: u32| {
        // ∫_{−1}^{μ} t^j dt
        let e = j + 1;
        let lower = if e % 2 == 0 { 1.0 } else { -1.0 };
        (powi(mu, e) - lower) / e as f64
    };
    let (mut sum, mut rk) = (0.0, 1.0);
    for k in 0..400u32 {
        let term = rk * (prim(n + k) + prim(n + k + 2));
        sum += term;
        rk *= r;
        if Math::abs(rk) < 1e-18 {
            break;
        }
    }
    sum / a
}

fn powi(x: f64, e: u32) -> f64 {
    (0..e).fold(1.0, |p, _| p * x)
}

fn amplitude(g: f64) -> f64 {
    1.5 * (1.0 - g * g) / (2.0 + g * g)
}

impl<F: Real> Xlf<F> {
    /// XLF with parameter g; `None` if |g| > [`XLF_G_MAX`] (p would turn negative).
    pub fn new(g: F) -> Option<Self> {
        let gd = g.f64();
        if !(Math::abs(gd) <= XLF_G_MAX) {
            return None;
        }
        let norm = 2.0 * core::f64::consts::PI * amplitude(gd) * series(gd, 1.0, 0);
        Some(Self {
            g,
            norm: F::of(norm),
        })
    }

    /// The CDF F(μ) = ∫_{−1}^{μ} 2π p dμ′, in f64.
    pub fn cdf(&self, mu: F) -> F {
        F::of(self.cdf_f64(mu.f64()))
    }

    fn cdf_f64(&self, mu: f64) -> f64 {
        let g = self.g.f64();
        let a = amplitude(g);
        (a * series(g, mu, 0) + 0.5 * g * (mu * mu - 1.0)) * 2.0 * core::f64::consts::PI
            / self.norm.f64()
    }
}

impl<F: Real> PhaseFunction<F> for Xlf<F> {
    fn eval(&self, mu: F) -> F {
        let g = self.g;
        let one = F::of(1.0);
        let d = one + g * g - F::of(2.0) * g * mu;
        (F::of(amplitude(g.f64())) * (one + mu * mu) / d + g * mu) / self.norm
    }

    fn sample_cosine(&self, xi: F) -> Cosine<F> {
        let xi = xi.f64();
        let mu = invert_cdf(
            |mu| self.cdf_f64(mu),
            |mu| self.eval(F::of(mu)).f64(),
            xi,
            2.0 * xi - 1.0,
        );
        Cosine {
            mu: F::of(mu),
            one_minus_mu: F::of(1.0 - mu),
        }
    }

    fn mean_cosine(&self) -> Option<F> {
        let g = self.g.f64();
        let a = amplitude(g);
        Some(F::of(
            (a * series(g, 1.0, 1) + 2.0 * g / 3.0) / (a * series(g, 1.0, 0)),
        ))
    }
}
