//! The sun's side of a scene for the fast renderers (docs/collector.md): the lit surface the
//! collector search filters ([`LitSurface`]) and the sun's optical depth anywhere — exact for a
//! slab (its lit face is a plane), from light-space maps for bounded media.

use super::light_map::{LightMaps, MapOptions};
use crate::render::geometry::Vec3;
use crate::render::medium::Medium;
use crate::render::scene::{MediumSpec, Scene};
use anyhow::{bail, ensure, Result};
use nephele_runtime::transport::{FilteredSurface, Lateral, LitSurface};

/// The sun's side of a scene: the lit surface and the sun's optical depth anywhere.
pub enum SunSide {
    /// A homogeneous slab z ∈ [0, h]: its lit face is the plane z = h (exact, no map).
    Plane {
        /// Thickness (m).
        h: f64,
        /// Extinction (1/m).
        sigma_t: f64,
        /// Toward the sun (unit, z > 0).
        sun: Vec3,
    },
    /// Light-space maps of a bounded medium.
    Maps(Box<LightMaps>),
    /// Another side whose chords (geometric and optical alike, so κ̄ and the depths stay)
    /// are scaled: the thickness ablation.
    Scaled(Box<SunSide>, f32),
}

impl SunSide {
    /// This side with its chords scaled by `k` (itself for k = 1).
    pub fn scaled(self, k: f64) -> Self {
        if k == 1.0 {
            self
        } else {
            SunSide::Scaled(Box::new(self), k as f32)
        }
    }

    /// The sun's optical depth to `p` (mfp).
    pub fn optical_depth(&self, p: Vec3) -> f64 {
        match self {
            SunSide::Plane { h, sigma_t, sun } => sigma_t * (h - p[2]).clamp(0.0, *h) / sun[2],
            SunSide::Maps(m) => m.sun_optical_depth(p),
            SunSide::Scaled(side, _) => side.optical_depth(p),
        }
    }
}

impl LitSurface for SunSide {
    fn filtered(&self, at: [f32; 3], sigma: f32) -> Option<FilteredSurface> {
        match self {
            SunSide::Plane { h, sigma_t, sun } => {
                let back = (*h as f32 - at[2]) / sun[2] as f32;
                let chord = *h as f32 / sun[2] as f32;
                Some(FilteredSurface {
                    entry: std::array::from_fn(|k| at[k] + back * sun[k] as f32),
                    normal: [0.0, 0.0, 1.0],
                    length: chord,
                    optical_length: chord * *sigma_t as f32,
                })
            }
            SunSide::Maps(m) => m.filtered(at, sigma),
            SunSide::Scaled(side, k) => side.filtered(at, sigma).map(|mut s| {
                s.length *= k;
                s.optical_length *= k;
                s
            }),
        }
    }

    fn initial_scale(&self) -> f32 {
        match self {
            SunSide::Plane { h, .. } => 10.0 * *h as f32,
            SunSide::Maps(m) => m.initial_scale(),
            SunSide::Scaled(side, _) => side.initial_scale(),
        }
    }

    fn lateral(&self, at: [f32; 3], sigma: f32) -> Option<Lateral> {
        match self {
            SunSide::Plane { .. } => None,
            SunSide::Maps(m) => m.lateral(at, sigma),
            SunSide::Scaled(side, _) => side.lateral(at, sigma),
        }
    }

    fn sun_depth(&self, at: [f32; 3]) -> Option<f32> {
        Some(self.optical_depth(at.map(f64::from)) as f32)
    }
}

/// The scene's sun side: the exact plane for a slab, light-space maps otherwise.
pub fn sun_side(
    scene: &Scene,
    medium: &dyn Medium,
    maps: &MapOptions,
    thickness_scale: f64,
) -> Result<SunSide> {
    let sun = scene.sun.direction;
    if let MediumSpec::Slab { thickness } = scene.medium {
        ensure!(
            sun[2] > 1e-3,
            "the sun must be above the slab's lit face (sun.direction z > 0)"
        );
        let side = SunSide::Plane {
            h: thickness,
            sigma_t: scene.sigma_t,
            sun,
        };
        return Ok(side.scaled(thickness_scale));
    }
    let Some(bounds) = medium.bounds() else {
        bail!("the fast renderers need a bounded medium or a slab");
    };
    let side = SunSide::Maps(Box::new(LightMaps::build(medium, bounds, sun, maps)));
    Ok(side.scaled(thickness_scale))
}
