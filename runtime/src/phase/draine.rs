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
//! Hermite guess when that step's own error bound is below 1e-14 (nearly always: the table
//! refines itself where the guess is poor), else inside a shrinking bracket to |F − ξ| ≤
//! 1e-14 — whatever the output precision: an f32 sample is the exact root rounded once.

use super::{invert_cdf, Cosine, HenyeyGreenstein, PhaseFunction};
use crate::real::Real;

/// Draine's phase function with asymmetry-like g ∈ (−1, 1) and α ≥ 0.
///
/// Construction tabulates the inverse CDF at up to 257 nodes, refined where a cubic Hermite
/// guess between them is poor (≈ 0.1–0.5 ms, 8 KB in the struct), so that sampling can start
/// Newton's method from that guess and nearly always stop after one step. Build it with
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

/// Most nodes of the inverse-CDF guess table, and the first, uniform ones in ξ.
const GUESS_NODES: usize = 257;
const GUESS_START: usize = 16;

/// Buckets of the guide from ξ to the node interval.
const GUIDE_N: usize = 64;

/// The table's aim: the Hermite guess within this of the inverse at every interval's middle,
/// in μ and in the CDF (μ's miss times 2πp), so that one Newton step lands within ~C·1e-16
/// (C = |p′/(2p)|) of the root.
const GUESS_TOLERANCE: f64 = 2e-8;

/// The inverse CDF μ(ξ) at nodes ξ_k, refined where a cubic Hermite guess between them is
/// poor (where the density is small, dμ/dξ is large and changes fast: the backward
/// hemisphere of a forward peak, the middle of a strong μ² term): per node (ξ, μ, dμ/dξ,
/// 1/(ξ_{k+1} − ξ_k)), and a guide from 64 buckets of ξ to the first interval of each.
#[derive(Clone, Copy, Debug, PartialEq)]
struct InverseGuess {
    nodes: [[f64; 4]; GUESS_NODES],
    count: usize,
    guide: [u16; GUIDE_N + 1],
}

impl InverseGuess {
    fn new(g: f64, alpha: f64) -> Self {
        let node = |xi: f64| {
            let mu = invert_cdf(
                |m| cdf_f64(g, alpha, m),
                |m| pdf_f64(g, alpha, m),
                xi,
                HenyeyGreenstein::new(g).sample_mu(xi),
            );
            [xi, mu, cdf_and_inverse_density(g, alpha, mu).1, 0.0]
        };
        let mut nodes = [[0.0; 4]; GUESS_NODES];
        let mut count = GUESS_START + 1;
        for (k, n) in nodes[..count].iter_mut().enumerate() {
            *n = node(k as f64 / GUESS_START as f64);
        }
        // Halve the intervals whose guess misses the inverse at their middle, pass by pass
        // (from the start each pass, so the table does not depend on any order but ξ's); an
        // interval that passed keeps its ends, so it is not checked again.
        let mut settled = [false; GUESS_NODES];
        loop {
            let mut split = false;
            let mut k = 0;
            while k + 1 < count && count < GUESS_NODES {
                if settled[k] {
                    k += 1;
                    continue;
                }
                let (a, b) = (nodes[k], nodes[k + 1]);
                let middle = node(0.5 * (a[0] + b[0]));
                let miss = (hermite(&a, &b, middle[0]) - middle[1]).abs();
                if miss > GUESS_TOLERANCE * middle[2].min(1.0) {
                    nodes.copy_within(k + 1..count, k + 2);
                    settled.copy_within(k + 1..count, k + 2);
                    nodes[k + 1] = middle;
                    settled[k + 1] = false;
                    count += 1;
                    split = true;
                    k += 2;
                } else {
                    settled[k] = true;
                    k += 1;
                }
            }
            if !split || count >= GUESS_NODES {
                break;
            }
        }
        for k in 0..count - 1 {
            nodes[k][3] = 1.0 / (nodes[k + 1][0] - nodes[k][0]);
        }
        let mut guide = [0u16; GUIDE_N + 1];
        let mut k = 0;
        for (j, entry) in guide.iter_mut().enumerate() {
            let xi = j as f64 / GUIDE_N as f64;
            while k + 2 < count && nodes[k + 1][0] <= xi {
                k += 1;
            }
            *entry = k as u16;
        }
        Self {
            nodes,
            count,
            guide,
        }
    }

    /// The cubic Hermite guess of μ(ξ) in its interval.
    #[inline]
    fn at(&self, xi: f64) -> f64 {
        let xi = xi.clamp(0.0, 1.0);
        let mut k = self.guide[((xi * GUIDE_N as f64) as usize).min(GUIDE_N)] as usize;
        while k + 2 < self.count && self.nodes[k + 1][0] <= xi {
            k += 1;
        }
        hermite(&self.nodes[k], &self.nodes[k + 1], xi)
    }
}

/// The cubic Hermite interpolation between nodes a and b (ξ, μ, dμ/dξ, 1/(ξ_b − ξ_a)) at ξ;
/// `a[3]` = 0 (not yet known) is taken from the two ξ.
#[inline]
fn hermite(a: &[f64; 4], b: &[f64; 4], xi: f64) -> f64 {
    let h = b[0] - a[0];
    let inv = if a[3] > 0.0 { a[3] } else { 1.0 / h };
    let t = (xi - a[0]) * inv;
    let (t2, t3) = (t * t, t * t * t);
    let (h00, h10, h01, h11) = (
        2.0 * t3 - 3.0 * t2 + 1.0,
        t3 - 2.0 * t2 + t,
        -2.0 * t3 + 3.0 * t2,
        t3 - t2,
    );
    (h00 * a[1] + h10 * h * a[2] + h01 * b[1] + h11 * h * b[2]).clamp(-1.0, 1.0)
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
    cdf_and_inverse_density(g, alpha, mu).0
}

/// (F(μ), 1/F′(μ) = 1/(2π p(μ))) sharing one square root; see `cdf_f64`'s notes for the
/// algebra. F_HG and M₂ share their denominator: with w = 1/(v (v₀ + v)) and P = v v₀,
/// F_HG = (1 − g)(1 + μ) w and M₂ = (1 − g)(1 + μ) T w / 12, so that
/// F = (1 − g)(1 + μ) w (1 + α T/12) / N — four independent divisions instead of eight on the
/// square root's chain (Newton's step multiplies by the returned reciprocal density).
#[inline]
fn cdf_and_inverse_density(g: f64, alpha: f64, mu: f64) -> (f64, f64) {
    let norm = 1.0 + alpha * (1.0 + 2.0 * g * g) * (1.0 / 3.0);
    let a = 1.0 + g * g;
    // d = 1 + g² − 2gμ written to keep its digits in the peak (as in HG).
    let d = if g >= 0.0 {
        (1.0 - g) * (1.0 - g) + 2.0 * g * (1.0 - mu)
    } else {
        (1.0 + g) * (1.0 + g) - 2.0 * g * (1.0 + mu)
    };
    let v = Real::sqrt(d.max(0.0));
    let v0 = 1.0 + g;
    let r1 = 1.0 / (v + 1.0);
    let w = 1.0 / (v * (v0 + v));
    let p = v * v0;
    let q = (g - 2.0 * mu) * (1.0 + g) * r1 + 1.0 - g;
    let s = (g - 2.0 * mu - v + mu * (g - 2.0 * mu) * r1) * r1;
    let t = 3.0 * (1.0 - mu) * q + s * (p - 3.0 * a);
    let f = (1.0 - g) * (1.0 + mu) * w * (1.0 + alpha * t * (1.0 / 12.0)) / norm;
    let inverse_density = 2.0 * (d * v) * norm / ((1.0 - g * g) * (1.0 + alpha * mu * mu));
    (f, inverse_density)
}

/// p(μ) of Draine(g, α) in f64.
fn pdf_f64(g: f64, alpha: f64, mu: f64) -> f64 {
    1.0 / (2.0 * core::f64::consts::PI * cdf_and_inverse_density(g, alpha, mu).1)
}

/// μ with F(μ) = ξ (see [`invert_cdf`]).
fn invert_cdf_f64(g: f64, alpha: f64, xi: f64, guess: &InverseGuess) -> f64 {
    let xi = xi.clamp(0.0, 1.0);
    match one_step(g, alpha, xi, guess) {
        Ok(mu) => mu,
        Err(mu0) => invert_cdf(
            |mu| cdf_f64(g, alpha, mu),
            |mu| pdf_f64(g, alpha, mu),
            xi,
            mu0,
        ),
    }
}

/// One Newton step from the Hermite guess: Ok(μ) when it is the root, else Err(the guess).
/// It leaves an error of C s² in μ, s the step and C = |p′/(2p)| = |3g/(2d) + αμ/(1 + αμ²)|,
/// and of 2πp C s² in the CDF: when both are below 1e-14 the result stands without another
/// CDF evaluation. (A bound on s alone does not do: inside a strong peak C and p are both
/// large.)
#[inline]
fn one_step(g: f64, alpha: f64, xi: f64, guess: &InverseGuess) -> Result<f64, f64> {
    let mu0 = guess.at(xi);
    let (f, inverse_density) = cdf_and_inverse_density(g, alpha, mu0);
    let step = (f - xi) * inverse_density;
    let mu1 = mu0 - step;
    if step.abs() < 1e-5 && (-1.0..=1.0).contains(&mu1) {
        // C s² ≤ 1e-14 min(1, 1/(2πp)), times d (1 + αμ²) > 0 so as not to divide.
        let (d, e) = (1.0 + g * g - 2.0 * g * mu1, 1.0 + alpha * mu1 * mu1);
        let c = (1.5 * g * e + alpha * mu1 * d).abs();
        if c * step * step <= 1e-14 * inverse_density.min(1.0) * d * e {
            return Ok(mu1);
        }
    }
    Err(mu0)
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

#[cfg(test)]
mod tests {
    use super::*;

    /// The guess table does its job: over 10⁵ ξ, one Newton step from it is the root for at
    /// least 99 % of them, across the fits' range (a strong μ² term, peaks of both signs).
    #[test]
    fn one_newton_step_from_the_guess_nearly_always_suffices() {
        for (g, alpha) in [
            (0.594, 27.1),
            (0.65, 131.0),
            (1e-6, 250.0),
            (-0.99, 250.0),
            (0.99, 0.0),
            (0.9, 10.0),
            (0.3, 0.5),
        ] {
            let guess = InverseGuess::new(g, alpha);
            let n = 100_000;
            let stopped = (0..n)
                .filter(|&i| one_step(g, alpha, (i as f64 + 0.5) / n as f64, &guess).is_ok())
                .count();
            assert!(
                stopped as f64 >= 0.99 * n as f64,
                "g = {g}, α = {alpha}: {stopped} of {n} after one step ({} nodes)",
                guess.count
            );
        }
    }
}
