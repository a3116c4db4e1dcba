//! Lights besides the sun and the sky (docs/render.md, "Lights"): point and spot lights, and
//! sphere and rectangle area lights, all seen by next-event estimation through the medium (fog
//! shadows).
//!
//! A point light of intensity I (W/sr, RGB) lights a point at distance r along −ω (ω the unit
//! vector from the point toward the light) with irradiance I T_r / r² on a surface facing it.
//! A spot light is a point light whose intensity falls with the angle θ from its axis as
//! Mitsuba 3's `spot` does: I for θ ≤ the beam width, then linearly in θ to 0 at the cutoff,
//! 0 beyond.
//!
//! An area light of radiance L_e is sampled: a direction ω with density q(ω) (1/sr) toward a
//! point y of it at distance r, returned as the point light that gives the same estimate,
//! I = L_e r² / q(ω), so that f T_r I / r² = f T_r L_e / q. A sphere (centre c, radius R, at
//! distance d) is sampled uniformly in the cone it subtends, q = 1/(2π(1 − cos θ_max)) with
//! cos θ_max = √(1 − R²/d²); a rectangle uniformly by area A, q = r² / (A cos θ_y) with θ_y
//! the angle at y from its normal (it emits on the side of edge_u × edge_v only). Area lights
//! are invisible to camera rays and do not block light (Mitsuba 3's area emitter on a shape
//! with a null BSDF, rendered with `hide_emitters`); a point inside a sphere light gets none
//! of its light.

use super::geometry::{cross, dot, normalize, Vec3};
use anyhow::{ensure, Result};
use rand::Rng;
use serde::{Deserialize, Serialize};
use std::f64::consts::PI;

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
    /// A sphere emitting `radiance` from every point of its surface, outward.
    Sphere {
        /// Centre (m).
        center: Vec3,
        /// Radius (m).
        radius: f64,
        /// Radiance (linear RGB, W m⁻² sr⁻¹).
        radiance: [f64; 3],
    },
    /// A parallelogram {corner + a edge_u + b edge_v, a, b ∈ [0, 1]} emitting `radiance` on
    /// the side of edge_u × edge_v (a rectangle when the edges are perpendicular).
    Rectangle {
        /// One corner (m).
        corner: Vec3,
        /// The first edge from the corner (m).
        edge_u: Vec3,
        /// The second edge from the corner (m).
        edge_v: Vec3,
        /// Radiance (linear RGB, W m⁻² sr⁻¹).
        radiance: [f64; 3],
    },
}

/// What a light sends toward a point: the unit vector from the point toward the light (or the
/// point sampled on it), the distance (m) and the radiant intensity that gives its estimate
/// (W/sr, RGB; for an area light L_e r² / q, see the module docs).
pub struct Incident {
    pub toward: Vec3,
    pub distance: f64,
    pub intensity: [f64; 3],
}

fn finite(v: &[f64]) -> bool {
    v.iter().all(|x| x.is_finite())
}

fn non_negative(v: &[f64; 3]) -> bool {
    v.iter().all(|&i| i >= 0.0 && i.is_finite())
}

impl Light {
    /// Checks the light's values, naming the first bad one (`at`: its place in the scene).
    pub fn validate(&self, at: &str) -> Result<()> {
        match self {
            Light::Point {
                position,
                intensity,
            } => Self::validate_point(at, position, intensity),
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
                Self::validate_point(at, position, intensity)
            }
            Light::Sphere {
                center,
                radius,
                radiance,
            } => {
                ensure!(
                    finite(center),
                    "{at}.center must be three finite numbers (m)"
                );
                ensure!(
                    *radius > 0.0 && radius.is_finite(),
                    "{at}.radius must be a positive radius (m)"
                );
                ensure!(
                    non_negative(radiance),
                    "{at}.radiance must be three non-negative numbers (W m⁻² sr⁻¹)"
                );
                Ok(())
            }
            Light::Rectangle {
                corner,
                edge_u,
                edge_v,
                radiance,
            } => {
                ensure!(
                    finite(corner) && finite(edge_u) && finite(edge_v),
                    "{at}.corner, edge_u and edge_v must be three finite numbers each (m)"
                );
                let n = cross(*edge_u, *edge_v);
                ensure!(
                    dot(n, n).sqrt() > 1e-9 * dot(*edge_u, *edge_u).max(dot(*edge_v, *edge_v)),
                    "{at}.edge_u and edge_v must be non-zero and not parallel"
                );
                ensure!(
                    non_negative(radiance),
                    "{at}.radiance must be three non-negative numbers (W m⁻² sr⁻¹)"
                );
                Ok(())
            }
        }
    }

    fn validate_point(at: &str, position: &Vec3, intensity: &[f64; 3]) -> Result<()> {
        ensure!(
            finite(position),
            "{at}.position must be three finite numbers (m)"
        );
        ensure!(
            non_negative(intensity),
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

    /// What the light sends toward `x`: exactly for a point or a spot light (no random number
    /// drawn), by one sample for an area light (two drawn); None where it sends nothing
    /// (outside a spot's cone, behind a rectangle, inside a sphere, at the light itself).
    pub fn sample<R: Rng>(&self, x: Vec3, rng: &mut R) -> Option<Incident> {
        match self {
            Light::Point { .. } | Light::Spot { .. } => self.toward(x),
            Light::Sphere {
                center,
                radius,
                radiance,
            } => sample_sphere(x, *center, *radius, radiance, [rng.random(), rng.random()]),
            Light::Rectangle {
                corner,
                edge_u,
                edge_v,
                radiance,
            } => sample_rectangle(
                x,
                (*corner, *edge_u, *edge_v),
                radiance,
                [rng.random(), rng.random()],
            ),
        }
    }

    /// What a point or spot light sends toward `x`; None where it sends nothing (outside a
    /// spot's cone, or at the light itself) and for area lights (see `sample`).
    pub fn toward(&self, x: Vec3) -> Option<Incident> {
        let (position, intensity, scale) = match self {
            Light::Point {
                position,
                intensity,
            } => (*position, *intensity, None),
            Light::Spot {
                position,
                intensity,
                direction,
                cutoff_deg,
                beam_width_deg,
            } => (
                *position,
                *intensity,
                Some((
                    *direction,
                    cutoff_deg.to_radians(),
                    beam_width_deg.to_radians(),
                )),
            ),
            Light::Sphere { .. } | Light::Rectangle { .. } => return None,
        };
        let d: Vec3 = std::array::from_fn(|k| position[k] - x[k]);
        let distance = dot(d, d).sqrt();
        if !(distance > 0.0) {
            return None;
        }
        let toward = d.map(|v| v / distance);
        let scale = scale.map_or(1.0, |(axis, cutoff, beam)| {
            spot_falloff(-dot(axis, toward), cutoff, beam)
        });
        (scale > 0.0).then(|| Incident {
            toward,
            distance,
            intensity: intensity.map(|i| i * scale),
        })
    }
}

/// A direction from x uniform in the cone the sphere (c, R) subtends, to its near side.
fn sample_sphere(x: Vec3, c: Vec3, r: f64, radiance: &[f64; 3], u: [f64; 2]) -> Option<Incident> {
    let to_c: Vec3 = std::array::from_fn(|k| c[k] - x[k]);
    let d2 = dot(to_c, to_c);
    if !(d2 > r * r) {
        return None;
    }
    let d = d2.sqrt();
    let axis = to_c.map(|v| v / d);
    let cos_max = (1.0 - r * r / d2).max(0.0).sqrt();
    let cos = 1.0 - u[0] * (1.0 - cos_max);
    let sin = (1.0 - cos * cos).max(0.0).sqrt();
    let phi = 2.0 * PI * u[1];
    let (t, b) = nephele_runtime::frame::orthonormal_basis(axis);
    let toward = normalize(std::array::from_fn(|k| {
        sin * phi.cos() * t[k] + sin * phi.sin() * b[k] + cos * axis[k]
    }));
    // The near intersection of x + s ω with the sphere.
    let distance = (d * cos - (r * r - d2 * sin * sin).max(0.0).sqrt()).max(0.0);
    let solid_angle = 2.0 * PI * (1.0 - cos_max);
    let scale = solid_angle * distance * distance;
    Some(Incident {
        toward,
        distance,
        intensity: radiance.map(|l| l * scale),
    })
}

/// A point uniform by area on the parallelogram (corner, edge_u, edge_v), seen from x.
fn sample_rectangle(
    x: Vec3,
    (corner, eu, ev): (Vec3, Vec3, Vec3),
    radiance: &[f64; 3],
    u: [f64; 2],
) -> Option<Incident> {
    let y: Vec3 = std::array::from_fn(|k| corner[k] + u[0] * eu[k] + u[1] * ev[k]);
    let d: Vec3 = std::array::from_fn(|k| y[k] - x[k]);
    let distance = dot(d, d).sqrt();
    let n = cross(eu, ev);
    let area = dot(n, n).sqrt();
    // cos θ_y: the light's normal against the direction back toward x.
    let cos_y = -dot(n, d) / (area * distance);
    if !(distance > 0.0 && cos_y > 0.0) {
        return None;
    }
    Some(Incident {
        toward: d.map(|v| v / distance),
        distance,
        intensity: radiance.map(|l| l * area * cos_y),
    })
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
