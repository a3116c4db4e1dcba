//! The photon walk of one slice (t, μ_L): an analog random walk in a plane-parallel slab, depth
//! in mean free paths, launched at the origin of the lit face along the sun direction; every
//! crossing of a tally plane is recorded in its cell (see [`super::tally`]).
//!
//! Frame: position and direction are (x, z, d): x across the sun's horizontal travel direction,
//! z along it, d the depth (down). The sun direction is (0, sin φ_L, μ_L). A propagation
//! direction ω has μ_V = −ω_d and ψ_V = |atan2(ω_x, ω_z)|; a negative azimuth is mirrored, which
//! flips x.

use super::grid::SlabGrid;
use super::lanes::{free_path as free_path_of, Lane, LaneRng, LANES};
use super::tally::BatchTally;
use nephele_runtime::fitting::sin_cos_small;
#[cfg(target_arch = "x86_64")]
use nephele_runtime::fitting::Simd;
use nephele_runtime::frame::orthonormal_basis;
use nephele_runtime::phase::Cosine;
use nephele_runtime::PhaseFunction;
use rand::{Rng, SeedableRng};
use rand_xoshiro::Xoshiro256PlusPlus;
use std::f64::consts::PI;
use std::sync::LazyLock;

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

/// The photons of the lanes ([`super::lanes`]), one per lane of each array.
struct Photons {
    /// (x, z, d) relative to the entry point, mfp.
    pos: [Lane<f64>; 3],
    /// Propagation direction, unit.
    dir: [Lane<f64>; 3],
    /// Scatterings so far.
    order: Lane<u32>,
    /// Weight (1 unless albedo < 1).
    weight: Lane<f64>,
    /// Planes at or above the photon's depth (plane 0, the lit face, holds the start): the
    /// planes a flight crosses are found by stepping from here, not by searching.
    above: Lane<usize>,
    /// Whether the lane holds a photon (the batch's last ones leave lanes empty).
    alive: Lane<bool>,
}

/// A flight's frame for the tally: its μ_V and ψ_V bins, 1/ω_d, the projection of (x, z) onto
/// its cells' two coordinates (row-major 2 × 2), the weight w/|μ| of each crossing, and its
/// aureole annulus if it goes down (the number of annuli: none).
struct FlightFrame {
    m: Lane<usize>,
    k: Lane<usize>,
    inv_dz: Lane<f64>,
    proj: [Lane<f64>; 4],
    inv_mu: Lane<f64>,
    annulus: Lane<usize>,
}

impl Slice<'_> {
    /// Walks `photons` photons with `rng`, returning the batch's sums: [`LANES`] photons side
    /// by side ([`super::lanes`]), a photon that leaves replaced by the next one at once; the
    /// walk compiled for the best of AVX-512, AVX2 and baseline x86-64 the CPU has, all three
    /// the same bits.
    pub fn run_batch(&self, photons: u64, rng: &mut Xoshiro256PlusPlus) -> BatchTally {
        #[cfg(target_arch = "x86_64")]
        match Simd::detected() {
            // SAFETY: the CPU has the features the function is compiled for.
            Simd::Avx512 => return unsafe { self.run_batch_avx512(photons, rng) },
            // SAFETY: as above.
            Simd::Avx2 => return unsafe { self.run_batch_avx2(photons, rng) },
            Simd::Baseline => {}
        }
        self.run_lanes(photons, rng)
    }

    #[cfg(target_arch = "x86_64")]
    #[target_feature(enable = "avx512f,avx512dq,avx512vl,avx2")]
    unsafe fn run_batch_avx512(&self, photons: u64, rng: &mut Xoshiro256PlusPlus) -> BatchTally {
        self.run_lanes(photons, rng)
    }

    #[cfg(target_arch = "x86_64")]
    #[target_feature(enable = "avx2")]
    unsafe fn run_batch_avx2(&self, photons: u64, rng: &mut Xoshiro256PlusPlus) -> BatchTally {
        self.run_lanes(photons, rng)
    }

    /// The walk of [`Self::run_batch`], compiled into each of its variants.
    #[inline(always)]
    fn run_lanes(&self, photons: u64, rng: &mut Xoshiro256PlusPlus) -> BatchTally {
        let mut tally = BatchTally::new(self.grid);
        // The unscattered flights by the number of planes at or above their end (see
        // `cross_planes`); the direct beam's fluxes follow from them after the walk.
        let mut direct_ends = vec![0.0; self.grid.depths.len() + 1];
        let mut lanes = LaneRng::new(rng);
        let mut p = Photons {
            pos: [[0.0; LANES]; 3],
            dir: [[0.0; LANES]; 3],
            order: [0; LANES],
            weight: [1.0; LANES],
            above: [1; LANES],
            alive: [false; LANES],
        };
        let mut launched = 0;
        for l in 0..LANES {
            if launched < photons {
                self.launch(&mut p, l);
                launched += 1;
            }
        }
        let thickness = self.grid.thickness();
        // The azimuth table taken once per batch: behind its lazy static, the check at every
        // step cost ~55 instructions (cachegrind, the AVX2 copy).
        let azimuths = &*AZIMUTH_TABLE;
        while p.alive.iter().any(|&a| a) {
            let mut s = lanes.uniforms();
            for v in s.iter_mut() {
                *v = free_path_of(*v);
            }
            let d1: Lane<f64> = std::array::from_fn(|l| p.pos[2][l] + s[l] * p.dir[2][l]);
            let frame = self.flight_frames(&p);
            let mut left = [false; LANES];
            for l in 0..LANES {
                if !p.alive[l] {
                    continue;
                }
                let sums = (&mut tally, &mut direct_ends[..]);
                p.above[l] = self.cross_planes(&p, l, d1[l], &frame, sums);
                if d1[l] <= 0.0 {
                    tally.escaped_top += p.weight[l];
                    left[l] = true;
                } else if d1[l] >= thickness {
                    tally.escaped_bottom += p.weight[l];
                    left[l] = true;
                }
            }
            for i in 0..3 {
                for l in 0..LANES {
                    p.pos[i][l] += s[l] * p.dir[i][l];
                }
            }
            self.scatter_lanes(&mut p, &mut lanes, azimuths);
            let survive = if self.albedo < 1.0 {
                Some(lanes.uniforms())
            } else {
                None
            };
            // A photon still in the slab has scattered (an event, even if absorption then ends
            // it): counted for all lanes side by side, without a branch.
            let mut events = 0;
            for l in 0..LANES {
                let scattered = p.alive[l] && !left[l];
                p.order[l] = p.order[l].saturating_add(u32::from(scattered));
                events += u64::from(scattered);
            }
            tally.events += events;
            for l in 0..LANES {
                if !p.alive[l] {
                    continue;
                }
                let absorbed =
                    !left[l] && survive.is_some_and(|u| self.absorb(&mut p, l, u[l], &mut tally));
                if left[l] || absorbed {
                    p.alive[l] = false;
                    if launched < photons {
                        self.launch(&mut p, l);
                        launched += 1;
                    }
                }
            }
        }
        direct_fluxes(&direct_ends, &mut tally.direct);
        if self.mu_l == 1.0 {
            expand_pooled(self.grid, &mut tally);
        }
        tally.photons = photons;
        tally
    }

    /// A photon at the origin of the lit face, along the sun direction, in lane `l`.
    fn launch(&self, p: &mut Photons, l: usize) {
        for i in 0..3 {
            p.pos[i][l] = 0.0;
        }
        p.dir[0][l] = 0.0;
        p.dir[1][l] = (1.0 - self.mu_l * self.mu_l).max(0.0).sqrt();
        p.dir[2][l] = self.mu_l;
        p.order[l] = 0;
        p.weight[l] = 1.0;
        p.above[l] = 1;
        p.alive[l] = true;
    }

    /// Every lane's direction turned by a scattering: the cosines from the phase function's
    /// exact sampler in one call for all lanes (`sample_cosines`), then the azimuth, the frame
    /// and the turn side by side.
    #[inline(always)]
    fn scatter_lanes(&self, p: &mut Photons, lanes: &mut LaneRng, table: &[(f64, f64); AZIMUTHS]) {
        let xi = lanes.uniforms();
        let phi = lanes.outputs();
        let mut cosine = [Cosine::from_mu(1.0); LANES];
        self.phase.sample_cosines(&xi, &mut cosine);
        for l in 0..LANES {
            let dir = [p.dir[0][l], p.dir[1][l], p.dir[2][l]];
            let azimuth = unit_circle_of_output(table, phi[l]);
            let turn = turn_of(cosine[l].mu, cosine[l].one_minus_mu, azimuth);
            let new = turn_direction(dir, turn);
            for i in 0..3 {
                p.dir[i][l] = new[i];
            }
        }
    }

    /// Absorption at a scattering of lane `l` (albedo < 1), with Russian roulette below
    /// [`ROULETTE_BELOW`] on the uniform `u`; true if the photon is gone.
    fn absorb(&self, p: &mut Photons, l: usize, u: f64, tally: &mut BatchTally) -> bool {
        let w = &mut p.weight[l];
        tally.absorbed += *w * (1.0 - self.albedo);
        *w *= self.albedo;
        if *w < ROULETTE_BELOW {
            if u >= ROULETTE_SURVIVAL {
                tally.absorbed += *w;
                return true;
            }
            tally.absorbed -= *w * (1.0 / ROULETTE_SURVIVAL - 1.0);
            *w /= ROULETTE_SURVIVAL;
        }
        false
    }

    /// Every lane's flight frame for the tally, side by side: at normal incidence the pooled
    /// frame ([`pooled_frame`]), else the view bins with the mirror of x.
    #[inline(always)]
    fn flight_frames(&self, p: &Photons) -> FlightFrame {
        let g = self.grid;
        let [dx, dy, dz] = &p.dir;
        let mu_v: Lane<f64> = std::array::from_fn(|l| -dz[l]);
        let mut f = FlightFrame {
            m: g.mu_bins(&mu_v),
            k: [0; LANES],
            inv_dz: [0.0; LANES],
            proj: [[0.0; LANES]; 4],
            inv_mu: [0.0; LANES],
            annulus: [0; LANES],
        };
        if self.mu_l == 1.0 {
            for l in 0..LANES {
                let (inv_dz, proj) = pooled_frame([dx[l], dy[l], dz[l]]);
                f.inv_dz[l] = inv_dz;
                for (i, v) in proj.into_iter().enumerate() {
                    f.proj[i][l] = v;
                }
            }
        } else {
            f.k = g.psi_bins_of(dx, dy);
            for l in 0..LANES {
                f.inv_dz[l] = 1.0 / dz[l];
                f.proj[0][l] = if dx[l] < 0.0 { -1.0 } else { 1.0 };
                f.proj[3][l] = 1.0;
            }
        }
        for l in 0..LANES {
            f.inv_mu[l] = g.crossing_weight(p.weight[l], f.inv_dz[l].abs());
        }
        // The angle from the beam, for the aureole's annuli (used by flights going down).
        let sin_l = (1.0 - self.mu_l * self.mu_l).max(0.0).sqrt();
        let cos_beam: Lane<f64> = std::array::from_fn(|l| dy[l] * sin_l + dz[l] * self.mu_l);
        f.annulus = g.aureole.bins(&cos_beam);
        f
    }

    /// Records every plane the flight of lane `l` to depth `d1` crosses, given the number of
    /// planes at or above its start; returns that number at its end.
    #[inline(always)]
    fn cross_planes(
        &self,
        p: &Photons,
        l: usize,
        d1: f64,
        f: &FlightFrame,
        (tally, direct_ends): (&mut BatchTally, &mut [f64]),
    ) -> usize {
        let (depths, above, weight) = (&self.grid.depths[..], p.above[l], p.weight[l]);
        let planes = depths.len();
        let pos = [p.pos[0][l], p.pos[1][l], p.pos[2][l]];
        let dir = [p.dir[0][l], p.dir[1][l], p.dir[2][l]];
        let down = dir[2] > 0.0;
        let crosses = if down {
            above < planes && depths[above] <= d1
        } else {
            above > 0 && depths[above - 1] >= d1
        };
        if !crosses {
            return above;
        }
        let order = p.order[l];
        if order == 0 {
            // The unscattered flight goes down from the lit face (plane 0 above it) and adds its
            // weight to the direct flux of every plane it crosses: only where it ends matters.
            // It is counted without a loop whose exit the predictor cannot know, and
            // [`direct_fluxes`] spreads the counts over the planes after the walk.
            debug_assert!(down && above == 1 && weight == 1.0);
            let end = above + depths[above..].iter().filter(|&&d| d <= d1).count();
            direct_ends[end] += weight;
            return end;
        }
        let group = self.grid.group(order);
        let first = self.grid.cell(group, 0, f.m[l], f.k[l]);
        let (inv_dz, inv_mu) = (f.inv_dz[l], f.inv_mu[l]);
        let proj = [f.proj[0][l], f.proj[1][l], f.proj[2][l], f.proj[3][l]];
        let n_annuli = self.grid.aureole.n_bins();
        let halo = (down && f.annulus[l] < n_annuli)
            .then(|| self.grid.aureole_cell(group, 0, f.annulus[l]));
        // The flight's cells and fluxes as slices of one entry per plane, so that the crossing
        // loop's own test on the plane bounds every access (no check per access).
        let flux = &mut if down { &mut tally.down } else { &mut tally.up }[..planes];
        let cells = &mut tally.cells[first..first + planes];
        let aureole = &mut tally.aureole;
        // The crossed planes found and visited in one loop (one mispredicted exit per flight,
        // not two), written out: a closure would be compiled apart from the vector variants of
        // the walk, without their instructions.
        // The aureole's test is taken once per flight, not at every crossing: a loop for the
        // flights down in a cone around the beam, one for the others down, one for those up
        // (never in a cone).
        macro_rules! visit {
            ($j:expr, $halo:expr) => {{
                let j = $j;
                flux[j] += weight;
                if let Some(first) = $halo {
                    aureole[first + j * n_annuli] += inv_mu;
                }
                let along = (depths[j] - pos[2]) * inv_dz;
                let (x, z) = (pos[0] + along * dir[0], pos[1] + along * dir[1]);
                let cell = &mut cells[j];
                cell[0] += inv_mu;
                cell[1] += inv_mu * (proj[0] * x + proj[1] * z);
                cell[2] += inv_mu * (proj[2] * x + proj[3] * z);
                cell[3] += inv_mu * (x * x + z * z);
            }};
        }
        let mut end = above;
        match halo {
            Some(first) => {
                while end < planes && depths[end] <= d1 {
                    visit!(end, Some(first));
                    end += 1;
                }
            }
            None if down => {
                while end < planes && depths[end] <= d1 {
                    visit!(end, None::<usize>);
                    end += 1;
                }
            }
            None => {
                while end > 0 && depths[end - 1] >= d1 {
                    end -= 1;
                    visit!(end, None::<usize>);
                }
            }
        }
        end
    }
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
/// frame of the flight). Returns 1/dz and the projection (x, z) → (a, b) as a
/// row-major 2×2 matrix.
#[inline(always)]
fn pooled_frame(dir: [f64; 3]) -> (f64, [f64; 4]) {
    let r = (dir[0] * dir[0] + dir[1] * dir[1]).sqrt();
    // 1/dz and the (sin, cos) of the flight's own azimuth from one division; a vertical flight
    // (r = 0) takes r = 1 in the division, which gives 1/dz exactly, and the azimuth 0. Both
    // sides computed, then chosen: a select that lanes take together, not a branch.
    // The choice as a bit mask: written as `if`, the AVX2 copy of the walk branched on it, and
    // a vertical flight (every photon's first at μ_L = 1) cost a mispredicted branch.
    let vertical = (!(r > 0.0) as u64).wrapping_neg();
    let pick = |if_vertical: f64, otherwise: f64| {
        f64::from_bits((if_vertical.to_bits() & vertical) | (otherwise.to_bits() & !vertical))
    };
    let r1 = pick(1.0, r);
    let inv = 1.0 / (dir[2] * r1);
    let s_c = pick(0.0, dir[0] * inv * dir[2]);
    let c_c = pick(1.0, dir[1] * inv * dir[2]);
    (inv * r1, [s_c, c_c, c_c, -s_c])
}

/// The direct beam's flux at every plane from the unscattered flights counted by where they
/// ended (`ends[e]`: the flights from the lit face that crossed planes 1 … e − 1): plane j ≥ 1
/// is crossed by every flight with e > j. Their weights are 1 (nothing has scattered or been
/// absorbed yet), so the sums are whole numbers, exact in any order: the same bits as adding
/// each flight's weight at each plane it crosses.
fn direct_fluxes(ends: &[f64], direct: &mut [f64]) {
    let mut beyond = 0.0;
    for j in (1..direct.len()).rev() {
        beyond += ends[j + 1];
        direct[j] += beyond;
    }
}

/// Spreads the normal-incidence sums w/|μ| · (1, a, b, a² + b²) of the ψ_V = 0 cells (see
/// [`pooled_frame`]) over every ψ_V bin k: Δψ_k/π · (1, a S_k + b C_k, a C_k − b S_k,
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

/// A free path in mean free paths from `rng`: the walk's own −ln(1 − ξ)
/// ([`super::lanes::free_path`]), for tests of the walk's steps one photon at a time.
pub fn free_path(rng: &mut Xoshiro256PlusPlus) -> f64 {
    free_path_of(rng.random::<f64>())
}

/// A new direction: the cosine from the phase function's exact sampler, the azimuth from
/// [`unit_circle`], in the frame of Duff et al. around the old direction (the walk's own
/// steps, [`Slice::run_batch`], one photon at a time).
pub fn scatter(
    phase: &(dyn PhaseFunction<f64> + Sync),
    dir: [f64; 3],
    rng: &mut Xoshiro256PlusPlus,
) -> [f64; 3] {
    let c = phase.sample_cosine(rng.random::<f64>());
    let table = &*AZIMUTH_TABLE;
    turn_direction(
        dir,
        turn_of(
            c.mu,
            c.one_minus_mu,
            unit_circle_in(table, rng.random::<f64>()),
        ),
    )
}

/// A scattering apart from the direction it turns, (cos θ, sin θ cos φ, sin θ sin φ), from its
/// cosine μ (and 1 − μ, exact near the forward peak) and the azimuth's (cos φ, sin φ).
#[inline(always)]
fn turn_of(mu: f64, one_minus_mu: f64, (cos_phi, sin_phi): (f64, f64)) -> [f64; 3] {
    let sin2 = if mu > 0.0 {
        one_minus_mu * (2.0 - one_minus_mu)
    } else {
        1.0 - mu * mu
    };
    let sin_theta = sin2.max(0.0).sqrt();
    [mu, cos_phi * sin_theta, sin_phi * sin_theta]
}

/// `dir` turned by `turn` (see [`turn_of`]), in the frame of Duff et al. around it.
#[inline(always)]
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
#[inline(always)]
pub fn unit_circle(xi: f64) -> (f64, f64) {
    unit_circle_in(&AZIMUTH_TABLE, xi)
}

/// [`unit_circle`] with the table at hand (the walk takes it once per batch, not through the
/// lazy static's check at every scattering).
#[inline(always)]
fn unit_circle_in(table: &[(f64, f64); AZIMUTHS], xi: f64) -> (f64, f64) {
    let scaled = xi * AZIMUTHS as f64;
    // Through i32, not usize: AVX2 converts doubles to 32-bit integers side by side but has no
    // instruction for 64-bit ones (the same k: 0 ≤ scaled < 256).
    let k = (scaled as i32).clamp(0, AZIMUTHS as i32 - 1) as usize;
    table_entry_turned(table, k, scaled - k as f64)
}

/// (cos φ, sin φ) of φ = 2π(k + f)/AZIMUTHS, f ∈ [0, 1): table entry k turned by the remainder.
#[inline(always)]
fn table_entry_turned(table: &[(f64, f64); AZIMUTHS], k: usize, f: f64) -> (f64, f64) {
    let (sin_d, cos_d) = sin_cos_small(f * (2.0 * PI / AZIMUTHS as f64));
    let (c, s) = table[k];
    (c * cos_d - s * sin_d, s * cos_d + c * sin_d)
}

/// [`unit_circle_in`] of the uniform number of a stream's output `r` ([`uniform_of`]), bit
/// for bit, with its table index and remainder read from r's bits: ξ = m/2⁵² with m = r >> 12,
/// so 256ξ has the integer part r >> 56 and the fraction (m mod 2⁴⁴)/2⁴⁴, both exact. A
/// double's conversion to an integer would take each lane apart (Rust's saturating `as`).
#[inline(always)]
fn unit_circle_of_output(table: &[(f64, f64); AZIMUTHS], r: u64) -> (f64, f64) {
    const _: () = assert!(AZIMUTHS == 1 << 8);
    let k = (r >> 56) as usize;
    // The fraction as the mantissa of a number in [1, 2), less one (exact).
    let fraction = f64::from_bits((((r >> 12) << 20) >> 12) | 0x3FF0_0000_0000_0000) - 1.0;
    table_entry_turned(table, k, fraction)
}

/// The direction rescaled to unit length, so that rounding does not drift over thousands of
/// scatterings. |v|² is within ~1e-15 of 1, so one Newton step for 1/√|v|² (1.5 − |v|²/2) is
/// exact to f64 without a square root or a division.
#[inline(always)]
fn normalised(v: [f64; 3]) -> [f64; 3] {
    let inv = 1.5 - 0.5 * (v[0] * v[0] + v[1] * v[1] + v[2] * v[2]);
    [v[0] * inv, v[1] * inv, v[2] * inv]
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::slab::lanes::uniform_of;
    use nephele_runtime::phase::{HenyeyGreenstein, TabulatedTable};

    /// The walk compiled for AVX-512, AVX2 and baseline x86-64 gives the same sums, bit for
    /// bit (no fused multiply–add anywhere), at normal and oblique incidence, with absorption,
    /// with HG and a tabulated phase function, the aureole's annuli tallied.
    #[test]
    fn every_variant_walks_the_same_bits() {
        let grid = SlabGrid::default_with_annuli(2.0).unwrap();
        let hg = HenyeyGreenstein::new(0.8);
        // A tabulated phase function with a forward peak on the reference grid (it keeps its
        // guide and half-angle sines, so the walk samples 8 of its cosines side by side).
        let theta_deg: Vec<f64> = (0..=500)
            .map(|k| k as f64 * 0.01)
            .chain((1..=1750).map(|k| 5.0 + k as f64 * 0.1))
            .collect();
        let peak: Vec<f64> = theta_deg
            .iter()
            .map(|t| 1e3 / (1.0 + t * t) + 0.1)
            .collect();
        let table = TabulatedTable::<f64>::from_phase(&theta_deg, &peak).unwrap();
        let phases: [&(dyn PhaseFunction<f64> + Sync); 2] = [&hg, &table];
        for ((mu_l, albedo), phase) in [(1.0, 1.0), (0.6, 0.9)]
            .into_iter()
            .flat_map(|c| phases.map(|p| (c, p)))
        {
            let slice = Slice {
                grid: &grid,
                mu_l,
                albedo,
                phase,
            };
            let base = slice.run_lanes(3000, &mut batch_rng(9, 1, 2));
            assert!(
                base.aureole.iter().any(|&v| v > 0.0),
                "the annuli hold light"
            );
            let same = |t: &BatchTally| {
                t.cells == base.cells
                    && t.up == base.up
                    && t.down == base.down
                    && t.direct == base.direct
                    && t.events == base.events
                    && t.escaped_top == base.escaped_top
                    && t.escaped_bottom == base.escaped_bottom
                    && t.absorbed == base.absorbed
                    && t.aureole == base.aureole
            };
            #[cfg(target_arch = "x86_64")]
            {
                let simd = Simd::detected();
                if simd.has_avx2() {
                    // SAFETY: the CPU has AVX2.
                    let t = unsafe { slice.run_batch_avx2(3000, &mut batch_rng(9, 1, 2)) };
                    assert!(same(&t), "AVX2 differs at mu_L = {mu_l}");
                }
                if simd == Simd::Avx512 {
                    // SAFETY: the CPU has AVX-512 F, DQ and VL.
                    let t = unsafe { slice.run_batch_avx512(3000, &mut batch_rng(9, 1, 2)) };
                    assert!(same(&t), "AVX-512 differs at mu_L = {mu_l}");
                }
            }
            assert!(same(&slice.run_batch(3000, &mut batch_rng(9, 1, 2))));
        }
    }

    /// The pooled frame without a branch is the frame with one (1/dz and the flight's own
    /// azimuth from one division, any azimuth for a vertical flight), bit for bit: vertical
    /// flights up and down, nearly vertical ones down to the least r that is not 0, r = 0 from
    /// components whose squares vanish, and directions all round.
    #[test]
    fn pooled_frame_is_the_branchy_frame() {
        let branchy = |dir: [f64; 3]| {
            let r = (dir[0] * dir[0] + dir[1] * dir[1]).sqrt();
            let (inv_dz, s_c, c_c) = if r > 0.0 {
                let inv = 1.0 / (dir[2] * r);
                (inv * r, dir[0] * inv * dir[2], dir[1] * inv * dir[2])
            } else {
                (1.0 / dir[2], 0.0, 1.0)
            };
            (inv_dz, [s_c, c_c, c_c, -s_c])
        };
        let mut dirs = vec![[0.0, 0.0, 1.0], [0.0, 0.0, -1.0], [-0.0, 0.0, 1.0]];
        for tiny in [1e-300, 1e-160, 1e-154, 1.5e-154, 5e-324, f64::MIN_POSITIVE] {
            dirs.extend([[tiny, 0.0, 1.0], [0.0, -tiny, -1.0], [tiny, tiny, 1.0]]);
        }
        for i in 0..5000 {
            let (s, c) = (i as f64 * 0.0137).sin_cos();
            let (sz, cz) = (i as f64 * 0.00071).sin_cos();
            dirs.push([sz * s, sz * c, cz]);
        }
        let bits = |(d, p): (f64, [f64; 4])| (d.to_bits(), p.map(f64::to_bits));
        for dir in dirs {
            assert_eq!(bits(pooled_frame(dir)), bits(branchy(dir)), "{dir:?}");
        }
    }

    /// The azimuth read from a stream's output bits is the one of its uniform number, bit for
    /// bit: random outputs, the ends, and every table index with the least and largest
    /// remainders.
    #[test]
    fn unit_circle_of_an_output_is_that_of_its_uniform() {
        let table = &*AZIMUTH_TABLE;
        let mut rng = Xoshiro256PlusPlus::seed_from_u64(13);
        let edges = (0..256u64).flat_map(|k| {
            let top = k << 56;
            [
                top,
                top | (1 << 12),
                top | ((1 << 56) - 1),
                top | ((1 << 56) - (1 << 12)),
            ]
        });
        let outputs = (0..200_000).map(|_| rng.random::<u64>()).chain(edges);
        for r in outputs.chain([0, u64::MAX, 4095, 1 << 12]) {
            let bits = |(c, s): (f64, f64)| (c.to_bits(), s.to_bits());
            assert_eq!(
                bits(unit_circle_of_output(table, r)),
                bits(unit_circle_in(table, uniform_of(r))),
                "{r:#x}"
            );
        }
    }

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
