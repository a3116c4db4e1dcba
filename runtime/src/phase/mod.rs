//! Phase-function models: evaluation, pdf, exact sampling, mean cosine.
//!
//! Conventions: μ = cos θ between the incident and scattered propagation directions (μ = 1 is
//! forward); every model is normalised, ∮ p dΩ = 1, unit sr⁻¹. `sample_mu(ξ)` maps ξ ∈ [0, 1]
//! to a cosine distributed as p; for single-lobe models it is the inverse CDF (monotone in ξ),
//! for mixtures it picks a lobe with ξ and reuses the rescaled ξ within it.

pub(crate) use crate::simd::Simd;

/// `unsafe fn sample_cosines_with(&self, simd, xi, out)` for a model `$ty` whose
/// `$any(&self, xi, out)` (`#[inline(always)]`) takes many samples at once: that loop compiled
/// for AVX-512 (F, DQ and VL), for AVX2 or as built, as `simd` says. No fused multiply–add is
/// formed in any copy, so all give the one-at-a-time samples' bits. The model's
/// `sample_cosines` calls it with [`Simd::detected`].
macro_rules! sample_cosines_on_cpu {
    ($ty:ty, $any:ident) => {
        /// [`PhaseFunction::sample_cosines`] on the vector units `simd`.
        ///
        /// # Safety
        /// The CPU has what `simd` names ([`Simd::detected`] or a level below it).
        #[inline]
        unsafe fn sample_cosines_with(&self, simd: Simd, xi: &[F], out: &mut [Cosine<F>]) {
            #[cfg(all(feature = "std", target_arch = "x86_64"))]
            {
                #[target_feature(enable = "avx512f,avx512dq,avx512vl,avx2")]
                fn avx512<F: Real>(model: &$ty, xi: &[F], out: &mut [Cosine<F>]) {
                    model.$any(xi, out)
                }
                #[target_feature(enable = "avx2")]
                fn avx2<F: Real>(model: &$ty, xi: &[F], out: &mut [Cosine<F>]) {
                    model.$any(xi, out)
                }
                match simd {
                    // SAFETY: the caller's promise.
                    Simd::Avx512 => return unsafe { avx512(self, xi, out) },
                    // SAFETY: the caller's promise.
                    Simd::Avx2 => return unsafe { avx2(self, xi, out) },
                    Simd::Baseline => {}
                }
            }
            let _ = simd;
            self.$any(xi, out);
        }
    };
}

mod draine;
mod hg;
mod mixture;
pub mod named;
mod rayleigh;
mod reynolds_mccormick;
mod schlick;
mod tabulated;
mod vmf;
mod xlf;

pub use draine::{phase_draine, Draine};
pub use hg::HenyeyGreenstein;
pub use mixture::{HgDraine, TwoTermHg};
pub use rayleigh::Rayleigh;
pub use reynolds_mccormick::ReynoldsMcCormick;
pub use schlick::Schlick;
#[cfg(feature = "std")]
pub use tabulated::TabulatedTable;
pub(crate) use tabulated::{angle, phase_between};
pub use tabulated::{TableError, Tabulated, TabulatedChannels};
pub use vmf::VonMisesFisher;
pub use xlf::{Xlf, XLF_G_MAX};

use crate::frame::{direction_from_cosine, Vec3};
use crate::real::{Math, Real};

/// A sampled scattering cosine with 1 − μ carried separately: near a strong forward peak
/// (HG with g = 0.998 at 50 µm) f32 cannot tell μ from 1, while 1 − μ keeps full precision.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Cosine<F> {
    /// μ = cos θ.
    pub mu: F,
    /// 1 − μ, accurate to relative precision.
    pub one_minus_mu: F,
}

impl<F: Real> Cosine<F> {
    /// From μ alone (1 − μ then has only absolute precision).
    pub fn from_mu(mu: F) -> Self {
        Self {
            mu,
            one_minus_mu: F::of(1.0) - mu,
        }
    }

    /// From 1 − μ.
    pub fn from_one_minus_mu(one_minus_mu: F) -> Self {
        Self {
            mu: F::of(1.0) - one_minus_mu,
            one_minus_mu,
        }
    }
}

/// A normalised phase function of the scattering cosine.
pub trait PhaseFunction<F: Real> {
    /// p(μ), sr⁻¹.
    fn eval(&self, mu: F) -> F;

    /// Density of `sample`'s directions per steradian: p(μ) for exact samplers.
    fn pdf(&self, mu: F) -> F {
        self.eval(mu)
    }

    /// A scattering cosine distributed as p, from ξ ∈ [0, 1]. Single-lobe models invert the
    /// CDF of μ, F(μ) = 2π ∫_{−1}^{μ} p: ξ = 0 gives μ = −1 and μ increases with ξ. Mixtures
    /// pick a lobe with ξ, so theirs is not monotone (docs/conventions.md, Sampling tables).
    fn sample_mu(&self, xi: F) -> F {
        self.sample_cosine(xi).mu
    }

    /// [`Self::sample_mu`] with 1 − μ kept precise.
    fn sample_cosine(&self, xi: F) -> Cosine<F>;

    /// [`Self::sample_cosine`] of every ξ in `xi` into `out`, in order: one call for many
    /// samples (a slab walk's lanes), so that the model's own sampler is inlined into the loop
    /// rather than called through a trait object for each. The same values as one at a time.
    fn sample_cosines(&self, xi: &[F], out: &mut [Cosine<F>]) {
        for (c, &x) in out.iter_mut().zip(xi) {
            *c = self.sample_cosine(x);
        }
    }

    /// [`Self::pdf`] from a [`Cosine`], using 1 − μ where it matters.
    fn pdf_cosine(&self, c: Cosine<F>) -> F {
        self.pdf(c.mu)
    }

    /// ⟨μ⟩ in closed form, where one exists.
    fn mean_cosine(&self) -> Option<F>;

    /// The table behind this model, for a tabulated one (so that several channels' tables can
    /// be evaluated together: [`TabulatedChannels`]).
    fn as_tabulated(&self) -> Option<Tabulated<'_, F>> {
        None
    }

    /// A scattered propagation direction around the incident one `wi` (unit), from two uniform
    /// numbers, and its pdf per steradian.
    fn sample(&self, xi1: F, xi2: F, wi: Vec3<F>) -> (Vec3<F>, F) {
        let c = self.sample_cosine(xi1);
        (
            direction_from_cosine(wi, c.mu, c.one_minus_mu, xi2),
            self.pdf_cosine(c),
        )
    }
}

/// 1 / (4π) in the working precision.
#[inline]
pub(crate) fn inv_four_pi<F: Real>() -> F {
    F::of(0.25) / F::PI
}

/// μ ∈ [−1, 1] with cdf(μ) = ξ: Newton steps (F′ = 2π p) from `start`, kept inside a bracket
/// that every step shrinks (bisection when a step would leave it), to |F − ξ| ≤ 1e-14, in f64.
pub(crate) fn invert_cdf(
    cdf: impl Fn(f64) -> f64,
    pdf: impl Fn(f64) -> f64,
    xi: f64,
    start: f64,
) -> f64 {
    let xi = xi.clamp(0.0, 1.0);
    let (mut lo, mut hi) = (-1.0f64, 1.0f64);
    let mut mu = start.clamp(-1.0, 1.0);
    for _ in 0..100 {
        let f = cdf(mu) - xi;
        if Math::abs(f) <= 1e-14 {
            break;
        }
        if f > 0.0 {
            hi = mu;
        } else {
            lo = mu;
        }
        let next = mu - f / (2.0 * core::f64::consts::PI * pdf(mu));
        mu = if next > lo && next < hi {
            next
        } else {
            0.5 * (lo + hi)
        };
        if hi - lo < 1e-15 {
            break;
        }
    }
    mu
}
