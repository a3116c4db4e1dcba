//! Directions from a sampled scattering cosine: an orthonormal frame around the incident
//! propagation direction (Duff et al. 2017, "Building an Orthonormal Basis, Revisited").

use crate::real::Real;

/// A 3-vector (a direction or a point).
pub type Vec3<F> = [F; 3];

/// Two unit vectors completing `n` (unit) to a right-handed orthonormal basis.
pub fn orthonormal_basis<F: Real>(n: Vec3<F>) -> (Vec3<F>, Vec3<F>) {
    let one = F::of(1.0);
    let sign = if n[2] < F::of(0.0) { -one } else { one };
    let a = -one / (sign + n[2]);
    let b = n[0] * n[1] * a;
    let t = [one + sign * n[0] * n[0] * a, sign * b, -sign * n[0]];
    let s = [b, sign + n[1] * n[1] * a, -n[1]];
    (t, s)
}

/// The direction at cosine `mu` from the propagation direction `wi` and azimuth 2π`xi`;
/// `one_minus_mu` = 1 − μ, given separately because it carries the precision of directions
/// near the forward peak (in f32, μ rounds to 1 within 3e-8 of it; 1 − μ does not).
pub fn direction_from_cosine<F: Real>(wi: Vec3<F>, mu: F, one_minus_mu: F, xi: F) -> Vec3<F> {
    let (t, s) = orthonormal_basis(wi);
    let sin2 = if mu > F::of(0.0) {
        one_minus_mu * (F::of(2.0) - one_minus_mu)
    } else {
        F::of(1.0) - mu * mu
    };
    let sin_theta = sin2.clamp_to(F::of(0.0), F::of(1.0)).sqrt();
    let (sp, cp) = (F::of(2.0) * F::PI * xi).sin_cos();
    let (a, b) = (sin_theta * cp, sin_theta * sp);
    [
        a * t[0] + b * s[0] + mu * wi[0],
        a * t[1] + b * s[1] + mu * wi[1],
        a * t[2] + b * s[2] + mu * wi[2],
    ]
}

/// a × b.
pub fn cross<F: Real>(a: Vec3<F>, b: Vec3<F>) -> Vec3<F> {
    [
        a[1] * b[2] - a[2] * b[1],
        a[2] * b[0] - a[0] * b[2],
        a[0] * b[1] - a[1] * b[0],
    ]
}

/// Dot product.
pub fn dot<F: Real>(a: Vec3<F>, b: Vec3<F>) -> F {
    a[0] * b[0] + a[1] * b[1] + a[2] * b[2]
}
