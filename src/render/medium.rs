//! Participating media of the path tracer: an extinction coefficient σ_t(p) (1/m) inside
//! bounds, and majorants σ̄ ≥ σ_t for delta tracking (a coarse grid for the heterogeneous
//! media, see `majorant.rs`).

use super::fbm::Fbm;
use super::geometry::{box_clip, outside_box, slab_clip, Affine, Vec3};
use super::majorant::{Bounds, MajorantGrid, Majorants};
use super::mesh::TriangleMesh;
use nephele_runtime::fitting::Simd;

/// The medium as the integrator sees it.
pub trait Medium: Sync {
    /// σ_t at `p` (1/m); 0 outside the medium.
    fn sigma_t(&self, p: Vec3) -> f64;

    /// The segment [t0, t1] (t0 ≥ 0) of the ray o + t w where the medium may be non-zero, or
    /// None if the ray misses it.
    fn clip(&self, o: Vec3, w: Vec3) -> Option<(f64, f64)>;

    /// Bounds σ_c ≤ σ_t ≤ σ̄ (1/m) over the medium's extent; where they meet, shadow rays
    /// cost nothing and add no noise.
    fn majorants(&self) -> Majorants<'_>;

    /// The majorants delta and ratio tracking walk (the path tracer's free flights and shadow
    /// rays); [`Medium::majorants`] unless the medium keeps coarser ones for them.
    fn tracking_majorants(&self) -> Majorants<'_> {
        self.majorants()
    }

    /// A box (lowest and highest corners, m) outside which σ_t = 0, or None if the medium is
    /// unbounded.
    fn bounds(&self) -> Option<(Vec3, Vec3)>;

    /// σ_t at `p` (1/m, the bits of [`Medium::sigma_t`]) and a distance r (m) such that σ_t is
    /// exactly that value everywhere within r of p: a march skips the lookups there. 0 (no
    /// promise) unless the medium knows better.
    fn sigma_t_reach(&self, p: Vec3) -> (f64, f64) {
        (self.sigma_t(p), 0.0)
    }
}

/// A homogeneous slab z ∈ [0, h] (m), unbounded in x and y: the canonical slab (docs/conventions.md) with
/// its lit face at z = h.
#[derive(Clone, Copy, Debug)]
pub struct Slab {
    /// Thickness (m).
    pub h: f64,
    /// Extinction coefficient (1/m).
    pub sigma_t: f64,
}

impl Medium for Slab {
    fn sigma_t(&self, p: Vec3) -> f64 {
        if (0.0..=self.h).contains(&p[2]) {
            self.sigma_t
        } else {
            0.0
        }
    }

    fn clip(&self, o: Vec3, w: Vec3) -> Option<(f64, f64)> {
        slab_clip(o[2], w[2], 0.0, self.h)
    }

    fn majorants(&self) -> Majorants<'_> {
        Majorants::Constant(Bounds {
            min: self.sigma_t,
            max: self.sigma_t,
        })
    }

    fn bounds(&self) -> Option<(Vec3, Vec3)> {
        None
    }
}

/// An ellipsoid: centre and semi-axes (m).
#[derive(Clone, Copy, Debug, serde::Serialize, serde::Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Ellipsoid {
    /// Centre (m).
    pub center: Vec3,
    /// Semi-axes along x, y, z (m).
    pub radii: Vec3,
}

/// An implicit cloud: a union of ellipsoids whose boundary is displaced by fBm noise (a
/// hypertexture, as in Bouthors et al.). With ρ_i = |(p − c_i)/r_i| and r_i⁻ the smallest
/// semi-axis, the signed depth below the displaced surface is
///
///   s(p) = max_i (1 − ρ_i(p)) r_i⁻ + A · fbm(f p)   (m),
///
/// and the density rises linearly over the boundary layer: min(max(s/edge, 0), 1); σ_t is the
/// scene's extinction times the density. The majorant grid bounds s on each cell by the
/// smallest ρ_i over the cell and the largest fbm over it, and from below by the largest ρ_i
/// and the smallest fbm: the deep interior, where s ≥ edge everywhere, is homogeneous. The
/// fbm over a cell lies within L r of its value at the centre (r the half-diagonal, L the
/// fbm's Lipschitz bound `fbm_slope`) and within the clamp ±1.2: the uncertain shell where
/// the noise has to be evaluated is edge + 2 (L r A + r) thick instead of edge + 2.4 A.
pub struct Cloud {
    /// The blobs, laid out for [`Cloud::inside`].
    chunks: Vec<BlobChunk>,
    /// Whether the CPU has AVX2 ([`Cloud::density`] then takes its AVX2 copy).
    avx2: bool,
    edge: f64,
    amplitude: f64,
    frequency: f64,
    fbm: Fbm,
    sigma_t: f64,
    lo: Vec3,
    hi: Vec3,
    /// Majorants on [`CLOUD_GRID`]³ cells (the march's).
    grid: MajorantGrid,
    /// The same in blocks of [`TRACKING_BLOCK`]³ cells (delta and ratio tracking's).
    tracking: MajorantGrid,
    /// Per octave k, a Lipschitz bound (m/m) on the signed depth as known after octave k: 1
    /// for the blobs' depth, A f Lₖ for the octaves up to k ([`Fbm::partial_slopes`]).
    reach_slopes: Vec<f64>,
}

/// Blobs side by side in a [`BlobChunk`]: four f64, one AVX2 register.
const BLOB_LANES: usize = 4;

/// Up to [`BLOB_LANES`] blobs coordinate by coordinate, so that [`Cloud::inside`] takes their
/// divisions and square roots side by side, in vector registers. The last chunk is filled up
/// with copies of the first blob: a copy cannot change the largest depth.
#[derive(Clone, Debug)]
struct BlobChunk {
    center: [[f64; BLOB_LANES]; 3],
    radii: [[f64; BLOB_LANES]; 3],
    /// The smallest semi-axis r⁻.
    r_min: [f64; BLOB_LANES],
}

impl BlobChunk {
    /// `blobs` in chunks (at least one blob).
    fn chunks(blobs: &[Ellipsoid]) -> Vec<Self> {
        blobs
            .chunks(BLOB_LANES)
            .map(|part| {
                let blob = |l: usize| part.get(l).unwrap_or(&blobs[0]);
                Self {
                    center: std::array::from_fn(|k| std::array::from_fn(|l| blob(l).center[k])),
                    radii: std::array::from_fn(|k| std::array::from_fn(|l| blob(l).radii[k])),
                    r_min: std::array::from_fn(|l| {
                        blob(l).radii.iter().copied().fold(f64::INFINITY, f64::min)
                    }),
                }
            })
            .collect()
    }
}

/// Majorant cells per axis of the implicit cloud's bounding box.
const CLOUD_GRID: usize = 80;

/// The path tracer's free flights and shadow rays walk the cloud's majorants in blocks of
/// `TRACKING_BLOCK`³ cells (16 per axis): the fine grid is 8 MB, and a ray through it waits on
/// memory at every one of its many cell faces, where a looser bound costs only a few more
/// density lookups. Measured on the default cloud (scripts/bench_render_noise.py, 32 spp,
/// 4 seeds): blocks of 1, 4, 5 and 8 gave efficiencies 5.3, 6.8, 6.8 and 6.7 with
/// the sun in front, 5.0, 6.3, 6.4 and 6.3 from behind, the noise per sample unchanged. The
/// fast renderers' march keeps the fine grid: its sub-steps follow its faces and skip its
/// empty cells.
const TRACKING_BLOCK: usize = 5;

/// A bound on the slope of one octave of the `noise` crate's Perlin noise, |∇n| per unit of its
/// input: the largest directional derivative found at 9·10⁶ random points of three seeds is
/// 3.46 (tests/render.rs measures it again), and 4.5 leaves 30 % of margin.
pub const PERLIN_SLOPE: f64 = 4.5;

/// A bound on the slope of `fbm` per unit of its input: octave k adds persistence^(k+1) of a
/// Perlin noise at lacunarity^k times the frequency, and the sum is divided by
/// Σ_{k=1}^{octaves} persistence^k (the crate's normalisation); its input is scaled by its
/// own frequency first.
fn fbm_slope(fbm: &noise::Fbm<noise::Perlin>) -> f64 {
    let (p, l) = (fbm.persistence, fbm.lacunarity);
    let slope: f64 = (0..fbm.octaves)
        .map(|k| p.powi(k as i32 + 1) * l.powi(k as i32))
        .sum();
    let norm: f64 = (1..=fbm.octaves).map(|k| p.powi(k as i32)).sum();
    PERLIN_SLOPE * fbm.frequency * slope / norm
}

impl Cloud {
    /// The cloud of `blobs` with boundary layer `edge` (m), noise (amplitude m, frequency
    /// 1/m, octaves), extinction `sigma_t` (1/m) at density 1 and a noise seed.
    pub fn new(
        blobs: Vec<Ellipsoid>,
        edge: f64,
        (amplitude, frequency, octaves): (f64, f64, usize),
        sigma_t: f64,
        seed: u32,
    ) -> Self {
        use noise::MultiFractal;
        let (mut lo, mut hi) = ([f64::INFINITY; 3], [f64::NEG_INFINITY; 3]);
        for b in &blobs {
            let r_min = b.radii.iter().copied().fold(f64::INFINITY, f64::min);
            // s > 0 needs ρ < 1 + A/r⁻ (|fbm| ≤ 1 is assumed with a 20 % margin).
            let grow = 1.0 + 1.2 * amplitude / r_min;
            for k in 0..3 {
                lo[k] = lo[k].min(b.center[k] - grow * b.radii[k]);
                hi[k] = hi[k].max(b.center[k] + grow * b.radii[k]);
            }
        }
        let definition = noise::Fbm::<noise::Perlin>::new(seed).set_octaves(octaves);
        let slope = fbm_slope(&definition) * frequency;
        let fbm = Fbm::new(&definition);
        let grid = MajorantGrid::build(lo, hi, [CLOUD_GRID; 3], |c_lo, c_hi| {
            let (mut deepest, mut shallowest) = (f64::NEG_INFINITY, f64::NEG_INFINITY);
            for b in &blobs {
                let (lo, hi) = Self::depth_range(b, c_lo, c_hi);
                (deepest, shallowest) = (deepest.max(hi), shallowest.max(lo));
            }
            let density = |s: f64| (s / edge).clamp(0.0, 1.0);
            // Where no noise within its clamp (±1.2) can lift the depth above 0, or take it
            // below the edge, both bounds are what they would be for any noise: the fBm is not
            // evaluated (most cells: the empty box around the cloud and its interior). Each
            // side is monotone in n, so the bounds are the same bits as below.
            if deepest + amplitude * 1.2 < 0.0 || shallowest + amplitude * -1.2 >= edge {
                let settled = sigma_t * density(deepest + amplitude * 1.2);
                return Bounds {
                    min: settled,
                    max: settled,
                };
            }
            let centre: Vec3 = std::array::from_fn(|k| 0.5 * (c_lo[k] + c_hi[k]) * frequency);
            let half_diagonal = 0.5
                * (0..3)
                    .map(|k| (c_hi[k] - c_lo[k]).powi(2))
                    .sum::<f64>()
                    .sqrt();
            let (n, spread) = (fbm.get(centre), slope * half_diagonal);
            let n_lo = (n - spread).clamp(-1.2, 1.2);
            let n_hi = (n + spread).clamp(-1.2, 1.2);
            Bounds {
                min: sigma_t * density(shallowest + amplitude * n_lo),
                max: sigma_t * density(deepest + amplitude * n_hi),
            }
        });
        let tracking = grid.coarsened(TRACKING_BLOCK);
        let reach_slopes = fbm
            .partial_slopes(PERLIN_SLOPE)
            .into_iter()
            .map(|l| 1.0 + amplitude * frequency * l)
            .collect();
        Self {
            chunks: BlobChunk::chunks(&blobs),
            avx2: Simd::detected().has_avx2(),
            edge,
            amplitude,
            frequency,
            fbm,
            sigma_t,
            lo,
            hi,
            grid,
            tracking,
            reach_slopes,
        }
    }

    /// (1 − ρ) r⁻ of blob b at p (m): positive inside the undisplaced ellipsoid.
    fn depth(b: &Ellipsoid, p: Vec3) -> f64 {
        let rho = (0..3)
            .map(|k| ((p[k] - b.center[k]) / b.radii[k]).powi(2))
            .sum::<f64>()
            .sqrt();
        (1.0 - rho) * b.radii.iter().copied().fold(f64::INFINITY, f64::min)
    }

    /// The smallest and largest `depth` over the box [lo, hi]: at its corner farthest from
    /// the centre and at its point nearest to it, in the ellipsoid's scaled coordinates (where
    /// ρ is largest and smallest).
    fn depth_range(b: &Ellipsoid, lo: Vec3, hi: Vec3) -> (f64, f64) {
        let far = std::array::from_fn(|k| {
            let c = b.center[k];
            if (lo[k] - c).abs() > (hi[k] - c).abs() {
                lo[k]
            } else {
                hi[k]
            }
        });
        let near = std::array::from_fn(|k| b.center[k].clamp(lo[k], hi[k]));
        (Self::depth(b, far), Self::depth(b, near))
    }

    /// The largest [`Cloud::depth`] of the blobs at p (m), a chunk of blobs at a time: the
    /// same operations on each blob in the same order, so the same bits.
    #[inline(always)]
    fn inside(&self, p: Vec3) -> f64 {
        let mut deepest = [f64::NEG_INFINITY; BLOB_LANES];
        for c in &self.chunks {
            let mut rho2 = [0.0; BLOB_LANES];
            for k in 0..3 {
                for l in 0..BLOB_LANES {
                    let q = (p[k] - c.center[k][l]) / c.radii[k][l];
                    rho2[l] += q * q;
                }
            }
            for l in 0..BLOB_LANES {
                deepest[l] = deepest[l].max((1.0 - rho2[l].sqrt()) * c.r_min[l]);
            }
        }
        deepest.into_iter().fold(f64::NEG_INFINITY, f64::max)
    }

    /// Density in [0, 1] at p.
    pub fn density(&self, p: Vec3) -> f64 {
        #[cfg(target_arch = "x86_64")]
        if self.avx2 {
            // SAFETY: the CPU has AVX2 (checked when the cloud was made).
            return unsafe { self.density_avx2::<false>(p).0 };
        }
        self.density_any::<false>(p).0
    }

    /// [`Cloud::density`] at p (the same bits) and a distance r (m) within which the density
    /// is that same 0 or 1 (r = 0 in between): see [`Cloud::density_any`].
    pub fn density_reach(&self, p: Vec3) -> (f64, f64) {
        #[cfg(target_arch = "x86_64")]
        if self.avx2 {
            // SAFETY: the CPU has AVX2 (checked when the cloud was made).
            return unsafe { self.density_avx2::<true>(p) };
        }
        self.density_any::<true>(p)
    }

    /// [`Cloud::density_any`] compiled for AVX2, the noise inlined: a chunk of blobs in one
    /// register (with the Perlin corners side by side, 95 → 74 ns a lookup at the march's
    /// points of the default cloud). No FMA: the same bits.
    #[cfg(target_arch = "x86_64")]
    #[target_feature(enable = "avx2")]
    fn density_avx2<const REACH: bool>(&self, p: Vec3) -> (f64, f64) {
        self.density_any::<REACH>(p)
    }

    /// The density at p, and with `REACH` the distance r (m) within which it stays the same 0
    /// or 1. The signed depth s = inside + A clamp(n) moves by at most Lₖ per metre
    /// (`reach_slopes`: 1 for the blobs, whose depths (1 − ρ) r⁻ have slopes ≤ 1, plus A f
    /// times the slope bound of the octaves known), and the octaves not yet summed are bounded
    /// everywhere alike. So where s ≤ s⁺ < 0 is known, s < 0 within r = |s⁺|/Lₖ of p: the
    /// density is 0 there; likewise 1 within (s⁻ − edge)/Lₖ of p where s ≥ s⁻ > edge. The
    /// margins cover the rounding of the sums, as the settled octaves' do.
    #[inline(always)]
    fn density_any<const REACH: bool>(&self, p: Vec3) -> (f64, f64) {
        let inside = self.inside(p);
        let (a, edge) = (self.amplitude, self.edge);
        // Rounding of inside + A n: the settled octaves' margin below; twice it for the reach.
        let margin = 1e-9 * (inside.abs() + a + edge);
        // The reach of a depth known `beyond` 0 or the edge, at slope `slope` (none unasked).
        let reach_of = |beyond: f64, slope: f64| {
            if REACH {
                reach(beyond - 2.0 * margin, slope)
            } else {
                0.0
            }
        };
        // Where the noise cannot change the answer, it is not evaluated (most of the interior).
        if inside < -1.2 * a {
            return (0.0, reach_of(-(inside + 1.2 * a), 1.0));
        }
        if inside >= edge + 1.2 * a {
            return (1.0, reach_of(inside - 1.2 * a - edge, 1.0));
        }
        let f = self.frequency;
        // Nor the octaves that cannot: once the ones left cannot take the depth out of
        // (−∞, 0) or (edge, ∞), the clamp makes the density exactly 0 or 1 (the margin covers
        // the rounding of inside + A n).
        let settled = |k: usize, lo: f64, hi: f64| {
            let (high, low) = (
                inside + a * hi.clamp(-1.2, 1.2),
                inside + a * lo.clamp(-1.2, 1.2),
            );
            if high < -margin {
                Some((0.0, reach_of(-high, self.reach_slopes[k])))
            } else if low > edge + margin {
                Some((1.0, reach_of(low - edge, self.reach_slopes[k])))
            } else {
                None
            }
        };
        match self
            .fbm
            .get_or_settle([p[0] * f, p[1] * f, p[2] * f], settled)
        {
            Ok(n) => {
                let s = inside + a * n.clamp(-1.2, 1.2);
                let all = self.reach_slopes.last().copied().unwrap_or(1.0);
                let r = if s < -margin {
                    reach_of(-s, all)
                } else if s > edge + margin {
                    reach_of(s - edge, all)
                } else {
                    0.0
                };
                ((s / edge).clamp(0.0, 1.0), r)
            }
            Err(settled) => settled,
        }
    }
}

/// The distance (m) a depth `margin` (m) below 0 or beyond the edge lasts at slope `slope`,
/// shortened by a millionth for the rounding of the points it is used at.
#[inline(always)]
fn reach(margin: f64, slope: f64) -> f64 {
    (margin / slope).max(0.0) * (1.0 - 1e-6)
}

impl Medium for Cloud {
    fn sigma_t(&self, p: Vec3) -> f64 {
        if outside_box(p, self.lo, self.hi) {
            return 0.0;
        }
        self.sigma_t * self.density(p)
    }

    fn sigma_t_reach(&self, p: Vec3) -> (f64, f64) {
        if outside_box(p, self.lo, self.hi) {
            return (0.0, 0.0);
        }
        let (density, r) = self.density_reach(p);
        (self.sigma_t * density, r)
    }

    fn clip(&self, o: Vec3, w: Vec3) -> Option<(f64, f64)> {
        box_clip(o, w, self.lo, self.hi)
    }

    fn majorants(&self) -> Majorants<'_> {
        Majorants::Grid(&self.grid)
    }

    fn tracking_majorants(&self) -> Majorants<'_> {
        Majorants::Grid(&self.tracking)
    }

    fn bounds(&self) -> Option<(Vec3, Vec3)> {
        Some((self.lo, self.hi))
    }
}

/// A voxel grid of densities over the unit cube [0, 1]³ of its own coordinates, mapped to the
/// world by an affine map (by default the box [origin, origin + size], m): values at the voxel
/// centres, interpolated trilinearly and clamped at the borders (Mitsuba 3's gridvolume with
/// its default filter and wrap mode, so that both renderers see the same medium), 0 outside
/// the cube. `data` is [nz, ny, nx], x fastest (a C-order NumPy array indexed [z, y, x]).
pub struct Voxels {
    values: VoxelValues,
    to_world: Affine,
    sigma_t: f64,
    grid: MajorantGrid,
}

/// The densities at the voxel centres, [nz, ny, nx] with x fastest, and their trilinear lookup
/// in the unit cube's coordinates.
struct VoxelValues {
    /// Shared with the scene that read them: a large grid is held in memory once.
    data: std::sync::Arc<Vec<f32>>,
    /// Voxels along x, y, z.
    n: [usize; 3],
}

/// Voxels per majorant cell along each axis.
const VOXELS_PER_CELL: usize = 4;

impl Voxels {
    /// The grid over the box [origin, origin + size] (m); `sigma_t` (1/m) scales the densities.
    pub fn new(
        data: impl Into<std::sync::Arc<Vec<f32>>>,
        n: [usize; 3],
        origin: Vec3,
        size: Vec3,
        sigma_t: f64,
    ) -> Self {
        Self::with_transform(data, n, Affine::from_box(origin, size), sigma_t)
    }

    /// The grid over the image of the unit cube by `to_world`.
    pub fn with_transform(
        data: impl Into<std::sync::Arc<Vec<f32>>>,
        n: [usize; 3],
        to_world: Affine,
        sigma_t: f64,
    ) -> Self {
        let values = VoxelValues {
            data: data.into(),
            n,
        };
        let cells = n.map(|m| m.div_ceil(VOXELS_PER_CELL));
        let grid = MajorantGrid::build([0.0; 3], [1.0; 3], cells, |lo, hi| {
            let (min, max) = values.range_over(lo, hi);
            Bounds {
                min: sigma_t * min,
                max: sigma_t * max,
            }
        })
        .with_transform(to_world);
        Self {
            values,
            to_world,
            sigma_t,
            grid,
        }
    }

    /// Density at the world point `p` (trilinear between voxel centres, clamped; 0 outside).
    pub fn density(&self, p: Vec3) -> f64 {
        self.values.density(self.to_world.local_point(p))
    }
}

impl VoxelValues {
    /// The smallest and largest voxels the trilinear lookup can read anywhere in the box
    /// [lo, hi] of the unit cube: the voxels around the centres the box's corners fall
    /// between, one more each side for rounding.
    fn range_over(&self, lo: Vec3, hi: Vec3) -> (f64, f64) {
        let range = |k: usize| {
            let x = |u: f64| u * self.n[k] as f64 - 0.5;
            let a = (x(lo[k]).floor() - 1.0).max(0.0) as usize;
            let b = ((x(hi[k]).floor() + 2.0).max(0.0) as usize).min(self.n[k] - 1);
            a.min(self.n[k] - 1)..=b
        };
        let (rx, ry, rz) = (range(0), range(1), range(2));
        let (mut min, mut max) = (f64::INFINITY, 0.0f64);
        for z in rz {
            for y in ry.clone() {
                for x in rx.clone() {
                    let v = self.at([x, y, z]);
                    (min, max) = (min.min(v), max.max(v));
                }
            }
        }
        (min.min(max), max)
    }

    fn at(&self, i: [usize; 3]) -> f64 {
        self.data[(i[2] * self.n[1] + i[1]) * self.n[0] + i[0]] as f64
    }

    /// Density at `u` in the unit cube's coordinates (0 outside).
    fn density(&self, u: Vec3) -> f64 {
        let mut lo = [0usize; 3];
        let mut w = [0.0f64; 3];
        for k in 0..3 {
            if !(0.0..=1.0).contains(&u[k]) {
                return 0.0;
            }
            // Voxel centres at (i + ½)/n.
            let x = (u[k] * self.n[k] as f64 - 0.5).clamp(0.0, (self.n[k] - 1) as f64);
            lo[k] = (x as usize).min(self.n[k].saturating_sub(2));
            w[k] = if self.n[k] > 1 { x - lo[k] as f64 } else { 0.0 };
        }
        let mut v = 0.0;
        for corner in 0..8 {
            let mut weight = 1.0;
            let mut idx = [0usize; 3];
            for k in 0..3 {
                let up = (corner >> k) & 1 == 1;
                idx[k] = (lo[k] + usize::from(up)).min(self.n[k] - 1);
                weight *= if up { w[k] } else { 1.0 - w[k] };
            }
            if weight > 0.0 {
                v += weight * self.at(idx);
            }
        }
        v
    }
}

impl Medium for Voxels {
    fn sigma_t(&self, p: Vec3) -> f64 {
        self.sigma_t * self.density(p)
    }

    fn clip(&self, o: Vec3, w: Vec3) -> Option<(f64, f64)> {
        let (o, w) = (self.to_world.local_point(o), self.to_world.local_dir(w));
        box_clip(o, w, [0.0; 3], [1.0; 3])
    }

    fn majorants(&self) -> Majorants<'_> {
        // Trilinear interpolation never leaves the range of the voxels it reads.
        Majorants::Grid(&self.grid)
    }

    fn bounds(&self) -> Option<(Vec3, Vec3)> {
        let (mut lo, mut hi) = ([f64::INFINITY; 3], [f64::NEG_INFINITY; 3]);
        for c in 0..8 {
            let u: Vec3 = std::array::from_fn(|k| f64::from((c >> k) & 1));
            let p = self.to_world.apply(u);
            for k in 0..3 {
                lo[k] = lo[k].min(p[k]);
                hi[k] = hi[k].max(p[k]);
            }
        }
        Some((lo, hi))
    }
}

/// Fog filling a box [lo, hi] (m), or the inside of a closed triangle mesh: homogeneous, or
/// thinning with height as
///
///   σ_t(z) = σ_t · exp(−(z − lo_z) / H)   (H the scale height, m; σ_t at the floor),
///
/// the exponential height fog of real-time engines. The box bounds it so that free flights and
/// shadow rays end; make it as large as the scene (a "global" fog). In a box, the majorants
/// are a column of horizontal layers each at most H/8 thick, bounded exactly by the density at
/// their floor and ceiling (σ̄/σ ≤ e^{1/8}: 12 % of tentative collisions are null at most);
/// without a falloff the one layer is homogeneous (closed-form transmittance). In a mesh, a
/// grid of cells over its bounds: cells the surface may pass through (a triangle's box
/// overlaps them) are bounded by [0, σ(floor)], and σ_t there asks the mesh whether the point
/// is inside; the others are wholly inside (bounded as the layers are) or wholly outside (0).
pub struct Fog {
    lo: Vec3,
    hi: Vec3,
    sigma_t: f64,
    scale_height: Option<f64>,
    mesh: Option<TriangleMesh>,
    grid: MajorantGrid,
}

/// The most horizontal layers of a fog's majorant column.
const FOG_LAYERS: usize = 4096;

/// Majorant cells along the longest side of a mesh's bounds.
const MESH_CELLS: usize = 24;

impl Fog {
    /// Fog of extinction `sigma_t` (1/m, at the floor) over [lo, hi] (m), thinning with the
    /// scale height `scale_height` (m) if given.
    pub fn new(lo: Vec3, hi: Vec3, sigma_t: f64, scale_height: Option<f64>) -> Self {
        let layers = scale_height.map_or(1, |h| {
            ((8.0 * (hi[2] - lo[2]) / h).ceil() as usize).clamp(1, FOG_LAYERS)
        });
        let density = |z: f64| Self::density(lo[2], scale_height, z);
        let grid = MajorantGrid::build(lo, hi, [1, 1, layers], |a, b| Bounds {
            min: sigma_t * density(b[2]),
            max: sigma_t * density(a[2]),
        });
        Self {
            lo,
            hi,
            sigma_t,
            scale_height,
            mesh: None,
            grid,
        }
    }

    /// Fog inside the closed `mesh`, its floor the mesh's lowest point.
    pub fn in_mesh(mesh: TriangleMesh, sigma_t: f64, scale_height: Option<f64>) -> Self {
        let (lo, hi) = mesh.bounds();
        let longest = (0..3).map(|k| hi[k] - lo[k]).fold(0.0, f64::max);
        let n = std::array::from_fn(|k| {
            ((MESH_CELLS as f64 * (hi[k] - lo[k]) / longest).ceil() as usize).max(1)
        });
        let density = |z: f64| Self::density(lo[2], scale_height, z);
        let grid = MajorantGrid::build(lo, hi, n, |a, b| {
            let (min, max) = (sigma_t * density(b[2]), sigma_t * density(a[2]));
            if mesh.touches_box(a, b) {
                Bounds { min: 0.0, max }
            } else if mesh.contains(std::array::from_fn(|k| 0.5 * (a[k] + b[k]))) {
                Bounds { min, max }
            } else {
                Bounds { min: 0.0, max: 0.0 }
            }
        });
        Self {
            lo,
            hi,
            sigma_t,
            scale_height,
            mesh: Some(mesh),
            grid,
        }
    }

    /// The density (0…1) at height z over the floor z₀.
    fn density(floor: f64, scale_height: Option<f64>, z: f64) -> f64 {
        scale_height.map_or(1.0, |h| (-(z - floor) / h).exp())
    }
}

impl Medium for Fog {
    fn sigma_t(&self, p: Vec3) -> f64 {
        if outside_box(p, self.lo, self.hi) {
            return 0.0;
        }
        if self.mesh.as_ref().is_some_and(|m| !m.contains(p)) {
            return 0.0;
        }
        self.sigma_t * Self::density(self.lo[2], self.scale_height, p[2])
    }

    fn clip(&self, o: Vec3, w: Vec3) -> Option<(f64, f64)> {
        box_clip(o, w, self.lo, self.hi)
    }

    fn majorants(&self) -> Majorants<'_> {
        Majorants::Grid(&self.grid)
    }

    fn bounds(&self) -> Option<(Vec3, Vec3)> {
        Some((self.lo, self.hi))
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use noise::{MultiFractal, NoiseFn};
    use rand::{Rng, SeedableRng};

    /// The default cloud's five blobs (two chunks of [`BLOB_LANES`], the second filled up).
    fn five_blobs() -> Vec<Ellipsoid> {
        let blob = |c: Vec3, r: Vec3| Ellipsoid {
            center: c,
            radii: r,
        };
        vec![
            blob([0.0, 0.0, 600.0], [500.0, 450.0, 380.0]),
            blob([350.0, 120.0, 820.0], [330.0, 300.0, 300.0]),
            blob([-330.0, -80.0, 780.0], [300.0, 280.0, 280.0]),
            blob([80.0, -200.0, 1000.0], [260.0, 240.0, 240.0]),
            blob([-60.0, 180.0, 700.0], [320.0, 300.0, 260.0]),
        ]
    }

    /// (edge, amplitude, frequency, octaves, seed): the default cloud's, a thin-edged one of
    /// eight octaves and a wide-edged one of one octave.
    const CLOUD_SETTINGS: [(f64, f64, f64, usize, u32); 3] = [
        (40.0, 120.0, 0.004, 5, 1),
        (2.0, 60.0, 0.01, 8, 9),
        (200.0, 10.0, 0.002, 1, 4),
    ];

    fn cloud_of(blobs: &[Ellipsoid], setting: (f64, f64, f64, usize, u32)) -> Cloud {
        let (edge, amplitude, frequency, octaves, seed) = setting;
        Cloud::new(
            blobs.to_vec(),
            edge,
            (amplitude, frequency, octaves),
            0.05,
            seed,
        )
    }

    /// The density with its early outs (the shell test, the octaves that cannot change it) and
    /// its blobs in chunks is bit for bit the definition evaluated in full with the `noise`
    /// crate, blob by blob, over the whole bounding box of the default cloud's five blobs (two
    /// chunks, the second filled up) and of a thin-edged variant; so are its AVX2 copy (when
    /// the CPU has AVX2) and its baseline one.
    #[test]
    fn density_equals_its_definition() {
        let blobs = five_blobs();
        let mut rng = rand_xoshiro::Xoshiro256PlusPlus::seed_from_u64(3);
        for (edge, amplitude, frequency, octaves, seed) in CLOUD_SETTINGS {
            let cloud = cloud_of(&blobs, (edge, amplitude, frequency, octaves, seed));
            let fbm = noise::Fbm::<noise::Perlin>::new(seed).set_octaves(octaves);
            let (mut zeros, mut ones, mut between) = (0, 0, 0);
            for _ in 0..300_000 {
                let p: Vec3 = std::array::from_fn(|k| {
                    cloud.lo[k] + (cloud.hi[k] - cloud.lo[k]) * rng.random::<f64>()
                });
                let inside = blobs
                    .iter()
                    .map(|b| Cloud::depth(b, p))
                    .fold(f64::MIN, f64::max);
                let n = fbm.get(p.map(|x| x * frequency)).clamp(-1.2, 1.2);
                let expected = ((inside + amplitude * n) / edge).clamp(0.0, 1.0);
                let got = cloud.density(p);
                for value in [got, cloud.density_any::<false>(p).0] {
                    assert_eq!(
                        value.to_bits(),
                        expected.to_bits(),
                        "{p:?}: {value} vs {expected}"
                    );
                }
                match got {
                    0.0 => zeros += 1,
                    1.0 => ones += 1,
                    _ => between += 1,
                }
            }
            assert!(
                zeros > 1000 && ones > 1000 && between > 1000,
                "{zeros} {ones} {between}"
            );
        }
    }

    /// The reach of a density lookup holds: at random points of the same clouds, the density
    /// is the lookup's bits, and at points within its reach (a random distance up to it in a
    /// random direction, and 0.999 999 of it along one) the density is the same 0 or 1, in the
    /// noisy shell too. The
    /// march's skipped lookups rest on this ([`crate::render::fast`]'s `substeps`).
    #[test]
    fn density_is_the_same_within_its_reach() {
        let blobs = five_blobs();
        let mut rng = rand_xoshiro::Xoshiro256PlusPlus::seed_from_u64(11);
        for setting in CLOUD_SETTINGS {
            let cloud = cloud_of(&blobs, setting);
            let (mut reached, mut in_shell, mut checked) = (0usize, 0usize, 0usize);
            for _ in 0..100_000 {
                let p: Vec3 = std::array::from_fn(|k| {
                    cloud.lo[k] + (cloud.hi[k] - cloud.lo[k]) * rng.random::<f64>()
                });
                let (d, r) = cloud.density_reach(p);
                assert_eq!(d.to_bits(), cloud.density(p).to_bits(), "{p:?}");
                if r == 0.0 {
                    continue;
                }
                assert!(d == 0.0 || d == 1.0, "{p:?}: reach {r} at density {d}");
                reached += 1;
                // Where the noise had to be evaluated (the shell), not only the blobs.
                let inside = blobs
                    .iter()
                    .map(|b| Cloud::depth(b, p))
                    .fold(f64::MIN, f64::max);
                let (_, amplitude, ..) = setting;
                if inside.abs() < amplitude {
                    in_shell += 1;
                }
                for far in [false, false, true] {
                    let w: Vec3 = loop {
                        let v: Vec3 = std::array::from_fn(|_| 2.0 * rng.random::<f64>() - 1.0);
                        let n = v.iter().map(|x| x * x).sum::<f64>().sqrt();
                        if n > 0.1 && n <= 1.0 {
                            break v.map(|x| x / n);
                        }
                    };
                    let dist = if far {
                        0.999_999 * r
                    } else {
                        r * rng.random::<f64>()
                    };
                    let q: Vec3 = std::array::from_fn(|k| p[k] + dist * w[k]);
                    assert_eq!(
                        cloud.density(q).to_bits(),
                        d.to_bits(),
                        "{q:?}, {dist} m from {p:?} (reach {r} m)"
                    );
                    checked += 1;
                }
            }
            assert!(reached > 1000, "{reached} points with a reach");
            assert!(
                in_shell > 300,
                "{in_shell} points of the shell with a reach"
            );
            assert!(checked > 3000);
        }
    }
}
