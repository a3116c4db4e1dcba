//! Opaque surfaces of the path tracer (docs/render.md, "Surfaces"): a ground plane and
//! triangle meshes read from OBJ files ([`super::mesh`]), diffuse (Lambertian: BRDF ρ/π) or
//! a mirror (reflectance ρ along ω_r = ω − 2 (ω · n) n). A surface blocks light from both
//! sides and reflects on the side a ray arrives from; its shading normal (the geometric one)
//! faces that side.
//!
//! Its vertex counts as one scattering order in the images' order groups (an interaction, as a
//! collision in the medium is).

use super::geometry::{dot, self_hit_distance, Vec3};
use super::mesh::TriangleMesh;
use anyhow::{ensure, Result};
use serde::{Deserialize, Serialize};
use std::f64::consts::PI;
use std::path::PathBuf;

/// How a surface reflects.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum Material {
    /// Lambertian: ρ/π in every direction.
    #[default]
    Diffuse,
    /// A perfect mirror of reflectance ρ (Mitsuba 3's `conductor` with `material: none`).
    Mirror,
}

/// One surface of a scene.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(tag = "kind", rename_all = "snake_case", deny_unknown_fields)]
pub enum Surface {
    /// The horizontal plane z = `height` (m), infinite.
    Ground {
        /// Its height (m).
        height: f64,
        /// Reflectance ρ (linear RGB, each in [0, 1]).
        reflectance: [f64; 3],
        /// Diffuse (default) or mirror.
        #[serde(default)]
        material: Material,
    },
    /// The triangles of a Wavefront OBJ file (m; relative paths from the scene's directory).
    Mesh {
        /// The OBJ file.
        obj: PathBuf,
        /// Reflectance ρ (linear RGB, each in [0, 1]).
        reflectance: [f64; 3],
        /// Diffuse (default) or mirror.
        #[serde(default)]
        material: Material,
    },
}

/// A scene's surfaces, built (meshes read): what the path tracer intersects.
#[derive(Default)]
pub struct Surfaces(Vec<Built>);

/// One surface, built.
enum Built {
    Ground { height: f64, look: Look },
    Mesh { mesh: TriangleMesh, look: Look },
}

/// What a surface looks like: its reflectance and material.
#[derive(Clone, Copy, Debug)]
struct Look {
    reflectance: [f64; 3],
    material: Material,
}

/// Where a ray meets a surface.
#[derive(Clone, Copy, Debug)]
pub struct Hit {
    /// Distance along the ray (m).
    pub t: f64,
    /// Unit normal on the side the ray came from.
    pub normal: Vec3,
    /// Reflectance ρ (RGB).
    pub reflectance: [f64; 3],
    /// Diffuse or mirror.
    pub material: Material,
}

impl Surface {
    /// Checks the surface's values, naming the first bad one (`at`: its place in the scene).
    pub fn validate(&self, at: &str) -> Result<()> {
        let reflectance = match self {
            Surface::Ground {
                height,
                reflectance,
                ..
            } => {
                ensure!(
                    height.is_finite(),
                    "{at}.height must be a finite height (m)"
                );
                reflectance
            }
            Surface::Mesh { reflectance, .. } => reflectance,
        };
        ensure!(
            reflectance.iter().all(|r| (0.0..=1.0).contains(r)),
            "{at}.reflectance must be three numbers in [0, 1]"
        );
        Ok(())
    }
}

impl Surfaces {
    /// No surface at all.
    pub const NONE: Surfaces = Surfaces(Vec::new());

    /// The surfaces of `specs`, their meshes read.
    pub fn build(specs: &[Surface]) -> Result<Self> {
        let built = specs
            .iter()
            .map(|s| {
                Ok(match s {
                    Surface::Ground {
                        height,
                        reflectance,
                        material,
                    } => Built::Ground {
                        height: *height,
                        look: Look {
                            reflectance: *reflectance,
                            material: *material,
                        },
                    },
                    Surface::Mesh {
                        obj,
                        reflectance,
                        material,
                    } => Built::Mesh {
                        mesh: TriangleMesh::load(obj)?,
                        look: Look {
                            reflectance: *reflectance,
                            material: *material,
                        },
                    },
                })
            })
            .collect::<Result<_>>()?;
        Ok(Self(built))
    }

    /// The nearest hit of o + t w with t in (ε, t_max).
    pub fn nearest(&self, o: Vec3, w: Vec3, t_max: f64) -> Option<Hit> {
        let mut best: Option<Hit> = None;
        for s in &self.0 {
            let reach = best.map_or(t_max, |h| h.t);
            if let Some(h) = s.intersect(o, w, reach) {
                best = Some(h);
            }
        }
        best
    }
}

impl Built {
    /// The first hit of o + t w with t in (ε, t_max), its normal turned toward the ray's origin.
    fn intersect(&self, o: Vec3, w: Vec3, t_max: f64) -> Option<Hit> {
        let (t, normal, look) = match self {
            Built::Ground { height, look } => {
                let eps = self_hit_distance(o);
                let t = (height - o[2]) / w[2];
                if !(t > eps && t < t_max) {
                    return None;
                }
                (t, [0.0, 0.0, 1.0], *look)
            }
            Built::Mesh { mesh, look } => {
                let (t, n) = mesh.intersect(o, w, t_max)?;
                (t, n, *look)
            }
        };
        let normal = if dot(normal, w) > 0.0 {
            normal.map(|x| -x)
        } else {
            normal
        };
        Some(Hit {
            t,
            normal,
            reflectance: look.reflectance,
            material: look.material,
        })
    }
}

/// The mirror direction of `w` (arriving) about the unit normal `n`: w − 2 (w · n) n.
pub fn reflect(w: Vec3, n: Vec3) -> Vec3 {
    let d = 2.0 * dot(w, n);
    std::array::from_fn(|k| w[k] - d * n[k])
}

/// The Lambertian BRDF ρ/π of channel k.
pub fn brdf(hit: &Hit, k: usize) -> f64 {
    hit.reflectance[k] / PI
}

/// A direction about `n` with density cos θ / π (Malley's method: a uniform point on the unit
/// disc lifted to the hemisphere), from two uniform numbers.
pub fn sample_cosine(n: Vec3, u1: f64, u2: f64) -> Vec3 {
    let r = u1.sqrt();
    let phi = 2.0 * PI * u2;
    let (x, y) = (r * phi.cos(), r * phi.sin());
    let z = (1.0 - u1).max(0.0).sqrt();
    let (t, b) = nephele_runtime::frame::orthonormal_basis(n);
    std::array::from_fn(|k| x * t[k] + y * b[k] + z * n[k])
}
