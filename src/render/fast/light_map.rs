//! Light-space maps of a medium for the fast renderers (docs/collector.md): an orthographic
//! view along the sun over the medium's bounds, one light column per texel, built once per
//! frame.
//!
//! Per texel: coverage A (1 where the column crosses the lit surface, the iso-surface
//! σ_t = ρ₀ σ_t,scene), the front and back depths Z_min, Z_max of that surface along the beam
//! (m), the optical length τ of the chord between them (mfp) and the outward normal N of the
//! front, from the neighbouring texels' depths ([`with_normals`]). Depths are geometric, because the
//! collector search places points in the world; the chord's optical length rides beside them,
//! so that the slab of a heterogeneous column (a voxel cloud, the fBm boundary layer) has the
//! optical thickness the light actually crosses: κ̄ = τ/(Z_max − Z_min) converts the tables'
//! mean free paths into metres. The channels are premultiplied by A and mip-mapped (2 × 2 box
//! filter), so that the surface filtered at scale σ is ⟨A X⟩_ℓ / ⟨A⟩_ℓ at level
//! ℓ = log₂(σ / texel), trilinear between levels (Bouthors et al. 2008, §7).
//!
//! Beside them, a deep optical-depth map: per texel the optical depth from the sun τ_sun(s) at
//! `planes` + 1 depths s along the beam, from where its column first meets the medium and
//! crowded there (quadratic spacing: order 1 comes from the first mean free paths), linear
//! between them, for the sun's transmittance at any point (order 1 and the octave baseline).

use super::substeps::substeps;
use crate::render::geometry::{cross, dot, normalize, Vec3};
use crate::render::medium::Medium;
use nephele_runtime::fitting::Simd;
use nephele_runtime::transport::{FilteredSurface, Lateral, LitSurface};
use rayon::prelude::*;
use std::ops::ControlFlow;

/// Channels per texel: A, A·Z_min, A·Z_max, A·τ, A·N (3), A·δ (the distance across the
/// light to the cross-section's edge, m: [`with_edge_distances`]).
const CHANNELS: usize = 8;

/// Orthographic light space: u, v across the beam, s along it (m, 0 on the sun's side of the
/// bounds).
#[derive(Clone, Copy, Debug)]
pub struct LightFrame {
    origin: Vec3,
    e1: Vec3,
    e2: Vec3,
    /// Unit vector toward the sun.
    sun: Vec3,
    u0: f64,
    v0: f64,
    /// Texel size at level 0 (m).
    texel: f64,
    /// Texels per side at level 0.
    n: usize,
    /// s of the origin.
    s_origin: f64,
    /// The range of s over the bounds (m).
    depth: f64,
}

impl LightFrame {
    /// The frame of an `n` × `n` map covering the box [lo, hi] seen from `sun` (unit).
    fn new(lo: Vec3, hi: Vec3, sun: Vec3, n: usize) -> Self {
        let origin: Vec3 = std::array::from_fn(|k| 0.5 * (lo[k] + hi[k]));
        let helper = if sun[2].abs() < 0.9 {
            [0.0, 0.0, 1.0]
        } else {
            [1.0, 0.0, 0.0]
        };
        let e1 = normalize(cross(helper, sun));
        let e2 = cross(sun, e1);
        let (mut ur, mut vr, mut sr) = ([f64::MAX, f64::MIN], [f64::MAX, f64::MIN], [0f64; 2]);
        sr[0] = f64::MAX;
        sr[1] = f64::MIN;
        for c in 0..8 {
            let p: Vec3 = std::array::from_fn(|k| if c >> k & 1 == 1 { hi[k] } else { lo[k] });
            let r: Vec3 = std::array::from_fn(|k| p[k] - origin[k]);
            for (range, x) in [
                (&mut ur, dot(r, e1)),
                (&mut vr, dot(r, e2)),
                (&mut sr, dot(r, sun)),
            ] {
                range[0] = range[0].min(x);
                range[1] = range[1].max(x);
            }
        }
        let size = (ur[1] - ur[0]).max(vr[1] - vr[0]);
        let texel = size / n as f64;
        Self {
            origin,
            e1,
            e2,
            sun,
            u0: 0.5 * (ur[0] + ur[1]) - 0.5 * size,
            v0: 0.5 * (vr[0] + vr[1]) - 0.5 * size,
            texel,
            n,
            s_origin: sr[1],
            depth: sr[1] - sr[0],
        }
    }

    /// (u, v, s) of a world point.
    #[inline(always)]
    fn to_light(self, p: Vec3) -> (f64, f64, f64) {
        let r: Vec3 = std::array::from_fn(|k| p[k] - self.origin[k]);
        (
            dot(r, self.e1),
            dot(r, self.e2),
            self.s_origin - dot(r, self.sun),
        )
    }

    /// The world point at (u, v, s).
    fn to_world(self, u: f64, v: f64, s: f64) -> Vec3 {
        let a = self.s_origin - s;
        std::array::from_fn(|k| self.origin[k] + u * self.e1[k] + v * self.e2[k] + a * self.sun[k])
    }

    /// The centre of texel (i, j) of level 0.
    fn texel_centre(&self, i: usize, j: usize) -> (f64, f64) {
        (
            self.u0 + (i as f64 + 0.5) * self.texel,
            self.v0 + (j as f64 + 0.5) * self.texel,
        )
    }
}

/// The maps of one frame.
pub struct LightMaps {
    frame: LightFrame,
    /// Mip levels, finest first: (texels per side, [row][column][channel]).
    levels: Vec<(usize, Vec<f32>)>,
    /// Cross-sections at several depths (none: the lateral extent is the projection's).
    sections: Vec<Section>,
    /// `MapOptions::section_depth`.
    section_depth: f64,
    /// The section that follows the lit surface (`MapOptions::surface_section`).
    surface: Option<Section>,
    /// Per texel, the depth s₀ where its column first meets the medium (s_max where it never
    /// does), [row][column]: apart from the planes, so that the lookup's first pass over four
    /// texels reads a small array that stays in cache.
    first: Vec<f32>,
    /// Per texel, the optical depth from the sun at the `planes` + 1 depths
    /// s₀ + (s_max − s₀)(k/planes)², [row][column][plane].
    shadow: Vec<f32>,
    planes: usize,
    /// The CPU has AVX2: [`LightMaps::sun_optical_depth`] takes its AVX2 copy.
    avx2: bool,
}

/// What one light column holds besides its optical depths (written in place).
struct Column {
    texel: [f32; CHANNELS],
    first: f32,
}

/// Settings of the maps.
#[derive(Clone, Copy, Debug)]
pub struct MapOptions {
    /// Texels per side (a power of two).
    pub resolution: usize,
    /// Depth planes of the optical-depth map.
    pub planes: usize,
    /// Sub-step of the marches through the medium's non-homogeneous parts (m).
    pub step: f64,
    /// σ_t of the lit surface (1/m): ρ₀ times the scene's σ_t.
    pub threshold: f64,
    /// Cross-sections of the cloud at this many depths along the light, for the lateral
    /// extent (0: none; without the surface section either, the whole projection's).
    pub sections: usize,
    /// How far below the point handed to `lateral` its cross-section is read, at most (m):
    /// one transport mean free path, where diffusion's source lies.
    pub section_depth: f64,
    /// One section that follows the lit surface ([`surface_section`], `section_depth` its
    /// scale); with `sections`, `lateral` reads the larger of the two.
    pub surface_section: bool,
}

impl LightMaps {
    /// Casts one light column per texel through `medium` within the box [lo, hi] (rows in
    /// parallel, the same bits for any thread count).
    pub fn build(medium: &dyn Medium, (lo, hi): (Vec3, Vec3), sun: Vec3, o: &MapOptions) -> Self {
        let frame = LightFrame::new(lo, hi, sun, o.resolution);
        let n = o.resolution;
        let mut shadow = vec![0f32; n * n * (o.planes + 1)];
        let columns: Vec<Column> = shadow
            .par_chunks_mut(o.planes + 1)
            .enumerate()
            .map(|(idx, depths)| column(medium, &frame, (idx % n, idx / n), o, depths))
            .collect();
        let mut level0 = Vec::with_capacity(n * n * CHANNELS);
        let mut first = Vec::with_capacity(n * n);
        for c in columns {
            level0.extend_from_slice(&c.texel);
            first.push(c.first);
        }
        with_normals(&frame, &mut level0);
        with_edge_distances(&frame, &mut level0);
        let levels = pyramid::<CHANNELS>(n, level0);
        let sections = cross_sections(&frame, &levels[0].1, o);
        let surface = o
            .surface_section
            .then(|| surface_section(&frame, &levels, o.section_depth));
        Self {
            frame,
            levels,
            sections,
            section_depth: o.section_depth,
            surface,
            first,
            shadow,
            planes: o.planes,
            avx2: Simd::detected().has_avx2(),
        }
    }

    /// The optical depth from the sun to `p` (mfp): bilinear across texels, linear in depth
    /// between each texel's own planes; 0 outside the map. The texels' profiles are aligned on
    /// where their columns meet the medium before they are blended (each is read at its own
    /// s₀ plus p's depth below the blended s₀): a tilted surface then interpolates exactly,
    /// where blending τ at one depth would mix a column still above the surface with one
    /// already deep inside it.
    pub fn sun_optical_depth(&self, p: Vec3) -> f64 {
        #[cfg(target_arch = "x86_64")]
        if self.avx2 {
            // SAFETY: the CPU has AVX2 (checked when the maps were built).
            return unsafe { self.sun_optical_depth_avx2(p) };
        }
        self.sun_optical_depth_any(p)
    }

    /// [`Self::sun_optical_depth`] compiled for AVX2 (its floors and square roots inline, a
    /// tenth of a frame's samples). No FMA: the same bits.
    #[cfg(target_arch = "x86_64")]
    #[target_feature(enable = "avx2")]
    fn sun_optical_depth_avx2(&self, p: Vec3) -> f64 {
        self.sun_optical_depth_any(p)
    }

    #[inline(always)]
    fn sun_optical_depth_any(&self, p: Vec3) -> f64 {
        let f = &self.frame;
        let (u, v, s) = f.to_light(p);
        let (x, y) = ((u - f.u0) / f.texel - 0.5, (v - f.v0) / f.texel - 0.5);
        // The texels whose columns meet the medium: (index, weight, s₀).
        let mut taps = [(0usize, 0.0f64, 0.0f64); 4];
        let (mut count, mut first, mut weight) = (0, 0.0, 0.0);
        bilinear(f.n, x, y, |i, w| {
            let s0 = self.first[i] as f64;
            if s0 < f.depth {
                first += w * s0;
                weight += w;
                taps[count] = (i, w, s0);
                count += 1;
            }
        });
        if weight <= 0.0 {
            return 0.0;
        }
        let below = s - first / weight;
        if below <= 0.0 {
            return 0.0;
        }
        let stride = self.planes + 1;
        let mut tau = 0.0;
        for &(i, w, s0) in &taps[..count] {
            let column = &self.shadow[i * stride..(i + 1) * stride];
            let z = plane_index(s0 + below, s0, f.depth, self.planes);
            let k = (z as usize).min(self.planes - 1);
            let wz = (z - k as f64).min(1.0);
            tau += w * ((1.0 - wz) * column[k] as f64 + wz * column[k + 1] as f64);
        }
        tau
    }

    /// The light-space (u, v) of `at` and the channels filtered there at scale `sigma` (m);
    /// None where the cloud covers less than 10⁻⁴ of the footprint.
    fn covered(&self, at: [f32; 3], sigma: f32) -> Option<(f64, f64, [f64; CHANNELS])> {
        let f = &self.frame;
        let (u, v, _) = f.to_light(at.map(f64::from));
        let level = (sigma as f64 / f.texel).max(1.0).log2();
        let x = self.sample(u, v, level);
        (x[0] >= 1e-4).then_some((u, v, x))
    }

    /// Level-0 texel size (m).
    pub fn texel(&self) -> f64 {
        self.frame.texel
    }

    /// The premultiplied channels at (u, v) and real level ℓ, trilinear.
    fn sample(&self, u: f64, v: f64, level: f64) -> [f64; CHANNELS] {
        sample_pyramid(&self.frame, &self.levels, u, v, level)
    }
}

/// Mip levels of a map of C channels per texel, n texels per side: finest first, each texel
/// the mean of the four below it.
fn pyramid<const C: usize>(n: usize, level0: Vec<f32>) -> Vec<(usize, Vec<f32>)> {
    let mut levels = vec![(n, level0)];
    while levels.last().map_or(0, |l| l.0) > 1 {
        let (m, prev) = levels.last().expect("a level");
        let half = m / 2;
        let mut next = vec![0f32; half * half * C];
        for j in 0..half {
            for i in 0..half {
                for ch in 0..C {
                    let at = |a: usize, b: usize| prev[((2 * j + b) * m + 2 * i + a) * C + ch];
                    next[(j * half + i) * C + ch] =
                        0.25 * (at(0, 0) + at(1, 0) + at(0, 1) + at(1, 1));
                }
            }
        }
        levels.push((half, next));
    }
    levels
}

/// The channels of `levels` at (u, v) and real level ℓ, trilinear.
fn sample_pyramid<const C: usize>(
    frame: &LightFrame,
    levels: &[(usize, Vec<f32>)],
    u: f64,
    v: f64,
    level: f64,
) -> [f64; C] {
    let top = levels.len() - 1;
    let l = level.clamp(0.0, top as f64);
    let k = (l as usize).min(top);
    let w = l - k as f64;
    let mut out = [0.0; C];
    for (lev, weight) in [(k, 1.0 - w), ((k + 1).min(top), w)] {
        if weight <= 0.0 {
            continue;
        }
        let (m, data) = &levels[lev];
        let size = frame.texel * (frame.n / m) as f64;
        let x = (u - frame.u0) / size - 0.5;
        let y = (v - frame.v0) / size - 0.5;
        bilinear(*m, x, y, |i, b| {
            for ch in 0..C {
                out[ch] += weight * b * data[i * C + ch] as f64;
            }
        });
    }
    out
}

/// A section of the cloud: per texel (whether it is inside, that × the distance to the
/// section's edge), mip-mapped; across the light at one depth, or along the lit surface.
struct Section {
    depth: f64,
    levels: Vec<(usize, Vec<f32>)>,
}

impl Section {
    /// A section built from its `inside` texels.
    fn new(f: &LightFrame, depth: f64, inside: impl Fn(usize) -> bool) -> Self {
        let n = f.n;
        let delta = edge_distances(f, inside);
        let mut data = vec![0f32; n * n * 2];
        for (k, d) in delta.into_iter().enumerate() {
            if let Some(d) = d {
                data[2 * k] = 1.0;
                data[2 * k + 1] = d;
            }
        }
        Self {
            depth,
            levels: pyramid::<2>(n, data),
        }
    }

    /// δ̄ (m) over the footprint at (u, v) and real level ℓ; None where the section covers
    /// less than 10⁻⁴ of it.
    fn edge_distance(&self, f: &LightFrame, u: f64, v: f64, level: f64) -> Option<f64> {
        let r = sample_pyramid::<2>(f, &self.levels, u, v, level);
        (r[0] >= 1e-4).then(|| r[1] / r[0])
    }
}

/// `o.sections` cross-sections at depths evenly spread over the cloud's (light-space s from
/// the first entry to the last exit); a texel's column holds matter at depth s where
/// s₀ ≤ s ≤ s₁ (the gaps between lobes along one column are not seen).
fn cross_sections(f: &LightFrame, level0: &[f32], o: &MapOptions) -> Vec<Section> {
    let n = f.n;
    let texel = |k: usize| &level0[k * CHANNELS..(k + 1) * CHANNELS];
    let covered: Vec<usize> = (0..n * n).filter(|&k| texel(k)[0] > 0.0).collect();
    if o.sections == 0 || covered.is_empty() {
        return Vec::new();
    }
    let lo = covered
        .iter()
        .map(|&k| texel(k)[1] as f64)
        .fold(f64::INFINITY, f64::min);
    let hi = covered
        .iter()
        .map(|&k| texel(k)[2] as f64)
        .fold(f64::NEG_INFINITY, f64::max);
    (0..o.sections)
        .into_par_iter()
        .map(|i| {
            let depth = lo + (i as f64 + 0.5) / o.sections as f64 * (hi - lo);
            Section::new(f, depth, |k: usize| {
                let t = texel(k);
                t[0] > 0.0 && (t[1] as f64) <= depth && depth <= t[2] as f64
            })
        })
        .collect()
}

/// The cloud's section along its lit surface rather than across the light: a covered texel
/// is inside unless its column enters the cloud deeper than `depth` (m) below the lit surface
/// smoothed over `depth` around it (s₀ > s̄₀ + depth). A tilted sheet is then one wide body,
/// as its surface is smooth however it tilts, while a lobe seen behind another, whose entry
/// lies far below the smoothed surface next to the front lobe's edge, is cut off from it, as
/// is the far side of a crease deeper than `depth`.
fn surface_section(f: &LightFrame, levels: &[(usize, Vec<f32>)], depth: f64) -> Section {
    let n = f.n;
    let level0 = &levels[0].1;
    let level = (depth / f.texel).max(1.0).log2();
    let inside: Vec<bool> = (0..n * n)
        .into_par_iter()
        .map(|k| {
            let t = &level0[k * CHANNELS..(k + 1) * CHANNELS];
            if t[0] <= 0.0 {
                return false;
            }
            let (u, v) = f.texel_centre(k % n, k / n);
            let x = sample_pyramid::<CHANNELS>(f, levels, u, v, level);
            t[1] as f64 <= x[1] / x[0] + depth
        })
        .collect();
    Section::new(f, depth, |k| inside[k])
}

/// The outward normal of each covered texel from the front depths around it: the lit surface
/// is the height field P(u, v) = (u, v, Z_min(u, v)) seen from the sun, whose normal is
/// N ∝ ω_L + ∂Z/∂u e₁ + ∂Z/∂v e₂ (central differences where both neighbours are covered,
/// one-sided where one is, 0 where none: a silhouette texel tilts toward the covered side).
/// Depths, not ∇σ_t: the density is clamped to [0, 1] over a boundary layer that may be
/// thinner than a texel, where its differences say nothing of the surface's slope.
fn with_normals(f: &LightFrame, level0: &mut [f32]) {
    let n = f.n;
    let z = |i: i64, j: i64| -> Option<f64> {
        if i < 0 || j < 0 || i >= n as i64 || j >= n as i64 {
            return None;
        }
        let t = &level0[(j as usize * n + i as usize) * CHANNELS..];
        (t[0] > 0.0).then_some(t[1] as f64)
    };
    let slope = |a: Option<f64>, c: f64, b: Option<f64>| match (a, b) {
        (Some(a), Some(b)) => (b - a) / (2.0 * f.texel),
        (Some(a), None) => (c - a) / f.texel,
        (None, Some(b)) => (b - c) / f.texel,
        (None, None) => 0.0,
    };
    let mut normals = vec![[0f32; 3]; n * n];
    for j in 0..n as i64 {
        for i in 0..n as i64 {
            let Some(c) = z(i, j) else { continue };
            let zu = slope(z(i - 1, j), c, z(i + 1, j));
            let zv = slope(z(i, j - 1), c, z(i, j + 1));
            let v: Vec3 = std::array::from_fn(|k| f.sun[k] + zu * f.e1[k] + zv * f.e2[k]);
            normals[j as usize * n + i as usize] = normalize(v).map(|x| x as f32);
        }
    }
    for (t, nrm) in level0.chunks_mut(CHANNELS).zip(normals) {
        if t[0] > 0.0 {
            t[4..7].copy_from_slice(&nrm);
        }
    }
}

/// The distance δ (m) from each covered texel's centre to the edge of the cloud's cross-section
/// across the light: the exact Euclidean distance to the nearest uncovered texel centre (the
/// map's border counts as uncovered), less half a texel (the edge lies between the two
/// centres). Two passes of the 1-D lower envelope of parabolas (Felzenszwalb & Huttenlocher
/// 2012), by columns then by rows.
fn with_edge_distances(f: &LightFrame, level0: &mut [f32]) {
    let delta = edge_distances(f, |k| level0[k * CHANNELS] > 0.0);
    for (k, d) in delta.into_iter().enumerate() {
        if let Some(d) = d {
            level0[k * CHANNELS + 7] = d;
        }
    }
}

/// Per texel of the region `inside` (texel index → bool), its distance to the region's edge
/// (m; a texel at the edge is half a texel from it), None outside: an exact Euclidean
/// distance transform (Felzenszwalb & Huttenlocher) of the map padded by one outside texel.
fn edge_distances(f: &LightFrame, inside: impl Fn(usize) -> bool) -> Vec<Option<f32>> {
    let n = f.n;
    let m = n + 2;
    let far = (4 * m * m) as f64;
    // Squared distances (texels²) on the map padded by one uncovered texel on every side.
    let mut d2: Vec<f64> = (0..m * m)
        .map(|k| {
            let (i, j) = (k % m, k / m);
            let within = i >= 1 && j >= 1 && i <= n && j <= n;
            if within && inside((j - 1) * n + i - 1) {
                far
            } else {
                0.0
            }
        })
        .collect();
    let mut line = vec![0.0; m];
    for pass in 0..2 {
        for a in 0..m {
            let at = |b: usize| if pass == 0 { b * m + a } else { a * m + b };
            for (b, x) in line.iter_mut().enumerate() {
                *x = d2[at(b)];
            }
            let out = lower_envelope(&line);
            for (b, x) in out.into_iter().enumerate() {
                d2[at(b)] = x;
            }
        }
    }
    (0..n * n)
        .map(|k| {
            let (i, j) = (k % n, k / n);
            inside(k).then(|| {
                let d = d2[(j + 1) * m + i + 1].sqrt();
                ((d - 0.5).max(0.5) * f.texel) as f32
            })
        })
        .collect()
}

/// min over q of (p − q)² + g(q) for every p: the squared distance transform of one line.
fn lower_envelope(g: &[f64]) -> Vec<f64> {
    let n = g.len();
    let (mut v, mut z) = (vec![0usize; n], vec![0.0f64; n + 1]);
    let mut k = 0;
    z[0] = f64::NEG_INFINITY;
    z[1] = f64::INFINITY;
    let cross = |q: usize, p: usize| {
        ((g[q] + (q * q) as f64) - (g[p] + (p * p) as f64)) / (2.0 * (q as f64 - p as f64))
    };
    for q in 1..n {
        let mut s = cross(q, v[k]);
        while s <= z[k] {
            k -= 1;
            s = cross(q, v[k]);
        }
        k += 1;
        v[k] = q;
        z[k] = s;
        z[k + 1] = f64::INFINITY;
    }
    let mut out = vec![0.0; n];
    k = 0;
    for (p, o) in out.iter_mut().enumerate() {
        while z[k + 1] < p as f64 {
            k += 1;
        }
        let d = p as f64 - v[k] as f64;
        *o = d * d + g[v[k]];
    }
    out
}

/// Calls `f(texel index, weight)` for the texels of an m × m map around the continuous texel
/// coordinates (x, y) (texel centres at integers): bilinear, zero outside the map.
#[inline(always)]
fn bilinear(m: usize, x: f64, y: f64, mut f: impl FnMut(usize, f64)) {
    let (fx, fy) = (x.floor(), y.floor());
    let (wx, wy) = (x - fx, y - fy);
    for (dj, wj) in [(0, 1.0 - wy), (1, wy)] {
        for (di, wi) in [(0, 1.0 - wx), (1, wx)] {
            let (i, j) = (fx as i64 + di, fy as i64 + dj);
            if i < 0 || j < 0 || i >= m as i64 || j >= m as i64 || wi * wj <= 0.0 {
                continue;
            }
            f(j as usize * m + i as usize, wi * wj);
        }
    }
}

/// The real plane index of depth s in a column whose medium starts at `first`: planes at
/// first + (depth − first)(k/planes)², crowded where the sun's optical depth changes fastest
/// (near the lit surface, where order 1 comes from).
#[inline(always)]
fn plane_index(s: f64, first: f64, depth: f64, planes: usize) -> f64 {
    ((s - first) / (depth - first).max(1e-9))
        .clamp(0.0, 1.0)
        .sqrt()
        * planes as f64
}

/// The light column through texel (i, j): marched from the sun's side with the medium's
/// majorants (empty cells skipped, homogeneous ones in closed form); its optical depths at the
/// planes go into `shadow` (zeroed, `planes` + 1 long).
fn column(
    medium: &dyn Medium,
    f: &LightFrame,
    (i, j): (usize, usize),
    o: &MapOptions,
    shadow: &mut [f32],
) -> Column {
    let (u, v) = f.texel_centre(i, j);
    let start = f.to_world(u, v, 0.0);
    let w = f.sun.map(|x| -x);
    let mut first: Option<f64> = None;
    let plane_at =
        |first: f64, k: usize| first + (f.depth - first) * (k as f64 / o.planes as f64).powi(2);
    let (mut tau, mut next_plane) = (0.0f64, 1usize);
    let (mut entry, mut exit): (Option<(f64, f64)>, Option<(f64, f64)>) = (None, None);
    let mut prev: Option<(f64, f64)> = None;
    if let Some(range) = medium.clip(start, w) {
        let range = (range.0, range.1.min(f.depth));
        let _: Option<()> = substeps(medium, start, w, range, o.step, |a, b, sigma| {
            // Where the surface is crossed: between the previous midpoint and this one.
            let mid = 0.5 * (a + b);
            let inside = sigma >= o.threshold;
            let crossing = |(pm, ps): (f64, f64)| {
                if (ps - sigma).abs() > 0.0 {
                    pm + (mid - pm) * ((o.threshold - ps) / (sigma - ps)).clamp(0.0, 1.0)
                } else {
                    a
                }
            };
            if inside && entry.is_none() {
                let s = prev.filter(|p| p.1 < o.threshold).map_or(a, crossing);
                entry = Some((s, tau + sigma * (s - a).max(0.0)));
            }
            if inside {
                exit = Some((b, tau + sigma * (b - a)));
            } else if let (Some(_), Some(pp)) = (exit, prev) {
                if pp.1 >= o.threshold {
                    let s = crossing(pp);
                    exit = Some((s, tau + sigma * (s - a).max(0.0)));
                }
            }
            let s0 = *first.get_or_insert(a);
            while next_plane <= o.planes && plane_at(s0, next_plane) <= b {
                let s = plane_at(s0, next_plane);
                shadow[next_plane] = (tau + sigma * (s - a).max(0.0)) as f32;
                next_plane += 1;
            }
            tau += sigma * (b - a);
            prev = Some((mid, sigma));
            ControlFlow::Continue(())
        });
    }
    for s in &mut shadow[next_plane.min(o.planes + 1)..] {
        *s = tau as f32;
    }
    let mut texel = [0f32; CHANNELS];
    if let (Some((s0, t0)), Some((s1, t1))) = (entry, exit) {
        // The normal comes from the neighbours' depths (`with_normals`).
        texel[..4].copy_from_slice(&[1.0, s0 as f32, s1.max(s0) as f32, (t1 - t0).max(0.0) as f32]);
    }
    Column {
        texel,
        first: first.unwrap_or(f.depth) as f32,
    }
}

impl LitSurface for LightMaps {
    fn filtered(&self, at: [f32; 3], sigma: f32) -> Option<FilteredSurface> {
        let f = &self.frame;
        let (u, v, x) = self.covered(at, sigma)?;
        let (z0, z1, tau) = (x[1] / x[0], x[2] / x[0], x[3] / x[0]);
        let nl = (x[4] * x[4] + x[5] * x[5] + x[6] * x[6]).sqrt();
        let normal = if nl > 1e-9 {
            [x[4] / nl, x[5] / nl, x[6] / nl]
        } else {
            f.sun
        };
        Some(FilteredSurface {
            entry: f.to_world(u, v, z0).map(|x| x as f32),
            normal: normal.map(|x| x as f32),
            length: (z1 - z0).max(0.0) as f32,
            optical_length: tau as f32,
        })
    }

    fn initial_scale(&self) -> f32 {
        (self.frame.texel * self.frame.n as f64) as f32
    }

    /// δ̄ over the footprint of the larger of the two cuts through diffusion's source that the
    /// maps hold (the section across the light one transport mean free path below `at`, and
    /// the section along the lit surface): each bounds from below the body the light can
    /// spread through. Without either, the whole projection's.
    fn lateral(&self, at: [f32; 3], sigma: f32) -> Option<Lateral> {
        let (u, v, x) = self.covered(at, sigma)?;
        let level = (sigma as f64 / self.frame.texel).max(1.0).log2();
        let across = self.across_light(at, u, v, level);
        let along = self
            .surface
            .as_ref()
            .and_then(|c| c.edge_distance(&self.frame, u, v, level));
        let edge = match (across, along) {
            (Some(a), Some(b)) => a.max(b),
            (a, b) => a.or(b).unwrap_or(x[7] / x[0]),
        };
        Some(Lateral {
            coverage: x[0] as f32,
            edge_distance: edge as f32,
        })
    }
}

impl LightMaps {
    /// δ̄ (m) of the section across the light one transport mean free path below `at`, but
    /// not past the middle of its column (a body thinner than that spreads its light through
    /// its whole section), between the two nearest sections; None without sections or where
    /// they do not cover the footprint.
    fn across_light(&self, at: [f32; 3], u: f64, v: f64, level: f64) -> Option<f64> {
        if self.sections.is_empty() {
            return None;
        }
        let (_, _, s) = self.frame.to_light(at.map(f64::from));
        let column = self.sample(u, v, 0.0);
        let half_chord = if column[0] > 0.0 {
            0.5 * (column[2] - column[1]) / column[0]
        } else {
            0.0
        };
        let s = s + self.section_depth.min(half_chord.max(0.0));
        let k = self.sections.partition_point(|c| c.depth <= s);
        let (a, b) = (k.saturating_sub(1), k.min(self.sections.len() - 1));
        let w = if a == b {
            0.0
        } else {
            let (da, db) = (self.sections[a].depth, self.sections[b].depth);
            ((s - da) / (db - da)).clamp(0.0, 1.0)
        };
        let read =
            |i: usize| sample_pyramid::<2>(&self.frame, &self.sections[i].levels, u, v, level);
        let (ra, rb) = (read(a), read(b));
        let mass = (1.0 - w) * ra[0] + w * rb[0];
        (mass >= 1e-4).then(|| ((1.0 - w) * ra[1] + w * rb[1]) / mass)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::render::medium::{Cloud, Ellipsoid};

    /// A homogeneous ball seen from the sun: coverage inside its disc, the chord 2√(r² − q²),
    /// the normal radial, the optical depth σ_t × the path inside.
    #[test]
    fn a_ball_maps_to_its_chords() {
        let r = 300.0;
        let ball = ball(r);
        let sun = normalize([0.3, -0.4, 0.8]);
        let o = MapOptions {
            resolution: 64,
            planes: 128,
            step: 1.0,
            threshold: 0.025,
            sections: 0,
            section_depth: 0.0,
            surface_section: false,
        };
        let maps = LightMaps::build(&ball, ball_bounds(&ball), sun, &o);
        let c = [0.0, 0.0, 500.0];
        for q in [0.0, 100.0, 200.0, 280.0] {
            let side = normalize(cross(sun, [0.0, 0.0, 1.0]));
            let at: Vec3 = std::array::from_fn(|k| c[k] + q * side[k]);
            let s = maps
                .filtered(at.map(|x| x as f32), 0.0)
                .expect("inside the disc");
            // The iso-surface σ_t = σ/2 lies 1 m inside the radius (edge 2 m).
            let chord = 2.0 * ((r - 1.0f64).powi(2) - q * q).sqrt();
            assert!(
                (s.length as f64 - chord).abs() < 0.03 * chord + 2.0 * maps.texel(),
                "q {q}: {} vs {chord}",
                s.length
            );
            let opt = s.optical_length as f64 / 0.05;
            assert!(
                (opt - chord).abs() < 0.03 * chord + 2.0 * maps.texel(),
                "τ {q}"
            );
            let radial = normalize(std::array::from_fn(|k| s.entry[k] as f64 - c[k]));
            let n = s.normal.map(f64::from);
            assert!(
                dot(radial, n) > 0.98,
                "normal at q {q}: {n:?} vs {radial:?}"
            );
            // The sun's optical depth just past the entry and at the centre.
            let centre_tau = maps.sun_optical_depth(c);
            assert!(
                (centre_tau - 0.05 * (r - 1.0)).abs() < 0.5,
                "τ_sun(centre) {centre_tau}"
            );
        }
        let far: Vec3 = [5000.0, 5000.0, 500.0];
        assert_eq!(maps.sun_optical_depth(far), 0.0);
    }

    /// The lateral extent of a ball from its cross-sections: read at the middle of each
    /// column (a section depth of r) it is the whole disc's, as the projection's (δ = r − q at
    /// distance q from the axis); read 50 m below the lit point on the axis, the section there
    /// is the disc of radius √(r² − (r − 50)²) = 166 m.
    #[test]
    fn a_ball_has_its_cross_sections() {
        let r = 300.0;
        let ball = ball(r);
        let sun = normalize([0.3, -0.4, 0.8]);
        let options = |sections, section_depth| MapOptions {
            resolution: 128,
            planes: 64,
            step: 1.0,
            threshold: 0.025,
            sections,
            section_depth,
            surface_section: false,
        };
        let bounds = ball_bounds(&ball);
        let projection = LightMaps::build(&ball, bounds, sun, &options(0, 0.0));
        let middle = LightMaps::build(&ball, bounds, sun, &options(32, r));
        let shallow = LightMaps::build(&ball, bounds, sun, &options(32, 50.0));
        let c = [0.0, 0.0, 500.0];
        let side = normalize(cross(sun, [0.0, 0.0, 1.0]));
        let texel = projection.texel();
        for q in [0.0, 100.0, 200.0] {
            let on_axis: Vec3 = std::array::from_fn(|k| c[k] + q * side[k]);
            // The lit point of that column: back toward the sun by half its chord.
            let half = (r * r - q * q).sqrt();
            let lit: Vec3 = std::array::from_fn(|k| on_axis[k] + half * sun[k]);
            let at = lit.map(|x| x as f32);
            let a = projection.lateral(at, 0.0).expect("covered").edge_distance as f64;
            let b = middle.lateral(at, 0.0).expect("covered").edge_distance as f64;
            assert!((a - (r - q)).abs() < 2.0 * texel, "projection at {q}: {a}");
            assert!(
                (b - (r - q)).abs() < 0.02 * r + 2.0 * texel,
                "sections at {q}: {b}"
            );
        }
        let top: Vec3 = std::array::from_fn(|k| c[k] + r * sun[k]);
        let d = shallow
            .lateral(top.map(|x| x as f32), 0.0)
            .expect("covered")
            .edge_distance;
        let disc = (r * r - (r - 50.0f64).powi(2)).sqrt();
        assert!(
            (d as f64 - disc).abs() < 0.08 * disc,
            "50 m down: {d} vs {disc}"
        );
    }

    /// The section along the lit surface: a sheet tilted 45° to the light is one wide body
    /// (its section across the light at one depth is a band as wide as the sheet is thick
    /// over sin 45°), and a ball seen behind another is cut off from it where the front
    /// ball's edge hides its surface.
    #[test]
    fn the_surface_section_follows_a_tilted_sheet_and_cuts_hidden_lobes() {
        let options = |sections, surface_section| MapOptions {
            resolution: 128,
            planes: 64,
            step: 1.0,
            threshold: 0.025,
            sections,
            section_depth: 140.0,
            surface_section,
        };
        let blob = |center, radii| Ellipsoid { center, radii };
        let cloud = |blobs| Cloud::new(blobs, 2.0, (0.0, 0.01, 1), 0.05, 1);
        let sheet = cloud(vec![blob([0.0, 0.0, 500.0], [600.0, 600.0, 60.0])]);
        let sun = normalize([0.0, -1.0, 1.0]);
        let bounds = ball_bounds(&sheet);
        let across = LightMaps::build(&sheet, bounds, sun, &options(32, false));
        let along = LightMaps::build(&sheet, bounds, sun, &options(0, true));
        let projection = LightMaps::build(&sheet, bounds, sun, &options(0, false));
        let top = [0.0f32, 0.0, 560.0];
        let read = |m: &LightMaps| m.lateral(top, 0.0).expect("covered").edge_distance as f64;
        let (a, b, p) = (read(&across), read(&along), read(&projection));
        let band = 120.0 / 0.5f64.sqrt();
        assert!(a < 0.6 * band, "across the light: {a} m, band {band} m");
        assert!(
            b > 0.9 * p && b > 3.0 * a,
            "along the surface: {b} m, projection {p} m"
        );

        // Two balls along the light, the back one shifted aside by 1.2 radii: near the
        // front ball's edge the back one's surface lies ~r below the front one's.
        let r = 200.0;
        let sun = [0.0, 0.0, 1.0];
        let pair = cloud(vec![
            blob([0.0, 0.0, 900.0], [r; 3]),
            blob([1.2 * r, 0.0, 300.0], [r; 3]),
        ]);
        let bounds = ball_bounds(&pair);
        let along = LightMaps::build(&pair, bounds, sun, &options(0, true));
        let projection = LightMaps::build(&pair, bounds, sun, &options(0, false));
        // On the back ball, just beside the front ball's edge.
        let at = [(1.0 * r + 30.0) as f32, 0.0, 480.0];
        let b = along.lateral(at, 0.0).expect("covered").edge_distance as f64;
        let p = projection.lateral(at, 0.0).expect("covered").edge_distance as f64;
        assert!(p > 100.0, "the projection merges the balls: {p} m");
        assert!(b < 0.5 * p, "the hidden ball cut off: {b} m against {p} m");
    }

    /// A homogeneous ball of radius r (m) centred at (0, 0, 500), σ_t = 0.05 /m, edge 2 m.
    fn ball(r: f64) -> Cloud {
        Cloud::new(
            vec![Ellipsoid {
                center: [0.0, 0.0, 500.0],
                radii: [r; 3],
            }],
            2.0,
            (0.0, 0.01, 1),
            0.05,
            1,
        )
    }

    fn ball_bounds(b: &Cloud) -> (Vec3, Vec3) {
        b.bounds().expect("a bounded cloud")
    }
}
