//! One frame of the fast renderers: the pixels in bands of rows, each pixel's rays marched
//! ([`super::view_ray`]) with order 1, the collector's branch or the octaves, the corner rays
//! shared between neighbouring pixels, and the per-band sums of the search statistics.

use super::super::camera::Pinhole;
use super::super::geometry::{dot, Vec3};
use super::super::image::{Rendered, GROUP_FIRST};
use super::super::medium::Medium;
use super::super::regions::region_of;
use super::super::scene::Scene;
use super::collector::{GroupStats, Searched};
use super::octaves::MAX_OCTAVES;
use super::sky::SkyTable;
use super::sky_order1::SkyOrder1;
use super::sun_side::SunSide;
use super::view_ray::ViewRay;
use super::{FastOptions, Method};
use crate::phase::Phase;
use nephele_runtime::transport::{FiniteCloud, TransportTables, Viewpoint};
use rayon::prelude::*;
use std::collections::HashMap;
use std::sync::atomic::{AtomicUsize, Ordering};

/// Rows of a band and width of a tile of the pixels' work (at least one search block).
const TILE: usize = 8;

/// Everything a frame needs, built once.
pub(super) struct Frame<'a> {
    pub(super) scene: &'a Scene,
    pub(super) medium: Box<dyn Medium>,
    pub(super) side: SunSide,
    pub(super) tables: &'a TransportTables<'a>,
    pub(super) sky: Option<SkyTable>,
    /// The sky's order 1 marched through maps toward the sky (none: from the sky table).
    pub(super) sky_order1: Option<SkyOrder1>,
    pub(super) opts: FastOptions,
    pub(super) step: f64,
    pub(super) threshold: f64,
    /// p(θ) per channel and the mean cosine g (for the octaves).
    pub(super) phases: Vec<Phase>,
    pub(super) g: f64,
    /// The collector's finite-cloud correction, with the tables' mean cosine and the scene's
    /// absorption.
    pub(super) finite: FiniteCloud,
    /// The sub-pixel offsets of a pixel's rays ([`RayPattern::offsets`]).
    pub(super) offsets: Vec<(f64, f64)>,
}

impl Frame<'_> {
    /// The order groups of orders ≥ 2 rendered: the tables' (at most the image's).
    pub(super) fn groups(&self) -> usize {
        self.tables.groups().min(GROUP_FIRST.len() - 1)
    }

    /// Every pixel, rows in parallel (deterministic: no randomness, sums in a fixed order),
    /// each row written straight into the images (no frame-sized buffer of pixels between).
    /// Also the sky term's share of the scattered light.
    pub(super) fn pixels(
        &self,
        cam: &Pinhole,
        progress: &(dyn Fn(f64) + Sync),
    ) -> (Rendered, Vec<GroupStats>, f64) {
        let (w, h) = (cam.width, cam.height);
        let ng = GROUP_FIRST.len();
        let done = AtomicUsize::new(0);
        let mut out = Rendered::empty(w, h);
        out.method = format!("{:?}", self.opts.method).to_lowercase();
        out.regions = vec![0; w * h];
        // Bands of whole blocks of `search_block` rows (a search may serve pixels of several
        // rows), at least `TILE` rows: the band's pixels go tile by tile, and where pixels
        // share their corner rays a band marches the row of corners below its last row again.
        // Each band's rows in every group's plane, side by side.
        let block = self.opts.search_block as usize;
        let band = block * TILE.div_ceil(block);
        let mut group_bands: Vec<Vec<&mut [f32]>> = (0..h.div_ceil(band))
            .map(|_| Vec::with_capacity(ng))
            .collect();
        for plane in out.groups.chunks_mut(h * w * 3) {
            for (bands, rows) in group_bands.iter_mut().zip(plane.chunks_mut(band * w * 3)) {
                bands.push(rows);
            }
        }
        let bands: Vec<BandSums> = out
            .transmittance
            .par_chunks_mut(band * w)
            .zip(out.regions.par_chunks_mut(band * w))
            .zip(out.unscattered.par_chunks_mut(band * w * 3))
            .zip(out.beauty.par_chunks_mut(band * w * 3))
            .zip(group_bands.into_par_iter())
            .enumerate()
            .map(
                |(b, ((((transmittance, regions), unscattered), beauty), mut groups))| {
                    let mut sums = BandSums {
                        stats: self.empty_stats(),
                        sky: 0.0,
                        all: 0.0,
                    };
                    let rows = transmittance.len() / w;
                    let images = BandImages {
                        transmittance,
                        regions,
                        unscattered,
                        beauty,
                        groups: &mut groups,
                    };
                    self.band(cam, b * band, images, &mut sums);
                    let finished = done.fetch_add(rows, Ordering::Relaxed) + rows;
                    progress(finished as f64 / h as f64);
                    sums
                },
            )
            .collect();
        let mut stats = self.empty_stats();
        let (mut sky_sum, mut all) = (0.0f64, 0.0f64);
        for sums in bands {
            for (a, b) in stats.iter_mut().zip(&sums.stats) {
                a.add(b);
            }
            sky_sum += sums.sky;
            all += sums.all;
        }
        (out, stats, sky_sum / all.max(1e-300))
    }

    /// The rows from `j0` on that `images` hold (whole blocks of `search_block` rows): every
    /// pixel's rays marched, then one collector search per block of pixels, at the block's
    /// most opaque ray, each pixel weighing what it found by its own opacity (a corner ray's
    /// search is shared by the blocks that choose it) — or, in a block that holds a pixel
    /// less opaque than `search_block_opacity`, one search per pixel; the searches and the
    /// light added into `sums`.
    pub(super) fn band(&self, cam: &Pinhole, j0: usize, images: BandImages, sums: &mut BandSums) {
        let w = cam.width;
        let rows = images.transmittance.len() / w;
        let corners = self.corner_rays(cam, j0, rows);
        let b = self.opts.search_block as usize;
        // Tiles of the band's rows, `TILE` (or a block) wide, one after the other: a tile's
        // rays cross the same light-map columns, which stay in the core's cache between them.
        let tile = b * TILE.div_ceil(b);
        let tile_order = |step: usize| {
            (0..w).step_by(tile).flat_map(move |i0| {
                (0..rows)
                    .step_by(step)
                    .flat_map(move |j| (i0..(i0 + tile).min(w)).step_by(step).map(move |i| (j, i)))
            })
        };
        let mut marched: Vec<Option<(Pixel, Option<Densest>)>> = vec![None; rows * w];
        for (j, i) in tile_order(1) {
            marched[j * w + i] =
                Some(self.marched_pixel(cam, i, j0 + j, &corners, &mut sums.stats));
        }
        let mut pixels: Vec<(Pixel, Option<Densest>)> = marched
            .into_iter()
            .map(|p| p.expect("every pixel marched"))
            .collect();
        let mut shared: HashMap<usize, Searched> = HashMap::new();
        for (bj, bi) in tile_order(b) {
            // The block's pixels, row by row.
            let block = || {
                (bj..(bj + b).min(rows))
                    .flat_map(move |j| (bi..(bi + b).min(w)).map(move |i| j * w + i))
            };
            // A block with a pixel less opaque than the threshold (a silhouette, thin matter)
            // searches pixel by pixel: there orders ≥ 2 change from pixel to pixel.
            let alone = b > 1
                && block().any(|k| {
                    pixels[k].1.is_some()
                        && 1.0 - pixels[k].0.transmittance < self.opts.search_block_opacity
                });
            if alone {
                for k in block() {
                    self.search_for(
                        std::iter::once(k),
                        &mut pixels,
                        &mut shared,
                        &mut sums.stats,
                    );
                }
            } else {
                self.search_for(block(), &mut pixels, &mut shared, &mut sums.stats);
            }
        }
        let (sun, sky) = (self.scene.sun.irradiance, self.scene.sky);
        for (k, (px, _)) in pixels.iter_mut().enumerate() {
            px.region = region_of(1.0 - px.transmittance, px.sun_tau);
            images.transmittance[k] = px.transmittance as f32;
            images.regions[k] = px.region;
            for c in 0..3 {
                let mut total = px.transmittance * sky[c];
                images.unscattered[k * 3 + c] = total as f32;
                for (g, plane) in images.groups.iter_mut().enumerate() {
                    let v = px.sun[g][c] * sun[c] + px.sky[g] * sky[c];
                    sums.sky += px.sky[g] * sky[c];
                    sums.all += v;
                    plane[k * 3 + c] = v as f32;
                    total += v;
                }
                images.beauty[k * 3 + c] = total as f32;
            }
        }
    }

    /// One collector search for the pixels `members` (indices into `pixels`), at their most
    /// opaque ray, each of them weighing the light found by its own opacity; a corner ray's
    /// search is kept in `shared` for every block that chooses it.
    pub(super) fn search_for(
        &self,
        members: impl Iterator<Item = usize> + Clone,
        pixels: &mut [(Pixel, Option<Densest>)],
        shared: &mut HashMap<usize, Searched>,
        stats: &mut [GroupStats],
    ) {
        let mut densest: Option<Densest> = None;
        for k in members.clone() {
            if let Some(d) = pixels[k].1 {
                if densest.as_ref().is_none_or(|best| d.alpha > best.alpha) {
                    densest = Some(d);
                }
            }
        }
        let Some(d) = densest else {
            return;
        };
        let found = match d.corner {
            Some(c) => *shared
                .entry(c)
                .or_insert_with(|| self.search(&d.viewpoint, stats)),
            None => self.search(&d.viewpoint, stats),
        };
        for k in members {
            let (px, own) = &mut pixels[k];
            if own.is_some() {
                let alpha = 1.0 - px.transmittance;
                self.apply(px, alpha, &found);
            }
        }
    }

    /// The rays through the corners of the `rows` rows of pixels from `j0` on, for the
    /// patterns that share them (none otherwise).
    pub(super) fn corner_rays(&self, cam: &Pinhole, j0: usize, rows: usize) -> Corners {
        let w = cam.width + 1;
        let rays = if self.opts.pattern.corners() {
            (0..(rows + 1) * w)
                .map(|k| {
                    let dir = cam.direction(k % w, j0 + k / w, 0.0, 0.0);
                    let (one, ray) = self.ray(cam.position, dir, None);
                    let densest = ray.viewpoint(dir).map(|viewpoint| Densest {
                        alpha: 1.0 - ray.transmittance,
                        viewpoint,
                        corner: Some(j0 * w + k),
                    });
                    (one, densest)
                })
                .collect()
        } else {
            Vec::new()
        };
        Corners { j0, width: w, rays }
    }

    /// One pixel's rays marched: the weighted mean over its own rays and its corner rays
    /// (opacity, order 1, the sky term, the octaves), and, for the collector, the most opaque
    /// ray's opacity and viewpoint, where [`Self::band`] searches once for the pixel or its
    /// block — unless `search_every_ray` (each own ray its own searches here). `corners` are
    /// the band's corner rays ([`Self::corner_rays`]), pixel (i, j) of the band's row j − j0.
    pub(super) fn marched_pixel(
        &self,
        cam: &Pinhole,
        i: usize,
        j: usize,
        corners: &Corners,
        stats: &mut [GroupStats],
    ) -> (Pixel, Option<Densest>) {
        let once = self.opts.method == Method::Collector && !self.opts.search_every_ray;
        let mut px = Pixel::default();
        let (w_own, w_corner) = self.opts.pattern.weights(self.offsets.len());
        // The most opaque ray: where the sky term's sides are read, whatever the method, and
        // where the collector searches once for the pixel.
        let mut densest: Option<Densest> = None;
        let mut consider = |d: Option<Densest>| match d {
            Some(d) if densest.as_ref().is_none_or(|best| d.alpha > best.alpha) => {
                densest = Some(d)
            }
            _ => {}
        };
        for &(u, v) in &self.offsets {
            let dir = cam.direction(i, j, u, v);
            let (one, ray) = self.ray(cam.position, dir, (!once).then_some(&mut *stats));
            px.add(&one, w_own);
            consider(ray.viewpoint(dir).map(|viewpoint| Densest {
                alpha: 1.0 - ray.transmittance,
                viewpoint,
                corner: None,
            }));
        }
        for (di, dj) in [(0, 0), (1, 0), (0, 1), (1, 1)] {
            let Some((one, d)) = corners.at(i + di, j + dj) else {
                continue;
            };
            px.add(one, w_corner);
            consider(*d);
        }
        if let Some(d) = &densest {
            self.sky_sides(&mut px, d.viewpoint.position);
        }
        self.sky_marched_order1(&mut px);
        (px, densest.filter(|_| once))
    }

    /// One view ray: its transmittance, order 1, and the scattered orders of the method (the
    /// collector's only with `stats` to count its searches in); and the march itself.
    pub(super) fn ray(
        &self,
        o: Vec3,
        w: Vec3,
        stats: Option<&mut [GroupStats]>,
    ) -> (Pixel, ViewRay) {
        let v = self.march(o, w);
        let mut px = Pixel {
            transmittance: v.transmittance,
            ..Default::default()
        };
        let alpha = 1.0 - v.transmittance;
        let sun = self.scene.sun.direction;
        let cos = dot(w, sun).clamp(-1.0, 1.0);
        let albedo = self.scene.albedo;
        for (c, p) in px.sun[0].iter_mut().enumerate() {
            let phase = &self.phases[c.min(self.phases.len() - 1)];
            *p = albedo * phase.with(|f| f.eval(cos)) * v.integrals[0];
        }
        self.sky_term(&mut px, &v);
        let Some(vp) = v.viewpoint(w) else {
            return (px, v);
        };
        px.sun_tau = v.sun_depth;
        match (self.opts.method, stats) {
            (Method::Collector, Some(stats)) => self.collector(&mut px, alpha, &vp, stats),
            (Method::Octaves, _) => px.sun[1] = self.octaves(cos, &v.integrals),
            _ => {}
        }
        (px, v)
    }

    /// Σ_{1 ≤ i < N} bⁱ ϖ p_HG(θ; cⁱ g) I_{aⁱ} (per unit E_sun; octave 0 is order 1).
    pub(super) fn octaves(&self, cos: f64, integrals: &[f64; MAX_OCTAVES]) -> [f64; 3] {
        let o = &self.opts.octaves;
        [o.scattered(self.g, self.scene.albedo, cos, integrals); 3]
    }
}

/// A ray a collector search may start from: its opacity, its viewpoint, and which corner ray
/// it is (a corner's search serves every block that chooses it).
#[derive(Clone, Copy, Debug)]
pub(super) struct Densest {
    alpha: f64,
    viewpoint: Viewpoint,
    /// The corner's index in the frame, (width + 1) per row.
    corner: Option<usize>,
}

/// A band's corner rays ((rows + 1) × (width + 1), row by row, from pixel row `j0`): what
/// each ray gathers and the search it may start.
pub(super) struct Corners {
    j0: usize,
    width: usize,
    rays: Vec<(Pixel, Option<Densest>)>,
}

impl Corners {
    /// The ray through corner (i, j) (the top-left corner of pixel (i, j)); None without
    /// corner rays.
    pub(super) fn at(&self, i: usize, j: usize) -> Option<&(Pixel, Option<Densest>)> {
        self.rays.get((j - self.j0) * self.width + i)
    }
}

/// A band of rows of a frame's images, written by [`Frame::band`].
pub(super) struct BandImages<'a, 'b> {
    transmittance: &'a mut [f32],
    regions: &'a mut [u8],
    unscattered: &'a mut [f32],
    beauty: &'a mut [f32],
    /// The band's rows in each group's plane.
    groups: &'a mut [&'b mut [f32]],
}

/// What a band adds up: its searches, and its sky term's and all its scattered light (the
/// bands' sums are added in order).
pub(super) struct BandSums {
    stats: Vec<GroupStats>,
    sky: f64,
    all: f64,
}

/// What one pixel (or ray) gathers, per unit sun irradiance and sky radiance.
#[derive(Clone, Copy, Debug, Default)]
pub(super) struct Pixel {
    pub(super) transmittance: f64,
    /// Per group and channel, per unit E_sun.
    pub(super) sun: [[f64; 3]; GROUP_FIRST.len()],
    /// Per group, per unit L_sky.
    pub(super) sky: [f64; GROUP_FIRST.len()],
    /// The sky's order 1 marched (ϖ included), per unit L_sky.
    pub(super) sky_order1: f64,
    /// τ_sun at the surface point.
    pub(super) sun_tau: f64,
    pub(super) region: u8,
}

impl Pixel {
    /// Adds `o` with weight `w`.
    pub(super) fn add(&mut self, o: &Pixel, w: f64) {
        self.transmittance += w * o.transmittance;
        for g in 0..GROUP_FIRST.len() {
            for c in 0..3 {
                self.sun[g][c] += w * o.sun[g][c];
            }
            self.sky[g] += w * o.sky[g];
        }
        self.sky_order1 += w * o.sky_order1;
        self.sun_tau += w * o.sun_tau;
    }
}
