//! The walk's photons in SIMD lanes: [`LANES`] photons, each in its own lane of every array, take
//! their steps together. The arithmetic that is the same for all of them (random numbers, the
//! flight, the flight's frame for the tally, the turn to the new direction) runs as loops over
//! the lanes, which the compiler turns into vector instructions; what differs (the planes a
//! flight crosses, leaving the slab) runs lane by lane, and the phase function's sampler takes
//! all lanes in one call (`PhaseFunction::sample_cosines`). The
//! whole walk is compiled three times, for AVX-512, AVX2 and baseline x86-64, and picked at run
//! time ([`super::walk::Slice::run_batch`]); no fused multiply–add is formed, so the three give
//! the same bits.

use rand::RngCore;
use rand_xoshiro::Xoshiro256PlusPlus;

/// Photons walked side by side.
pub const LANES: usize = 8;

/// A value per lane.
pub type Lane<T> = [T; LANES];

/// One xoshiro256++ stream per lane (Blackman & Vigna), seeded from the batch's stream: the
/// same numbers whichever thread or CPU runs the batch.
pub struct LaneRng {
    s: [Lane<u64>; 4],
}

impl LaneRng {
    /// Lane states drawn from `rng` (a state of all zeros, which xoshiro cannot leave, is
    /// replaced by a one).
    pub fn new(rng: &mut Xoshiro256PlusPlus) -> Self {
        let mut s = [[0u64; LANES]; 4];
        for l in 0..LANES {
            for row in s.iter_mut() {
                row[l] = rng.next_u64();
            }
            if s.iter().all(|row| row[l] == 0) {
                s[0][l] = 1;
            }
        }
        Self { s }
    }

    /// A uniform number in [0, 1) per lane, from the top 52 bits of each stream's next output
    /// (the mantissa of a number in [1, 2), less one: exact, and no integer-to-float
    /// conversion, which AVX2 lacks for 64-bit integers).
    #[inline(always)]
    pub fn uniforms(&mut self) -> Lane<f64> {
        // A loop, not `array::map`, which LLVM may compile apart from the walk's vector copies.
        let r = self.outputs();
        let mut u = [0.0; LANES];
        for l in 0..LANES {
            u[l] = uniform_of(r[l]);
        }
        u
    }

    /// Each stream's next output.
    #[inline(always)]
    pub fn outputs(&mut self) -> Lane<u64> {
        let [s0, s1, s2, s3] = &mut self.s;
        let mut out = [0; LANES];
        for l in 0..LANES {
            let r = s0[l]
                .wrapping_add(s3[l])
                .rotate_left(23)
                .wrapping_add(s0[l]);
            let t = s1[l] << 17;
            s2[l] ^= s0[l];
            s3[l] ^= s1[l];
            s1[l] ^= s2[l];
            s0[l] ^= s3[l];
            s2[l] ^= t;
            s3[l] = s3[l].rotate_left(45);
            out[l] = r;
        }
        out
    }
}

/// The uniform number in [0, 1) of a stream's output `r` ([`LaneRng::uniforms`]): its top 52
/// bits over 2⁵².
#[inline(always)]
pub fn uniform_of(r: u64) -> f64 {
    f64::from_bits((r >> 12) | 0x3FF0_0000_0000_0000) - 1.0
}

/// A free path in mean free paths, −ln(1 − ξ) for ξ ∈ [0, 1), without a library call, so that
/// lanes take it together: 1 − ξ = 2^e m with m ∈ [√½, √2), ln m = 2 atanh s = 2 Σ s^(2k+1)/(2k+1)
/// with s = (m − 1)/(m + 1), |s| ≤ 0.1716, summed to s¹⁹ (the next term is below 10⁻¹⁶ of the
/// sum). Within 2 ulp of `-(1 - ξ).ln()` (test `free_path_is_the_logarithm`).
#[inline(always)]
pub fn free_path(xi: f64) -> f64 {
    let v = 1.0 - xi;
    let bits = v.to_bits();
    let m = f64::from_bits((bits & 0x000F_FFFF_FFFF_FFFF) | 0x3FF0_0000_0000_0000);
    let big = m > std::f64::consts::SQRT_2;
    let m = if big { 0.5 * m } else { m };
    // The biased exponent as a float: its bits under 2⁵² (exact), less 2⁵² and the bias.
    let biased = f64::from_bits(0x4330_0000_0000_0000 | (bits >> 52)) - 4_503_599_627_370_496.0;
    let e = biased - 1023.0 + if big { 1.0 } else { 0.0 };
    let s = (m - 1.0) / (m + 1.0);
    let z = s * s;
    let mut series = 1.0 / 19.0;
    for k in (0..9).rev() {
        series = 1.0 / (2 * k + 1) as f64 + z * series;
    }
    // ln 2 in two parts (fdlibm's), the first with 21 trailing zero bits, so that e ln 2 keeps
    // its digits for every exponent.
    const LN2_HI: f64 = f64::from_bits(0x3FE6_2E42_FEE0_0000);
    const LN2_LO: f64 = f64::from_bits(0x3DEA_39EF_3579_3C76);
    -(e * LN2_HI + (e * LN2_LO + 2.0 * s * series))
}

/// ⌊x⌋ held to 0 … `last` (NaN to 0), for bin and table indices: the same index as
/// `(x as i32).clamp(0, last)`, but the lanes convert together. Rust's saturating `as` is
/// compiled lane by lane, each with its NaN test (AVX2 has no such conversion); clamped as a
/// float first (`max` ignores a NaN), the value cannot overflow, and the conversion is one
/// vector instruction.
#[inline(always)]
pub fn floor_index(x: f64, last: usize) -> usize {
    let x = x.max(0.0).min(last.min(i32::MAX as usize) as f64);
    // SAFETY: x is neither NaN nor infinite, and lies in [0, i32::MAX].
    (unsafe { x.to_int_unchecked::<i32>() }) as usize
}

/// For each lane, how many of `edges` satisfy `holds(edge, lane)`: counted over the edges with
/// the lanes innermost, so that the lanes take every comparison together (a binary search's
/// branches go either way at random, a mispredicted jump each).
#[inline(always)]
pub fn count_edges(edges: &[f64], holds: impl Fn(f64, usize) -> bool) -> Lane<usize> {
    let mut n = [0usize; LANES];
    for &e in edges {
        for (l, n) in n.iter_mut().enumerate() {
            *n += holds(e, l) as usize;
        }
    }
    n
}

#[cfg(test)]
mod tests {
    use super::*;
    use rand::{Rng, SeedableRng};

    #[test]
    fn free_path_is_the_logarithm() {
        let mut rng = Xoshiro256PlusPlus::seed_from_u64(3);
        let mut worst = 0.0f64;
        let points = (0..1_000_000).map(|_| rng.random::<f64>()).chain([
            0.0,
            0.5,
            1.0 - f64::EPSILON,
            f64::EPSILON,
            1e-300,
        ]);
        for xi in points {
            let want = -(1.0 - xi).ln();
            let got = free_path(xi);
            let ulp = (want.abs() * f64::EPSILON).max(f64::MIN_POSITIVE);
            if want == 0.0 {
                assert_eq!(got, 0.0);
                continue;
            }
            worst = worst.max((got - want).abs() / ulp);
        }
        assert!(worst <= 2.0, "worst {worst} ulp");
    }

    /// The index is Rust's saturating conversion, held to the bins: inside, at the edges,
    /// beyond them both ways, at ±0, ±∞ and NaN.
    #[test]
    fn floor_index_is_the_saturating_conversion() {
        let mut rng = Xoshiro256PlusPlus::seed_from_u64(11);
        let special = [
            0.0,
            -0.0,
            -0.5,
            -1.0,
            15.0,
            15.999,
            16.0,
            1e300,
            -1e300,
            f64::INFINITY,
            f64::NEG_INFINITY,
            f64::NAN,
            f64::MIN_POSITIVE,
            255.99999999999997,
            256.0,
        ];
        let points = (0..100_000).map(|_| rng.random::<f64>() * 300.0 - 20.0);
        for x in points.chain(special) {
            for last in [0usize, 1, 15, 255] {
                let want = (x as i32).clamp(0, last as i32) as usize;
                assert_eq!(floor_index(x, last), want, "{x} {last}");
            }
        }
    }

    #[test]
    fn lane_uniforms_are_uniform_and_distinct() {
        let mut lanes = LaneRng::new(&mut Xoshiro256PlusPlus::seed_from_u64(5));
        let n = 100_000;
        let mut sum = [0.0; LANES];
        for _ in 0..n {
            let u = lanes.uniforms();
            for l in 0..LANES {
                assert!((0.0..1.0).contains(&u[l]));
                sum[l] += u[l];
            }
        }
        // Mean ½ within 5 standard errors (1/√(12 n)) in every lane, and no two lanes alike.
        let se = 1.0 / (12.0 * n as f64).sqrt();
        assert!(
            sum.iter().all(|s| (s / n as f64 - 0.5).abs() < 5.0 * se),
            "{sum:?}"
        );
        let first = lanes.uniforms();
        assert!((1..LANES).all(|l| first[l] != first[0]));
    }
}
