//! Lights besides the sun and the sky (docs/render.md, "Lights"): a point light and a spot
//! light, both seen by next-event estimation through the medium (fog shadows).
//!
//! A point light of intensity I (W/sr, RGB) lights a point at distance r along −ω (ω the unit
//! vector from the point toward the light) with irradiance I T_r / r² on a surface facing it.
//! A spot light is a point light whose intensity falls with the angle θ from its axis as
//! Mitsuba 3's `spot` does: I for θ ≤ the beam width, then linearly in θ to 0 at the cutoff,
//! 0 beyond.

use super::geometry::{dot, Vec3};
use anyhow::{ensure, Result};
use serde::{Deserialize, Serialize};

/// One light of a scene.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
#[serde(tag = "kind", rename_all = "snake_case", deny_unknown_fields)]
pub enum Light {
    /// An isotropic point light.
    Point {
        /// Position (m).
        position: Vec3,
        /// Radiant intensity (linear RGB, W/sr).
        intensity: [f64; 3],
    },
    /// A spot light: a point light limited to a cone around `direction`.
    Spot {
        /// Position (m).
        position: Vec3,
        /// The cone's axis (normalised on load).
        direction: Vec3,
        /// Radiant intensity on the axis (linear RGB, W/sr).
        intensity: [f64; 3],
        /// The cone's half-angle (degrees, in (0, 90]): no light beyond it.
        cutoff_deg: f64,
        /// The half-angle of full intensity (degrees, in (0, cutoff_deg]).
        beam_width_deg: f64,
    },
}

/// What a light sends toward a point: the unit vector from the point toward the light, the
/// distance (m) and the radiant intensity it emits toward the point (W/sr, RGB).
pub struct Incident {
    pub toward: Vec3,
    pub distance: f64,
    pub intensity: [f64; 3],
}

impl Light {
    /// Checks the light's values, naming the first bad one (`at`: its place in the scene).
    pub fn validate(&self, at: &str) -> Result<()> {
        let finite = |v: &[f64]| v.iter().all(|x| x.is_finite());
        let (position, intensity) = match self {
            Light::Point {
                position,
                intensity,
            } => (position, intensity),
            Light::Spot {
                position,
                direction,
                intensity,
                cutoff_deg,
                beam_width_deg,
            } => {
                ensure!(
                    finite(direction) && dot(*direction, *direction) > 0.0,
                    "{at}.direction must be a non-zero vector"
                );
                ensure!(
                    *cutoff_deg > 0.0 && *cutoff_deg <= 90.0,
                    "{at}.cutoff_deg must be in (0, 90] degrees"
                );
                ensure!(
                    *beam_width_deg > 0.0 && beam_width_deg <= cutoff_deg,
                    "{at}.beam_width_deg must be in (0, cutoff_deg] degrees"
                );
                (position, intensity)
            }
        };
        ensure!(
            finite(position),
            "{at}.position must be three finite numbers (m)"
        );
        ensure!(
            intensity.iter().all(|&i| i >= 0.0 && i.is_finite()),
            "{at}.intensity must be three non-negative numbers (W/sr)"
        );
        Ok(())
    }

    /// The light with its direction normalised.
    pub fn normalised(mut self) -> Self {
        if let Light::Spot { direction, .. } = &mut self {
            let n = dot(*direction, *direction).sqrt();
            *direction = direction.map(|x| x / n);
        }
        self
    }

    /// What the light sends toward `x`; None where it sends nothing (outside a spot's cone, or
    /// at the light itself).
    pub fn toward(&self, x: Vec3) -> Option<Incident> {
        let (position, intensity) = match self {
            Light::Point {
                position,
                intensity,
            }
            | Light::Spot {
                position,
                intensity,
                ..
            } => (*position, *intensity),
        };
        let d: Vec3 = std::array::from_fn(|k| position[k] - x[k]);
        let distance = dot(d, d).sqrt();
        if !(distance > 0.0) {
            return None;
        }
        let toward = d.map(|v| v / distance);
        let scale = match self {
            Light::Point { .. } => 1.0,
            Light::Spot {
                direction,
                cutoff_deg,
                beam_width_deg,
                ..
            } => spot_falloff(
                -dot(*direction, toward),
                cutoff_deg.to_radians(),
                beam_width_deg.to_radians(),
            ),
        };
        (scale > 0.0).then(|| Incident {
            toward,
            distance,
            intensity: intensity.map(|i| i * scale),
        })
    }
}

/// Mitsuba 3's spot profile at cos θ from the axis: 1 within the beam width, then linear in θ
/// to 0 at the cutoff.
fn spot_falloff(cos: f64, cutoff: f64, beam: f64) -> f64 {
    if cos <= cutoff.cos() {
        return 0.0;
    }
    if cos >= beam.cos() {
        return 1.0;
    }
    ((cutoff - cos.clamp(-1.0, 1.0).acos()) / (cutoff - beam)).clamp(0.0, 1.0)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_spot_is_full_in_its_beam_linear_to_its_cutoff_and_dark_beyond() {
        let spot = Light::Spot {
            position: [0.0, 0.0, 10.0],
            direction: [0.0, 0.0, -1.0],
            intensity: [2.0, 2.0, 2.0],
            cutoff_deg: 30.0,
            beam_width_deg: 10.0,
        };
        let at = |deg: f64| {
            let r = 10.0 * deg.to_radians().tan();
            spot.toward([r, 0.0, 0.0]).map_or(0.0, |i| i.intensity[0])
        };
        assert_eq!(at(0.0), 2.0);
        assert_eq!(at(9.0), 2.0);
        assert!((at(20.0) - 1.0).abs() < 1e-9, "{}", at(20.0));
        assert!((at(25.0) - 0.5).abs() < 1e-9);
        assert_eq!(at(31.0), 0.0);
        let i = spot.toward([0.0, 0.0, 0.0]).expect("on the axis");
        assert!((i.distance - 10.0).abs() < 1e-12 && (i.toward[2] - 1.0).abs() < 1e-12);
    }

    #[test]
    fn bad_lights_are_refused_by_name() {
        let bad = Light::Spot {
            position: [0.0; 3],
            direction: [0.0; 3],
            intensity: [1.0; 3],
            cutoff_deg: 30.0,
            beam_width_deg: 10.0,
        };
        let e = bad.validate("lights[2]").unwrap_err().to_string();
        assert!(e.contains("lights[2].direction"), "{e}");
        let bad = Light::Point {
            position: [0.0; 3],
            intensity: [-1.0, 0.0, 0.0],
        };
        assert!(bad.validate("lights[0]").is_err());
    }
}
