//! Opaque surfaces of the path tracer (docs/render.md, "Surfaces"): a ground plane and
//! triangle meshes read from OBJ files ([`super::mesh`]), with a diffuse (Lambertian)
//! reflectance ρ, whose BRDF is ρ/π. A surface blocks light from both sides and reflects on
//! the side a ray arrives from; its shading normal (the geometric one) faces that side.
//!
//! Its vertex counts as one scattering order in the images' order groups (an interaction, as a
//! collision in the medium is).

use super::geometry::{dot, Vec3};
use super::mesh::TriangleMesh;
use anyhow::{ensure, Result};
use serde::{Deserialize, Serialize};
use std::f64::consts::PI;
use std::path::PathBuf;

/// One surface of a scene.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(tag = "kind", rename_all = "snake_case", deny_unknown_fields)]
pub enum Surface {
    /// The horizontal plane z = `height` (m), infinite, diffuse.
    Ground {
        /// Its height (m).
        height: f64,
        /// Diffuse reflectance ρ (linear RGB, each in [0, 1]).
        reflectance: [f64; 3],
    },
    /// The triangles of a Wavefront OBJ file (m; relative paths from the scene's directory),
    /// diffuse.
    Mesh {
        /// The OBJ file.
        obj: PathBuf,
        /// Diffuse reflectance ρ (linear RGB, each in [0, 1]).
        reflectance: [f64; 3],
    },
}

/// A scene's surfaces, built (meshes read): what the path tracer intersects.
#[derive(Default)]
pub struct Surfaces(Vec<Built>);

/// One surface, built.
enum Built {
    Ground {
        height: f64,
        reflectance: [f64; 3],
    },
    Mesh {
        mesh: TriangleMesh,
        reflectance: [f64; 3],
    },
}

/// Where a ray meets a surface.
#[derive(Clone, Copy, Debug)]
pub struct Hit {
    /// Distance along the ray (m).
    pub t: f64,
    /// Unit normal on the side the ray came from.
    pub normal: Vec3,
    /// Diffuse reflectance ρ (RGB).
    pub reflectance: [f64; 3],
}

/// Hits closer than this fraction of the origin's distance from the world's origin (or than
/// this many metres near it) are the surface the ray leaves from, not a new one.
const SELF_HIT: f64 = 1e-9;

impl Surface {
    /// Checks the surface's values, naming the first bad one (`at`: its place in the scene).
    pub fn validate(&self, at: &str) -> Result<()> {
        let reflectance = match self {
            Surface::Ground {
                height,
                reflectance,
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
                    } => Built::Ground {
                        height: *height,
                        reflectance: *reflectance,
                    },
                    Surface::Mesh { obj, reflectance } => Built::Mesh {
                        mesh: TriangleMesh::load(obj)?,
                        reflectance: *reflectance,
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
        let (t, normal, reflectance) = match self {
            Built::Ground {
                height,
                reflectance,
            } => {
                let eps = SELF_HIT * dot(o, o).sqrt().max(1.0);
                let t = (height - o[2]) / w[2];
                if !(t > eps && t < t_max) {
                    return None;
                }
                (t, [0.0, 0.0, 1.0], *reflectance)
            }
            Built::Mesh { mesh, reflectance } => {
                let (t, n) = mesh.intersect(o, w, t_max)?;
                (t, n, *reflectance)
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
            reflectance,
        })
    }
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
