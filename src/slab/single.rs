//! Order 1 in closed form: the bin-averaged single scattering of the collimated beam, the
//! sharpest test of the walk's normalisation and phase sampling (spec 40).
//!
//! With depths in mfp, albedo ϖ, the beam attenuated as e^{−d′/μ_L} and the scattered light as
//! e^{−|d − d′|/|μ_V|} on its way to depth d:
//!
//!   μ_V > 0 (going up, scattered below d):   T₁ = ϖ p(Θ) e^{d/μ_V} (e^{−a d} − e^{−a t}) / (a μ_V),
//!                                            a = 1/μ_L + 1/μ_V;
//!   μ_V < 0 (going down, scattered above d): T₁ = ϖ p(Θ) e^{−d/m} (1 − e^{−b d}) / (b m),
//!                                            m = −μ_V, b = 1/μ_L − 1/m (→ d/m as b → 0);
//!
//! cos Θ = sin φ_L √(1 − μ_V²) cos ψ_V − μ_L μ_V, then averaged over the bin by Gauss–Legendre.

use crate::stats::gauss::{gauss_legendre, integrate_n};
use nephele_runtime::PhaseFunction;

/// T₁ (sr⁻¹) at depth `d` of a slab of thickness `t`, view (μ_V, ψ_V), sun `mu_l`.
pub fn single_scattering(
    phase: &dyn PhaseFunction<f64>,
    albedo: f64,
    mu_l: f64,
    t: f64,
    d: f64,
    mu_v: f64,
    psi_v: f64,
) -> f64 {
    let p = albedo * phase_at(phase, mu_l, mu_v, psi_v);
    if mu_v > 0.0 {
        let a = 1.0 / mu_l + 1.0 / mu_v;
        // e^{d/μ_V}(e^{−ad} − e^{−at}) = e^{−d/μ_L}(1 − e^{−a(t − d)}).
        p * (-d / mu_l).exp() * -(-a * (t - d)).exp_m1() / (a * mu_v)
    } else {
        let m = -mu_v;
        let b = 1.0 / mu_l - 1.0 / m;
        let path = if (b * d).abs() < 1e-12 {
            d
        } else {
            -(-b * d).exp_m1() / b
        };
        p * (-d / m).exp() * path / m
    }
}

/// The average of T₁ over μ_V ∈ [mu_a, mu_b] (one sign) and ψ_V ∈ [psi_a, psi_b].
#[allow(clippy::too_many_arguments)]
pub fn single_scattering_bin(
    phase: &dyn PhaseFunction<f64>,
    albedo: f64,
    mu_l: f64,
    t: f64,
    d: f64,
    (mu_a, mu_b): (f64, f64),
    (psi_a, psi_b): (f64, f64),
    pieces: usize,
) -> f64 {
    let [sum] = bin_integral(
        &|mu, psi| [single_scattering(phase, albedo, mu_l, t, d, mu, psi)],
        (mu_a, mu_b),
        (psi_a, psi_b),
        pieces,
    );
    sum / ((mu_b - mu_a) * (psi_b - psi_a))
}

/// p(Θ) between the sun (μ_L) and the view (μ_V, ψ_V):
/// cos Θ = sin φ_L √(1 − μ_V²) cos ψ_V − μ_L μ_V.
fn phase_at(phase: &dyn PhaseFunction<f64>, mu_l: f64, mu_v: f64, psi_v: f64) -> f64 {
    let sin_l = (1.0 - mu_l * mu_l).max(0.0).sqrt();
    let cos_theta = sin_l * (1.0 - mu_v * mu_v).max(0.0).sqrt() * psi_v.cos() - mu_l * mu_v;
    phase.eval(cos_theta.clamp(-1.0, 1.0))
}

/// ∫∫ f over μ ∈ [mu_a, mu_b], ψ ∈ [psi_a, psi_b] (8-point Gauss–Legendre on `pieces` pieces
/// per dimension).
fn bin_integral<const N: usize>(
    f: &dyn Fn(f64, f64) -> [f64; N],
    (mu_a, mu_b): (f64, f64),
    (psi_a, psi_b): (f64, f64),
    pieces: usize,
) -> [f64; N] {
    let rule = gauss_legendre(8);
    let over_psi = |mu: f64| integrate_n(&|psi| f(mu, psi), psi_a, psi_b, &rule, pieces);
    integrate_n(&over_psi, mu_a, mu_b, &rule, pieces)
}

/// Order-1 sums per unit solid angle at depth `d`, view (μ_V, ψ_V): the cell vector
/// (W, X, Z, Q) of [`super::tally`] divided by N ΔΩ/μ_L, i.e. T₁ and T₁ times the mean of x′,
/// z and x′² + z² over the depths d′ of the scattering. The photon entered at the origin, reached
/// (0, d′ tan φ_L, d′) along the sun, and flew ℓ = (d − d′)/(−μ_V) to the plane:
/// x′ = ℓ sin θ_V sin ψ_V, z = d′ tan φ_L + ℓ sin θ_V cos ψ_V. By quadrature over d′.
pub fn single_scattering_moments(
    phase: &dyn PhaseFunction<f64>,
    mu_l: f64,
    t: f64,
    d: f64,
    mu_v: f64,
    psi_v: f64,
) -> [f64; 4] {
    let sin_l = (1.0 - mu_l * mu_l).max(0.0).sqrt();
    let sin_v = (1.0 - mu_v * mu_v).max(0.0).sqrt();
    let p = phase_at(phase, mu_l, mu_v, psi_v);
    let m = mu_v.abs();
    // Scattering depths: below d for light going up, above it for light going down.
    let (a, b) = if mu_v > 0.0 { (d, t) } else { (0.0, d) };
    let f = |dp: f64| {
        let w = p * (-dp / mu_l - (d - dp).abs() / m).exp() / m;
        let ell = (d - dp) / -mu_v;
        let x = ell * sin_v * psi_v.sin();
        let z = dp * sin_l / mu_l + ell * sin_v * psi_v.cos();
        [w, w * x, w * z, w * (x * x + z * z)]
    };
    integrate_n(&f, a, b, &gauss_legendre(8), 16)
}

/// The order-1 collector of a bin: (c_x, c_z, σ) from the bin integrals of
/// [`single_scattering_moments`].
#[allow(clippy::too_many_arguments)]
pub fn single_scattering_collector(
    phase: &dyn PhaseFunction<f64>,
    mu_l: f64,
    t: f64,
    d: f64,
    (mu_a, mu_b): (f64, f64),
    (psi_a, psi_b): (f64, f64),
    pieces: usize,
) -> [f64; 3] {
    let [w, x, z, q] = bin_integral(
        &|mu, psi| single_scattering_moments(phase, mu_l, t, d, mu, psi),
        (mu_a, mu_b),
        (psi_a, psi_b),
        pieces,
    );
    let (cx, cz) = (-x / w, -z / w);
    [cx, cz, (q / w - cx * cx - cz * cz).max(0.0).sqrt()]
}
