//! Henyey–Greenstein (1941).
//!
//!   p(μ) = (1 − g²) / (4π (1 + g² − 2gμ)^{3/2}),  ⟨μ⟩ = g.
//!
//! Sampling inverts the CDF F(μ) = (1 − g)(1 + μ) / (v (1 + g + v)), v = √(1 + g² − 2gμ). With
//! μ₀ = 2ξ − 1 the textbook root is μ = (1 + g² − t²)/(2g), t = (1 − g²)/(1 + g μ₀), which
//! cancels as g → 0; for |g| ≤ 1/2 we use the same root with the 1/g divided out,
//!   μ = [μ₀ + (g/2)(3 + μ₀²) + g² μ₀ + (g³/2)(μ₀² − 1)] / (1 + g μ₀)²,
//! which in turn cancels in the far tail when |g| → 1 (its numerator tends to (1 + g μ₀)²), so
//! the textbook form serves |g| > 1/2. Both stay accurate in f32 (chi-square test at g = 0.998).

use super::{inv_four_pi, Cosine, PhaseFunction, Simd};
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

    /// p from d = 1 + g² − 2gμ ([`Self::d_of`]) times num/den:
    /// (1 − g²) num / (4π den d^{3/2}) in one division. A model built on HG (Draine's) folds its
    /// own factor and normalisation in here instead of dividing again: the divider is what
    /// bounds a loop of evaluations. With num = den = 1 it is HG's p, bit for bit.
    #[inline]
    pub(crate) fn p_from_d_over(&self, d: F, num: F, den: F) -> F {
        let one = F::of(1.0);
        inv_four_pi::<F>() * (one - self.g) * (one + self.g) * num / (den * (d * d.sqrt()))
    }

    /// d = 1 + g² − 2gμ, written as (1 − g)² + 2g(1 − μ) for g ≥ 0 and (1 + g)² − 2g(1 + μ)
    /// for g < 0, so that the peak's small d keeps its digits (the branch is on g, not μ: free
    /// in a loop).
    #[inline]
    pub(crate) fn d_of(&self, mu: F) -> F {
        let one = F::of(1.0);
        self.d_from(one - mu, one + mu)
    }

    /// [`Self::d_of`] with 1 − μ taken from the cosine (exact near the forward peak).
    #[inline]
    pub(crate) fn d_of_cosine(&self, c: Cosine<F>) -> F {
        self.d_from(c.one_minus_mu, F::of(1.0) + c.mu)
    }

    /// [`Self::d_of`] from 1 − μ and 1 + μ.
    #[inline]
    fn d_from(&self, one_minus_mu: F, one_plus_mu: F) -> F {
        let (one, two, g) = (F::of(1.0), F::of(2.0), self.g);
        if g >= F::of(0.0) {
            (one - g) * (one - g) + two * g * one_minus_mu
        } else {
            (one + g) * (one + g) - two * g * one_plus_mu
        }
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
        self.p_from_d_over(self.d_of(mu), F::of(1.0), F::of(1.0))
    }

    /// As `eval`, with 1 − μ taken from the cosine (exact near the forward peak).
    #[inline]
    fn pdf_cosine(&self, c: Cosine<F>) -> F {
        self.p_from_d_over(self.d_of_cosine(c), F::of(1.0), F::of(1.0))
    }

    #[inline]
    fn sample_cosine(&self, xi: F) -> Cosine<F> {
        let g = self.g;
        let (one, half, two) = (F::of(1.0), F::of(0.5), F::of(2.0));
        let m0 = two * xi - one;
        let s = one + g * m0;
        if g.abs() > half {
            // μ > 0 ⟺ t² < 1 + g² with t = (1 − g²)/s, tested without dividing; then
            // 1 − μ = (1 − g)(1 − ξ)(t + 1 − g)/s = (1 − g)²(1 − ξ)(1 + g + s)/s², exact where μ
            // is not, in one division.
            let (a, b, s2) = ((one - g) * (one + g), one + g * g, s * s);
            if g > F::of(0.0) && a * a < b * s2 {
                let omm = (one - g) * (one - g) * (one - xi) * (one + g + s) / s2;
                return Cosine::from_one_minus_mu(omm.clamp_to(F::of(0.0), one));
            }
            let t = a / s;
            return Cosine::from_mu(((b - t * t) / (two * g)).clamp_to(-one, one));
        }
        let num = m0
            + half * g * (F::of(3.0) + m0 * m0)
            + g * g * m0
            + half * g * g * g * (m0 * m0 - one);
        Cosine::from_mu((num / (s * s)).clamp_to(-one, one))
    }

    fn mean_cosine(&self) -> Option<F> {
        Some(self.g)
    }

    /// Many samples at once, on the CPU's best vector units ([`sample_cosines_on_cpu`]).
    fn sample_cosines(&self, xi: &[F], out: &mut [Cosine<F>]) {
        // SAFETY: the level the CPU has.
        unsafe { self.sample_cosines_with(Simd::detected(), xi, out) }
    }
}

impl<F: Real> HenyeyGreenstein<F> {
    sample_cosines_on_cpu!(HenyeyGreenstein<F>, sample_cosines_any);

    /// `sample_cosine` of each ξ, in a loop the compiler vectorises.
    #[inline(always)]
    fn sample_cosines_any(&self, xi: &[F], out: &mut [Cosine<F>]) {
        for (c, &x) in out.iter_mut().zip(xi) {
            *c = self.sample_cosine(x);
        }
    }
}

#[cfg(all(test, feature = "std"))]
mod tests {
    use super::*;

    /// Many samples at once are each one-at-a-time sample's bits on every vector level the
    /// CPU can run (AVX-512, AVX2, baseline), in f64 and f32, for forward, backward and weak
    /// lobes, at ξ's ends included.
    #[test]
    fn many_samples_are_each_samples_bits() {
        let xi: Vec<f64> = (0..4099)
            .map(|k| k as f64 / 4098.0)
            .chain([1e-300, 1.0 - f64::EPSILON, 0.5])
            .collect();
        let xi32: Vec<f32> = xi.iter().map(|&x| x as f32).collect();
        for g in [0.9, 0.6, 0.3, 0.0, -0.4, -0.85] {
            same_as_one_at_a_time(g, &xi);
            same_as_one_at_a_time(g as f32, &xi32);
        }
    }

    /// Many samples of `xi` on each vector level against `sample_cosine` of each, bit for bit
    /// (f32 values are compared as their exact f64 widening).
    fn same_as_one_at_a_time<F: Real>(g: F, xi: &[F]) {
        let hg = HenyeyGreenstein::new(g);
        let bits = |c: Cosine<F>| (c.mu.f64().to_bits(), c.one_minus_mu.f64().to_bits());
        for simd in Simd::available() {
            let mut many = vec![Cosine::from_mu(F::of(0.0)); xi.len()];
            // SAFETY: a level the CPU has.
            unsafe { hg.sample_cosines_with(simd, xi, &mut many) };
            for (&c, &x) in many.iter().zip(xi) {
                let (g, x) = (g.f64(), x.f64());
                let one = bits(hg.sample_cosine(F::of(x)));
                assert_eq!(bits(c), one, "{simd:?}, g {g}, xi {x}");
            }
        }
    }
}
