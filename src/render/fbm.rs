//! Fractal Brownian motion of Perlin noise, the cloud's boundary displacement: the `noise`
//! crate's `Fbm<Perlin>` (the definition: its permutation tables, its arithmetic), evaluated
//! without its per-corner 16-way branch. The crate picks each lattice corner's gradient by a
//! `match` on a hash, a branch no predictor can learn (8 per octave); here the gradient is two
//! signed components read from small tables, the same two-term sum in the same order, so the
//! answers are bit for bit the crate's (tests below, on every kind of point), at a fifth of the
//! cost at scattered points. Both renderers spend much of their time here (the cloud's
//! boundary layer). `get_or_settle` also lets a caller stop at the octave after which the
//! ones left cannot change what it needs (the density's clamp to [0, 1]).
//!
//! Perlin noise at p (one octave, the crate's conventions): corner c = ⌊p⌋ (with the crate's
//! rounding: c = trunc(p) − 1 for p ≤ 0), d = p − c; per corner o ∈ {0, 1}³ the gradient g of
//! hash(c + o) mod 16 dotted with d − o; trilinear blend of the 8 by the quintic
//! s(x) = x³(x(6x − 15) + 10), times 2/√3, clamped to [−1, 1]. fBm sums octaves k = 0…n−1 of
//! seeds seed + k at frequency f λᵏ with weight πᵏ⁺¹, divided by Σ_{k=1}^{n} πᵏ.

use noise::permutationtable::{NoiseHasher, PermutationTable};
use noise::Seedable;

/// The crate's normalisation of one octave to (−1, 1): 2/√3.
const SCALE: f64 = 1.154_700_538_379_251_5;

/// Per hash value h mod 16, the gradient's two non-zero components: (axis, sign) each, in the
/// order the crate adds them (its gradients (±1, ±1, 0), (±1, 0, ±1), (0, ±1, ±1), with 12–15
/// repeating four of them).
const GRADIENT: [[(usize, f64); 2]; 16] = [
    [(0, 1.0), (1, 1.0)],
    [(0, -1.0), (1, 1.0)],
    [(0, 1.0), (1, -1.0)],
    [(0, -1.0), (1, -1.0)],
    [(0, 1.0), (2, 1.0)],
    [(0, -1.0), (2, 1.0)],
    [(0, 1.0), (2, -1.0)],
    [(0, -1.0), (2, -1.0)],
    [(1, 1.0), (2, 1.0)],
    [(1, -1.0), (2, 1.0)],
    [(1, 1.0), (2, -1.0)],
    [(1, -1.0), (2, -1.0)],
    [(0, 1.0), (1, 1.0)],
    [(0, -1.0), (1, 1.0)],
    [(1, -1.0), (2, 1.0)],
    [(1, -1.0), (2, -1.0)],
];

/// fBm of Perlin noise, equal to `noise::Fbm<noise::Perlin>` of the same settings.
#[derive(Clone, Debug)]
pub struct Fbm {
    /// Each octave's permutation of 0…255 (the crate's table of seed + k).
    tables: Vec<[u8; 256]>,
    frequency: f64,
    lacunarity: f64,
    persistence: f64,
    scale_factor: f64,
    /// After octave k, a bound on what the octaves after it can still add to the result
    /// (Σ_{j>k} πʲ⁺¹ × the scale factor, widened for rounding).
    rest: Vec<f64>,
}

/// Relative and absolute widening of `rest`: far above the few ulps by which a sum of at most
/// 32 octaves can differ from its partial sum plus the exact rest.
const REST_SLACK: (f64, f64) = (1e-9, 1e-12);

impl Fbm {
    /// The fBm of `source`'s seed, octaves, frequency, lacunarity and persistence.
    pub fn new(source: &noise::Fbm<noise::Perlin>) -> Self {
        let seed = source.seed();
        let tables = (0..source.octaves as u32)
            .map(|k| {
                // The crate's seed of octave k (wrapping, as its release build does).
                let table = PermutationTable::new(seed.wrapping_add(k));
                std::array::from_fn(|i| table.hash(&[i as isize]) as u8)
            })
            .collect();
        let denom =
            (1..=source.octaves).fold(0.0, |acc, k| acc + source.persistence.powi(k as i32));
        let scale_factor = 1.0 / denom;
        let weight = |k: usize| source.persistence.powi(k as i32 + 1) * scale_factor;
        let rest = (0..source.octaves)
            .map(|k| {
                let r: f64 = (k + 1..source.octaves).map(weight).sum();
                r * (1.0 + REST_SLACK.0) + REST_SLACK.1
            })
            .collect();
        Self {
            tables,
            frequency: source.frequency,
            lacunarity: source.lacunarity,
            persistence: source.persistence,
            scale_factor,
            rest,
        }
    }

    /// The fBm at p (its input units: the cloud scales p by its frequency first).
    pub fn get(&self, p: [f64; 3]) -> f64 {
        match self.get_or_settle(p, |_, _, _| None::<std::convert::Infallible>) {
            Ok(value) => value,
            Err(never) => match never {},
        }
    }

    /// The fBm at p, or what `settled(k, lo, hi)` returns as soon as it returns something: it
    /// is asked after each octave k but the last, with [lo, hi] holding the final value
    /// whatever the octaves left add. A caller that needs only which side of a threshold the
    /// value falls on skips the octaves that cannot change it.
    #[inline(always)]
    pub fn get_or_settle<T>(
        &self,
        p: [f64; 3],
        mut settled: impl FnMut(usize, f64, f64) -> Option<T>,
    ) -> Result<f64, T> {
        let mut point = p.map(|x| x * self.frequency);
        let (mut result, mut attenuation) = (0.0, self.persistence);
        let last = self.tables.len() - 1;
        for (k, table) in self.tables.iter().enumerate() {
            result += perlin(table, point) * attenuation;
            if k < last {
                let so_far = result * self.scale_factor;
                if let Some(answer) = settled(k, so_far - self.rest[k], so_far + self.rest[k]) {
                    return Err(answer);
                }
            }
            attenuation *= self.persistence;
            point = point.map(|x| x * self.lacunarity);
        }
        Ok(result * self.scale_factor)
    }

    /// Per octave k, a bound on the slope of the sum of octaves 0 … k (the part of the value
    /// `get_or_settle` knows after octave k, scaled as the value is) per unit of its input,
    /// given `perlin_slope`, a bound on one octave's slope per unit of the octave's own input:
    /// octave j contributes πʲ⁺¹ λʲ f times the scale factor. Within a distance r of p the
    /// value then lies within [lo − Lₖ r, hi + Lₖ r] of the [lo, hi] known after octave k
    /// (the octaves left are bounded everywhere by the same `rest`).
    pub fn partial_slopes(&self, perlin_slope: f64) -> Vec<f64> {
        let (mut slope, mut each) = (0.0, perlin_slope * self.frequency * self.persistence);
        (0..self.tables.len())
            .map(|_| {
                slope += each * self.scale_factor;
                each *= self.lacunarity * self.persistence;
                slope * (1.0 + REST_SLACK.0)
            })
            .collect()
    }
}

/// Per hash value h mod 16, the gradient (x, y, z) of [`GRADIENT`] with its zero component.
/// Its dot product (g_x q_x + g_y q_y) + g_z q_z adds the same two non-zero terms in the same
/// order as the crate, and a term 0·q changes a sum only in the sign of an exact zero, which the
/// octave sum (from +0) loses.
const GRADIENT_XYZ: [[f64; 3]; 16] = {
    let mut g = [[0.0; 3]; 16];
    let mut h = 0;
    while h < 16 {
        let [(a, sa), (b, sb)] = GRADIENT[h];
        g[h][a] = sa;
        g[h][b] = sb;
        h += 1;
    }
    g
};

/// One octave of Perlin noise with permutation `perm`. The eight corners are taken side by
/// side (corner index 4 o_z + 2 o_x + o_y), so that their dot products and the blends along z
/// fill vector registers.
#[inline(always)]
fn perlin(perm: &[u8; 256], p: [f64; 3]) -> f64 {
    // The crate's corner: truncation, one lower at p ≤ 0 (so p = 0 lies at d = 1).
    let corner = p.map(|x| if x <= 0.0 { x as isize - 1 } else { x as isize });
    let d: [f64; 3] = std::array::from_fn(|k| p[k] - corner[k] as f64);
    let wrap = |k: usize, o: isize| ((corner[k] + o) & 0xff) as usize;
    // The crate's hash, level by level: x, then y, then z.
    let hx = [perm[wrap(0, 0)] as usize, perm[wrap(0, 1)] as usize];
    let hxy = [
        perm[hx[0] ^ wrap(1, 0)] as usize,
        perm[hx[0] ^ wrap(1, 1)] as usize,
        perm[hx[1] ^ wrap(1, 0)] as usize,
        perm[hx[1] ^ wrap(1, 1)] as usize,
    ];
    let mut dot = [0.0f64; 8];
    for (c, v) in dot.iter_mut().enumerate() {
        let (oz, ox, oy) = (c >> 2, (c >> 1) & 1, c & 1);
        let h = perm[hxy[2 * ox + oy] ^ wrap(2, oz as isize)] as usize;
        let g = GRADIENT_XYZ[h & 0b1111];
        let q = [d[0] - ox as f64, d[1] - oy as f64, d[2] - oz as f64];
        *v = (g[0] * q[0] + g[1] * q[1]) + g[2] * q[2];
    }
    let s = d.map(quintic);
    // Along z: the crate's linear(g(x, y, 0), g(x, y, 1), s_z) for (x, y) = 00, 01, 10, 11.
    let along_z: [f64; 4] = std::array::from_fn(|i| linear(dot[i], dot[4 + i], s[2]));
    let x0 = linear(along_z[0], along_z[1], s[1]);
    let x1 = linear(along_z[2], along_z[3], s[1]);
    (linear(x0, x1, s[0]) * SCALE).clamp(-1.0, 1.0)
}

/// The crate's blend: b α + a (1 − α).
fn linear(a: f64, b: f64, alpha: f64) -> f64 {
    b * alpha + a * (1.0 - alpha)
}

/// The quintic fade s(x) = x³(x(6x − 15) + 10) of x clamped to [0, 1].
fn quintic(x: f64) -> f64 {
    let x = x.clamp(0.0, 1.0);
    x * x * x * (x * (x * 6.0 - 15.0) + 10.0)
}

#[cfg(test)]
mod tests {
    use super::*;
    use noise::{MultiFractal, NoiseFn};
    use rand::{Rng, SeedableRng};

    /// Bit for bit the crate's fBm at random points of every scale, at lattice points (integer
    /// coordinates, where the crate's corner rounding differs from ⌊p⌋), at ±0 and at
    /// negative coordinates, for several seeds, octave counts and frequencies.
    #[test]
    fn equals_the_noise_crate_bit_for_bit() {
        let mut rng = rand_xoshiro::Xoshiro256PlusPlus::seed_from_u64(7);
        for (seed, octaves, frequency) in [(1, 4, 1.0), (7, 6, 1.0), (3, 1, 0.37), (0, 10, 2.5)] {
            let reference = noise::Fbm::<noise::Perlin>::new(seed)
                .set_octaves(octaves)
                .set_frequency(frequency);
            let fast = Fbm::new(&reference);
            let check = |p: [f64; 3]| {
                let (a, b) = (reference.get(p), fast.get(p));
                assert_eq!(a.to_bits(), b.to_bits(), "{p:?}: crate {a}, ours {b}");
            };
            for _ in 0..200_000 {
                let scale = [1e-3, 1.0, 10.0, 300.0, 1e5][rng.random_range(0..5)];
                check(std::array::from_fn(|_| {
                    scale * (2.0 * rng.random::<f64>() - 1.0)
                }));
            }
            for _ in 0..20_000 {
                check(std::array::from_fn(|_| rng.random_range(-300..300) as f64));
            }
            for p in [[0.0; 3], [-0.0; 3], [0.0, -0.0, 1.0], [-1.0, -256.0, 255.5]] {
                check(p);
            }
        }
    }
}
