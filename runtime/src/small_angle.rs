//! Sines and cosines of small angles without a library call.

/// (sin d, cos d) of a small angle d (radians, |d| ≤ 0.025) by their Taylor series to d⁷ and
/// d⁶ (truncation below 4e-18): a few multiplications where a library call would cost ~20 ns.
/// For turning a tabulated angle by its remainder (the slab walk's azimuths, a tabulated phase
/// function's half angles).
#[inline]
pub fn sin_cos_small(d: f64) -> (f64, f64) {
    let d2 = d * d;
    let cos_d = 1.0 - d2 * (0.5 - d2 * (1.0 / 24.0 - d2 * (1.0 / 720.0)));
    let sin_d = d * (1.0 - d2 * (1.0 / 6.0 - d2 * (1.0 / 120.0 - d2 * (1.0 / 5040.0))));
    (sin_d, cos_d)
}
