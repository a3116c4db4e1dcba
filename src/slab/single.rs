//! The order-1 collector by quadrature: the test of the walk's lateral moments. T₁ itself, the
//! bin-averaged single scattering of the collimated beam, is
//! [`nephele_runtime::transport::single_scattering`] (the renderers' code, used here too).

use crate::stats::gauss::{gauss_legendre, integrate_n};
use nephele_runtime::transport::{scattering_cosine, SlabPoint};
use nephele_runtime::PhaseFunction;

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
pub fn single_scattering_moments(phase: &dyn PhaseFunction<f64>, at: &SlabPoint<f64>) -> [f64; 4] {
    let SlabPoint {
        depth: d,
        thickness: t,
        mu_v,
        psi_v,
        mu_l,
    } = *at;
    let sin_l = (1.0 - mu_l * mu_l).max(0.0).sqrt();
    let sin_v = (1.0 - mu_v * mu_v).max(0.0).sqrt();
    let p = phase.pdf_cosine(scattering_cosine(at));
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

/// The order-1 collector of a bin at the depth, thickness and sun of `at` (its view is not
/// used): (c_x, c_z, σ) from the bin integrals of [`single_scattering_moments`].
pub fn single_scattering_collector(
    phase: &dyn PhaseFunction<f64>,
    at: &SlabPoint<f64>,
    (mu_a, mu_b): (f64, f64),
    (psi_a, psi_b): (f64, f64),
    pieces: usize,
) -> [f64; 3] {
    let [w, x, z, q] = bin_integral(
        &|mu, psi| single_scattering_moments(phase, &at.with_view(mu, psi)),
        (mu_a, mu_b),
        (psi_a, psi_b),
        pieces,
    );
    let (cx, cz) = (-x / w, -z / w);
    [cx, cz, (q / w - cx * cx - cz * cz).max(0.0).sqrt()]
}
