//! Scenes of the path tracer (JSON; examples in fit-configs/scenes/): a medium (homogeneous slab,
//! implicit cloud, voxel grid, or fog in a box or a closed mesh), its extinction scale, albedo
//! and phase function, a directional sun, an optional constant sky, lights and surfaces (the
//! path tracer only) and a pinhole camera. World units are metres, z is up. The file may also
//! carry its renderer's settings ([`RENDERER_KEYS`]), which the scene leaves unread.

use super::geometry::{cross, dot, Affine, Vec3};
use super::grid_file::{grid_warnings, read_grid, Grid};
use super::light::Light;
use super::medium::{Cloud, Ellipsoid, Fog, Medium, Slab, Voxels};
use super::mesh::TriangleMesh;
use super::surface::Surface;
use crate::phase::PhaseSpec;
use anyhow::{bail, ensure, Context, Result};
use serde::{Deserialize, Serialize};
use std::path::{Path, PathBuf};

/// Optical size σ_t × extent (mean free paths across the medium) above which a scene gets a
/// warning: 10× the largest of the shipped scenes (strato.json, 212), and well past real
/// clouds (a towering cumulus 10 km across at 0.1 /m is 1000); a σ_t per km written per
/// metre lands 1000× too high.
pub const MAX_OPTICAL_SIZE: f64 = 2000.0;

/// The largest optical size among fit-configs/scenes (strato.json: 0.05 /m × 4250 m; held to
/// it by tests/first_hour_units.rs).
pub const SHIPPED_MAX_OPTICAL_SIZE: f64 = 212.5;

/// Top-level keys of a scene file that say how to render it, not what: the path tracer's
/// settings (`render::path::Settings`), which a scene file may carry beside the scene.
pub const RENDERER_KEYS: [&str; 4] = ["spp", "time_budget_s", "sun_lobe_steps", "seed"];

/// A scene file.
#[derive(Clone, Debug, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Scene {
    /// Free text.
    #[serde(default)]
    pub description: String,
    /// The medium's shape; its density (0…1) is scaled by `sigma_t`.
    pub medium: MediumSpec,
    /// Extinction coefficient at density 1 (1/m).
    pub sigma_t: f64,
    /// Single-scattering albedo.
    #[serde(default = "one")]
    pub albedo: f64,
    /// Phase function: {"kind": "mie", "diameter_um": 10}, "hg", "hg_draine", "table".
    pub phase: PhaseSpec,
    /// The sun.
    pub sun: Sun,
    /// Constant sky radiance (linear RGB, W m⁻² sr⁻¹); none by default.
    #[serde(default)]
    pub sky: [f64; 3],
    /// Lights besides the sun and the sky (point, spot, sphere, rectangle; the path tracer
    /// only).
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub lights: Vec<Light>,
    /// Opaque surfaces (a ground plane and OBJ meshes, diffuse or mirror; the path tracer
    /// only).
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub surfaces: Vec<Surface>,
    /// The camera.
    pub camera: Camera,
    /// The renderer's keys ([`RENDERER_KEYS`]): read by the path tracer's settings, left
    /// here so that any other key is refused.
    #[serde(default, rename = "spp", skip_serializing)]
    _spp: Option<serde::de::IgnoredAny>,
    #[serde(default, rename = "time_budget_s", skip_serializing)]
    _time_budget_s: Option<serde::de::IgnoredAny>,
    #[serde(default, rename = "sun_lobe_steps", skip_serializing)]
    _sun_lobe_steps: Option<serde::de::IgnoredAny>,
    #[serde(default, rename = "seed", skip_serializing)]
    _seed: Option<serde::de::IgnoredAny>,
    /// A voxel grid's densities, read once (by the warnings or the first medium built).
    #[serde(skip)]
    grid: std::sync::OnceLock<Grid>,
}

fn one() -> f64 {
    1.0
}

/// The medium's shape.
#[derive(Clone, Debug, Serialize, Deserialize)]
#[serde(tag = "kind", rename_all = "snake_case", deny_unknown_fields)]
pub enum MediumSpec {
    /// A homogeneous slab z ∈ [0, thickness] (m), unbounded in x and y, lit face on top.
    Slab {
        /// Thickness (m).
        thickness: f64,
    },
    /// A union of ellipsoids whose boundary layer carries fBm noise (a hypertexture).
    Cloud {
        /// The ellipsoids: centre and semi-axes (m).
        blobs: Vec<Ellipsoid>,
        /// Width of the boundary layer over which the density rises from 0 to 1 (m).
        edge: f64,
        /// fBm displacement of the boundary: amplitude (m), base frequency (1/m), octaves.
        noise: NoiseSpec,
    },
    /// A voxel grid of densities: a float32 .npy [nz, ny, nx] (x fastest) over the box
    /// [origin, origin + size] (m), or over the unit cube mapped to the world by `to_world`,
    /// trilinear between voxel centres (as Mitsuba's gridvolume).
    Voxels {
        /// The .npy (relative paths are taken from the scene file's directory).
        npy: PathBuf,
        /// The box's lowest corner (m).
        #[serde(default, skip_serializing_if = "Option::is_none")]
        origin: Option<Vec3>,
        /// The box's extent (m).
        #[serde(default, skip_serializing_if = "Option::is_none")]
        size: Option<Vec3>,
        /// Instead of origin and size: the affine map of the unit cube [0, 1]³ to the world, a
        /// 4 × 4 matrix by rows (the last row 0 0 0 1), as Mitsuba's gridvolume `to_world`.
        #[serde(default, skip_serializing_if = "Option::is_none")]
        to_world: Option<[[f64; 4]; 4]>,
    },
    /// Fog filling the box [min, max] (m) or a closed mesh: homogeneous, or thinning with
    /// height as exp(−(z − floor)/scale_height) (σ_t at the floor). Make the box as large as
    /// the scene for a global fog.
    Fog {
        /// The box's lowest corner (m).
        #[serde(default, skip_serializing_if = "Option::is_none")]
        min: Option<Vec3>,
        /// The box's highest corner (m).
        #[serde(default, skip_serializing_if = "Option::is_none")]
        max: Option<Vec3>,
        /// Instead of the box: a closed triangle mesh (Wavefront OBJ, m; relative paths from
        /// the scene's directory) holding the fog.
        #[serde(default, skip_serializing_if = "Option::is_none")]
        mesh: Option<PathBuf>,
        /// Scale height of the density (m, from the box's or the mesh's floor); none:
        /// homogeneous.
        #[serde(default, skip_serializing_if = "Option::is_none")]
        scale_height: Option<f64>,
    },
}

/// fBm displacement of a cloud's boundary.
#[derive(Clone, Copy, Debug, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct NoiseSpec {
    /// Amplitude (m).
    pub amplitude: f64,
    /// Base frequency (1/m).
    pub frequency: f64,
    /// Octaves (1…10).
    pub octaves: usize,
    /// Seed of the noise (the cloud's shape; independent of the render's seed).
    #[serde(default = "one_u32")]
    pub seed: u32,
}

fn one_u32() -> u32 {
    1
}

/// A directional sun.
#[derive(Clone, Copy, Debug, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Sun {
    /// Direction toward the sun (normalised on load).
    pub direction: Vec3,
    /// Irradiance on a surface facing it (linear RGB, W/m²).
    pub irradiance: [f64; 3],
}

/// A pinhole camera.
#[derive(Clone, Copy, Debug, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Camera {
    /// Eye position (m).
    pub position: Vec3,
    /// Point looked at (m).
    pub look_at: Vec3,
    /// Up vector (default +z).
    #[serde(default = "up")]
    pub up: Vec3,
    /// Vertical field of view (degrees).
    pub fov_deg: f64,
    /// Image width and height (pixels).
    pub width: u32,
    /// See `width`.
    pub height: u32,
}

fn up() -> Vec3 {
    [0.0, 0.0, 1.0]
}

fn finite(v: &[f64]) -> bool {
    v.iter().all(|x| x.is_finite())
}

fn norm(v: Vec3) -> f64 {
    dot(v, v).sqrt()
}

impl Scene {
    /// Reads and validates a scene file.
    pub fn load(path: &Path) -> Result<Self> {
        let text = std::fs::read_to_string(path)
            .with_context(|| format!("cannot read scene '{}'", path.display()))?;
        let mut scene =
            Self::parse(&text).with_context(|| format!("scene '{}'", path.display()))?;
        let dir = path.parent().unwrap_or(Path::new("."));
        let from_scene = |file: &mut PathBuf| {
            if file.is_relative() {
                *file = dir.join(&*file);
            }
        };
        match &mut scene.medium {
            MediumSpec::Voxels { npy, .. } => from_scene(npy),
            MediumSpec::Fog {
                mesh: Some(obj), ..
            } => from_scene(obj),
            _ => {}
        }
        for s in &mut scene.surfaces {
            if let Surface::Mesh { obj, .. } = s {
                from_scene(obj);
            }
        }
        Ok(scene)
    }

    /// Parses and validates scene JSON.
    pub fn parse(text: &str) -> Result<Self> {
        let mut s: Scene = serde_json::from_str(text)?;
        s.validate()?;
        let n = norm(s.sun.direction);
        s.sun.direction = s.sun.direction.map(|x| x / n);
        s.lights = s.lights.into_iter().map(Light::normalised).collect();
        Ok(s)
    }

    /// Checks every value, naming the first bad one.
    pub fn validate(&self) -> Result<()> {
        ensure!(
            self.sigma_t > 0.0 && self.sigma_t.is_finite(),
            "sigma_t must be a positive extinction (1/m)"
        );
        ensure!(
            (0.0..=1.0).contains(&self.albedo),
            "albedo must be in [0, 1]"
        );
        ensure!(
            finite(&self.sun.direction) && norm(self.sun.direction) > 0.0,
            "sun.direction must be a non-zero vector"
        );
        ensure!(
            self.sun
                .irradiance
                .iter()
                .all(|&e| e >= 0.0 && e.is_finite()),
            "sun.irradiance must be three non-negative numbers"
        );
        ensure!(
            self.sky.iter().all(|&e| e >= 0.0 && e.is_finite()),
            "sky must be three non-negative numbers"
        );
        for (i, light) in self.lights.iter().enumerate() {
            light.validate(&format!("lights[{i}]"))?;
        }
        for (i, surface) in self.surfaces.iter().enumerate() {
            surface.validate(&format!("surfaces[{i}]"))?;
        }
        let c = &self.camera;
        ensure!(
            finite(&c.position) && finite(&c.look_at) && finite(&c.up),
            "camera vectors must be finite"
        );
        let fwd = [
            c.look_at[0] - c.position[0],
            c.look_at[1] - c.position[1],
            c.look_at[2] - c.position[2],
        ];
        ensure!(
            norm(fwd) > 0.0 && norm(cross(fwd, c.up)) > 1e-9 * norm(fwd) * norm(c.up),
            "camera.look_at must differ from camera.position and not lie along camera.up"
        );
        ensure!(
            c.fov_deg > 0.0 && c.fov_deg < 179.0,
            "camera.fov_deg must be in (0, 179)"
        );
        ensure!(
            (1..=16384).contains(&c.width) && (1..=16384).contains(&c.height),
            "camera.width and camera.height must be 1…16384 pixels"
        );
        self.phase.validate()?;
        match &self.medium {
            MediumSpec::Slab { thickness } => ensure!(
                *thickness > 0.0 && thickness.is_finite(),
                "medium.thickness must be positive (m)"
            ),
            MediumSpec::Cloud { blobs, edge, noise } => {
                ensure!(
                    !blobs.is_empty(),
                    "medium.blobs must hold at least one ellipsoid"
                );
                for (i, b) in blobs.iter().enumerate() {
                    ensure!(
                        finite(&b.center),
                        "medium.blobs[{i}].center must be three finite numbers (m)"
                    );
                    ensure!(
                        b.radii.iter().all(|&r| r > 0.0 && r.is_finite()),
                        "medium.blobs[{i}].radii must be three positive numbers (m)"
                    );
                }
                ensure!(
                    *edge > 0.0 && edge.is_finite(),
                    "medium.edge must be positive (m)"
                );
                ensure!(
                    noise.amplitude >= 0.0
                        && noise.amplitude.is_finite()
                        && noise.frequency > 0.0
                        && noise.frequency.is_finite()
                        && (1..=10).contains(&noise.octaves),
                    "medium.noise: amplitude ≥ 0, frequency > 0, octaves 1…10"
                );
            }
            MediumSpec::Voxels { .. } => {
                self.voxel_transform()?;
            }
            MediumSpec::Fog {
                min,
                max,
                mesh,
                scale_height,
            } => {
                match (min, max, mesh) {
                    (Some(min), Some(max), None) => ensure!(
                        finite(min) && finite(max) && (0..3).all(|k| min[k] < max[k]),
                        "medium.min and medium.max must be finite corners with min < max on \
                         every axis (m)"
                    ),
                    (None, None, Some(_)) => {}
                    _ => bail!("medium: give either min and max (a box), or mesh, for fog"),
                }
                if let Some(h) = scale_height {
                    ensure!(
                        *h > 0.0 && h.is_finite(),
                        "medium.scale_height must be a positive height (m)"
                    );
                }
            }
        }
        Ok(())
    }

    /// Legal but implausible values, one sentence each naming the units (the caller prints
    /// them as warnings; the scene still renders): an optical size far beyond any cloud's (a
    /// σ_t per km written per metre, a voxel grid's densities far above 1), voxels stretched
    /// as by swapped axes, a sun below the horizon.
    pub fn warnings(&self) -> Vec<String> {
        let mut w = Vec::new();
        let (extent, tau) = (self.extent_m(), self.optical_size());
        let voxels = matches!(self.medium, MediumSpec::Voxels { .. });
        if voxels {
            // The grid's own densities say how thick it is, not the box at density 1.
            w.extend(self.voxel_warnings());
        } else if tau > MAX_OPTICAL_SIZE {
            w.push(format!(
                "σ_t is per metre: sigma_t = {} /m over the medium's {extent:.0} m is {tau:.0} mean \
                 free paths (real clouds: up to a few hundred; the shipped scenes at most {:.0}) \
                 — did you mean {} /km, sigma_t = {}?",
                self.sigma_t,
                SHIPPED_MAX_OPTICAL_SIZE,
                self.sigma_t,
                self.sigma_t / 1e3
            ));
        }
        let z = self.sun.direction[2] / norm(self.sun.direction);
        if z < 0.0 {
            w.push(format!(
                "the sun is {:.0}° below the horizon (sun.direction z = {z:.2}; z is up): with \
                 no ground in the scene it lights the medium from below; make z positive for a \
                 sun in the sky",
                -z.asin().to_degrees()
            ));
        }
        w
    }

    /// σ_t × the medium's largest extent: mean free paths across it at density 1.
    pub fn optical_size(&self) -> f64 {
        self.sigma_t * self.extent_m()
    }

    /// The medium's largest extent (m): a slab's thickness, the largest side of the blobs' or
    /// the voxel box's bounding box.
    fn extent_m(&self) -> f64 {
        match &self.medium {
            MediumSpec::Slab { thickness } => *thickness,
            MediumSpec::Cloud { blobs, .. } => (0..3)
                .map(|i| {
                    let lo = blobs.iter().map(|b| b.center[i] - b.radii[i]);
                    let hi = blobs.iter().map(|b| b.center[i] + b.radii[i]);
                    hi.fold(f64::MIN, f64::max) - lo.fold(f64::MAX, f64::min)
                })
                .fold(0.0, f64::max),
            MediumSpec::Voxels { size, to_world, .. } => match (size, to_world) {
                (Some(size), _) => size.iter().copied().fold(0.0, f64::max),
                // The unit cube's image: its bounding box side along world axis r.
                (None, Some(m)) => (0..3)
                    .map(|r| m[r][..3].iter().map(|v| v.abs()).sum::<f64>())
                    .fold(0.0, f64::max),
                (None, None) => 0.0,
            },
            // A mesh's size is known once it is read: no warning from it.
            MediumSpec::Fog { min, max, .. } => match (min, max) {
                (Some(min), Some(max)) => (0..3).map(|k| max[k] - min[k]).fold(0.0, f64::max),
                _ => 0.0,
            },
        }
    }

    /// A voxel grid's densities, read on first use (refused when larger than the memory
    /// available).
    fn voxel_grid(&self) -> Result<Grid> {
        let MediumSpec::Voxels { npy, .. } = &self.medium else {
            bail!("not a voxel grid");
        };
        if let Some(g) = self.grid.get() {
            return Ok(g.clone());
        }
        let g = read_grid(npy, crate::io::available_memory())?;
        Ok(self.grid.get_or_init(|| g).clone())
    }

    /// A voxel grid's own warnings: its thickest column, its voxels' shape (none when the grid
    /// cannot be read: building the medium says why).
    fn voxel_warnings(&self) -> Vec<String> {
        let (Ok(grid), Ok(m)) = (self.voxel_grid(), self.voxel_transform()) else {
            return Vec::new();
        };
        let voxel_m = std::array::from_fn(|k| m.axis_length(k) / grid.n[k] as f64);
        grid_warnings(&grid, voxel_m, self.sigma_t, MAX_OPTICAL_SIZE)
    }

    /// A voxel grid's map of the unit cube to the world, from origin and size or to_world.
    fn voxel_transform(&self) -> Result<Affine> {
        let MediumSpec::Voxels {
            origin,
            size,
            to_world,
            ..
        } = &self.medium
        else {
            bail!("not a voxel grid");
        };
        match (origin, size, to_world) {
            (Some(origin), Some(size), None) => {
                ensure!(
                    finite(origin) && size.iter().all(|&x| x > 0.0 && x.is_finite()),
                    "medium.origin must be finite and medium.size positive (m)"
                );
                Ok(Affine::from_box(*origin, *size))
            }
            (None, None, Some(m)) => {
                ensure!(
                    m.iter().flatten().all(|x| x.is_finite()) && m[3] == [0.0, 0.0, 0.0, 1.0],
                    "medium.to_world must be a finite 4 × 4 affine matrix (last row 0 0 0 1)"
                );
                Affine::new(
                    std::array::from_fn(|r| [m[r][0], m[r][1], m[r][2]]),
                    [m[0][3], m[1][3], m[2][3]],
                )
                .context("medium.to_world must be invertible")
            }
            _ => bail!("medium: give either origin and size, or to_world, for a voxel grid"),
        }
    }

    /// The medium, σ_t included (a voxel grid is read here).
    pub fn build_medium(&self) -> Result<Box<dyn Medium>> {
        Ok(match &self.medium {
            MediumSpec::Slab { thickness } => Box::new(Slab {
                h: *thickness,
                sigma_t: self.sigma_t,
            }),
            MediumSpec::Voxels { .. } => {
                let grid = self.voxel_grid()?;
                let to_world = self.voxel_transform()?;
                Box::new(Voxels::with_transform(
                    grid.data.clone(),
                    grid.n,
                    to_world,
                    self.sigma_t,
                ))
            }
            MediumSpec::Cloud { blobs, edge, noise } => Box::new(Cloud::new(
                blobs.clone(),
                *edge,
                (noise.amplitude, noise.frequency, noise.octaves),
                self.sigma_t,
                noise.seed,
            )),
            MediumSpec::Fog {
                min,
                max,
                mesh,
                scale_height,
            } => match (min, max, mesh) {
                (Some(min), Some(max), None) => {
                    Box::new(Fog::new(*min, *max, self.sigma_t, *scale_height))
                }
                (None, None, Some(obj)) => {
                    let mesh = TriangleMesh::load(obj)?;
                    ensure!(
                        mesh.open_edges() == 0,
                        "mesh '{}' is not closed: {} edges do not belong to exactly two faces \
                         (fog fills the inside of a closed surface)",
                        obj.display(),
                        mesh.open_edges()
                    );
                    Box::new(Fog::in_mesh(mesh, self.sigma_t, *scale_height))
                }
                _ => bail!("medium: give either min and max (a box), or mesh, for fog"),
            },
        })
    }
}
