//! What a collector search works on and gives back: the renderer's lit surface
//! ([`LitSurface`], filtered samples of it), the viewpoint and the search's settings, and a
//! search's result (the collector, the local slab, what was held at the tables' ends). The
//! search itself is in `search.rs`; `sun_depth.rs` and `finite.rs` read these types too.

use super::geometry::SlabPoint;
use super::tables::{Transport, TransportTables};
use crate::frame::Vec3;
use crate::real::Math;

/// The lit surface filtered at one place and scale, as a renderer's light-space maps give it.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct FilteredSurface {
    /// The filtered lit face's point on the light line of the query (m, world).
    pub entry: Vec3<f32>,
    /// Its outward unit normal (toward the sun's side).
    pub normal: Vec3<f32>,
    /// Geometric length of the chord from the lit face to the far face along the light (m).
    pub length: f32,
    /// Optical length of the same chord (mfp).
    pub optical_length: f32,
}

/// What a renderer supplies: its cloud's lit surface seen from the sun, filtered.
pub trait LitSurface {
    /// The surface filtered at scale `sigma` (m, the collector's spread) around the light line
    /// through `at` (m, world); None where no cloud covers it.
    fn filtered(&self, at: Vec3<f32>, sigma: f32) -> Option<FilteredSurface>;

    /// σ₀ (m): the scale of the first filtering, the cloud's size.
    fn initial_scale(&self) -> f32;

    /// The cloud's section that the light entering at `at` spreads through (the toolchain's
    /// maps: the larger of its sections across the light one transport mean free path below
    /// `at` and along the lit surface; docs/collector.md), filtered at scale `sigma` (m)
    /// around the light line through `at`: what the finite-cloud correction reads
    /// ([`super::finite_cloud`]). None (the default) where the surface does not know it:
    /// an unbounded slab.
    fn lateral(&self, _at: Vec3<f32>, _sigma: f32) -> Option<Lateral> {
        None
    }

    /// The sun's optical depth (mfp) to `at` (m, world) through the cloud as it is, unfiltered
    /// (the toolchain's deep optical-depth map): what the search averages across the light
    /// over each group's spread ([`SearchOptions::sun_spread`]). None (the default) where the
    /// surface does not know it: every group then reads [`Viewpoint::sun_depth`] as it is.
    fn sun_depth(&self, _at: Vec3<f32>) -> Option<f32> {
        None
    }
}

/// The cloud's section around a point, filtered at a scale.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Lateral {
    /// The share of the footprint the cloud covers, in [0, 1].
    pub coverage: f32,
    /// The mean, over the covered part of the footprint, of the distance to the section's
    /// edge (m).
    pub edge_distance: f32,
}

/// The search's settings.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct SearchOptions {
    /// Most table reads, N (≥ 1).
    pub max_reads: u32,
    /// ε: converged when the collector moves less than ε σ across the light and σ changes
    /// by less than ε σ.
    pub tolerance: f32,
    /// Clamp each step to |c_i − c_{i−1}|⊥ ≤ σ_i (from the second step).
    pub step_clamp: bool,
    /// Filter the surface at σ (else always at the finest scale: an ablation).
    pub filter: bool,
    /// Some(g), the medium's mean cosine: each group reads p's depth to the sun averaged
    /// across the light over its walks' spread ([`super::sun_depth`]; where the surface knows
    /// the sun's depth). None: p's own depth for every group.
    pub sun_spread: Option<f32>,
}

impl Default for SearchOptions {
    /// The default search, p's own depth to the sun for every group (no mean cosine is known
    /// here: [`Self::for_tables`] sets it).
    fn default() -> Self {
        Self {
            max_reads: 8,
            tolerance: 0.1,
            step_clamp: true,
            filter: true,
            sun_spread: None,
        }
    }
}

impl SearchOptions {
    /// The default search for `tables`: the sun's depth spread by their phase function.
    pub fn for_tables(tables: &TransportTables) -> Self {
        Self {
            sun_spread: Some(tables.mean_cosine()),
            ..Self::default()
        }
    }
}

/// Where the light is seen, along which direction, and how much medium the view ray holds
/// beyond that point (what the renderer's march knows).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Viewpoint {
    /// p (m, world).
    pub position: Vec3<f32>,
    /// ω_V: the direction the light travels toward the eye (unit).
    pub view: Vec3<f32>,
    /// The optical depth (mfp) the view ray crosses beyond p, away from the eye, is at least
    /// this…
    pub behind_min: f32,
    /// …and at most this (infinite when unknown).
    pub behind_max: f32,
    /// The optical depth (mfp) from p toward the sun through the cloud as it is, unfiltered
    /// (a light map's; infinite when unknown).
    pub sun_depth: f32,
}

impl Viewpoint {
    /// p seen along `view`, nothing known of the medium beyond it nor of its depth to the sun.
    pub fn new(position: Vec3<f32>, view: Vec3<f32>) -> Self {
        Self {
            position,
            view,
            behind_min: 0.0,
            behind_max: f32::INFINITY,
            sun_depth: f32::INFINITY,
        }
    }
}

/// Which slab parameters of the last read were outside the tables' domain and held at its end.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct Clamps {
    /// t below or above the tables' thicknesses.
    pub thickness: bool,
    /// μ_L below the tables' smallest sun cosine (a filtered face turned from the sun).
    pub mu_l: bool,
    /// p above the filtered lit face (d < 0) or below its far face (d > t).
    pub depth: bool,
    /// d moved so that the slab's path beyond p matches the view ray's medium beyond p (a thin
    /// or grazing ray seen going up: p moved down toward the far face; seen going down, p
    /// moved to hold the ray's medium above it).
    pub view: bool,
    /// The slab above p cut to p's own depth to the sun, which the filtered face put deeper
    /// (a cloud's sunlit edge seen grazing), or grown to it where the slab is thinner.
    pub sun: bool,
}

impl Clamps {
    /// Whether any parameter was clamped.
    pub fn any(&self) -> bool {
        self.thickness || self.mu_l || self.depth || self.view || self.sun
    }
}

/// The result of one group's search.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Collector {
    /// T (sr⁻¹), c and σ (mfp, slab frame) of the last read.
    pub transport: Transport,
    /// The slab it was read at.
    pub at: SlabPoint<f32>,
    /// The collector's centre on the filtered lit face (m, world).
    pub centre: Vec3<f32>,
    /// Its spread σ (m).
    pub sigma: f32,
    /// Table reads.
    pub reads: u32,
    /// Whether the stopping rule was met before the cap.
    pub converged: bool,
    /// Parameters held at the tables' domain in the last read.
    pub clamps: Clamps,
    /// The last read's t and μ_L before they were held ([`Unheld`]).
    pub unheld: Unheld,
    /// κ̄ (1/m) of the last read's slab: mfp per metre.
    pub extinction: f32,
}

/// A local slab's thickness and sun cosine as the surface gave them, before they were held
/// within the tables' grid: how far a search reached past it.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct Unheld {
    /// The largest t (mfp) the slab took on its way, before any hold (at least the slab's
    /// own: the steps after the first start from the held value).
    pub thickness: f32,
    /// μ_L = n̄·ω_L (≤ 0 on a face turned from the sun).
    pub mu_l: f32,
}

/// The local slab of a viewpoint under a filtered surface, and its horizontal frame.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct LocalSlab {
    /// The slab parameters, clamped to the tables' domain.
    pub at: SlabPoint<f32>,
    /// What the clamping changed.
    pub clamps: Clamps,
    /// t and μ_L before they were held.
    pub unheld: Unheld,
    /// p's projection along the normal on the lit face (m, world): the origin of c.
    pub foot: Vec3<f32>,
    /// Unit vectors along c_z (the beam's horizontal travel) and c_x (across, toward the
    /// view's side).
    pub z_axis: Vec3<f32>,
    /// See `z_axis`.
    pub x_axis: Vec3<f32>,
    /// κ̄ (1/m): mfp per metre of this slab.
    pub extinction: f32,
}

impl LocalSlab {
    /// The point the tables are read at: the slab's, under the sun's own μ_L where it lies
    /// below the tables' lowest (they scale T for it); a face turned from the sun (μ_L ≤ 0)
    /// under μ_L = 10⁻⁶, next to no light.
    pub fn read_at(&self) -> SlabPoint<f32> {
        SlabPoint {
            mu_l: self.unheld.mu_l.clamp_to(GRAZING_FLOOR, self.at.mu_l),
            ..self.at
        }
    }
}

/// The sun cosine a face turned from the sun is read under: T scaled by 10⁻⁶/μ₀, next to no
/// light, in normal f32 numbers whatever T is (a GPU may flush subnormals to 0, the CPU does
/// not: the two would part).
const GRAZING_FLOOR: f32 = 1e-6;
