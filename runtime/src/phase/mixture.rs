//! Two-lobe mixtures: two-term HG and the HG + Draine blend of Jendersie & d'Eon (2023).
//!
//!   p(μ) = w p₁(μ) + (1 − w) p₂(μ),  ⟨μ⟩ = w ⟨μ⟩₁ + (1 − w) ⟨μ⟩₂.
//!
//! Sampling picks lobe 1 when ξ < w and reuses ξ/w (else (ξ − w)/(1 − w)) inside the lobe; the
//! pdf of the sample is the mixture's.

use super::{Cosine, Draine, HenyeyGreenstein, PhaseFunction};
use crate::real::Real;

/// A weighted pair of lobes.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Mixture<A, B, F> {
    /// Lobe taken with probability `w`.
    pub first: A,
    /// Lobe taken with probability 1 − `w`.
    pub second: B,
    /// Weight of the first lobe, in [0, 1].
    pub w: F,
}

impl<F: Real, A: PhaseFunction<F>, B: PhaseFunction<F>> PhaseFunction<F> for Mixture<A, B, F> {
    #[inline]
    fn eval(&self, mu: F) -> F {
        self.w * self.first.eval(mu) + (F::of(1.0) - self.w) * self.second.eval(mu)
    }

    #[inline]
    fn pdf_cosine(&self, c: Cosine<F>) -> F {
        self.w * self.first.pdf_cosine(c) + (F::of(1.0) - self.w) * self.second.pdf_cosine(c)
    }

    #[inline]
    fn sample_cosine(&self, xi: F) -> Cosine<F> {
        let one = F::of(1.0);
        if xi < self.w {
            self.first.sample_cosine(xi / self.w)
        } else {
            self.second
                .sample_cosine(((xi - self.w) / (one - self.w)).clamp_to(F::of(0.0), one))
        }
    }

    fn mean_cosine(&self) -> Option<F> {
        let (a, b) = (self.first.mean_cosine()?, self.second.mean_cosine()?);
        Some(self.w * a + (F::of(1.0) - self.w) * b)
    }
}

/// Two-term HG: w HG(g₁) + (1 − w) HG(g₂).
pub type TwoTermHg<F> = Mixture<HenyeyGreenstein<F>, HenyeyGreenstein<F>, F>;

impl<F: Real> TwoTermHg<F> {
    /// w HG(g1) + (1 − w) HG(g2).
    pub fn two_term(g1: F, g2: F, w: F) -> Self {
        Self {
            first: HenyeyGreenstein::new(g1),
            second: HenyeyGreenstein::new(g2),
            w,
        }
    }
}

/// HG + Draine (Jendersie & d'Eon 2023): (1 − w_D) HG(g_HG) + w_D Draine(g_D, α).
pub type HgDraine<F> = Mixture<HenyeyGreenstein<F>, Draine<F>, F>;

impl<F: Real> HgDraine<F> {
    /// (1 − w_d) HG(g_hg) + w_d Draine(g_d, α).
    pub fn hg_draine(g_hg: F, g_d: F, alpha: F, w_d: F) -> Self {
        Self {
            first: HenyeyGreenstein::new(g_hg),
            second: Draine::new(g_d, alpha),
            w: F::of(1.0) - w_d,
        }
    }
}
