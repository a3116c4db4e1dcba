//! Order 1 in closed form: the radiance of light scattered exactly once out of the collimated
//! sun beam, per unit sun irradiance E⊥ (sr⁻¹) — the `T` of order group 1 of the slab tables,
//! from the phase function alone.
//!
//! The beam is attenuated as e^{−d′/μ_L} down to the scattering depth d′; the scattered light
//! as e^{−|d − d′|/|μ_V|} on to the viewpoint at depth d:
//!
//!   T₁ = ϖ p(Θ) ∫ e^{−d′/μ_L} e^{−|d − d′|/|μ_V|} dd′ / |μ_V|,
//!
//! over d′ ∈ [d, t] for μ_V > 0 (light going up, scattered below) and d′ ∈ [0, d] for μ_V < 0:
//!
//!   μ_V > 0:  T₁ = ϖ p(Θ) e^{−d/μ_L} (1 − e^{−a(t − d)}) / (1 + μ_V/μ_L),  a = 1/μ_L + 1/μ_V,
//!   μ_V < 0:  T₁ = ϖ p(Θ) e^{−d/μ_L} (e^{bd} − 1) / (m/μ_L − 1),          m = −μ_V,
//!                                                                          b = 1/μ_L − 1/m,
//!
//! written so that the horizon (μ_V → 0, T₁ → ϖ p e^{−d/μ_L}, the local source) and m = μ_L
//! (T₁ → ϖ p e^{−d/μ_L} d/m) stay finite. The scattering angle Θ between the sun's direction
//! (0, sin φ_L, μ_L) and the view (sin θ_V sin ψ_V, sin θ_V cos ψ_V, −μ_V) in (x, z, depth) is
//! taken as 1 − cos Θ = |ω_L − ω_V|²/2, accurate near the forward peak where cos Θ is not.

use super::geometry::SlabPoint;
use crate::phase::{Cosine, PhaseFunction};
use crate::real::{exp_m1, Real};

/// What order 1 needs of a phase function: its value at a scattering cosine (sr⁻¹). Every
/// [`PhaseFunction`] has it; so do tabulated phase functions stored with compressed tables.
pub trait PhaseValue<F> {
    /// p at `c`.
    fn value(&self, c: Cosine<F>) -> F;
}

impl<F: Real, P: PhaseFunction<F> + ?Sized> PhaseValue<F> for P {
    fn value(&self, c: Cosine<F>) -> F {
        self.pdf_cosine(c)
    }
}

/// 8-point Gauss–Legendre nodes on [−1, 1].
const GL8_X: [f64; 8] = [
    -0.960_289_856_497_536_2,
    -0.796_666_477_413_626_7,
    -0.525_532_409_916_329,
    -0.183_434_642_495_649_8,
    0.183_434_642_495_649_8,
    0.525_532_409_916_329,
    0.796_666_477_413_626_7,
    0.960_289_856_497_536_2,
];
/// Their weights.
const GL8_W: [f64; 8] = [
    0.101_228_536_290_376_26,
    0.222_381_034_453_374_47,
    0.313_706_645_877_887_3,
    0.362_683_783_378_362,
    0.362_683_783_378_362,
    0.313_706_645_877_887_3,
    0.222_381_034_453_374_47,
    0.101_228_536_290_376_26,
];

/// T₁ (sr⁻¹) at `at`, single-scattering albedo `albedo`.
pub fn single_scattering<F: Real, P: PhaseValue<F> + ?Sized>(
    phase: &P,
    albedo: F,
    at: &SlabPoint<F>,
) -> F {
    beam_scattered_once(albedo * phase.value(scattering_cosine(at)), at)
}

/// T₁ at `at` for a phase function of the constant value `p` (sr⁻¹, albedo included): the
/// depth and direction factor of [`single_scattering`], which the log-additive form's F₁ reads
/// with p = 1/(4π) without computing a scattering angle.
pub(crate) fn beam_scattered_once<F: Real>(p: F, at: &SlabPoint<F>) -> F {
    let (zero, one) = (F::of(0.0), F::of(1.0));
    let SlabPoint {
        depth: d,
        thickness: t,
        mu_v,
        mu_l,
        ..
    } = *at;
    let source = p * (-d / mu_l).exp();
    if mu_v == zero {
        // The horizon (either zero): the local source, at the faces too (the limit from
        // inside; the boundary factor of the forms says the same).
        return source;
    }
    if mu_v > zero {
        if t - d <= zero {
            return zero;
        }
        let m = mu_v;
        let a = one / mu_l + one / m;
        source * -exp_m1(-a * (t - d)) / (one + m / mu_l)
    } else {
        if d <= zero {
            return zero;
        }
        let m = -mu_v;
        // m/μ_L − 1 and 1/μ_L − 1/m from m − μ_L, exact where m is near μ_L (Sterbenz): the
        // quotients first would cancel there, up to 1/|m/μ_L − 1| ulps off.
        let ratio_m1 = (m - mu_l) / mu_l;
        let bd = ratio_m1 / m * d;
        if bd.abs() < F::of(1e-3) {
            // (e^{bd} − 1)/(m/μ_L − 1) = (d/m) (e^{bd} − 1)/(bd), the latter by its series.
            source * (d / m) * (one + bd * F::of(0.5) * (one + bd / F::of(3.0)))
        } else if bd < one {
            source * exp_m1(bd) / ratio_m1
        } else {
            // e^{−d/μ_L}(e^{bd} − 1) = e^{−d/m} − e^{−d/μ_L}: e^{bd} alone would overflow
            // (a grazing sun deep in the slab) where the difference does not cancel.
            p * ((-d / m).exp() - (-d / mu_l).exp()) / ratio_m1
        }
    }
}

/// The average of T₁ at the depth, thickness and sun of `at` over the direction bin
/// μ_V ∈ [`mu_a`, `mu_b`] (one sign; the horizon may be an edge), ψ_V ∈ [`psi_a`, `psi_b`]
/// (the view of `at` is not used): 8-point Gauss–Legendre on `pieces` × `pieces` pieces (the
/// Mie forward peak, a few degrees wide, needs several pieces in the bin that holds it).
pub fn single_scattering_bin<F: Real, P: PhaseValue<F> + ?Sized>(
    phase: &P,
    albedo: F,
    at: &SlabPoint<F>,
    (mu_a, mu_b): (F, F),
    (psi_a, psi_b): (F, F),
    pieces: usize,
) -> F {
    let n = F::of(pieces.max(1) as f64);
    let (h_mu, h_psi) = ((mu_b - mu_a) / n, (psi_b - psi_a) / n);
    let half = F::of(0.5);
    let mut sum = F::of(0.0);
    for i in 0..pieces.max(1) {
        let mu_mid = mu_a + h_mu * (F::of(i as f64) + half);
        for (xm, wm) in GL8_X.iter().zip(GL8_W) {
            let mu = mu_mid + half * h_mu * F::of(*xm);
            for k in 0..pieces.max(1) {
                let psi_mid = psi_a + h_psi * (F::of(k as f64) + half);
                for (xp, wp) in GL8_X.iter().zip(GL8_W) {
                    let psi = psi_mid + half * h_psi * F::of(*xp);
                    let w = F::of(wm * wp);
                    sum = sum + w * single_scattering(phase, albedo, &at.with_view(mu, psi));
                }
            }
        }
    }
    // Each piece's rule sums to 2 × 2 over its half-widths: the mean is sum / (4 n²).
    sum / (F::of(4.0) * n * n)
}

/// cos Θ between the sun's propagation direction and the view (μ_V, ψ_V) of `at`, with
/// 1 − cos Θ = |ω_L − ω_V|²/2.
pub fn scattering_cosine<F: Real>(at: &SlabPoint<F>) -> Cosine<F> {
    let SlabPoint {
        mu_v, psi_v, mu_l, ..
    } = *at;
    let one = F::of(1.0);
    // sin from (1 − |μ|)(1 + |μ|): 1 − μ² itself cancels near |μ| = 1 (the sun overhead, a
    // view straight up or down), where 1 − |μ| is exact.
    let sin = |mu: F| {
        ((one - mu.abs()) * (one + mu.abs()))
            .clamp_to(F::of(0.0), one)
            .sqrt()
    };
    let (sin_l, sin_v) = (sin(mu_l), sin(mu_v));
    let (s, c) = psi_v.sin_cos();
    let (dx, dz, dd) = (sin_v * s, sin_l - sin_v * c, mu_l + mu_v);
    let omm = F::of(0.5) * (dx * dx + dz * dz + dd * dd);
    Cosine::from_one_minus_mu(omm.clamp_to(F::of(0.0), F::of(2.0)))
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A slab point from (μ_L, t, d, μ_V, ψ_V), the order of the tests' tables.
    fn at<F>(mu_l: F, thickness: F, depth: F, mu_v: F, psi_v: F) -> SlabPoint<F> {
        SlabPoint {
            depth,
            thickness,
            mu_v,
            psi_v,
            mu_l,
        }
    }
    use crate::phase::HenyeyGreenstein;

    /// T₁ by brute-force quadrature over the scattering depth (f64, 20 000 midpoints).
    fn brute(g: f64, mu_l: f64, t: f64, d: f64, mu_v: f64, psi_v: f64) -> f64 {
        let hg = HenyeyGreenstein::new(g);
        let p = hg.pdf_cosine(scattering_cosine(&at(mu_l, t, d, mu_v, psi_v)));
        let (lo, hi) = if mu_v > 0.0 { (d, t) } else { (0.0, d) };
        let n = 20_000;
        let h = (hi - lo) / n as f64;
        (0..n)
            .map(|i| {
                let dp = lo + (i as f64 + 0.5) * h;
                p * (-dp / mu_l - (d - dp).abs() / mu_v.abs()).exp() / mu_v.abs() * h
            })
            .sum()
    }

    #[test]
    fn closed_form_matches_quadrature_and_limits() {
        let hg = HenyeyGreenstein::new(0.8);
        for &(mu_l, t, d, mu_v, psi) in &[
            (0.5, 2.0, 0.7, 0.3, 0.4),
            (0.5, 2.0, 0.7, -0.3, 2.0),
            (0.9, 8.0, 3.0, -0.9, 0.0), // m = μ_L: the series branch
            (0.3, 1.0, 0.2, -0.95, 1.0),
            (0.2, 8.0, 3.0, -0.8, 0.5), // bd = 11: the difference branch
            (1.0, 4.0, 4.0, -0.5, 0.0),
            (0.7, 4.0, 0.0, 0.6, 3.0),
        ] {
            let c = single_scattering(&hg, 1.0, &at(mu_l, t, d, mu_v, psi));
            let b = brute(0.8, mu_l, t, d, mu_v, psi);
            assert!(
                (c - b).abs() <= 1e-7 * b.abs().max(1e-12),
                "{mu_l} {t} {d} {mu_v}: {c} vs {b}"
            );
        }
        // The horizon: T₁ → ϖ p e^{−d/μ_L} from both sides, finite at 0.
        let horizon = |mu_v: f64| single_scattering(&hg, 1.0, &at(0.5, 4.0, 1.0, mu_v, 1.0));
        let local =
            hg.pdf_cosine(scattering_cosine(&at(0.5, 4.0, 1.0, 0.0, 1.0))) * (-2.0f64).exp();
        for mu_v in [0.0, -0.0, 1e-9, -1e-9] {
            assert!(
                (horizon(mu_v) - local).abs() < 1e-6 * local,
                "{mu_v}: {} vs {local}",
                horizon(mu_v)
            );
        }
        // Faces: nothing below the far face going up, nothing above the lit face going down.
        assert_eq!(
            single_scattering(&hg, 1.0, &at(0.5, 4.0, 4.0, 0.5, 0.0)),
            0.0
        );
        assert_eq!(
            single_scattering(&hg, 1.0, &at(0.5, 4.0, 0.0, -0.5, 0.0)),
            0.0
        );
    }

    /// f32 within a few ulps of f64 at the same (f32) point, also where the view looks down
    /// at nearly the sun's angle (m = −μ_V → μ_L, where m/μ_L − 1 would cancel) and where eˣ − 1
    /// is small (0.01 ≤ |x| < 0.5, where eˣ − 1 itself would lose up to 1.2e-5).
    #[test]
    fn f32_follows_f64() {
        let (h32, h64) = (
            HenyeyGreenstein::new(0.85f32),
            HenyeyGreenstein::new(0.85f64),
        );
        let mut worst = 0.0f64;
        let near = [0.2f32, 0.5, 1.0]
            .into_iter()
            .flat_map(|mu_l| (-40..=40).map(move |k| (mu_l, -mu_l * (1.0 + k as f32 * 1e-3))));
        let spread = (0..40).flat_map(|i| {
            [0.5f32, 1.0, 0.2, 0.1].map(|mu_l| (mu_l, -0.99 + 1.98 * i as f32 / 39.0))
        });
        for (mu_l, mu_v) in near.chain(spread) {
            for k in 0..12 {
                let psi = 3.1 * k as f32 / 11.0;
                for &(t, d) in &[
                    (2.0f32, 0.7f32),
                    (16.0, 3.0),
                    (64.0, 0.1),
                    (30.0, 27.7), // e^{bd} beyond f32 for m > μ_L
                    (0.05, 0.02), // small exponents
                ] {
                    let p = at(mu_l, t, d, mu_v.clamp(-1.0, 1.0), psi);
                    let wide = at(mu_l as f64, t as f64, d as f64, p.mu_v as f64, psi as f64);
                    let a = single_scattering(&h64, 1.0, &wide);
                    let b = single_scattering(&h32, 1.0, &p);
                    assert!(b.is_finite(), "f32 T₁ = {b} at {p:?}");
                    // An f32 exponent x carries its own rounding, |x| ulp(1)/2 of relative
                    // error in eˣ: the conditioning, which the tolerance allows for.
                    let m = wide.mu_v.abs().max(1e-3);
                    let exponent = (wide.depth / wide.mu_l).max(wide.thickness / m);
                    let allowed = 1e-6 + 6e-8 * exponent;
                    if a > 1e-30 {
                        worst = worst.max(((b as f64) - a).abs() / a / allowed);
                    }
                }
            }
        }
        // In units of the allowance.
        assert!(
            worst < 1.0,
            "worst relative difference {worst:.2} of the allowance"
        );
    }

    #[test]
    fn bin_average_matches_a_fine_midpoint_rule() {
        // Isotropic scattering (g = 0): T₁ varies only through μ_V, and the rule must give the
        // mean of the closed form over the μ_V range.
        let hg = HenyeyGreenstein::new(0.0);
        let bin = single_scattering_bin(
            &hg,
            1.0,
            &at(0.5, 2.0, 0.5, 0.0, 0.0),
            (0.2, 0.4),
            (0.0, 1.0),
            4,
        );
        let n = 200_000;
        let exact: f64 = (0..n)
            .map(|i| {
                let mu_v = 0.2 + 0.2 * (i as f64 + 0.5) / n as f64;
                single_scattering(&hg, 1.0, &at(0.5, 2.0, 0.5, mu_v, 0.0))
            })
            .sum::<f64>()
            / n as f64;
        assert!((bin - exact).abs() < 1e-9 * exact, "{bin} vs {exact}");
    }
}
