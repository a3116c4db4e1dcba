//! The statistics nephele's stages and its ports share: the chi-square test every sampling
//! routine is held to, the adaptive quadrature its expected counts come from, and the seed
//! mixer that derives independent random streams. A crate of its own so that a port's tests
//! (nephele-wgsl) can use the same test without building the whole toolchain.

pub mod chi2;

/// The SplitMix64 finaliser (Steele, Lea & Flood 2014): a bijection of u64 that makes nearby
/// inputs unrelated, for deriving the seeds of independent random streams (a slab batch, a
/// pixel) from a run's seed and an index, the same whichever thread asks.
pub fn splitmix64(mut z: u64) -> u64 {
    z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
    z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
    z ^ (z >> 31)
}

/// ∫_a^b f by adaptive Simpson to absolute tolerance `tol` (never below what f64 resolves).
pub fn adaptive_simpson(f: &dyn Fn(f64) -> f64, a: f64, b: f64, tol: f64) -> f64 {
    #[allow(clippy::too_many_arguments)]
    fn rec(
        f: &dyn Fn(f64) -> f64,
        a: f64,
        b: f64,
        fa: f64,
        fm: f64,
        fb: f64,
        whole: f64,
        tol: f64,
        depth: u32,
    ) -> f64 {
        let m = 0.5 * (a + b);
        let (flm, frm) = (f(0.5 * (a + m)), f(0.5 * (m + b)));
        let left = (m - a) / 6.0 * (fa + 4.0 * flm + fm);
        let right = (b - m) / 6.0 * (fm + 4.0 * frm + fb);
        let err = left + right - whole;
        if depth == 0 || err.abs() <= 15.0 * tol.max(1e-16 * whole.abs()) {
            return left + right + err / 15.0;
        }
        rec(f, a, m, fa, flm, fm, left, 0.5 * tol, depth - 1)
            + rec(f, m, b, fm, frm, fb, right, 0.5 * tol, depth - 1)
    }
    let (fa, fm, fb) = (f(a), f(0.5 * (a + b)), f(b));
    rec(
        f,
        a,
        b,
        fa,
        fm,
        fb,
        (b - a) / 6.0 * (fa + 4.0 * fm + fb),
        tol,
        40,
    )
}
