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
use nephele_runtime::frame::{orthonormal_basis, sin_cos_small};
use nephele_runtime::PhaseFunction;
use rand::{Rng, SeedableRng};
use rand_xoshiro::Xoshiro256PlusPlus;
use std::f64::consts::PI;
use std::sync::LazyLock;

/// Photons walked side by side in a batch (see [`Slice::run_batch`]).
const LANES: usize = 2;

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
    /// The phase function (its exact `sample_cosine` gives the scattering angle).
    pub phase: &'a (dyn PhaseFunction<f64> + Sync),
}

/// The random stream of batch `batch` of slice `slice` for run seed `seed`: the same numbers
/// whichever thread runs it.
pub fn batch_rng(seed: u64, slice: u64, batch: u64) -> Xoshiro256PlusPlus {
    // SplitMix64 finaliser of a combination of the three: distinct inputs → unrelated seeds.
    let z = seed
        ^ slice.wrapping_mul(0x9E37_79B9_7F4A_7C15)
        ^ batch.wrapping_mul(0xD1B5_4A32_D192_ED03);
    Xoshiro256PlusPlus::seed_from_u64(crate::stats::splitmix64(z))
}

/// The state of one photon of the walk.
struct Photon {
    /// (x, z, d) relative to the entry point, mfp.
    pos: [f64; 3],
    /// Propagation direction, unit.
    dir: [f64; 3],
    /// Scatterings so far.
    order: u32,
    /// Weight (1 unless albedo < 1).
    weight: f64,
    /// Planes at or above the photon's depth (plane 0, the lit face, holds the start): the
    /// planes a flight crosses are found by stepping from here, not by searching.
    above: usize,
}

impl Slice<'_> {
    /// Walks `photons` photons with `rng`, returning the batch's sums. Two photons are walked
    /// side by side, one step of each in turn: their steps are independent chains of latency,
    /// which the core overlaps (a photon that leaves is replaced by the next one at once).
    pub fn run_batch(&self, photons: u64, rng: &mut Xoshiro256PlusPlus) -> BatchTally {
        let mut tally = BatchTally::new(self.grid);
        let mut launched = 0;
        let mut lanes: [Option<Photon>; LANES] = std::array::from_fn(|_| None);
        for lane in lanes.iter_mut() {
            if launched < photons {
                *lane = Some(self.launch());
                launched += 1;
            }
        }
        while lanes.iter().any(Option::is_some) {
            for lane in lanes.iter_mut() {
                if let Some(p) = lane {
                    if !self.step(p, rng, &mut tally) {
                        *lane = (launched < photons).then(|| self.launch());
                        launched += lane.is_some() as u64;
                    }
                }
            }
        }
        if self.mu_l == 1.0 {
            expand_pooled(self.grid, &mut tally);
        }
        tally.photons = photons;
        tally
    }

    /// A photon at the origin of the lit face, along the sun direction.
    fn launch(&self) -> Photon {
        Photon {
            pos: [0.0; 3],
            dir: [
                0.0,
                (1.0 - self.mu_l * self.mu_l).max(0.0).sqrt(),
                self.mu_l,
            ],
            order: 0,
            weight: 1.0,
            above: 1,
        }
    }

    /// One flight of `p` and, if it stays in the slab, its scattering; false once it has left
    /// (or been absorbed).
    #[inline(always)]
    fn step(&self, p: &mut Photon, rng: &mut Xoshiro256PlusPlus, tally: &mut BatchTally) -> bool {
        let s = free_path(rng);
        let d1 = p.pos[2] + s * p.dir[2];
        p.above = self.cross_planes(&p.pos, &p.dir, d1, p.above, p.order, p.weight, tally);
        if d1 <= 0.0 {
            tally.escaped_top += p.weight;
            return false;
        }
        if d1 >= self.grid.thickness() {
            tally.escaped_bottom += p.weight;
            return false;
        }
        for i in 0..3 {
            p.pos[i] += s * p.dir[i];
        }
        p.order = p.order.saturating_add(1);
        tally.events += 1;
        p.dir = scatter(self.phase, p.dir, rng);
        if self.albedo < 1.0 {
            tally.absorbed += p.weight * (1.0 - self.albedo);
            p.weight *= self.albedo;
            if p.weight < ROULETTE_BELOW {
                if rng.random::<f64>() >= ROULETTE_SURVIVAL {
                    tally.absorbed += p.weight;
                    return false;
                }
                tally.absorbed -= p.weight * (1.0 / ROULETTE_SURVIVAL - 1.0);
                p.weight /= ROULETTE_SURVIVAL;
            }
        }
        true
    }

    /// Records every plane the flight from `pos` along `dir` to depth `d1` crosses, given the
    /// number `above` of planes at or above the start; returns that number at the end.
    #[allow(clippy::too_many_arguments)]
    #[inline]
    fn cross_planes(
        &self,
        pos: &[f64; 3],
        dir: &[f64; 3],
        d1: f64,
        above: usize,
        order: u32,
        weight: f64,
        tally: &mut BatchTally,
    ) -> usize {
        let depths = &self.grid.depths;
        let down = dir[2] > 0.0;
        let crosses = if down {
            above < depths.len() && depths[above] <= d1
        } else {
            above > 0 && depths[above - 1] >= d1
        };
        if !crosses {
            return above;
        }
        if order == 0 {
            return visit_planes(depths, above, d1, down, |j| tally.direct[j] += weight);
        }
        let (first, inv_dz, proj) = if self.mu_l == 1.0 {
            self.pooled_frame(dir, order)
        } else {
            let (m, k, mirror) = self.direction_bin(dir);
            let first = self.grid.cell(self.grid.group(order), 0, m, k);
            (first, 1.0 / dir[2], [mirror, 0.0, 0.0, 1.0])
        };
        let inv_mu = self.grid.crossing_weight(weight, inv_dz.abs());
        let halo = if down {
            self.aureole_cell(dir, order)
        } else {
            None
        };
        let flux = if down { &mut tally.down } else { &mut tally.up };
        let cells = &mut tally.cells;
        let aureole = &mut tally.aureole;
        visit_planes(depths, above, d1, down, |j| {
            flux[j] += weight;
            if let Some((first, stride)) = halo {
                aureole[first + j * stride] += inv_mu;
            }
            let along = (depths[j] - pos[2]) * inv_dz;
            let (x, z) = (pos[0] + along * dir[0], pos[1] + along * dir[1]);
            let cell = &mut cells[first + j];
            cell[0] += inv_mu;
            cell[1] += inv_mu * (proj[0] * x + proj[1] * z);
            cell[2] += inv_mu * (proj[2] * x + proj[3] * z);
            cell[3] += inv_mu * (x * x + z * z);
        })
    }

    /// At normal incidence (μ_L = 1) nothing fixes an azimuth and the radiance does not depend
    /// on ψ_V. Every crossing belongs to every ψ_V bin k with weight Δψ_k/π, turned about the
    /// vertical to an azimuth uniform in the bin, its displacement turned with it; the turn is
    /// averaged out exactly. Turned to azimuth ψ, a displacement with components (a, b) along and
    /// across the flight's own horizontal direction becomes (x, z) = (a sin ψ + b cos ψ,
    /// a cos ψ − b sin ψ), linear in (sin ψ, cos ψ); so the walk sums w/|μ| · (1, a, b, a² + b²)
    /// once per crossing, in the ψ_V = 0 cell, and [`expand_pooled`] spreads the batch's sums over
    /// the bins with the bins' means of sin ψ and cos ψ. The expectation is that of the plain
    /// tally (the azimuth of a crossing is uniform and independent of everything else in the
    /// frame of the flight). Returns that cell, 1/dz and the projection (x, z) → (a, b) as a
    /// row-major 2×2 matrix.
    fn pooled_frame(&self, dir: &[f64; 3], order: u32) -> (usize, f64, [f64; 4]) {
        let g = self.grid;
        let first = g.cell(g.group(order), 0, g.mu_bin(-dir[2]), 0);
        let r = (dir[0] * dir[0] + dir[1] * dir[1]).sqrt();
        // 1/dz and the (sin, cos) of the flight's own azimuth from one division (any azimuth
        // for a vertical flight).
        let (inv_dz, s_c, c_c) = if r > 0.0 {
            let inv = 1.0 / (dir[2] * r);
            (inv * r, dir[0] * inv * dir[2], dir[1] * inv * dir[2])
        } else {
            (1.0 / dir[2], 0.0, 1.0)
        };
        (first, inv_dz, [s_c, c_c, c_c, -s_c])
    }

    /// For a flight going down within the aureole's widest cone around the beam: its cell at
    /// plane 0 and the stride from plane to plane ([`SlabGrid::aureole_cell`]).
    #[inline]
    fn aureole_cell(&self, dir: &[f64; 3], order: u32) -> Option<(usize, usize)> {
        let g = self.grid;
        let sin_l = (1.0 - self.mu_l * self.mu_l).max(0.0).sqrt();
        let b = g.aureole.bin(dir[1] * sin_l + dir[2] * self.mu_l)?;
        Some((g.aureole_cell(g.group(order), 0, b), g.aureole.n_bins()))
    }

    /// (μ_V bin, ψ_V bin, ±1 for the mirror of x) of a propagation direction.
    fn direction_bin(&self, dir: &[f64; 3]) -> (usize, usize, f64) {
        let mirror = if dir[0] < 0.0 { -1.0 } else { 1.0 };
        (
            self.grid.mu_bin(-dir[2]),
            self.grid.psi_bin_of(dir[0], dir[1]),
            mirror,
        )
    }
}

/// Calls `f` for every plane a flight to depth `d1` crosses, from the `above` planes at or above
/// its start, going down (`down`) or up; returns the number of planes at or above its end. One
/// loop both finds and visits the planes (one mispredicted exit per flight, not two).
#[inline(always)]
fn visit_planes(
    depths: &[f64],
    above: usize,
    d1: f64,
    down: bool,
    mut f: impl FnMut(usize),
) -> usize {
    let mut end = above;
    if down {
        while end < depths.len() && depths[end] <= d1 {
            f(end);
            end += 1;
        }
    } else {
        while end > 0 && depths[end - 1] >= d1 {
            end -= 1;
            f(end);
        }
    }
    end
}

/// Spreads the normal-incidence sums w/|μ| · (1, a, b, a² + b²) of the ψ_V = 0 cells (see
/// [`Slice::pooled_frame`]) over every ψ_V bin k: Δψ_k/π · (1, a S_k + b C_k, a C_k − b S_k,
/// a² + b²), with S_k, C_k the bin's means of sin ψ and cos ψ.
fn expand_pooled(g: &SlabGrid, tally: &mut BatchTally) {
    let means = g.psi_bin_means();
    for group in 0..g.groups.len() {
        for m in 0..g.n_mu() {
            for j in 0..g.depths.len() {
                let [w, a, b, q] = tally.cells[g.cell(group, j, m, 0)];
                if w == 0.0 {
                    continue;
                }
                for (k, &[share, s, c]) in means.iter().enumerate() {
                    tally.cells[g.cell(group, j, m, k)] = [
                        share * w,
                        share * (a * s + b * c),
                        share * (a * c - b * s),
                        share * q,
                    ];
                }
            }
        }
    }
}

/// A free path in mean free paths: −ln(1 − ξ), ξ ∈ [0, 1), never infinite.
#[inline]
pub fn free_path(rng: &mut Xoshiro256PlusPlus) -> f64 {
    -(1.0 - rng.random::<f64>()).ln()
}

/// A new direction: the cosine from the phase function's exact sampler, the azimuth from
/// [`unit_circle`], in the frame of Duff et al. around the old direction.
#[inline]
pub fn scatter(
    phase: &(dyn PhaseFunction<f64> + Sync),
    dir: [f64; 3],
    rng: &mut Xoshiro256PlusPlus,
) -> [f64; 3] {
    turn_direction(dir, sample_turn(phase, rng))
}

/// A scattering drawn apart from the direction it turns: (cos θ, sin θ cos φ, sin θ sin φ).
#[inline]
fn sample_turn(phase: &(dyn PhaseFunction<f64> + Sync), rng: &mut Xoshiro256PlusPlus) -> [f64; 3] {
    let c = phase.sample_cosine(rng.random::<f64>());
    let (cos_phi, sin_phi) = unit_circle(rng.random::<f64>());
    let sin2 = if c.mu > 0.0 {
        c.one_minus_mu * (2.0 - c.one_minus_mu)
    } else {
        1.0 - c.mu * c.mu
    };
    let sin_theta = sin2.max(0.0).sqrt();
    [c.mu, cos_phi * sin_theta, sin_phi * sin_theta]
}

/// `dir` turned by `turn` (see [`sample_turn`]), in the frame of Duff et al. around it.
#[inline]
fn turn_direction(dir: [f64; 3], [mu, u, v]: [f64; 3]) -> [f64; 3] {
    let (t, s) = orthonormal_basis(dir);
    normalised([
        u * t[0] + v * s[0] + mu * dir[0],
        u * t[1] + v * s[1] + mu * dir[1],
        u * t[2] + v * s[2] + mu * dir[2],
    ])
}

/// Entries of the azimuth table: φ = 2π(k + f)/AZIMUTHS splits into a tabulated angle and a
/// remainder δ < 2π/256 = 0.0245 whose sine and cosine take a few terms of their series.
const AZIMUTHS: usize = 256;

/// (cos, sin) of 2πk/AZIMUTHS.
static AZIMUTH_TABLE: LazyLock<[(f64, f64); AZIMUTHS]> = LazyLock::new(|| {
    std::array::from_fn(|k| {
        let (s, c) = (2.0 * PI * k as f64 / AZIMUTHS as f64).sin_cos();
        (c, s)
    })
});

/// (cos φ, sin φ) of φ = 2πξ, ξ ∈ [0, 1), without a branch or a library call: the table entry
/// of ⌊256ξ⌋ turned by the remainder δ, cos δ and sin δ by their Taylor series to δ⁶ and δ⁷
/// (truncation below 4e-18), so within a few ulps of `sin_cos`.
#[inline]
pub fn unit_circle(xi: f64) -> (f64, f64) {
    let scaled = xi * AZIMUTHS as f64;
    let k = (scaled as usize).min(AZIMUTHS - 1);
    let (sin_d, cos_d) = sin_cos_small((scaled - k as f64) * (2.0 * PI / AZIMUTHS as f64));
    let (c, s) = AZIMUTH_TABLE[k];
    (c * cos_d - s * sin_d, s * cos_d + c * sin_d)
}

/// The direction rescaled to unit length, so that rounding does not drift over thousands of
/// scatterings. |v|² is within ~1e-15 of 1, so one Newton step for 1/√|v|² (1.5 − |v|²/2) is
/// exact to f64 without a square root or a division.
#[inline]
fn normalised(v: [f64; 3]) -> [f64; 3] {
    let inv = 1.5 - 0.5 * (v[0] * v[0] + v[1] * v[1] + v[2] * v[2]);
    [v[0] * inv, v[1] * inv, v[2] * inv]
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn unit_circle_is_sin_cos() {
        let mut worst = 0.0f64;
        for i in 0..100_000 {
            let xi = (i as f64 + 0.37) / 100_000.0;
            let (c, s) = unit_circle(xi);
            let (s0, c0) = (2.0 * PI * xi).sin_cos();
            worst = worst.max((c - c0).abs()).max((s - s0).abs());
        }
        let (c, s) = unit_circle(1.0 - f64::EPSILON / 2.0);
        assert!((c - 1.0).abs() < 1e-15 && s.abs() < 1e-14);
        assert!(worst < 1e-15, "worst {worst}");
    }
}
