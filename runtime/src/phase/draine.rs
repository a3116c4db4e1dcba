//! Draine (2003), and Cornette–Shanks (1992) as its α = 1 case.
//!
//!   p(μ) = HG(μ; g) (1 + α μ²) / (1 + α (1 + 2g²)/3),
//!   ⟨μ⟩ = g (1 + α (3 + 2g²)/5) / (1 + α (1 + 2g²)/3).
//!
//! Sampling inverts the exact CDF, F(μ) = [F_HG(μ) + α M₂(μ)] / N, with M₂ = ∫ 2π HG μ′² dμ′.
//! With v = √(1 + g² − 2gμ), a = 1 + g², v₀ = 1 + g:
//!   M₂(μ) = −(1 − g²)/(8g³) [H(v) − H(v₀)],  H(v) = −a²/v − 2a v + v³/3,
//! (v·F = ξ·v is a quartic in v). The renderer-style closed-form root loses up to 0.1 of
//! CDF in f32 at α = 250; here the CDF is evaluated in f64 in a form free of the 1/g³
//! cancellation (below) and F(μ) = ξ solved by Newton's method — one step from a tabulated
//! Hermite guess when that step is below 1e-7, else inside a shrinking bracket to |F − ξ| ≤
//! 1e-14 — whatever the output precision: an f32 sample is the exact root rounded once.

use super::{invert_cdf, Cosine, HenyeyGreenstein, PhaseFunction};
use crate::real::Real;

/// Draine's phase function with asymmetry-like g ∈ (−1, 1) and α ≥ 0.
///
/// Construction tabulates the inverse CDF at 65 points (≈ 20 µs, 1 KB in the struct) so that
/// sampling can start Newton's method from a cubic Hermite guess and usually stop after one
/// step. Build it with
/// [`Draine::new`]; if `g` or `alpha` are changed afterwards sampling stays exact (the guess is
/// only a starting point) but slower.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Draine<F> {
    /// HG parameter g (not the mean cosine unless α = 0).
    pub g: F,
    /// Weight α of the μ² term.
    pub alpha: F,
    guess: InverseGuess,
}

/// Intervals of the inverse-CDF guess table.
const GUESS_N: usize = 64;

/// μ(ξ) and dμ/dξ = 1/(2π p(μ)) at ξ = k/64, k = 0..=64.
#[derive(Clone, Copy, Debug, PartialEq)]
struct InverseGuess {
    mu: [f64; GUESS_N + 1],
    slope: [f64; GUESS_N + 1],
}

impl InverseGuess {
    fn new(g: f64, alpha: f64) -> Self {
        let mut mu = [0.0; GUESS_N + 1];
        let mut slope = [0.0; GUESS_N + 1];
        for k in 0..=GUESS_N {
            let xi = k as f64 / GUESS_N as f64;
            mu[k] = invert_cdf(
                |m| cdf_f64(g, alpha, m),
                |m| pdf_f64(g, alpha, m),
                xi,
                HenyeyGreenstein::new(g).sample_mu(xi),
            );
            slope[k] = 1.0 / (2.0 * core::f64::consts::PI * pdf_f64(g, alpha, mu[k]));
        }
        Self { mu, slope }
    }

    /// Cubic Hermite interpolation of μ(ξ).
    fn at(&self, xi: f64) -> f64 {
        let u = xi.clamp(0.0, 1.0) * GUESS_N as f64;
        let k = (u as usize).min(GUESS_N - 1);
        let t = u - k as f64;
        let h = 1.0 / GUESS_N as f64;
        let (t2, t3) = (t * t, t * t * t);
        let (h00, h10, h01, h11) = (
            2.0 * t3 - 3.0 * t2 + 1.0,
            t3 - 2.0 * t2 + t,
            -2.0 * t3 + 3.0 * t2,
            t3 - t2,
        );
        (h00 * self.mu[k]
            + h10 * h * self.slope[k]
            + h01 * self.mu[k + 1]
            + h11 * h * self.slope[k + 1])
            .clamp(-1.0, 1.0)
    }
}

impl<F: Real> Draine<F> {
    /// Draine(g, α).
    pub fn new(g: F, alpha: F) -> Self {
        Self {
            g,
            alpha,
            guess: InverseGuess::new(g.f64(), alpha.f64()),
        }
    }

    /// Cornette–Shanks (1992): Draine with α = 1 (its ⟨μ⟩ = 3g(4 + g²)/(5(2 + g²)) ≠ g).
    pub fn cornette_shanks(g: F) -> Self {
        Self::new(g, F::of(1.0))
    }

    /// The normalisation N = 1 + α(1 + 2g²)/3.
    fn norm(&self) -> F {
        let g = self.g;
        F::of(1.0) + self.alpha * (F::of(1.0) + F::of(2.0) * g * g) / F::of(3.0)
    }

    /// The CDF F(μ) = ∫_{−1}^{μ} 2π p dμ′, in f64.
    pub fn cdf(&self, mu: F) -> F {
        F::of(cdf_f64(self.g.f64(), self.alpha.f64(), mu.f64()))
    }
}

/// F(μ) of Draine(g, α) in f64, without the 1/g³ of the textbook form (see the module notes):
///   M₂ = (1 − g²)(1 + μ) T / (12 P (v + v₀)),  P = v v₀,
///   T = 3(1 − μ) Q + s (P − 3a),  Q = (P − a)/g = (g − 2μ)(1 + g)/(v + 1) + 1 − g,
///   s = [g − 2μ − v + μ(g − 2μ)/(v + 1)]/(v + 1),
/// which is H(v) − H(v₀) with its two factors of g divided out analytically (at g = 0 it gives
/// M₂ = (1 + μ³)/6, the isotropic value).
fn cdf_f64(g: f64, alpha: f64, mu: f64) -> f64 {
    cdf_and_density(g, alpha, mu).0
}

/// (F(μ), F′(μ) = 2π p(μ)) sharing one square root; see `cdf_f64`'s notes for the algebra.
#[inline]
fn cdf_and_density(g: f64, alpha: f64, mu: f64) -> (f64, f64) {
    let norm = 1.0 + alpha * (1.0 + 2.0 * g * g) / 3.0;
    let a = 1.0 + g * g;
    // d = 1 + g² − 2gμ written to keep its digits in the peak (as in HG).
    let d = if g >= 0.0 {
        (1.0 - g) * (1.0 - g) + 2.0 * g * (1.0 - mu)
    } else {
        (1.0 + g) * (1.0 + g) - 2.0 * g * (1.0 + mu)
    };
    let v = Real::sqrt(d.max(0.0));
    let v0 = 1.0 + g;
    let f_hg = (1.0 - g) * (1.0 + mu) / (v * (v0 + v));
    let p = v * v0;
    let q = (g - 2.0 * mu) * (1.0 + g) / (v + 1.0) + 1.0 - g;
    let s = (g - 2.0 * mu - v + mu * (g - 2.0 * mu) / (v + 1.0)) / (v + 1.0);
    let t = 3.0 * (1.0 - mu) * q + s * (p - 3.0 * a);
    let m2 = (1.0 - g * g) * (1.0 + mu) * t / (12.0 * p * (v + v0));
    let density = 0.5 * (1.0 - g * g) / (d * v) * (1.0 + alpha * mu * mu) / norm;
    ((f_hg + alpha * m2) / norm, density)
}

/// p(μ) of Draine(g, α) in f64.
fn pdf_f64(g: f64, alpha: f64, mu: f64) -> f64 {
    cdf_and_density(g, alpha, mu).1 / (2.0 * core::f64::consts::PI)
}

/// μ with F(μ) = ξ (see [`invert_cdf`]).
fn invert_cdf_f64(g: f64, alpha: f64, xi: f64, guess: &InverseGuess) -> f64 {
    let xi = xi.clamp(0.0, 1.0);
    // One Newton step from the Hermite guess; a step below 1e-7 leaves an error of order
    // step² · p′/p — far below 1e-12 — so the result stands without another CDF evaluation.
    let mu0 = guess.at(xi);
    let (f, density) = cdf_and_density(g, alpha, mu0);
    let step = (f - xi) / density;
    let mu1 = mu0 - step;
    if step.abs() < 1e-7 && (-1.0..=1.0).contains(&mu1) {
        return mu1;
    }
    invert_cdf(
        |mu| cdf_f64(g, alpha, mu),
        |mu| pdf_f64(g, alpha, mu),
        xi,
        mu0,
    )
}

/// Draine's p(μ) (sr⁻¹) without building the sampler's table: for callers that only evaluate
/// at ever-changing (g, α), such as the fits of `nephele fit`.
#[inline]
pub fn phase_draine<F: Real>(g: F, alpha: F, mu: F) -> F {
    let one = F::of(1.0);
    let norm = one + alpha * (one + F::of(2.0) * g * g) / F::of(3.0);
    HenyeyGreenstein::new(g).eval(mu) * (one + alpha * mu * mu) / norm
}

impl<F: Real> PhaseFunction<F> for Draine<F> {
    #[inline]
    fn eval(&self, mu: F) -> F {
        phase_draine(self.g, self.alpha, mu)
    }

    #[inline]
    fn pdf_cosine(&self, c: Cosine<F>) -> F {
        let mu = c.mu;
        HenyeyGreenstein::new(self.g).pdf_cosine(c) * (F::of(1.0) + self.alpha * mu * mu)
            / self.norm()
    }

    fn sample_cosine(&self, xi: F) -> Cosine<F> {
        let mu = invert_cdf_f64(self.g.f64(), self.alpha.f64(), xi.f64(), &self.guess);
        Cosine {
            mu: F::of(mu),
            one_minus_mu: F::of(1.0 - mu),
        }
    }

    fn mean_cosine(&self) -> Option<F> {
        let (g, a) = (self.g, self.alpha);
        let one = F::of(1.0);
        Some(g * (one + a * (F::of(3.0) + F::of(2.0) * g * g) / F::of(5.0)) / self.norm())
    }
}
