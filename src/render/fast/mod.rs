//! The fast renderers (docs/collector.md): the collector renderer of Bouthors et al. 2008
//! (§§6–7, orders ≥ 2 from the compressed slab tables through nephele-runtime's collector
//! search), and two baselines rendered the same way — single scattering only, and the
//! multi-octave approximation of real-time engines (Wrenninge et al. 2013; Hillaire 2016).
//!
//! Per pixel, one ray through the pixel's centre (or an n × n grid of them) is marched through
//! the medium ([`substeps`], [`view_ray`]) in sub-steps of length h with extinction σ, view
//! transmittance T_v, and the sun's optical depth τ_sun from the light-space map, linear over
//! a sub-step (τ_a → τ_b):
//!
//! - opacity α = 1 − T_v at the end of the ray;
//! - order 1: L₁ = ϖ p(θ) E_sun I₀ with I_a = ∫ σ T_v e^{−a τ_sun} ds, in closed form per
//!   sub-step: σ T_v(s₀) e^{−a τ_a} (1 − e^{−(σ + a k) h}) / (σ + a k), k = (τ_b − τ_a)/h
//!   (θ is the same along the ray: p is evaluated once, per RGB channel);
//! - orders ≥ 2 (collector): the surface point p is where the ray first crosses the lit
//!   surface's iso-level ρ₀ (interpolated between sub-steps; where it never does, the sub-step
//!   of largest σ); per group g the collector search gives T_g, and L_g = α T_g E_sun;
//! - octaves: L ≈ Σ_{i<N} bⁱ ϖ p(θ; cⁱ g) E_sun I_{aⁱ} — octave 0 is order 1 exactly (the true
//!   p), octaves i ≥ 1 use Henyey–Greenstein at cⁱ g, g the phase function's mean cosine; their
//!   sum is written as the group of order 2 (the octaves do not split orders);
//! - sky: the sky seen through 1 − α (`unscattered`), and the sky term of [`sky`] for
//!   the scattered orders (α S_g L_sky per group), order 1 marched through maps toward the sky
//!   ([`sky_order1`]; from the table for a slab), reported apart in render.json;
//! - the march stops where T_v < 10⁻⁴ (what lies behind adds < 10⁻⁴ of the pixel).
//!
//! Files: this one holds the options and prepares a scene for any number of views; `frame.rs`
//! renders a view's pixels (one ray's order 1 and the baselines); [`view_ray`] marches a view
//! ray, [`collector`] is the collector's branch with its search statistics, [`table_check`]
//! checks the tables against the scene; the sun's side of the scene
//! ([`sun_side`](mod@sun_side)) comes from light-space maps ([`light_map`]), the sky term from
//! [`sky`] and [`sky_order1`], the octave baseline from [`octaves`]. The camera, the image and
//! its regions are the floor's (`render::{camera, image, regions}`), shared with the path
//! tracer.

pub mod collector;
mod frame;
pub mod light_map;
pub mod octaves;
pub mod orbit;
pub mod rays;
pub mod sky;
pub mod sky_order1;
pub mod substeps;
pub mod sun_side;
pub mod table_check;
pub mod view_ray;

use super::camera::Pinhole;
use super::image::Rendered;
use super::medium::Medium;
use super::scene::{Camera, Scene};
use crate::phase::Phase;
use anyhow::{ensure, Result};
pub use collector::{Finite, GroupStats};
use frame::Frame;
use light_map::MapOptions;
use nephele_runtime::transport::{FiniteCloud, SearchOptions, TransportTables, Viewpoint};
pub use octaves::{Octaves, MAX_OCTAVES};
pub use rays::RayPattern;
use serde::Serialize;
use sky::SkyTable;
use sky_order1::SkyOrder1;
use std::sync::atomic::{AtomicUsize, Ordering};
use std::time::Instant;
use sun_side::sun_side;
pub use sun_side::SunSide;
use table_check::{check_droplets, check_tables, mean_cosine};

/// How a frame is rendered.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize)]
#[serde(rename_all = "snake_case")]
pub enum Method {
    /// The Monte Carlo path tracer (the reference).
    PathTracer,
    /// The collector renderer: orders ≥ 2 from the transport tables.
    Collector,
    /// Order 1 only (plus the sky term).
    Single,
    /// The multi-octave approximation of real-time engines.
    Octaves,
}

/// Settings of the fast renderers.
#[derive(Clone, Copy, Debug, Serialize)]
pub struct FastOptions {
    /// Method (not the path tracer).
    pub method: Method,
    /// Light-map texels per side (a power of two, 16…4096).
    pub map_resolution: usize,
    /// Depth planes of the sun's optical-depth map.
    pub planes: usize,
    /// March sub-step (m); None: half a mean free path at density 1.
    pub step: Option<f64>,
    /// ρ₀: the lit surface is where σ_t = ρ₀ σ_t,scene.
    pub surface_density: f64,
    /// Rays per pixel: an n × n grid (the collector searches once per pixel unless
    /// `search_every_ray`), or n of its cells with `pattern` [`RayPattern::Rooks`].
    pub rays: u32,
    /// Where a pixel's rays go.
    pub pattern: RayPattern,
    /// The collector searches once per block of this many × this many pixels, at the most
    /// opaque ray of the block, each pixel weighing the found light by its own opacity (1:
    /// once per pixel).
    pub search_block: u32,
    /// A block shares its search only where each of its pixels is at least this opaque (the
    /// interior, as [`crate::render::regions`] names it); the pixels of other blocks search
    /// alone (0: every block shares).
    pub search_block_opacity: f64,
    /// The collector searches on every ray of a pixel, not once per pixel (an ablation).
    pub search_every_ray: bool,
    /// The collector search is not told p's depth to the sun (an ablation: the local slab
    /// is not cut to it).
    pub no_sun_depth: bool,
    /// Each group's search reads p's own depth to the sun, not that depth averaged across the
    /// light over the group's spread (an ablation; docs/collector.md, "The sun's depth,
    /// spread across the light").
    pub no_sun_spread: bool,
    /// Collector search settings (the sun's spread set by [`prepare`] from the tables).
    #[serde(skip)]
    pub search: SearchOptions,
    /// Octave baseline settings.
    pub octaves: Octaves,
    /// Use the tables even where the scene's phase function or albedo differs (a warning).
    pub allow_mismatch: bool,
    /// The Mie droplet diameter (µm) the tables were made for, when known
    /// ([`crate::io::tables::mie_diameter`]): a scene of droplets more than 10 % apart is
    /// refused before its own Mie table is computed.
    pub tables_diameter_um: Option<f64>,
    /// An ablation: the local slabs' thickness times this factor (1: the method as is).
    pub thickness_scale: f64,
    /// The collector's finite-cloud correction.
    pub finite: Finite,
    /// Texels per side (and depth planes) of each map toward the sky, for the sky's order 1
    /// marched (a power of two, 16…1024); 0: order 1 from the view ray's face-on slab (an
    /// ablation; docs/collector.md, "Sky").
    pub sky_map_resolution: usize,
}

impl Default for FastOptions {
    fn default() -> Self {
        Self {
            method: Method::Collector,
            map_resolution: 256,
            planes: 256,
            step: None,
            surface_density: 0.5,
            rays: 2,
            pattern: RayPattern::Grid,
            search_block: 1,
            search_block_opacity: crate::render::regions::OPAQUE,
            search_every_ray: false,
            no_sun_depth: false,
            no_sun_spread: false,
            search: SearchOptions::default(),
            octaves: Octaves::default(),
            allow_mismatch: false,
            tables_diameter_um: None,
            thickness_scale: 1.0,
            finite: Finite::default(),
            sky_map_resolution: sky_order1::MAP_RESOLUTION,
        }
    }
}

impl FastOptions {
    /// The light maps' settings for a march sub-step, a surface extinction and the transport
    /// mean free path 1/((1 − g) σ_t) (m).
    fn maps(&self, step: f64, threshold: f64, transport_mfp: f64) -> MapOptions {
        MapOptions {
            resolution: self.map_resolution,
            planes: self.planes,
            step,
            threshold,
            sections: if self.finite.leakage {
                self.finite.sections
            } else {
                0
            },
            section_depth: transport_mfp,
            surface_section: self.finite.leakage && self.finite.surface,
        }
    }

    /// Checks the settings.
    pub fn validate(&self) -> Result<()> {
        ensure!(
            self.method != Method::PathTracer,
            "the fast renderers do not trace paths"
        );
        ensure!(
            self.map_resolution.is_power_of_two() && (16..=4096).contains(&self.map_resolution),
            "map resolution must be a power of two, 16…4096"
        );
        let sky = self.sky_map_resolution;
        ensure!(
            sky == 0 || (sky.is_power_of_two() && (16..=1024).contains(&sky)),
            "sky map resolution {sky}: it must be 0 (order 1 from the slab) or a power of two, \
             16…1024"
        );
        ensure!(
            (8..=4096).contains(&self.planes),
            "depth planes must be 8…4096"
        );
        if let Some(h) = self.step {
            ensure!(h > 0.0 && h.is_finite(), "march step must be positive (m)");
        }
        ensure!(
            self.surface_density > 0.0 && self.surface_density.is_finite(),
            "surface density ρ₀ must be positive"
        );
        ensure!(
            (1..=8).contains(&self.rays),
            "rays per pixel side must be 1…8"
        );
        ensure!(
            (1..=16).contains(&self.search_block),
            "search blocks must be 1…16 pixels a side"
        );
        ensure!(
            !(self.search_every_ray && self.pattern.corners()),
            "--search-every-ray searches on a pixel's own rays; the quincunx shares its corner \
             rays among pixels: use the grid or the rooks"
        );
        ensure!(
            (0.0..=1.0).contains(&self.search_block_opacity),
            "--search-block-opacity must be in [0, 1]"
        );
        ensure!(
            self.search_block == 1 || !self.search_every_ray,
            "--search-block shares one search among a block's pixels; --search-every-ray \
             searches on every ray: choose one"
        );
        ensure!(
            (1..=64).contains(&self.search.max_reads),
            "search iterations must be 1…64"
        );
        let f = &self.finite;
        ensure!(
            f.rate_scale >= 0.0 && f.rate_scale.is_finite(),
            "the leakage scale must be ≥ 0"
        );
        ensure!(
            f.delay_scale >= 0.0 && f.delay_scale.is_finite(),
            "the leakage delay must be ≥ 0"
        );
        let o = &self.octaves;
        ensure!(
            (1..=MAX_OCTAVES).contains(&o.n),
            "octaves N must be 1…{MAX_OCTAVES}"
        );
        ensure!(
            [o.a, o.b, o.c].iter().all(|x| (0.0..=1.0).contains(x)),
            "octave factors a, b, c must be in [0, 1]"
        );
        Ok(())
    }
}

/// A scene prepared for the fast renderers: the medium, the phase functions, the light-space
/// maps and the sky table — everything that depends on the cloud and the sun, not on the
/// camera. Built once ([`prepare`]), it renders any number of views ([`Prepared::render`]).
pub struct Prepared<'a> {
    frame: Frame<'a>,
    warnings: Vec<String>,
    /// Seconds: the medium, the phase functions and the table check; the maps; the sky table;
    /// the maps toward the sky.
    setup: f64,
    maps: f64,
    sky: f64,
    sky_maps: f64,
    /// Views rendered so far (the first one is charged the maps and the sky table).
    views: AtomicUsize,
}

/// Prepares `scene` for the fast method of `opts` with `tables`.
pub fn prepare<'a>(
    scene: &'a Scene,
    tables: &'a TransportTables<'a>,
    opts: &FastOptions,
) -> Result<Prepared<'a>> {
    opts.validate()?;
    ensure!(
        scene.lights.is_empty(),
        "the fast renderers take the sun and the sky only: this scene has {} point, spot \
         or area light(s) (render it with --method path-tracer)",
        scene.lights.len()
    );
    ensure!(
        scene.surfaces.is_empty(),
        "the fast renderers draw a medium alone: this scene has {} surface(s) (render it with \
         --method path-tracer)",
        scene.surfaces.len()
    );
    check_droplets(scene, opts)?;
    let t_start = Instant::now();
    let medium = scene.build_medium()?;
    let phases = Phase::build_channels(&scene.phase)?;
    let g = mean_cosine(&phases);
    let mut warnings = Vec::new();
    check_tables(scene, tables, (&phases, g), opts, &mut warnings)?;
    let setup = t_start.elapsed().as_secs_f64();
    let step = opts.step.unwrap_or(0.5 / scene.sigma_t);
    let threshold = opts.surface_density * scene.sigma_t;
    let t0 = Instant::now();
    let side = sun_side(
        scene,
        medium.as_ref(),
        &opts.maps(step, threshold, transport_mfp(scene, g)),
        opts.thickness_scale,
    )?;
    let maps = t0.elapsed().as_secs_f64();
    let t0 = Instant::now();
    let has_sky = scene.sky.iter().any(|&s| s > 0.0);
    let sky = has_sky.then(|| SkyTable::build(tables));
    let sky_seconds = t0.elapsed().as_secs_f64();
    let t0 = Instant::now();
    let sky_order1 = (has_sky && opts.sky_map_resolution > 0)
        .then(|| sky_order1(medium.as_ref(), &phases, opts, step, threshold))
        .flatten();
    let sky_maps = t0.elapsed().as_secs_f64();
    let finite = opts.finite.runtime(tables, scene.albedo);
    let mut opts = *opts;
    opts.search.sun_spread =
        (!opts.no_sun_spread && !opts.no_sun_depth).then_some(finite.mean_cosine);
    let frame = Frame {
        scene,
        medium,
        side,
        tables,
        sky,
        sky_order1,
        opts,
        step,
        threshold,
        phases,
        g,
        finite,
        offsets: opts.pattern.offsets(opts.rays as usize),
    };
    Ok(Prepared {
        frame,
        warnings,
        setup,
        maps,
        sky: sky_seconds,
        sky_maps,
        views: AtomicUsize::new(0),
    })
}

impl Prepared<'_> {
    /// Seconds it took: the medium (its majorant grid), the phase functions and the table
    /// check; the light maps; the sky table and the maps toward the sky.
    pub fn seconds(&self) -> (f64, f64, f64) {
        (self.setup, self.maps, self.sky + self.sky_maps)
    }

    /// Renders the view of `camera`; `progress(fraction)` as rows finish. The first view's
    /// frame time includes building the maps and the sky table; later views reuse them
    /// (render.json: `maps_reused`). The pixels do not depend on which view came first.
    pub fn render(&self, camera: &Camera, progress: &(dyn Fn(f64) + Sync)) -> Rendered {
        let first = self.views.fetch_add(1, Ordering::Relaxed) == 0;
        let opts = &self.frame.opts;
        let t0 = Instant::now();
        let (image, stats, sky_share) = self.frame.pixels(&Pinhole::new(camera), progress);
        let mut warnings = self.warnings.clone();
        warnings.extend(collector::held_warnings(
            &stats,
            &self.frame.tables.domain(),
        ));
        let t_pixels = t0.elapsed().as_secs_f64();
        let shared = if first {
            self.maps + self.sky + self.sky_maps
        } else {
            0.0
        };
        let seconds = shared + t_pixels;
        let mut r = image;
        r.seconds = seconds;
        r.details = serde_json::json!({
            "method": opts.method,
            "correction": opts.finite.name()
                + if opts.no_sun_depth {
                    ", slab not cut to the sun's depth"
                } else if opts.no_sun_spread {
                    ", the sun's depth not spread"
                } else {
                    ""
                },
            "options": opts,
            "search": {
                "max_reads": opts.search.max_reads,
                "tolerance": opts.search.tolerance,
                "step_clamp": opts.search.step_clamp,
                "filter": opts.search.filter,
                "sun_spread_mean_cosine": opts.search.sun_spread,
            },
            "march_step_m": self.frame.step,
            "surface_sigma_t": self.frame.threshold,
            "mean_cosine_g": self.frame.g,
            "seconds_per_stage": {
                "setup_medium_phase_tables": self.setup,
                "light_maps": self.maps,
                "sky_table": self.sky,
                "sky_maps": self.sky_maps,
                "pixels": t_pixels,
                "frame": seconds,
            },
            "maps_reused": !first,
            "groups": stats,
            "sky_term_share_of_scattered_light": sky_share,
            "warnings": warnings,
        });
        r
    }
}

/// Renders `scene` with a fast method; `progress(fraction)` as rows finish.
pub fn render_fast(
    scene: &Scene,
    tables: &TransportTables,
    opts: &FastOptions,
    progress: &(dyn Fn(f64) + Sync),
) -> Result<Rendered> {
    Ok(prepare(scene, tables, opts)?.render(&scene.camera, progress))
}

/// The maps toward the sky for its marched order 1, with the phase function of the middle
/// channel; none for a slab.
fn sky_order1(
    medium: &dyn Medium,
    phases: &[Phase],
    opts: &FastOptions,
    step: f64,
    threshold: f64,
) -> Option<SkyOrder1> {
    let bounds = medium.bounds()?;
    let mut maps = opts.maps(step, threshold, 1.0);
    maps.resolution = opts.sky_map_resolution;
    let phase = &phases[1.min(phases.len() - 1)];
    Some(phase.with(|p| SkyOrder1::build(medium, bounds, &maps, p)))
}

/// ℓ* = 1/((1 − g) σ_t) (m): the transport mean free path of `scene` for mean cosine `g`.
fn transport_mfp(scene: &Scene, g: f64) -> f64 {
    1.0 / ((1.0 - g).max(1e-3) * scene.sigma_t)
}

/// The sun side of `scene` (default maps) and, for every `stride`-th pixel of its camera whose
/// ray meets the cloud, the viewpoint the collector search takes: what a benchmark of the
/// search runs on.
pub fn surface_points(scene: &Scene, stride: usize) -> Result<(SunSide, Vec<Viewpoint>)> {
    let medium = scene.build_medium()?;
    let opts = FastOptions::default();
    let step = 0.5 / scene.sigma_t;
    let threshold = opts.surface_density * scene.sigma_t;
    let g = mean_cosine(&Phase::build_channels(&scene.phase)?);
    let side = sun_side(
        scene,
        medium.as_ref(),
        &opts.maps(step, threshold, transport_mfp(scene, g)),
        1.0,
    )?;
    let cam = Pinhole::new(&scene.camera);
    let tables = nephele_runtime::embedded::mie_10um();
    let frame = Frame {
        scene,
        medium,
        side,
        tables: &tables,
        sky: None,
        sky_order1: None,
        opts,
        step,
        threshold,
        phases: Vec::new(),
        g: 0.0,
        finite: FiniteCloud::published(0.0),
        offsets: Vec::new(),
    };
    let mut points = Vec::new();
    for px in (0..cam.width * cam.height).step_by(stride.max(1)) {
        let w = cam.direction(px % cam.width, px / cam.width, 0.5, 0.5);
        points.extend(frame.march(cam.position, w).viewpoint(w));
    }
    Ok((frame.side, points))
}

#[cfg(test)]
mod tests {
    use super::{prepare, FastOptions, Method, RayPattern};
    use crate::render::camera::Pinhole;
    use crate::render::scene::Scene;

    /// With the quincunx, each pixel's opacity is the weighted mean of the transmittances of
    /// the rays through its own corners (⅛ each) and centre (½), marched on their own: the
    /// bands' shared corner rows are indexed right, each band's last row of corners included.
    #[test]
    fn pixels_take_the_rays_through_their_own_corners() {
        let tables = nephele_runtime::embedded::mie_10um();
        let mut scene = Scene::load(std::path::Path::new(concat!(
            env!("CARGO_MANIFEST_DIR"),
            "/fit-configs/scenes/cloud.json"
        )))
        .unwrap();
        (scene.camera.width, scene.camera.height) = (24, 18);
        let (pattern, w_centre) = (RayPattern::Quincunx, 0.5);
        let opts = FastOptions {
            method: Method::Single,
            map_resolution: 64,
            planes: 64,
            pattern,
            ..FastOptions::default()
        };
        let prepared = prepare(&scene, &tables, &opts).unwrap();
        let frame = &prepared.frame;
        let cam = Pinhole::new(&scene.camera);
        let (image, _, _) = frame.pixels(&cam, &|_| {});
        let w_corner = (1.0 - w_centre) / 4.0;
        let (mut checked, mut cloudy) = (0, 0);
        for j in 0..cam.height {
            for i in 0..cam.width {
                let t = |i: usize, j: usize, u: f64, v: f64| {
                    frame
                        .march(cam.position, cam.direction(i, j, u, v))
                        .transmittance
                };
                let corners = t(i, j, 0.0, 0.0)
                    + t(i + 1, j, 0.0, 0.0)
                    + t(i, j + 1, 0.0, 0.0)
                    + t(i + 1, j + 1, 0.0, 0.0);
                let expected = w_corner * corners + w_centre * t(i, j, 0.5, 0.5);
                let got = image.transmittance[j * cam.width + i] as f64;
                assert!(
                    (got - expected).abs() <= 1e-6,
                    "{pattern:?}, pixel ({i}, {j}): {got} vs {expected}"
                );
                checked += 1;
                cloudy += usize::from(expected < 0.99);
            }
        }
        assert!(
            cloudy > checked / 8,
            "{pattern:?}: {cloudy} of {checked} pixels see the cloud"
        );
    }
}
