//! The photon walk of one slice (t, μ_L): an analog random walk in a plane-parallel slab, depth
//! in mean free paths, launched at the origin of the lit face along the sun direction; every
//! crossing of a tally plane is recorded in its cell (see [`super::tally`]).
//!
//! Frame: position and direction are (x, z, d): x across the sun's horizontal travel direction,
//! z along it, d the depth (down). The sun direction is (0, sin φ_L, μ_L). A propagation
//! direction ω has μ_V = −ω_d and ψ_V = |atan2(ω_x, ω_z)|; a negative azimuth is mirrored, which
//! flips x.

use super::grid::SlabGrid;
use super::tally::BatchTally;
use nephele_runtime::PhaseFunction;
use rand::{Rng, SeedableRng};
use rand_xoshiro::Xoshiro256PlusPlus;

/// Weight below which a photon plays Russian roulette (albedo < 1 only).
const ROULETTE_BELOW: f64 = 1e-3;
/// Survival probability of the roulette.
const ROULETTE_SURVIVAL: f64 = 0.1;

/// One slice of the problem: a slab, a sun, a phase function.
pub struct Slice<'a> {
    /// Tally planes, bins and groups (its last depth is the thickness t).
    pub grid: &'a SlabGrid,
    /// Cosine of the sun beam with the inward normal, in (0, 1].
    pub mu_l: f64,
    /// Single-scattering albedo in (0, 1].
    pub albedo: f64,
    /// The phase function (sampled exactly; `sample` gives the new direction).
    pub phase: &'a (dyn PhaseFunction<f64> + Sync),
}

/// The random stream of batch `batch` of slice `slice` for run seed `seed`: the same numbers
/// whichever thread runs it.
pub fn batch_rng(seed: u64, slice: u64, batch: u64) -> Xoshiro256PlusPlus {
    // SplitMix64 finaliser of a combination of the three: distinct inputs → unrelated seeds.
    let mut z = seed ^ slice.wrapping_mul(0x9E37_79B9_7F4A_7C15) ^ batch.wrapping_mul(0xD1B5_4A32_D192_ED03);
    z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
    z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
    Xoshiro256PlusPlus::seed_from_u64(z ^ (z >> 31))
}

impl Slice<'_> {
    /// Walks `photons` photons with `rng`, returning the batch's sums.
    pub fn run_batch(&self, photons: u64, rng: &mut Xoshiro256PlusPlus) -> BatchTally {
        let mut tally = BatchTally::new(self.grid);
        for _ in 0..photons {
            self.walk(rng, &mut tally);
        }
        tally.photons = photons;
        tally
    }

    fn walk(&self, rng: &mut Xoshiro256PlusPlus, tally: &mut BatchTally) {
        let t = self.grid.thickness();
        let mut pos = [0.0f64; 3];
        let mut dir = [0.0, (1.0 - self.mu_l * self.mu_l).max(0.0).sqrt(), self.mu_l];
        let mut order: u32 = 0;
        let mut weight = 1.0;
        loop {
            // Free path in mfp: −ln(1 − ξ), ξ ∈ [0, 1), never infinite.
            let s = -(1.0 - rng.random::<f64>()).ln();
            let d1 = pos[2] + s * dir[2];
            self.cross_planes(&pos, &dir, d1, order, weight, tally);
            if d1 <= 0.0 {
                tally.escaped_top += weight;
                return;
            }
            if d1 >= t {
                tally.escaped_bottom += weight;
                return;
            }
            for i in 0..3 {
                pos[i] += s * dir[i];
            }
            order = order.saturating_add(1);
            tally.events += 1;
            let (xi1, xi2) = (rng.random::<f64>(), rng.random::<f64>());
            dir = normalised(self.phase.sample(xi1, xi2, dir).0);
            if self.albedo < 1.0 {
                tally.absorbed += weight * (1.0 - self.albedo);
                weight *= self.albedo;
                if weight < ROULETTE_BELOW {
                    if rng.random::<f64>() >= ROULETTE_SURVIVAL {
                        tally.absorbed += weight;
                        return;
                    }
                    tally.absorbed -= weight * (1.0 / ROULETTE_SURVIVAL - 1.0);
                    weight /= ROULETTE_SURVIVAL;
                }
            }
        }
    }

    /// Records every plane the flight from `pos` along `dir` to depth `d1` crosses.
    fn cross_planes(&self, pos: &[f64; 3], dir: &[f64; 3], d1: f64, order: u32, weight: f64, tally: &mut BatchTally) {
        let depths = &self.grid.depths;
        let d0 = pos[2];
        // Planes strictly beyond the start and up to the end (or the face the photon leaves by).
        let planes = if dir[2] > 0.0 {
            depths.partition_point(|d| *d <= d0)..depths.partition_point(|d| *d <= d1)
        } else if dir[2] < 0.0 {
            depths.partition_point(|d| *d < d1)..depths.partition_point(|d| *d < d0)
        } else {
            0..0
        };
        if planes.is_empty() {
            return;
        }
        if order == 0 {
            planes.for_each(|j| tally.direct[j] += weight);
            return;
        }
        let (m, k, mirror) = self.direction_bin(dir);
        let group = self.grid.group(order);
        let inv_mu = weight / dir[2].abs();
        let flux = if dir[2] > 0.0 { &mut tally.down } else { &mut tally.up };
        for j in planes {
            flux[j] += weight;
            let along = (depths[j] - d0) / dir[2];
            let x = mirror * (pos[0] + along * dir[0]);
            let z = pos[1] + along * dir[1];
            let cell = &mut tally.cells[self.grid.cell(group, j, m, k)];
            cell[0] += inv_mu;
            cell[1] += inv_mu * x;
            cell[2] += inv_mu * z;
            cell[3] += inv_mu * (x * x + z * z);
        }
    }

    /// (μ_V bin, ψ_V bin, ±1 for the mirror of x) of a propagation direction.
    fn direction_bin(&self, dir: &[f64; 3]) -> (usize, usize, f64) {
        let mirror = if dir[0] < 0.0 { -1.0 } else { 1.0 };
        (self.grid.mu_bin(-dir[2]), self.grid.psi_bin_of(dir[0], dir[1]), mirror)
    }
}

/// The direction rescaled to unit length (the sampler's rounding would otherwise drift over
/// thousands of scatterings).
fn normalised(v: [f64; 3]) -> [f64; 3] {
    let inv = 1.0 / (v[0] * v[0] + v[1] * v[1] + v[2] * v[2]).sqrt();
    [v[0] * inv, v[1] * inv, v[2] * inv]
}
