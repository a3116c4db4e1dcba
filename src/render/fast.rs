//! The fast renderers (docs/collector.md): the collector renderer of Bouthors et al. 2008
//! (§§6–7, orders ≥ 2 from the compressed slab tables through nephele-runtime's collector
//! search), and two baselines rendered the same way — single scattering only, and the
//! multi-octave approximation of real-time engines (Wrenninge et al. 2013; Hillaire 2016).
//!
//! Per pixel, one ray through the pixel's centre (or an n × n grid of them) is marched through
//! the medium ([`super::march`]) in sub-steps of length h with extinction σ, view
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
//! - sky: the sky seen through 1 − α (`unscattered`), and the sky term of [`super::sky`] for
//!   the scattered orders (α S_g L_sky per group; order 1 from the same table), reported apart
//!   in render.json;
//! - the march stops where T_v < 10⁻⁴ (what lies behind adds < 10⁻⁴ of the pixel).

use super::geometry::{dot, Vec3};
use super::light_map::MapOptions;
use super::march::substeps;
use super::medium::Medium;
pub use super::octaves::{Octaves, MAX_OCTAVES};
use super::run::{Pinhole, Rendered, GROUP_FIRST};
use super::scene::Scene;
use super::sky::SkyTable;
use super::sun_side::sun_side;
pub use super::sun_side::SunSide;
use crate::phase::Phase;
use anyhow::{bail, ensure, Result};
use nephele_runtime::transport::{
    find_collector, local_slab, LitSurface, SearchOptions, SlabPoint, TransportTables, Viewpoint,
};
use rayon::prelude::*;
use serde::Serialize;
use std::ops::ControlFlow;
use std::sync::atomic::{AtomicUsize, Ordering};
use std::time::Instant;

/// How a frame is rendered.
#[derive(Clone, Copy, Debug, PartialEq, Eq, clap::ValueEnum, Serialize)]
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
    /// Rays per pixel: an n × n grid.
    pub rays: u32,
    /// Collector search settings.
    #[serde(skip)]
    pub search: SearchOptions,
    /// Octave baseline settings.
    pub octaves: Octaves,
    /// Use the tables even where the scene's phase function or albedo differs (a warning).
    pub allow_mismatch: bool,
    /// An ablation: the local slabs' thickness times this factor (1: the method as is).
    pub thickness_scale: f64,
}

impl Default for FastOptions {
    fn default() -> Self {
        Self {
            method: Method::Collector,
            map_resolution: 256,
            planes: 256,
            step: None,
            surface_density: 0.5,
            rays: 1,
            search: SearchOptions::default(),
            octaves: Octaves::default(),
            allow_mismatch: false,
            thickness_scale: 1.0,
        }
    }
}

impl FastOptions {
    /// The light maps' settings for a march sub-step and a surface extinction.
    fn maps(&self, step: f64, threshold: f64) -> MapOptions {
        MapOptions {
            resolution: self.map_resolution,
            planes: self.planes,
            step,
            threshold,
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
            (1..=64).contains(&self.search.max_reads),
            "search iterations must be 1…64"
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
}

/// What one view ray gathers.
#[derive(Clone, Copy, Debug, Default)]
struct ViewRay {
    /// T_v at the end.
    transmittance: f64,
    /// I_{aⁱ} per octave (I₀ is order 1's integral).
    integrals: [f64; MAX_OCTAVES],
    /// Where the ray meets the lit surface (or its densest sub-step).
    surface: Option<Vec3>,
    /// The optical depth of the ray beyond the surface point (mfp), and whether that is all of
    /// it (the ray left the medium) or a lower bound (the march stopped where T_v < 10⁻⁴).
    behind: f64,
    behind_exact: bool,
}

impl ViewRay {
    /// The viewpoint the collector search takes for this ray of direction `w`: its surface
    /// point, the light's travel toward the eye, and what the march knows of the medium
    /// beyond the point.
    fn viewpoint(&self, w: Vec3) -> Option<Viewpoint> {
        let p = self.surface?;
        Some(Viewpoint {
            position: p.map(|x| x as f32),
            view: w.map(|x| -x as f32),
            behind_min: self.behind as f32,
            behind_max: if self.behind_exact {
                self.behind as f32
            } else {
                f32::INFINITY
            },
        })
    }
}

/// Region codes of `regions.npy`.
pub mod region {
    /// Opacity ≤ 0.5.
    pub const EMPTY: u8 = 0;
    /// Opaque, the visible surface point sunlit (τ_sun < 2).
    pub const LIT: u8 = 1;
    /// Opaque, the visible surface point in the cloud's shadow (τ_sun ≥ 2).
    pub const SHADOWED: u8 = 2;
    /// 0.5 < opacity < 0.99: the silhouette.
    pub const SILHOUETTE: u8 = 3;
}

/// Everything a frame needs, built once.
struct Frame<'a> {
    scene: &'a Scene,
    medium: &'a dyn Medium,
    side: SunSide,
    tables: &'a TransportTables<'a>,
    sky: Option<SkyTable>,
    opts: FastOptions,
    step: f64,
    threshold: f64,
    /// p(θ) per channel and the mean cosine g (for the octaves).
    phases: Vec<Phase>,
    g: f64,
}

/// Renders `scene` with a fast method; `progress(fraction)` as rows finish.
pub fn render_fast(
    scene: &Scene,
    tables: &TransportTables,
    opts: &FastOptions,
    progress: &(dyn Fn(f64) + Sync),
) -> Result<Rendered> {
    opts.validate()?;
    let t_start = Instant::now();
    let medium = scene.build_medium()?;
    let phases = Phase::build_channels(&scene.phase)?;
    let mut warnings = Vec::new();
    check_tables(scene, tables, &phases, opts, &mut warnings)?;
    let g = mean_cosine(&phases);
    let t_setup = t_start.elapsed().as_secs_f64();
    let step = opts.step.unwrap_or(0.5 / scene.sigma_t);
    let threshold = opts.surface_density * scene.sigma_t;
    let t0 = Instant::now();
    let side = sun_side(
        scene,
        medium.as_ref(),
        &opts.maps(step, threshold),
        opts.thickness_scale,
    )?;
    let t_maps = t0.elapsed().as_secs_f64();
    let t0 = Instant::now();
    let has_sky = scene.sky.iter().any(|&s| s > 0.0);
    let sky = has_sky.then(|| SkyTable::build(tables));
    let t_sky = t0.elapsed().as_secs_f64();
    let frame = Frame {
        scene,
        medium: medium.as_ref(),
        side,
        tables,
        sky,
        opts: *opts,
        step,
        threshold,
        phases,
        g,
    };
    let t0 = Instant::now();
    let (image, stats, sky_share) = frame.pixels(progress);
    let t_pixels = t0.elapsed().as_secs_f64();
    let seconds = t_maps + t_sky + t_pixels;
    let mut r = image;
    r.seconds = seconds;
    r.details = serde_json::json!({
        "method": opts.method,
        "options": opts,
        "search": {
            "max_reads": opts.search.max_reads,
            "tolerance": opts.search.tolerance,
            "step_clamp": opts.search.step_clamp,
            "filter": opts.search.filter,
        },
        "march_step_m": step,
        "surface_sigma_t": threshold,
        "mean_cosine_g": g,
        "seconds_per_stage": {
            "setup_phase_function": t_setup,
            "light_maps": t_maps,
            "sky_table": t_sky,
            "pixels": t_pixels,
            "frame": seconds,
        },
        "groups": stats,
        "sky_term_share_of_scattered_light": sky_share,
        "warnings": warnings,
    });
    Ok(r)
}

/// The sun side of `scene` (default maps) and, for every `stride`-th pixel of its camera whose
/// ray meets the cloud, the viewpoint the collector search takes: what a benchmark of the
/// search runs on.
pub fn surface_points(scene: &Scene, stride: usize) -> Result<(SunSide, Vec<Viewpoint>)> {
    let medium = scene.build_medium()?;
    let opts = FastOptions::default();
    let step = 0.5 / scene.sigma_t;
    let threshold = opts.surface_density * scene.sigma_t;
    let side = sun_side(scene, medium.as_ref(), &opts.maps(step, threshold), 1.0)?;
    let cam = Pinhole::new(&scene.camera);
    let tables = nephele_runtime::embedded::mie_10um();
    let frame = Frame {
        scene,
        medium: medium.as_ref(),
        side,
        tables: &tables,
        sky: None,
        opts,
        step,
        threshold,
        phases: Vec::new(),
        g: 0.0,
    };
    let mut points = Vec::new();
    for px in (0..cam.width * cam.height).step_by(stride.max(1)) {
        let w = cam.direction(px % cam.width, px / cam.width, 0.5, 0.5);
        points.extend(frame.march(cam.position, w).viewpoint(w));
    }
    Ok((frame.side, points))
}

/// The tables are for one phase function and ϖ = 1: the scene's must match (p within 5 % at
/// every degree, the forward peak included) unless the caller allows a mismatch.
fn check_tables(
    scene: &Scene,
    tables: &TransportTables,
    phases: &[Phase],
    opts: &FastOptions,
    warnings: &mut Vec<String>,
) -> Result<()> {
    // Without a sky, only the collector reads the tables.
    if opts.method != Method::Collector && !scene.sky.iter().any(|&s| s > 0.0) {
        return Ok(());
    }
    let mut problems = Vec::new();
    if (scene.albedo - 1.0).abs() > 1e-9 {
        problems.push(format!(
            "the tables are for albedo 1, the scene's is {}",
            scene.albedo
        ));
    }
    let mut worst = (0.0f64, 0.0f64);
    for deg in 0..=180 {
        let mu = (deg as f64).to_radians().cos();
        let p = channel_mean(phases, mu);
        let q = tables.phase(mu as f32) as f64;
        let rel = (p - q).abs() / q.max(1e-30);
        if rel > worst.0 {
            worst = (rel, deg as f64);
        }
    }
    if worst.0 > 0.05 {
        problems.push(format!(
            "the scene's phase function differs from the tables' by {:.0} % at {}° (the \
             tables are for one phase function and droplet size; make tables for this one with \
             `nephele slab` and `nephele compress`, and pass them with --tables)",
            100.0 * worst.0,
            worst.1
        ));
    }
    if problems.is_empty() {
        return Ok(());
    }
    if opts.allow_mismatch {
        for p in problems {
            eprintln!("warning: {p}");
            warnings.push(p);
        }
        return Ok(());
    }
    bail!(
        "the scene does not match the transport tables: {} (--allow-table-mismatch renders \
         anyway)",
        problems.join("; ")
    )
}

fn channel_mean(phases: &[Phase], mu: f64) -> f64 {
    phases.iter().map(|p| p.with(|f| f.eval(mu))).sum::<f64>() / phases.len() as f64
}

/// g = ∫ μ p dΩ of the channels' mean, by the midpoint rule on 20 000 angles.
fn mean_cosine(phases: &[Phase]) -> f64 {
    let n = 20_000;
    let h = std::f64::consts::PI / n as f64;
    (0..n)
        .map(|k| {
            let th = (k as f64 + 0.5) * h;
            let mu = th.cos();
            2.0 * std::f64::consts::PI * mu * channel_mean(phases, mu) * th.sin() * h
        })
        .sum()
}

impl Frame<'_> {
    /// Every pixel, rows in parallel (deterministic: no randomness, sums in a fixed order).
    /// Also the sky term's share of the scattered light.
    fn pixels(&self, progress: &(dyn Fn(f64) + Sync)) -> (Rendered, Vec<GroupStats>, f64) {
        let cam = Pinhole::new(&self.scene.camera);
        let (w, h) = (cam.width, cam.height);
        let ng = GROUP_FIRST.len();
        let done = AtomicUsize::new(0);
        let rows: Vec<(Vec<Pixel>, Vec<GroupStats>)> = (0..h)
            .into_par_iter()
            .map(|j| {
                let mut stats = self.empty_stats();
                let row = (0..w).map(|i| self.pixel(&cam, i, j, &mut stats)).collect();
                progress((done.fetch_add(1, Ordering::Relaxed) + 1) as f64 / h as f64);
                (row, stats)
            })
            .collect();
        let mut out = Rendered::empty(w, h);
        out.method = format!("{:?}", self.opts.method).to_lowercase();
        out.regions = vec![0; w * h];
        let mut stats = self.empty_stats();
        let (sun, sky) = (self.scene.sun.irradiance, self.scene.sky);
        let (mut sky_sum, mut all) = (0.0f64, 0.0f64);
        for (j, (row, row_stats)) in rows.into_iter().enumerate() {
            for (a, b) in stats.iter_mut().zip(row_stats) {
                a.add(&b);
            }
            for (i, px) in row.into_iter().enumerate() {
                let at = j * w + i;
                out.transmittance[at] = px.transmittance as f32;
                out.regions[at] = px.region;
                for c in 0..3 {
                    let mut total = px.transmittance * sky[c];
                    out.unscattered[at * 3 + c] = total as f32;
                    for g in 0..ng {
                        let v = px.sun[g][c] * sun[c] + px.sky[g] * sky[c];
                        sky_sum += px.sky[g] * sky[c];
                        all += v;
                        out.groups[(g * h * w + at) * 3 + c] = v as f32;
                        total += v;
                    }
                    out.beauty[at * 3 + c] = total as f32;
                }
            }
        }
        (out, stats, sky_sum / all.max(1e-300))
    }

    fn empty_stats(&self) -> Vec<GroupStats> {
        GROUP_FIRST[1..]
            .iter()
            .map(|&f| GroupStats {
                first_order: f,
                ..Default::default()
            })
            .collect()
    }

    /// One pixel: the mean over its n × n rays.
    fn pixel(&self, cam: &Pinhole, i: usize, j: usize, stats: &mut [GroupStats]) -> Pixel {
        let n = self.opts.rays as usize;
        let mut px = Pixel::default();
        let inv = 1.0 / (n * n) as f64;
        for k in 0..n * n {
            let (u, v) = ((k % n) as f64 + 0.5, (k / n) as f64 + 0.5);
            let dir = cam.direction(i, j, u / n as f64, v / n as f64);
            let one = self.ray(cam.position, dir, stats);
            px.add(&one, inv);
        }
        px.region = region_of(1.0 - px.transmittance, px.sun_tau);
        px
    }

    /// One view ray: its transmittance, order 1, and the scattered orders of the method.
    fn ray(&self, o: Vec3, w: Vec3, stats: &mut [GroupStats]) -> Pixel {
        let v = self.march(o, w);
        let mut px = Pixel {
            transmittance: v.transmittance,
            ..Default::default()
        };
        let alpha = 1.0 - v.transmittance;
        let sun = self.scene.sun.direction;
        let cos = dot(w, sun).clamp(-1.0, 1.0);
        let albedo = self.scene.albedo;
        for (c, p) in px.sun[0].iter_mut().enumerate() {
            let phase = &self.phases[c.min(self.phases.len() - 1)];
            *p = albedo * phase.with(|f| f.eval(cos)) * v.integrals[0];
        }
        let (Some(p), Some(vp)) = (v.surface, v.viewpoint(w)) else {
            return px;
        };
        px.sun_tau = self.side.optical_depth(p);
        let sun32 = sun.map(|x| x as f32);
        match self.opts.method {
            Method::Collector => {
                let mut first_slab = None;
                for (g, st) in stats.iter_mut().enumerate() {
                    st.searches += 1;
                    let found =
                        find_collector(self.tables, g, &self.side, &vp, sun32, &self.opts.search);
                    let Some(f) = found else {
                        st.empty += 1;
                        match self.coarse_slab(&vp, sun32) {
                            Some(at) => {
                                let t = self.tables.evaluate(g, &at).t as f64;
                                px.sun[g + 1] = [alpha * t; 3];
                                if let Some(sky) = &self.sky {
                                    px.sky[g + 1] = alpha * sky.radiance(g + 1, &at);
                                }
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
                    px.sun[g + 1] = [alpha * f.transport.t as f64; 3];
                    if let Some(sky) = &self.sky {
                        px.sky[g + 1] = alpha * sky.radiance(g + 1, &f.at);
                    }
                    first_slab.get_or_insert(f.at);
                }
                if let (Some(sky), Some(at)) = (&self.sky, first_slab) {
                    px.sky[0] = alpha * sky.radiance(0, &at);
                }
            }
            Method::Single | Method::Octaves => {
                if self.opts.method == Method::Octaves {
                    px.sun[1] = self.octaves(cos, &v.integrals);
                }
                if let (Some(sky), Some(at)) = (&self.sky, self.coarse_slab(&vp, sun32)) {
                    // One slab for every group: the surface filtered at the cloud's size.
                    for g in 0..GROUP_FIRST.len() {
                        px.sky[g] = alpha * sky.radiance(g, &at);
                    }
                }
            }
            Method::PathTracer => unreachable!("validated"),
        }
        px
    }

    /// The slab of p under the surface filtered at the cloud's size (no search).
    fn coarse_slab(&self, v: &Viewpoint, sun: [f32; 3]) -> Option<SlabPoint<f32>> {
        let s = self.side.filtered(v.position, self.side.initial_scale())?;
        Some(local_slab(self.tables, &s, v, sun).at)
    }

    /// Σ_{1 ≤ i < N} bⁱ ϖ p_HG(θ; cⁱ g) I_{aⁱ} (per unit E_sun; octave 0 is order 1).
    fn octaves(&self, cos: f64, integrals: &[f64; MAX_OCTAVES]) -> [f64; 3] {
        let o = &self.opts.octaves;
        [o.scattered(self.g, self.scene.albedo, cos, integrals); 3]
    }

    /// Marches the view ray o + t w.
    fn march(&self, o: Vec3, w: Vec3) -> ViewRay {
        let mut v = ViewRay {
            transmittance: 1.0,
            ..Default::default()
        };
        let Some(range) = self.medium.clip(o, w) else {
            return v;
        };
        let n_oct = if self.opts.method == Method::Octaves {
            self.opts.octaves.n
        } else {
            1
        };
        let factors: [f64; MAX_OCTAVES] =
            std::array::from_fn(|i| self.opts.octaves.a.powi(i as i32));
        let at = |t: f64| -> Vec3 { std::array::from_fn(|k| o[k] + t * w[k]) };
        let mut tau_a: Option<(f64, f64)> = None;
        let (mut prev, mut densest) = (None::<(f64, f64)>, (0.0f64, 0.0f64));
        // The view ray's optical depth so far, and where the surface point was found.
        let (mut tau_v, mut tau_at_p, mut stopped) = (0.0f64, None::<f64>, false);
        let mut tau_at_densest = 0.0;
        let _: Option<()> = substeps(self.medium, o, w, range, self.step, |a, b, sigma| {
            let h = b - a;
            let ta = match tau_a {
                Some((s, t)) if s == a => t,
                _ => self.side.optical_depth(at(a)),
            };
            let tb = self.side.optical_depth(at(b));
            tau_a = Some((b, tb));
            let k = (tb - ta) / h;
            for (i, integral) in v.integrals.iter_mut().enumerate().take(n_oct) {
                let ai = factors[i];
                let rate = sigma + ai * k;
                let e = if rate.abs() * h < 1e-9 {
                    h
                } else {
                    -(-rate * h).exp_m1() / rate
                };
                *integral += sigma * v.transmittance * (-ai * ta).exp() * e;
            }
            let mid = 0.5 * (a + b);
            if v.surface.is_none() {
                if sigma >= self.threshold {
                    let s = match prev {
                        Some((pm, ps)) if ps < self.threshold && sigma > ps => {
                            pm + (mid - pm) * (self.threshold - ps) / (sigma - ps)
                        }
                        _ => a,
                    };
                    v.surface = Some(at(s));
                    tau_at_p = Some(tau_v + sigma * (s - a).max(0.0));
                } else if sigma > densest.1 {
                    densest = (mid, sigma);
                    tau_at_densest = tau_v + 0.5 * sigma * h;
                }
            }
            prev = Some((mid, sigma));
            tau_v += sigma * h;
            v.transmittance *= (-sigma * h).exp();
            if v.transmittance < 1e-4 {
                stopped = true;
                ControlFlow::Break(())
            } else {
                ControlFlow::Continue(())
            }
        });
        if v.surface.is_none() && densest.1 > 0.0 {
            v.surface = Some(at(densest.0));
            tau_at_p = Some(tau_at_densest);
        }
        v.behind = (tau_v - tau_at_p.unwrap_or(tau_v)).max(0.0);
        v.behind_exact = !stopped;
        v
    }
}

/// What one pixel (or ray) gathers, per unit sun irradiance and sky radiance.
#[derive(Clone, Copy, Debug, Default)]
struct Pixel {
    transmittance: f64,
    /// Per group and channel, per unit E_sun.
    sun: [[f64; 3]; GROUP_FIRST.len()],
    /// Per group, per unit L_sky.
    sky: [f64; GROUP_FIRST.len()],
    /// τ_sun at the surface point.
    sun_tau: f64,
    region: u8,
}

impl Pixel {
    fn add(&mut self, o: &Pixel, w: f64) {
        self.transmittance += w * o.transmittance;
        for g in 0..GROUP_FIRST.len() {
            for c in 0..3 {
                self.sun[g][c] += w * o.sun[g][c];
            }
            self.sky[g] += w * o.sky[g];
        }
        self.sun_tau += w * o.sun_tau;
    }
}

impl GroupStats {
    fn add(&mut self, o: &GroupStats) {
        self.searches += o.searches;
        self.empty += o.empty;
        self.dark += o.dark;
        self.reads += o.reads;
        self.converged += o.converged;
        self.clamped_thickness += o.clamped_thickness;
        self.clamped_mu_l += o.clamped_mu_l;
        self.clamped_depth += o.clamped_depth;
        self.held_by_view += o.held_by_view;
    }
}

/// The region code of a pixel of opacity `alpha` whose surface point has sun optical depth
/// `tau`.
fn region_of(alpha: f64, tau: f64) -> u8 {
    if alpha <= 0.5 {
        region::EMPTY
    } else if alpha < 0.99 {
        region::SILHOUETTE
    } else if tau < 2.0 {
        region::LIT
    } else {
        region::SHADOWED
    }
}
