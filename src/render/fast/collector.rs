//! The collector branch of the fast renderers (docs/collector.md, "The collector search"):
//! orders ≥ 2 of a view ray from its surface point p, per order group g of the tables, by
//! nephele-runtime's collector search on the sun side's lit surface — L_g = w T_g E_sun, with
//! w = α / (1 − e^{−τ_b}), α the ray's opacity and τ_b the found slab's own path beyond p
//! (`SlabPoint::view_weight`) — and the sky term S_g in the slab the search found; where the
//! search finds no light, T and S are read in the slab of the surface filtered at the cloud's
//! size. How the searches went is counted per group ([`GroupStats`], render.json).
//!
//! The finite-cloud correction (docs/collector.md, "Finite clouds"): each group's T and S are
//! multiplied by the share a finite, possibly absorbing cloud keeps of the infinite slab's
//! light ([`finite_cloud`]: the sides' leakage from the cross-section around the collector,
//! the medium's absorption; where no collector is found, the absorption alone); the sky term
//! in the view ray's chord, its orders moved by what the sides take from a walk from the eye
//! (under a uniform sky the sides gain what they leak, so the sum stays), absorption after.

use super::frame::{Frame, Pixel};
use super::view_ray::ViewRay;
use crate::render::image::GROUP_FIRST;
use nephele_runtime::transport::leakage::lateral_rate;
use nephele_runtime::transport::{
    absorbed, find_collectors, finite_cloud, local_slab, section_radius, Domain, FiniteCloud,
    LitSurface, SlabPoint, TransportTables, Viewpoint,
};
use serde::Serialize;

/// One group's light from a collector search, per unit E_sun before the view weight: the slab
/// it was read in (whose path beyond p sets the weight), the share the cloud keeps, T.
#[derive(Clone, Copy, Debug)]
pub(super) struct GroupLight {
    at: SlabPoint<f32>,
    kept: f64,
    t: f64,
}

/// Every group's light from one search (index g: the g-th group of orders ≥ 2).
pub(super) type Searched = [Option<GroupLight>; GROUP_FIRST.len() - 1];

/// The collector's finite-cloud correction (docs/collector.md, "Finite clouds").
#[derive(Clone, Copy, Debug, PartialEq, Serialize)]
pub struct Finite {
    /// Light lost through the cloud's sides, per order group (diffusion theory).
    pub leakage: bool,
    /// T weighed by the share of the collector's footprint the cloud covers (an ablation).
    pub coverage: bool,
    /// κ⊥ times this (1: diffusion theory as is, no fitted constant).
    pub rate_scale: f64,
    /// The sides count from order n_c = this × (δ̄ + z_e)²/D on (0: from the first order).
    pub delay_scale: f64,
    /// The sides count the orders by the walk's spread across the light (else order by
    /// order, from the first).
    pub spread: bool,
    /// R from the cloud's sections across the light at this many depths (0: none).
    pub sections: usize,
    /// R from the cloud's section along its lit surface; with `sections`, the larger of the
    /// two; with neither, R from the cloud's whole projection.
    pub surface: bool,
}

impl Finite {
    /// The method as published: the infinite slab's T.
    pub const PUBLISHED: Finite = Finite {
        leakage: false,
        coverage: false,
        rate_scale: 1.0,
        delay_scale: 0.0,
        spread: false,
        sections: 0,
        surface: false,
    };

    /// Its name in render.json and in `nephele compare`'s columns.
    pub fn name(&self) -> String {
        let mut name = match (self.leakage, self.coverage) {
            (false, false) => "as published".to_string(),
            (true, false) => "leakage".to_string(),
            (false, true) => "coverage".to_string(),
            (true, true) => "leakage+coverage".to_string(),
        };
        if self.leakage && self.rate_scale != 1.0 {
            name += &format!(", κ⊥ × {}", self.rate_scale);
        }
        if self.leakage && self.delay_scale != 0.0 {
            name += &format!(", delay {}", self.delay_scale);
        }
        let default = Finite::default();
        if self.leakage && self.spread != default.spread {
            name += if self.spread {
                ", spread"
            } else {
                ", by order"
            };
        }
        if self.leakage && (self.sections, self.surface) != (default.sections, default.surface) {
            name += &match (self.sections, self.surface) {
                (0, false) => ", R from the projection".to_string(),
                (0, true) => ", R along the surface".to_string(),
                (k, false) => format!(", R across the light ({k} sections)"),
                (k, true) => format!(", R from {k} sections and the surface"),
            };
        }
        name
    }

    /// The runtime's settings: the tables' mean cosine, the scene's absorption κ_a = −ln ϖ
    /// per scattering (applied whatever the correction: the tables are for ϖ = 1).
    pub fn runtime(&self, tables: &TransportTables, albedo: f64) -> FiniteCloud {
        FiniteCloud {
            leakage: self.leakage,
            coverage: self.coverage,
            rate_scale: self.rate_scale as f32,
            delay_scale: self.delay_scale as f32,
            spread: self.spread,
            absorption: (-albedo.ln()).max(0.0) as f32,
            mean_cosine: tables.mean_cosine(),
        }
    }
}

impl Default for Finite {
    /// Lateral leakage counted by the walk's spread, R from the larger of the sections across
    /// the light (16) and along the lit surface; no fitted constant.
    fn default() -> Self {
        Finite {
            leakage: true,
            spread: true,
            sections: 16,
            surface: true,
            ..Finite::PUBLISHED
        }
    }
}

/// Per group of orders ≥ 2: how the searches went.
#[derive(Clone, Debug, Default, Serialize)]
pub struct GroupStats {
    /// First order of the group.
    pub first_order: u32,
    /// Searches run (pixels × rays with a surface point).
    pub searches: u64,
    /// Searches that found no light (no cloud on the light line through p, or T = 0 there):
    /// T read instead in the slab of the surface filtered at the cloud's size.
    pub empty: u64,
    /// Of those, how many found no light there either (the group is 0 in that pixel).
    pub dark: u64,
    /// Table reads, summed.
    pub reads: u64,
    /// Searches that met the stopping rule before the cap.
    pub converged: u64,
    /// Searches whose last read held t, μ_L or d at the tables' domain.
    pub clamped_thickness: u64,
    /// See `clamped_thickness`.
    pub clamped_mu_l: u64,
    /// See `clamped_thickness`.
    pub clamped_depth: u64,
    /// Searches whose last read moved d so that the slab holds the view ray's medium beyond p.
    pub held_by_view: u64,
    /// Searches whose last read cut the slab above p to p's depth to the sun.
    pub held_by_sun: u64,
    /// Searches whose last read held t at the tables' thickest slab, and the largest t
    /// they reached (mfp).
    pub past_thickest: u64,
    pub thickest: Option<f32>,
    /// Searches whose last read held μ_L at the tables' lowest sun, and the smallest μ_L
    /// they reached (≤ 0: a face turned from the sun).
    pub below_lowest_sun: u64,
    pub lowest_mu_l: Option<f32>,
    /// The finite-cloud correction's factors on T, summed over the searches that found a
    /// collector (their mean: the share of the slab's light the cloud keeps).
    pub kept: f64,
}

/// The extreme of two optional values by `pick` (None: no value yet).
fn extreme(a: Option<f32>, b: Option<f32>, pick: fn(f32, f32) -> f32) -> Option<f32> {
    match (a, b) {
        (Some(a), Some(b)) => Some(pick(a, b)),
        (a, b) => a.or(b),
    }
}

/// The warnings of a render whose searches held the local slab at the tables' grid: the share
/// of the searches held (over every group) and how far past the grid they reached, when the
/// share is at least 0.1 %.
pub(super) fn held_warnings(stats: &[GroupStats], domain: &Domain) -> Vec<String> {
    let searches: u64 = stats.iter().map(|s| s.searches).sum();
    let share = |n: u64| 100.0 * n as f64 / searches.max(1) as f64;
    let mut out = Vec::new();
    let past: u64 = stats.iter().map(|s| s.past_thickest).sum();
    let thickest = stats
        .iter()
        .filter_map(|s| s.thickest)
        .fold(0.0f32, f32::max);
    if share(past) >= 0.1 {
        out.push(format!(
            "{:.1} % of the collector searches held t at the tables' thickest slab: t up to {:.0} \
             mfp against the tables' {}",
            share(past),
            thickest,
            domain.thickness.1
        ));
    }
    let low: u64 = stats.iter().map(|s| s.below_lowest_sun).sum();
    let lowest = stats
        .iter()
        .filter_map(|s| s.lowest_mu_l)
        .fold(1.0f32, f32::min);
    if share(low) >= 0.1 {
        let up = |mu: f32| mu.clamp(0.0, 1.0).asin().to_degrees();
        out.push(format!(
            "{:.1} % of the collector searches held the sun at the tables' lowest (mu_L = {}, {:.1} \
             deg up): mu_L down to {:.3} ({:.1} deg up{}); their orders >= 2 are the lowest sun's \
             T/mu_L times mu_L, too bright the lower the sun (on a 10-mfp slab +88 % at 1 deg up, \
             +14 % at 6 deg)",
            share(low),
            domain.mu_l.0,
            up(domain.mu_l.0),
            lowest.max(0.0),
            up(lowest),
            if lowest <= 0.0 { ", faces turned from the sun among them" } else { "" }
        ));
    }
    out
}

impl GroupStats {
    /// Adds the counts of `o` (another row of pixels).
    pub(super) fn add(&mut self, o: &GroupStats) {
        self.searches += o.searches;
        self.empty += o.empty;
        self.dark += o.dark;
        self.reads += o.reads;
        self.converged += o.converged;
        self.clamped_thickness += o.clamped_thickness;
        self.clamped_mu_l += o.clamped_mu_l;
        self.clamped_depth += o.clamped_depth;
        self.held_by_view += o.held_by_view;
        self.held_by_sun += o.held_by_sun;
        self.past_thickest += o.past_thickest;
        self.below_lowest_sun += o.below_lowest_sun;
        self.thickest = extreme(self.thickest, o.thickest, f32::max);
        self.lowest_mu_l = extreme(self.lowest_mu_l, o.lowest_mu_l, f32::min);
        self.kept += o.kept;
    }
}

impl Frame<'_> {
    /// Orders ≥ 2 of a view ray of opacity `alpha` whose surface point the collector search
    /// takes as `vp`, group by group into `px` (sun and sky; order 1's sky term from the first
    /// slab found), the searches counted in `stats` (one entry per group).
    pub(super) fn collector(
        &self,
        px: &mut Pixel,
        alpha: f64,
        vp: &Viewpoint,
        stats: &mut [GroupStats],
    ) {
        let found = self.search(vp, stats);
        self.apply(px, alpha, &found);
    }

    /// Every group's collector search from the viewpoint `vp`, counted in `stats`: the slab
    /// each read its light in and what the cloud keeps of it; where the search finds no
    /// collector, the slab of the surface filtered at the cloud's size.
    pub(super) fn search(&self, vp: &Viewpoint, stats: &mut [GroupStats]) -> Searched {
        let sun32 = self.scene.sun.direction.map(|x| x as f32);
        let mut found = [None; GROUP_FIRST.len()];
        let vp = &Viewpoint {
            sun_depth: if self.opts.no_sun_depth {
                f32::INFINITY
            } else {
                vp.sun_depth
            },
            ..*vp
        };
        find_collectors(
            self.tables,
            &self.side,
            vp,
            sun32,
            &self.opts.search,
            &mut found,
        );
        let mut light = [None; GROUP_FIRST.len() - 1];
        let domain = self.tables.domain();
        for (((g, st), found), light) in stats.iter_mut().enumerate().zip(found).zip(&mut light) {
            st.searches += 1;
            let Some(f) = found else {
                st.empty += 1;
                match self.coarse_slab(vp, sun32) {
                    Some(at) => {
                        let t = self.tables.evaluate(g, &at).t as f64;
                        *light = Some(GroupLight {
                            at,
                            kept: self.absorbed(g, &at),
                            t,
                        });
                        st.dark += (t == 0.0) as u64;
                    }
                    None => st.dark += 1,
                }
                continue;
            };
            st.reads += f.reads as u64;
            st.converged += f.converged as u64;
            st.clamped_thickness += f.clamps.thickness as u64;
            st.clamped_mu_l += f.clamps.mu_l as u64;
            st.clamped_depth += f.clamps.depth as u64;
            st.held_by_view += f.clamps.view as u64;
            st.held_by_sun += f.clamps.sun as u64;
            if f.clamps.thickness && f.at.thickness >= domain.thickness.1 {
                st.past_thickest += 1;
                st.thickest = extreme(st.thickest, Some(f.unheld.thickness), f32::max);
            }
            // Held at the lowest sun (not a cosine a rounding past 1, held at 1).
            if f.unheld.mu_l < domain.mu_l.0 {
                st.below_lowest_sun += 1;
                st.lowest_mu_l = extreme(st.lowest_mu_l, Some(f.unheld.mu_l), f32::min);
            }
            let kept = finite_cloud(self.tables, g, &self.side, &f, &self.finite).factor as f64;
            st.kept += kept;
            *light = Some(GroupLight {
                at: f.at,
                kept,
                t: f.transport.t as f64,
            });
        }
        light
    }

    /// Orders ≥ 2 of a ray or pixel of opacity `alpha` from the searches' `found` into `px`:
    /// L_g = w kept T with w = α over the slab's own opacity beyond p — T already holds the
    /// slab's sources over its path beyond p (docs/collector.md, "Thin matter").
    pub(super) fn apply(&self, px: &mut Pixel, alpha: f64, found: &Searched) {
        for (g, f) in found.iter().enumerate() {
            if let Some(f) = f {
                let w = f.at.view_weight(alpha as f32) as f64;
                px.sun[g + 1] = [w * f.kept * f.t; 3];
            }
        }
    }

    /// The sky term of every method, group by group into `px` (per unit L_sky), for the view
    /// ray `v`: S_g in the ray's own slab across its chord ([`super::sky::SkyTable::view_slab`]),
    /// what absorption leaves of it; the pixel's sides come after ([`Self::sky_sides`]).
    pub(super) fn sky_term(&self, px: &mut Pixel, v: &ViewRay) {
        let Some(sky) = &self.sky else {
            return;
        };
        if !(v.chord > 0.0) {
            return;
        }
        let at = sky.view_slab(v.chord);
        sky.view_radiances(v.chord, &at, &mut px.sky);
        px.sky[0] *= self.scene.albedo;
        px.sky_order1 = self.scene.albedo * v.sky_order1;
        for g in 0..self.groups() {
            px.sky[g + 1] *= self.absorbed(g, &at);
        }
    }

    /// The sky term's sides, once per pixel: the light an adjoint walk from the eye loses
    /// through the cloud's sides before it leaves by the slab's faces, moved to the orders at
    /// which it leaves ([`super::sky::sides_escape`]; under a uniform sky a conservative body
    /// glows at the sky's radiance whatever its shape, so the sum stays). κ⊥ from the section
    /// the sun-side maps hold at `at` (the pixel's most opaque surface point) at the cloud's own
    /// scale, R = [`section_radius`] of its mean distance to the edge in mfp at the scene's σ_t
    /// (as [`finite_cloud`] takes it). Nothing where the maps know no edge (a slab). Every method
    /// takes it, the method as published included: the sky term is this project's, not the
    /// paper's. (With ϖ < 1 it follows the absorption's factors, an approximation.)
    pub(super) fn sky_sides(&self, px: &mut Pixel, at: [f32; 3]) {
        let Some(sky) = &self.sky else {
            return;
        };
        let Some(l) = self.side.lateral(at, self.side.initial_scale()) else {
            return;
        };
        if !l.edge_distance.is_finite() {
            return;
        }
        // (in m, then in mfp: the rule is linear)
        let radius = section_radius(l.edge_distance) * self.scene.sigma_t as f32;
        let kappa = f64::from(lateral_rate(radius, self.finite.mean_cosine));
        sky.sides_escape(&mut px.sky, kappa, f64::from(self.finite.mean_cosine));
    }

    /// The sky's order 1 marched ([`super::sky_order1`]) in place of the slab's, once per
    /// pixel after the sides: the orders ≥ 2 keep their split and take what is left of the
    /// scattered sky the slab gave (a conservative body under a uniform sky glows at its
    /// radiance, whatever its orders). Nothing without the maps (a slab, or the ablation).
    pub(super) fn sky_marched_order1(&self, px: &mut Pixel) {
        if self.sky.is_none() || self.sky_order1.is_none() {
            return;
        }
        let n = self.groups() + 1;
        let total: f64 = px.sky[..n].iter().sum();
        let rest = total - px.sky[0];
        let order1 = px.sky_order1;
        let scale = if rest > 0.0 {
            (total - order1).max(0.0) / rest
        } else {
            0.0
        };
        px.sky[0] = order1;
        px.sky[1..n].iter_mut().for_each(|s| *s *= scale);
    }

    /// Empty statistics, one entry per order group of the tables the image holds.
    pub(super) fn empty_stats(&self) -> Vec<GroupStats> {
        (0..self.groups())
            .map(|g| GroupStats {
                first_order: self.tables.group_first_order(g).map_or(0, |f| f as u32),
                ..Default::default()
            })
            .collect()
    }

    /// The share of group `g` an absorbing medium keeps in the slab `at` (1 for ϖ = 1).
    fn absorbed(&self, g: usize, at: &SlabPoint<f32>) -> f64 {
        absorbed(self.tables, g, at, &self.finite) as f64
    }

    /// The slab of p under the surface filtered at the cloud's size (no search).
    pub(super) fn coarse_slab(&self, v: &Viewpoint, sun: [f32; 3]) -> Option<SlabPoint<f32>> {
        let s = self.side.filtered(v.position, self.side.initial_scale())?;
        Some(local_slab(self.tables, &s, v, sun).read_at())
    }
}
