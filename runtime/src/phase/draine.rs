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
//! cancellation (below), and its inverse is tabulated once as quintic pieces in ξ, each with the
//! largest miss measured inside it. An f32 sample takes the piece's value where that miss is
//! below a sixteenth of an ulp of μ (for nearly every ξ: the result is then within one ulp of the
//! exact root, and almost always the root rounded once). Elsewhere, and always in f64, F(μ) = ξ
//! is solved by Newton's method: one step from the table's guess when that step's own error
//! bound is below 1e-14, else inside a shrinking bracket to |F − ξ| ≤ 1e-14.

use super::{invert_cdf, Cosine, HenyeyGreenstein, PhaseFunction};
use crate::real::{Math, Real};
use crate::soft_math::pow2;

/// Draine's phase function with asymmetry-like g ∈ (−1, 1) and α ≥ 0.
///
/// Construction tabulates the inverse CDF at up to 257 nodes, refined where a quintic Hermite
/// piece between them misses (≈ 0.01–0.4 ms, 27 KB in the struct), so that an f32 sample is
/// nearly always the piece's value and an f64 one nearly always one Newton step from it. Build
/// it with [`Draine::new`]; if `g` or `alpha` are changed afterwards sampling stays exact (the
/// table is then only Newton's starting point) but slower.
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

/// How many times an interval of 1/16 may be halved.
const MAX_HALVINGS: usize = 8;

/// Buckets of the guide from ξ to the interval: 16 × 2⁸, the finest the halvings go, so that
/// every bucket lies inside one interval (each node's ξ is a multiple of 2⁻¹²): no search.
const GUIDE_N: usize = GUESS_START << MAX_HALVINGS;

/// The table's aim: the quintic guess within this of the inverse (in μ) inside every
/// interval, so that an f32 sample can skip Newton's step wherever |μ| ≳ 5·10⁻⁴ (see
/// [`InverseGuess::at`]).
const GUESS_TOLERANCE: f64 = 2e-12;

/// Where an interval's guess is checked against the inverse: t = 1/8 … 7/8.
const CHECKS: usize = 7;

/// One interval of the inverse CDF μ(ξ): its start ξ_a, 1/h, the quintic Hermite
/// μ(ξ_a + t h) = Σ c_i t^i matching μ, dμ/dξ and d²μ/dξ² at both ends, and the largest miss of
/// the guess measured inside it (at t = k/8, k = 1…7).
#[derive(Clone, Copy, Debug, PartialEq)]
struct Interval {
    xi: f64,
    inverse_width: f64,
    c: [f64; 6],
    miss: f64,
}

/// The inverse CDF μ(ξ) as quintic pieces between nodes ξ_k, halved where the guess misses
/// (where the density is small, dμ/dξ is large and changes fast: the backward hemisphere of a
/// forward peak, the middle of a strong μ² term), and a guide from ξ to its interval.
#[derive(Clone, Copy, Debug, PartialEq)]
struct InverseGuess {
    /// The (g, α) it was made for.
    g: f64,
    alpha: f64,
    intervals: [Interval; GUESS_NODES - 1],
    count: usize,
    guide: [u16; GUIDE_N],
}

/// A node of the inverse CDF: ξ, μ(ξ), dμ/dξ = 1/(2πp), d²μ/dξ² = −(dμ/dξ)² p′/p.
type Node = [f64; 4];

impl InverseGuess {
    fn new(g: f64, alpha: f64) -> Self {
        let exact = |xi: f64, start: f64| {
            invert_cdf(
                |m| cdf_f64(g, alpha, m),
                |m| pdf_f64(g, alpha, m),
                xi,
                start,
            )
        };
        let node = |xi: f64| -> Node {
            let mu = exact(xi, HenyeyGreenstein::new(g).sample_mu(xi));
            let slope = cdf_and_inverse_density(g, alpha, mu).1;
            [xi, mu, slope, -slope * slope * log_slope(g, alpha, mu)]
        };
        // The largest miss inside [a, b] and the inverse at its middle.
        let check = |a: &Node, b: &Node| -> (f64, Node) {
            let piece = Interval::new(a, b, 0.0);
            let mut miss = 0.0f64;
            for k in 1..=CHECKS {
                let xi = a[0] + (b[0] - a[0]) * k as f64 / (CHECKS + 1) as f64;
                let guess = piece.eval(xi);
                miss = miss.max((guess - exact(xi, guess)).abs());
            }
            (miss, node(0.5 * (a[0] + b[0])))
        };
        let mut nodes = [[0.0; 4]; GUESS_NODES];
        let mut misses = [0.0f64; GUESS_NODES];
        let mut count = GUESS_START + 1;
        for (k, n) in nodes[..count].iter_mut().enumerate() {
            *n = node(k as f64 / GUESS_START as f64);
        }
        // Halve the intervals whose guess misses the inverse, pass by pass (from the start
        // each pass, so the table does not depend on any order but ξ's); an interval that
        // passed, or cannot be halved, keeps its ends and its measured miss.
        let mut settled = [false; GUESS_NODES];
        loop {
            let mut split = false;
            let mut k = 0;
            while k + 1 < count {
                if settled[k] {
                    k += 1;
                    continue;
                }
                let (miss, middle) = check(&nodes[k], &nodes[k + 1]);
                let narrowest = nodes[k + 1][0] - nodes[k][0] <= 1.0 / GUIDE_N as f64;
                if miss > GUESS_TOLERANCE && !narrowest && count < GUESS_NODES {
                    nodes.copy_within(k + 1..count, k + 2);
                    settled.copy_within(k + 1..count, k + 2);
                    misses.copy_within(k + 1..count, k + 2);
                    nodes[k + 1] = middle;
                    settled[k + 1] = false;
                    count += 1;
                    split = true;
                    k += 2;
                } else {
                    settled[k] = true;
                    misses[k] = miss;
                    k += 1;
                }
            }
            if !split {
                break;
            }
        }
        let mut intervals = [Interval::new(&nodes[0], &nodes[1], 0.0); GUESS_NODES - 1];
        for k in 0..count - 1 {
            intervals[k] = Interval::new(&nodes[k], &nodes[k + 1], misses[k]);
        }
        let mut guide = [0u16; GUIDE_N];
        let mut k = 0;
        for (j, entry) in guide.iter_mut().enumerate() {
            let xi = j as f64 / GUIDE_N as f64;
            while k + 2 < count && nodes[k + 1][0] <= xi {
                k += 1;
            }
            *entry = k as u16;
        }
        Self {
            g,
            alpha,
            intervals,
            count: count - 1,
            guide,
        }
    }

    /// The guess of μ(ξ) and the largest miss measured in its interval.
    #[inline]
    fn at(&self, xi: f64) -> (f64, f64) {
        let bucket = (xi * GUIDE_N as f64) as usize;
        let piece = &self.intervals[self.guide[bucket.min(GUIDE_N - 1)] as usize];
        (piece.eval(xi), piece.miss)
    }
}

impl Interval {
    /// The quintic Hermite piece between nodes a and b (ξ, μ, μ′, μ″), in t = (ξ − ξ_a)/h.
    fn new(a: &Node, b: &Node, miss: f64) -> Self {
        let h = b[0] - a[0];
        let (y0, d0, s0) = (a[1], h * a[2], h * h * a[3]);
        let (y1, d1, s1) = (b[1], h * b[2], h * h * b[3]);
        let dy = y1 - y0;
        let c = [
            y0,
            d0,
            0.5 * s0,
            10.0 * dy - 6.0 * d0 - 4.0 * d1 - 1.5 * s0 + 0.5 * s1,
            -15.0 * dy + 8.0 * d0 + 7.0 * d1 + 1.5 * s0 - s1,
            6.0 * dy - 3.0 * d0 - 3.0 * d1 - 0.5 * s0 + 0.5 * s1,
        ];
        Self {
            xi: a[0],
            inverse_width: 1.0 / h,
            c,
            miss,
        }
    }

    /// Σ c_i t^i at ξ (Estrin's scheme: a short chain), held in [−1, 1].
    #[inline]
    fn eval(&self, xi: f64) -> f64 {
        let c = &self.c;
        let t = (xi - self.xi) * self.inverse_width;
        let t2 = t * t;
        let low = c[0] + c[1] * t;
        let mid = c[2] + c[3] * t;
        let high = c[4] + c[5] * t;
        (low + t2 * (mid + t2 * high)).clamp(-1.0, 1.0)
    }
}

/// p′/p of Draine(g, α): 3g/d + 2αμ/(1 + αμ²), d = 1 + g² − 2gμ.
fn log_slope(g: f64, alpha: f64, mu: f64) -> f64 {
    3.0 * g / (1.0 + g * g - 2.0 * g * mu) + 2.0 * alpha * mu / (1.0 + alpha * mu * mu)
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
        norm(self.g, self.alpha)
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
    let v = Math::sqrt(d.max(0.0));
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

/// μ with F(μ) = ξ to the output's precision: the table's guess where its measured miss is
/// below a sixteenth of an ulp of μ in `digits` bits (for f32, wherever |μ| ≳ 5e-4: the guess
/// rounded once is then within one ulp of the exact root), else Newton's method (see
/// [`invert_cdf`]).
#[inline]
fn invert_cdf_to(g: f64, alpha: f64, xi: f64, guess: &InverseGuess, digits: u32) -> f64 {
    let xi = xi.clamp(0.0, 1.0);
    let (mu0, miss) = guess.at(xi);
    // ulp(μ) > |μ| 2^−digits; the miss may be at most 1/16 of that (a factor 4 of safety on
    // the measured miss, which is sampled at seven points of the interval).
    let own = g == guess.g && alpha == guess.alpha;
    if own && miss * pow2(i64::from(digits) + 4) <= mu0.abs() {
        return mu0;
    }
    match one_step(g, alpha, xi, mu0) {
        Ok(mu) => mu,
        Err(mu0) => invert_cdf(
            |mu| cdf_f64(g, alpha, mu),
            |mu| pdf_f64(g, alpha, mu),
            xi,
            mu0,
        ),
    }
}

/// One Newton step from the guess μ₀: Ok(μ) when it is the root, else Err(μ₀).
/// It leaves an error of C s² in μ, s the step and C = |p′/(2p)| = |3g/(2d) + αμ/(1 + αμ²)|,
/// and of 2πp C s² in the CDF: when both are below 1e-14 the result stands without another
/// CDF evaluation. (A bound on s alone does not do: inside a strong peak C and p are both
/// large.)
#[inline]
fn one_step(g: f64, alpha: f64, xi: f64, mu0: f64) -> Result<f64, f64> {
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
/// at ever-changing (g, α), such as the fits of `nephele fit`. One division: Draine's factor
/// and normalisation ride on HG's ([`HenyeyGreenstein::p_from_d_over`]).
#[inline]
pub fn phase_draine<F: Real>(g: F, alpha: F, mu: F) -> F {
    let hg = HenyeyGreenstein::new(g);
    let one = F::of(1.0);
    hg.p_from_d_over(hg.d_of(mu), one + alpha * mu * mu, norm(g, alpha))
}

/// Draine's normalisation 1 + α(1 + 2g²)/3 (the mean of 1 + αμ² under HG(g)).
#[inline]
fn norm<F: Real>(g: F, alpha: F) -> F {
    let one = F::of(1.0);
    one + alpha * (one + F::of(2.0) * g * g) / F::of(3.0)
}

impl<F: Real> PhaseFunction<F> for Draine<F> {
    #[inline]
    fn eval(&self, mu: F) -> F {
        phase_draine(self.g, self.alpha, mu)
    }

    #[inline]
    fn pdf_cosine(&self, c: Cosine<F>) -> F {
        let (hg, mu) = (HenyeyGreenstein::new(self.g), c.mu);
        let num = F::of(1.0) + self.alpha * mu * mu;
        hg.p_from_d_over(hg.d_of_cosine(c), num, self.norm())
    }

    fn sample_cosine(&self, xi: F) -> Cosine<F> {
        let (g, alpha) = (self.g.f64(), self.alpha.f64());
        let mu = invert_cdf_to(g, alpha, xi.f64(), &self.guess, F::DIGITS);
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

    /// (g, α) across the fits' range and beyond: a strong μ² term, peaks of both signs.
    const PARAMETERS: [(f64, f64); 9] = [
        (0.594, 27.1),
        (0.65, 131.0),
        (1e-6, 250.0),
        (-0.99, 250.0),
        (0.99, 0.0),
        (0.999, 5.0),
        (0.9, 10.0),
        (0.3, 0.5),
        (0.0, 0.0),
    ];

    /// Whether an f32 μ is within one of its ulps of the exact root.
    fn within_one_ulp(mu: f32, exact: f64) -> bool {
        let ulp = (f32::from_bits(mu.abs().to_bits() + 1) - mu.abs()) as f64;
        (mu as f64 - exact).abs() <= ulp
    }

    /// The guess table does its job: over 10⁵ ξ, one Newton step from it is the root for at
    /// least 99 % of them in the fits' range, |g| ≤ 0.99 (at g = 0.999, 95 %: the peak is
    /// narrower than eight halvings of 1/16 in ξ can follow).
    #[test]
    fn one_newton_step_from_the_guess_nearly_always_suffices() {
        for (g, alpha) in PARAMETERS.into_iter().filter(|(g, _)| g.abs() <= 0.99) {
            let guess = InverseGuess::new(g, alpha);
            let n = 100_000;
            let stopped = (0..n)
                .filter(|&i| {
                    let xi = (i as f64 + 0.5) / n as f64;
                    one_step(g, alpha, xi, guess.at(xi).0).is_ok()
                })
                .count();
            assert!(
                stopped as f64 >= 0.99 * n as f64,
                "g = {g}, α = {alpha}: {stopped} of {n} after one step ({} nodes)",
                guess.count
            );
        }
    }

    /// An f32 sample is the exact root to within one ulp wherever the guess is taken as it is
    /// (at least 98 % of ξ), over 10⁵ random ξ and ξ = 0, 1; the others go through Newton's
    /// method.
    #[test]
    fn f32_samples_from_the_guess_are_within_one_ulp_of_the_root() {
        for (g, alpha) in PARAMETERS {
            let d32 = Draine::<f32>::new(g as f32, alpha as f32);
            let d64 = Draine::<f64>::new((g as f32) as f64, (alpha as f32) as f64);
            let n = 100_000;
            let mut from_guess = 0;
            let mut rng = nephele_stats::XorShift64::new(0x9e37_79b9_7f4a_7c15);
            for i in 0..n + 2 {
                let u = rng.unit_f32();
                let xi = match i {
                    0 => 0.0,
                    1 => 1.0,
                    _ => u,
                };
                let (guess, miss) = d32.guess.at(xi as f64);
                from_guess += usize::from(miss * pow2(i64::from(f32::DIGITS) + 4) <= guess.abs());
                let (mu, exact) = (d32.sample_mu(xi), d64.sample_mu(xi as f64));
                assert!(
                    within_one_ulp(mu, exact),
                    "g = {g}, α = {alpha}, ξ = {xi}: {mu} vs {exact}"
                );
            }
            assert!(
                from_guess as f64 >= 0.98 * n as f64,
                "g = {g}, α = {alpha}: {from_guess} of {n} from the guess"
            );
        }
    }

    /// A sampler whose g or α was changed after it was built samples its new parameters.
    #[test]
    fn changed_parameters_are_sampled_exactly() {
        let mut d = Draine::<f32>::new(0.594, 27.1);
        d.g = 0.8;
        d.alpha = 3.0;
        let fresh = Draine::<f64>::new(0.8f32 as f64, 3.0f32 as f64);
        for i in 0..=1000 {
            let xi = i as f32 / 1000.0;
            let (mu, exact) = (d.sample_mu(xi), fresh.sample_mu(xi as f64));
            assert!(within_one_ulp(mu, exact), "ξ = {xi}: {mu} vs {exact}");
        }
    }
}
