//! The finite-cloud correction of a collector (docs/collector.md, "Finite clouds"): what share
//! of the infinite slab's T_g a real cloud keeps.
//!
//! - **Lateral leakage**: the section of the cloud the light spreads through around the
//!   collector (the surface's [`LitSurface::lateral`]: the toolchain's light maps take the
//!   larger of the sections across the light one transport mean free path below it and along
//!   the lit surface), filtered at the collector's spread σ_g around its centre, has a mean
//!   distance δ̄ to its edge; a disk of radius R has δ̄ = R/3, so R = 3 δ̄ (a strip of width W
//!   gives R = 3W/4, whose κ⊥ is within 5 % of the strip's own π² D / W²). In mfp with the
//!   collector's κ̄, κ⊥ = D j₀²/R_e², and the group keeps [`group_survival`] of κ⊥ + κ_a
//!   ([`super::leakage`]), the sides counting each order by how far the walk has spread
//!   across the light ([`super::leakage::lateral_orders`], `spread`). A small footprint deep
//!   inside a wide cloud sees a large δ̄ and keeps nearly all; near an edge, or once σ_g spans
//!   the cloud, the cloud's own size sets the loss.
//! - **Absorption**: κ_a = −ln ϖ per scattering, exact for any ϖ given the orders' distribution.
//! - **Coverage** (an ablation): T_g times the share of the collector's footprint that the
//!   cloud covers, ⟨A⟩ at level log₂(σ_g/texel).

use super::geometry::SlabPoint;
use super::leakage::{
    diffusion_coefficient, extrapolation_length, group_survival, lateral_rate, Loss,
};
use super::surface::{Collector, LitSurface};
use super::tables::{group_orders, TransportTables};
use crate::real::{Math, Real};

/// Which corrections apply, and the medium's constants.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct FiniteCloud {
    /// Lateral leakage through the cloud's sides.
    pub leakage: bool,
    /// Weigh T by the share of the collector's footprint the cloud covers.
    pub coverage: bool,
    /// κ⊥ times this (1: diffusion theory as is, no fitted constant).
    pub rate_scale: f32,
    /// The sides count from order n_c = this × (δ̄ + z_e)²/D on (0: from the first order).
    pub delay_scale: f32,
    /// The sides count the orders by the walk's spread across the light
    /// ([`super::leakage::lateral_orders`]; the default), else order by order from the first.
    pub spread: bool,
    /// κ_a = −ln ϖ per scattering (0 for water clouds in the visible).
    pub absorption: f32,
    /// g, the phase function's mean cosine (the tables').
    pub mean_cosine: f32,
}

impl FiniteCloud {
    /// The method as published: the infinite slab's T.
    pub fn published(mean_cosine: f32) -> Self {
        Self {
            leakage: false,
            coverage: false,
            rate_scale: 1.0,
            delay_scale: 0.0,
            spread: false,
            absorption: 0.0,
            mean_cosine,
        }
    }

    /// Lateral leakage from diffusion theory, counted by the walk's spread across the light,
    /// no fitted constant, for `tables`' phase function.
    pub fn for_tables(tables: &TransportTables) -> Self {
        Self {
            leakage: true,
            spread: true,
            ..Self::published(tables.mean_cosine())
        }
    }

    /// Whether anything is corrected.
    pub fn any(&self) -> bool {
        self.leakage || self.coverage || self.absorption > 0.0
    }
}

/// What one group's collector keeps.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Kept {
    /// The factor on T_g, in [0, 1].
    pub factor: f32,
    /// The lateral radius R it used (mfp; infinite where the surface knows no edge).
    pub radius: f32,
    /// The footprint's coverage (1 where the surface does not know it).
    pub coverage: f32,
}

/// R (mfp) of a section whose mean distance to its edge is `edge` (mfp): a disk of radius R has
/// a mean distance R/3 (a strip of width W gives R = 3W/4, whose κ⊥ is within 5 % of the
/// strip's own).
pub fn section_radius<R: Real>(edge: R) -> R {
    R::of(3.0) * edge
}

/// The share of group `g`'s T that the cloud keeps at the collector `c` found on `surface`.
pub fn finite_cloud<S: LitSurface + ?Sized>(
    tables: &TransportTables,
    g: usize,
    surface: &S,
    c: &Collector,
    opts: &FiniteCloud,
) -> Kept {
    let mut kept = Kept {
        factor: 1.0,
        radius: f32::INFINITY,
        coverage: 1.0,
    };
    if !opts.any() {
        return kept;
    }
    let g_mean = opts.mean_cosine;
    let mut loss = Loss {
        absorption: opts.absorption.max(0.0),
        lateral: 0.0,
        delay: 0.0,
        spread: None,
    };
    if let Some(l) = surface.lateral(c.centre, c.sigma) {
        kept.coverage = l.coverage.clamp_to(0.0, 1.0);
        if opts.leakage && l.edge_distance.is_finite() {
            let edge = l.edge_distance * c.extinction;
            kept.radius = section_radius(edge);
            loss.lateral = opts.rate_scale * lateral_rate(kept.radius, g_mean);
            let reach = edge + extrapolation_length(g_mean);
            loss.delay = opts.delay_scale * reach * reach / diffusion_coefficient(g_mean);
            loss.spread = opts.spread.then_some(g_mean);
        }
    }
    let (first, last) = group_orders(tables, g);
    kept.factor = group_survival(first, last, c.at.depth, c.at.thickness, g_mean, &loss);
    if opts.coverage {
        kept.factor *= kept.coverage;
    }
    kept
}

/// The share of group `g`'s T an absorbing medium keeps in the slab `at` (1 for ϖ = 1): what
/// applies where no collector was found, and to the sky term (under a uniform sky a body's
/// sides gain what they leak, so only absorption takes light from it).
pub fn absorbed(
    tables: &TransportTables,
    g: usize,
    at: &SlabPoint<f32>,
    opts: &FiniteCloud,
) -> f32 {
    let loss = Loss {
        absorption: opts.absorption.max(0.0),
        lateral: 0.0,
        delay: 0.0,
        spread: None,
    };
    let (first, last) = group_orders(tables, g);
    group_survival(first, last, at.depth, at.thickness, opts.mean_cosine, &loss)
}
