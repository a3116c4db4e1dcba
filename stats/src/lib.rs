//! The statistics nephele's stages and its ports share: the chi-square test every sampling
//! routine is held to, the adaptive quadrature its expected counts come from, the seed
//! mixer that derives independent random streams, and the tests' point generators. A crate of
//! its own so that a port's tests (nephele-wgsl) can use the same test without building the
//! whole toolchain.

pub mod chi2;

/// The SplitMix64 finaliser (Steele, Lea & Flood 2014): a bijection of u64 that makes nearby
/// inputs unrelated, for deriving the seeds of independent random streams (a slab batch, a
/// pixel) from a run's seed and an index, the same whichever thread asks.
pub fn splitmix64(mut z: u64) -> u64 {
    z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
    z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
    z ^ (z >> 31)
}

/// Marsaglia's xorshift64 (shifts 13, 7, 17): the point generator of the tests and benches, a
/// stream fixed by its seed and cheap enough to sit inside a timing loop. Not for estimators
/// (they use rand's generators).
#[derive(Clone, Debug)]
pub struct XorShift64(u64);

impl XorShift64 {
    /// The stream from `seed` (0 is replaced by a fixed odd constant: xorshift stays at 0).
    pub fn new(seed: u64) -> Self {
        Self(if seed == 0 {
            0x9E37_79B9_7F4A_7C15
        } else {
            seed
        })
    }

    /// The next 64 bits.
    #[inline]
    pub fn next_u64(&mut self) -> u64 {
        self.0 ^= self.0 << 13;
        self.0 ^= self.0 >> 7;
        self.0 ^= self.0 << 17;
        self.0
    }

    /// Uniform on [0, 1) in steps of 2⁻²⁴ (the top 24 bits).
    #[inline]
    pub fn unit_f32(&mut self) -> f32 {
        (self.next_u64() >> 40) as f32 / (1u64 << 24) as f32
    }

    /// Uniform on [0, 1) in steps of 2⁻⁵³ (the top 53 bits).
    #[inline]
    pub fn unit_f64(&mut self) -> f64 {
        (self.next_u64() >> 11) as f64 / (1u64 << 53) as f64
    }
}

/// Marsaglia's xorshift32 (shifts 13, 17, 5), the 32-bit form of [`XorShift64`].
#[derive(Clone, Debug)]
pub struct XorShift32(u32);

impl XorShift32 {
    /// The stream from `seed` (0 is replaced by 1).
    pub fn new(seed: u32) -> Self {
        Self(seed.max(1))
    }

    /// The next 32 bits.
    #[inline]
    pub fn next_u32(&mut self) -> u32 {
        self.0 ^= self.0 << 13;
        self.0 ^= self.0 >> 17;
        self.0 ^= self.0 << 5;
        self.0
    }

    /// Uniform on [0, 1]: the bits over u32::MAX, in f32.
    #[inline]
    pub fn unit_f32(&mut self) -> f32 {
        self.next_u32() as f32 / u32::MAX as f32
    }
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
