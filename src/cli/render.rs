//! `nephele render`: renders a scene with the ground-truth path tracer or a fast method.

use anyhow::Result;
use clap::{ArgMatches, Args, ValueEnum};
use nephele::render::fast::orbit::render_orbit as render_orbit_views;
use nephele::render::fast::{
    prepare, render_fast, FastOptions, Finite, Method, Octaves, RayPattern,
};
use nephele::render::image::Rendered;
use nephele::render::output::{exposure as output_exposure, write_outputs_with};
use nephele::render::path::{render_until, Progress, Settings};
use nephele::render::scene::Scene;
use nephele_runtime::transport::SearchOptions;
use std::path::{Path, PathBuf};

/// Options of `nephele render`.
#[derive(Args, Debug)]
pub struct RenderArgs {
    /// Scene (JSON; keys in fit-configs/scenes/README.md).
    #[arg(long, value_name = "FILE")]
    pub scene: PathBuf,
    /// Output directory: beauty.png, beauty.exr, beauty.npy, groups.npy, unscattered.npy,
    /// transmittance.npy, opacity.npy, render.json; halves.npy (path tracer) or regions.npy
    /// (fast methods). [default: outputs/render]
    #[arg(long, value_name = "DIR")]
    pub out: Option<PathBuf>,
    /// How to render: the Monte Carlo path tracer (the reference), the collector renderer
    /// (orders ≥ 2 from the transport tables, docs/collector.md), order 1 only, or the
    /// multi-octave approximation of real-time engines.
    #[arg(long, value_enum, default_value = "path-tracer")]
    pub method: MethodArg,
    /// Path tracer: samples per pixel, overriding the scene's (with a time budget: the most a
    /// pass takes).
    #[arg(long, value_parser = clap::value_parser!(u32).range(1..=1_000_000))]
    pub spp: Option<u32>,
    /// Path tracer: wall-clock cap in seconds, overriding the scene's: a first pass of 2
    /// samples per pixel, then passes of a tenth of the budget until it is spent (the last one
    /// cut by rows). Ctrl-C writes the samples finished.
    #[arg(long, value_name = "SECONDS", value_parser = super::positive_f64)]
    pub time_budget: Option<f64>,
    /// Path tracer: most steps of the sun-lobe walks and directions of their MIS window
    /// (variance reduction for forward peaks, docs/render.md), overriding the scene's (default
    /// 16): 0 is plain next-event estimation, up to 32.
    #[arg(long, value_name = "K", value_parser = clap::value_parser!(u64).range(0..=32))]
    pub sun_lobe_steps: Option<u64>,
    /// Path tracer: seed of every random stream, overriding the scene file's (default 0).
    #[arg(long, value_name = "N")]
    pub seed: Option<u64>,
    /// Image width and height in pixels, overriding the scene's camera.
    #[arg(long, value_names = ["W", "H"], num_args = 2,
          value_parser = clap::value_parser!(u32).range(1..=16384))]
    pub size: Option<Vec<u32>>,
    /// Exposure K of beauty.png: 1 − e^{−K x} of the linear radiance x (render.json records the
    /// one used) [default: the 90th percentile of the cloud's luminance maps to 0.75].
    #[arg(long, value_name = "K", value_parser = nephele::render::output::parse_exposure)]
    pub exposure: Option<f32>,
    /// Fast methods: N views on an orbit around the vertical through the camera's look-at
    /// point, 360°/N apart (the scene's camera first), all from one set of light maps: each
    /// view a full output directory DIR/view_000 …, one exposure for all (the first view's),
    /// and DIR/views.json (the maps' seconds once, every view's frame seconds, frames per
    /// second with the maps reused).
    #[arg(long, value_name = "N", value_parser = clap::value_parser!(u32).range(1..=3600))]
    pub orbit: Option<u32>,
    #[command(flatten)]
    pub fast: FastArgs,
}

/// Options of the fast methods (collector, single, octaves).
#[derive(Args, Debug)]
pub struct FastArgs {
    /// Compressed transport tables (.ntt from `nephele compress`) [default: the embedded Mie
    /// 10 µm tables].
    #[arg(long, value_name = "FILE")]
    pub tables: Option<PathBuf>,
    /// Render even where the scene's phase function or albedo differs from the tables' (a
    /// warning instead of an error).
    #[arg(long)]
    pub allow_table_mismatch: bool,
    /// Light-space map texels per side (a power of two).
    #[arg(long, default_value_t = 256, value_name = "N")]
    pub map_resolution: usize,
    /// Depth planes of the sun's optical-depth map.
    #[arg(long, default_value_t = 256, value_name = "N")]
    pub planes: usize,
    /// March sub-step in metres [default: half a mean free path at density 1].
    #[arg(long, value_name = "M")]
    pub march_step: Option<f64>,
    /// ρ₀: the lit surface is where the density crosses this fraction of the scene's σ_t.
    #[arg(long, default_value_t = 0.5, value_name = "RHO")]
    pub surface_density: f64,
    /// Rays per pixel: an n × n grid over the pixel (antialiasing: the march — opacity, order
    /// 1, the sky term, the octaves — runs on every ray; the collector searches once per pixel,
    /// at its most opaque ray's surface point); n rays with `--ray-pattern rooks`, not used by
    /// the quincunx.
    #[arg(long, default_value_t = 2, value_name = "N")]
    pub rays: u32,
    /// Where a pixel's rays go: `grid`, n × n of them at the sub-pixels' centres; `rooks`, n
    /// of them, one in each row and column of that grid (n = 2: the diagonal, half the march);
    /// `quincunx`, one through each pixel corner, shared by the four pixels there (⅛ each),
    /// and one through the centre (½): about two marches a pixel, order 1 closer to the 2 × 2
    /// grid than the rooks' two, and a search a corner ray starts serves every pixel that
    /// chooses it (docs/collector.md, "Frame cost").
    #[arg(long, value_enum, default_value = "grid", value_name = "PATTERN")]
    pub ray_pattern: RayPatternArg,
    /// Collector: search once per block of N × N pixels, at the block's most opaque ray, each
    /// pixel weighing the light found by its own opacity (1: once per pixel; fewer searches,
    /// docs/collector.md, "Frame cost").
    #[arg(long, default_value_t = 1, value_name = "N")]
    pub search_block: u32,
    /// Collector, with --search-block N > 1: a block shares one search only where each of its
    /// pixels is at least this opaque (the cloud's interior); the pixels of any other block
    /// (silhouettes, thin matter, where orders ≥ 2 change from pixel to pixel) search alone.
    /// 0: every block shares.
    #[arg(long, default_value_t = nephele::render::regions::OPAQUE, value_name = "ALPHA")]
    pub search_block_opacity: f64,
    /// Collector: search on every ray of a pixel, not once per pixel (an ablation: n² times the
    /// searches).
    #[arg(long)]
    pub search_every_ray: bool,
    /// Collector: do not tell the search p's optical depth to the sun (an ablation: the local
    /// slab is not cut to it; docs/collector.md, "Shadowed faces and silhouettes").
    #[arg(long)]
    pub no_sun_depth: bool,
    /// Collector: each group reads p's own depth to the sun, not that depth averaged across the
    /// light over the spread of the group's walks (an ablation; docs/collector.md, "The sun's
    /// depth, spread across the light").
    #[arg(long)]
    pub no_sun_spread: bool,
    /// Texels per side of the 16 maps toward the sky for the sky's order 1 (a power of two;
    /// 0: order 1 from the view ray's face-on slab, an ablation; docs/collector.md, "Sky").
    #[arg(long, value_name = "N",
          default_value_t = nephele::render::fast::sky_order1::MAP_RESOLUTION)]
    pub sky_map_resolution: usize,
    /// Collector search: most table reads per group.
    #[arg(long, default_value_t = 8, value_name = "N")]
    pub iterations: u32,
    /// Collector search: converged when c moves less than this many σ (and σ changes by less).
    #[arg(long, default_value_t = 0.1, value_name = "EPS")]
    pub tolerance: f32,
    /// Collector search: no clamp of the steps to σ (an ablation).
    #[arg(long)]
    pub no_step_clamp: bool,
    /// Collector search: the surface unfiltered, at its finest level (an ablation).
    #[arg(long)]
    pub no_filter: bool,
    /// An ablation: multiply the local slabs' optical thickness by this factor (1: the
    /// method as published).
    #[arg(long, default_value_t = 1.0, value_name = "F")]
    pub thickness_scale: f64,
    /// Collector: the finite-cloud correction (docs/collector.md, "Finite clouds"): light lost
    /// through the cloud's sides per order group (leakage, the default), the footprint's
    /// coverage, both, or none (the method as published).
    #[arg(long, value_enum, default_value_t = Correction::Leakage)]
    pub correction: Correction,
    /// Collector: the lateral loss rate κ⊥ times this factor (1: diffusion theory as is).
    #[arg(long, default_value_t = 1.0, value_name = "K")]
    pub leakage_scale: f64,
    /// Collector: the sides count from order n_c = A (δ̄ + z_e)²/D on (0: from the first).
    #[arg(long, default_value_t = 0.0, value_name = "A")]
    pub leakage_delay: f64,
    /// Collector: how the sides count a path's orders: by how far the walk has spread across
    /// the light (the default), or order by order from the first (an ablation;
    /// docs/collector.md, "lateral spread").
    #[arg(long, value_enum, default_value_t = LeakageCount::Spread)]
    pub leakage_count: LeakageCount,
    /// Collector: where the lateral size R comes from: the larger of the cloud's sections
    /// across the light and along its lit surface (both, the default), either alone, or the
    /// cloud's whole projection (ablations; docs/collector.md).
    #[arg(long, value_enum, default_value_t = LateralFrom::Both)]
    pub lateral: LateralFrom,
    /// Collector: the sections across the light, at this many depths.
    #[arg(long, default_value_t = 16, value_name = "N", value_parser = clap::value_parser!(u32).range(1..=256))]
    pub lateral_sections: u32,
    /// Octaves: N, a, b, c of L ≈ Σ_{i<N} bⁱ σ_s p(θ; cⁱ g) E Tr_sun(aⁱ σ_t).
    #[arg(long, value_names = ["N", "A", "B", "C"], num_args = 4)]
    pub octaves: Option<Vec<f64>>,
}

/// How the sides count a path's orders.
#[derive(Clone, Copy, Debug, PartialEq, Eq, clap::ValueEnum)]
pub enum LeakageCount {
    /// By the walk's spread across the light.
    Spread,
    /// Order by order, from the first.
    Orders,
}

/// Where the lateral size R comes from.
#[derive(Clone, Copy, Debug, PartialEq, Eq, clap::ValueEnum)]
pub enum LateralFrom {
    /// The larger of the sections across the light and along the lit surface.
    Both,
    /// The section across the light one transport mean free path below the collector.
    Sections,
    /// The section along the lit surface.
    Surface,
    /// The cloud's whole projection along the light.
    Projection,
}

/// The collector's finite-cloud correction.
#[derive(Clone, Copy, Debug, PartialEq, Eq, clap::ValueEnum)]
pub enum Correction {
    /// The method as published: the infinite slab's T.
    None,
    /// Light lost through the cloud's sides, per order group.
    Leakage,
    /// T weighed by the share of the collector's footprint that the cloud covers.
    Coverage,
    /// Leakage and coverage.
    Both,
}

impl FastArgs {
    /// The fast renderers' options for `method`.
    pub fn options(&self, method: Method) -> Result<FastOptions> {
        let octaves = match &self.octaves {
            Some(v) => {
                anyhow::ensure!(
                    v[0].fract() == 0.0 && v[0] >= 1.0,
                    "--octaves: N must be a whole number ≥ 1"
                );
                Octaves {
                    n: v[0] as usize,
                    a: v[1],
                    b: v[2],
                    c: v[3],
                }
            }
            None => Octaves::default(),
        };
        let o = FastOptions {
            method,
            map_resolution: self.map_resolution,
            planes: self.planes,
            step: self.march_step,
            surface_density: self.surface_density,
            rays: self.rays,
            pattern: self.ray_pattern.into(),
            search_block: self.search_block,
            search_block_opacity: self.search_block_opacity,
            search_every_ray: self.search_every_ray,
            no_sun_depth: self.no_sun_depth,
            no_sun_spread: self.no_sun_spread,
            sky_map_resolution: self.sky_map_resolution,
            search: SearchOptions {
                max_reads: self.iterations,
                tolerance: self.tolerance,
                step_clamp: !self.no_step_clamp,
                filter: !self.no_filter,
                sun_spread: None,
            },
            octaves,
            allow_mismatch: self.allow_table_mismatch,
            tables_diameter_um: nephele::io::tables::mie_diameter(self.tables.as_deref()),
            finite: Finite {
                leakage: matches!(self.correction, Correction::Leakage | Correction::Both),
                coverage: matches!(self.correction, Correction::Coverage | Correction::Both),
                rate_scale: self.leakage_scale,
                delay_scale: self.leakage_delay,
                spread: self.leakage_count == LeakageCount::Spread,
                sections: match self.lateral {
                    LateralFrom::Both | LateralFrom::Sections => self.lateral_sections as usize,
                    _ => 0,
                },
                surface: matches!(self.lateral, LateralFrom::Both | LateralFrom::Surface),
            },
            thickness_scale: self.thickness_scale,
        };
        // Validated once, where every caller passes: `prepare`.
        Ok(o)
    }
}

/// Renders `scene` with `method` (the path tracer with `settings`), a progress bar on stderr.
pub fn render_with(
    scene: &Scene,
    settings: &Settings,
    method: Method,
    fast: &FastArgs,
) -> Result<Rendered> {
    for w in scene.warnings() {
        eprintln!("warning: {w}");
    }
    let bar = super::progress::work_bar("render", 1000);
    // Before the first row: a Mie phase table is computed (seconds), the medium and maps built.
    bar.set_message("preparing the phase function and the medium");
    bar.enable_steady_tick(std::time::Duration::from_millis(200));
    let progress = |done: f64| {
        if bar.position() == 0 && done > 0.0 {
            bar.set_message("");
        }
        bar.set_position((done * 1000.0) as u64)
    };
    let r = if method == Method::PathTracer {
        // A time budget runs passes: show them, the spp and the noise reached so far.
        let budget = settings.time_budget_s.is_some();
        super::interrupt::catch();
        let report = |p: &Progress| {
            progress(p.fraction);
            if budget && p.passes > 0 {
                bar.set_message(p.summary());
            }
        };
        render_until(scene, settings, &report, &super::interrupt::STOP)?
    } else {
        let opts = fast.options(method)?;
        nephele::io::tables::with_tables(fast.tables.as_deref(), |tables| {
            render_fast(scene, tables, &opts, &progress)
        })?
    };
    bar.finish_and_clear();
    Ok(r)
}

/// The flags of one method only, by clap id.
const PATH_TRACER_ONLY: [&str; 4] = ["spp", "time_budget", "sun_lobe_steps", "seed"];
const FAST_ONLY: [&str; 10] = [
    "orbit",
    "tables",
    "allow_table_mismatch",
    "map_resolution",
    "planes",
    "march_step",
    "surface_density",
    "rays",
    "ray_pattern",
    "sky_map_resolution",
];
const COLLECTOR_ONLY: [&str; 16] = [
    "search_block",
    "search_block_opacity",
    "search_every_ray",
    "no_sun_depth",
    "no_sun_spread",
    "iterations",
    "tolerance",
    "no_step_clamp",
    "no_filter",
    "thickness_scale",
    "correction",
    "leakage_scale",
    "leakage_delay",
    "leakage_count",
    "lateral",
    "lateral_sections",
];

/// Refuses the flags that `method` does not take (docs/render.md: a flag that does not apply
/// is an error, never ignored).
fn refuse_flags_of_other_methods(m: &ArgMatches, method: Method, fast: &FastArgs) -> Result<()> {
    let name = method_name(method);
    let reason = |only: &str| format!("to --method {name} ({only} only)");
    if method != Method::PathTracer {
        super::refuse_unused(m, &PATH_TRACER_ONLY, &reason("path-tracer"))?;
    } else {
        super::refuse_unused(m, &FAST_ONLY, &reason("collector, single and octaves"))?;
    }
    if method != Method::Collector {
        super::refuse_unused(m, &COLLECTOR_ONLY, &reason("collector"))?;
    } else if !matches!(fast.correction, Correction::Leakage | Correction::Both) {
        super::refuse_unused(
            m,
            &[
                "leakage_scale",
                "leakage_delay",
                "leakage_count",
                "lateral",
                "lateral_sections",
            ],
            "without the leakage correction (--correction leakage or both)",
        )?;
    }
    if matches!(fast.lateral, LateralFrom::Surface | LateralFrom::Projection) {
        super::refuse_unused(
            m,
            &["lateral_sections"],
            "without the sections across the light (--lateral both or sections)",
        )?;
    }
    if method != Method::Octaves {
        super::refuse_unused(m, &["octaves"], &reason("octaves"))?;
    }
    Ok(())
}

/// The method's command-line name.
fn method_name(method: Method) -> String {
    let arg = match method {
        Method::PathTracer => MethodArg::PathTracer,
        Method::Collector => MethodArg::Collector,
        Method::Single => MethodArg::Single,
        Method::Octaves => MethodArg::Octaves,
    };
    arg.to_possible_value()
        .map_or("?".into(), |v| v.get_name().to_string())
}

/// `--method`: how a frame is rendered ([`Method`]).
#[derive(Clone, Copy, Debug, PartialEq, Eq, ValueEnum)]
pub enum MethodArg {
    /// The Monte Carlo path tracer (the reference).
    PathTracer,
    /// The collector renderer: orders ≥ 2 from the transport tables.
    Collector,
    /// Order 1 only (plus the sky term).
    Single,
    /// The multi-octave approximation of real-time engines.
    Octaves,
}

impl From<MethodArg> for Method {
    fn from(m: MethodArg) -> Self {
        match m {
            MethodArg::PathTracer => Method::PathTracer,
            MethodArg::Collector => Method::Collector,
            MethodArg::Single => Method::Single,
            MethodArg::Octaves => Method::Octaves,
        }
    }
}

/// `--ray-pattern`: where a pixel's rays go ([`RayPattern`]).
#[derive(Clone, Copy, Debug, PartialEq, Eq, ValueEnum)]
pub enum RayPatternArg {
    /// n² rays, at the centres of an n × n grid of sub-pixels.
    Grid,
    /// n rays, one in each row and each column of that grid (n-rooks): half the march of the
    /// 2 × 2 grid.
    Rooks,
    /// A ray through each pixel corner, shared by the four pixels that meet there (⅛ each),
    /// and one through the pixel's centre (½): about two marches a pixel (n is not used).
    Quincunx,
}

impl From<RayPatternArg> for RayPattern {
    fn from(p: RayPatternArg) -> Self {
        match p {
            RayPatternArg::Grid => RayPattern::Grid,
            RayPatternArg::Rooks => RayPattern::Rooks,
            RayPatternArg::Quincunx => RayPattern::Quincunx,
        }
    }
}

/// The path tracer's settings: the scene file's, overridden by the flags.
fn path_settings(args: &RenderArgs) -> Result<Settings> {
    let mut s = Settings::load(&args.scene)?;
    if let Some(spp) = args.spp {
        s.spp = spp;
    }
    if let Some(budget) = args.time_budget {
        s.time_budget_s = Some(budget);
    }
    if let Some(k) = args.sun_lobe_steps {
        s.sun_lobe_steps = k as usize;
    }
    if let Some(seed) = args.seed {
        s.seed = seed;
    }
    s.validate()?;
    Ok(s)
}

/// Runs `nephele render`; `m` tells which flags were given.
pub fn run(args: RenderArgs, m: &ArgMatches) -> Result<()> {
    let method = Method::from(args.method);
    refuse_flags_of_other_methods(m, method, &args.fast)?;
    no_transparent_huge_pages();
    let mut scene = Scene::load(&args.scene)?;
    let settings = path_settings(&args)?;
    if let Some(s) = &args.size {
        scene.camera.width = s[0];
        scene.camera.height = s[1];
    }
    scene.validate()?;
    check_frame_memory(&scene, method)?;
    let out = args
        .out
        .clone()
        .unwrap_or_else(|| PathBuf::from("outputs/render"));
    let _claim = nephele::io::FolderLock::take(&out)?;
    if let Some(n) = args.orbit {
        return render_orbit(&scene, &args, n as usize, &out);
    }
    let r = render_with(&scene, &settings, method, &args.fast)?;
    write_outputs_with(&out, &scene, &r, args.exposure)?;
    if method == Method::PathTracer {
        let n = &r.details["samples_per_pixel"];
        let (spp, per_pixel) = match (n["min"].as_u64(), n["max"].as_u64()) {
            (Some(lo), Some(hi)) if lo != hi => (
                format!("{lo}–{hi} spp (the last pass cut)"),
                format!("{lo}–{hi} per pixel"),
            ),
            _ => (format!("{} spp", r.spp), format!("{} per pixel", r.spp)),
        };
        outln!(
            "{}×{} pixels, {spp}: {} camera paths in {} ({:.0} paths/s); wrote {}/beauty.png, \
             beauty.exr, beauty.npy, groups.npy, halves.npy, unscattered.npy, transmittance.npy, \
             opacity.npy, render.json",
            r.width,
            r.height,
            r.paths,
            super::seconds(r.seconds),
            r.paths as f64 / r.seconds.max(1e-9),
            out.display()
        );
        if r.details["interrupted"] == true {
            return Err(super::interrupt::Interrupted(format!(
                "interrupted (Ctrl-C) after {} passes: the samples finished ({per_pixel}) are \
                 written to '{}'",
                r.details["passes"],
                out.display()
            ))
            .into());
        }
    } else {
        let stages = &r.details["seconds_per_stage"];
        outln!(
            "{}×{} pixels, {}: {:.3} s a frame (maps {:.3} s, sky {:.3} s, pixels {:.3} s); wrote \
             {}/beauty.png, beauty.exr, beauty.npy, groups.npy, regions.npy, unscattered.npy, \
             transmittance.npy, opacity.npy, render.json",
            r.width,
            r.height,
            r.method,
            r.seconds,
            stages["light_maps"].as_f64().unwrap_or(0.0),
            stages["sky_table"].as_f64().unwrap_or(0.0)
                + stages["sky_maps"].as_f64().unwrap_or(0.0),
            stages["pixels"].as_f64().unwrap_or(0.0),
            out.display()
        );
        if r.method == "collector" {
            print_search_stats(&r.details["groups"]);
        }
        print_warnings(&r.details);
    }
    let opacity: Vec<f32> = r.transmittance.iter().map(|t| 1.0 - t).collect();
    for w in nephele::render::output::frame_warnings(&opacity) {
        eprintln!("warning: {w}");
    }
    Ok(())
}

/// Refuses a frame larger than the memory available, before anything is allocated.
fn check_frame_memory(scene: &Scene, method: Method) -> Result<()> {
    let (w, h) = (scene.camera.width, scene.camera.height);
    let need =
        nephele::render::image::frame_bytes(w as usize, h as usize, method == Method::PathTracer);
    let Some(available) = nephele::io::available_memory() else {
        return Ok(());
    };
    anyhow::ensure!(
        need <= available,
        "a {w} × {h} frame needs about {} of memory, more than the {} available; render a \
         smaller --size",
        nephele::io::text::bytes(need),
        nephele::io::text::bytes(available)
    );
    Ok(())
}

/// The render's own warnings (render.json `warnings`), one `warning:` line each on stderr.
fn print_warnings(details: &serde_json::Value) {
    for w in details["warnings"].as_array().into_iter().flatten() {
        if let Some(w) = w.as_str() {
            eprintln!("warning: {w}");
        }
    }
}

/// Renders `n` views of `scene` on an orbit from one set of light maps (`--orbit`).
fn render_orbit(scene: &Scene, args: &RenderArgs, n: usize, out: &Path) -> Result<()> {
    for w in scene.warnings() {
        eprintln!("warning: {w}");
    }
    let opts = args.fast.options(args.method.into())?;
    let bar = super::progress::work_bar("render", (n * 1000) as u64);
    bar.set_message("view 1: preparing the phase function, the medium and the light maps");
    bar.enable_steady_tick(std::time::Duration::from_millis(200));
    let mut first_details = serde_json::Value::Null;
    let summary = nephele::io::tables::with_tables(args.fast.tables.as_deref(), |tables| {
        let prepared = prepare(scene, tables, &opts)?;
        let mut exposure = args.exposure;
        let mut views = Vec::with_capacity(n);
        let progress = |done: f64| bar.set_position((done * n as f64 * 1000.0) as u64);
        render_orbit_views(&prepared, scene, n, &progress, &mut |k, view, r| {
            bar.set_message(format!("view {} of {n}", (k + 2).min(n)));
            let opacity: Vec<f32> = r.transmittance.iter().map(|t| 1.0 - t).collect();
            let k_used = *exposure.get_or_insert(output_exposure(&r.beauty, &opacity).k);
            write_outputs_with(&out.join(format!("view_{k:03}")), view, r, Some(k_used))?;
            views.push((
                view.camera,
                r.seconds,
                r.details["seconds_per_stage"].clone(),
            ));
            if k == 0 {
                first_details = r.details.clone();
            }
            Ok(())
        })?;
        Ok((prepared.seconds(), views, exposure))
    })?;
    bar.finish_and_clear();
    // The first view's warnings (each view's render.json has its own).
    print_warnings(&first_details);
    let ((setup, maps, sky), views, exposure) = summary;
    let reused: Vec<f64> = views.iter().skip(1).map(|v| v.1).collect();
    let mean_reused = reused.iter().sum::<f64>() / reused.len().max(1) as f64;
    let doc = serde_json::json!({
        "method": method_name(args.method.into()),
        "views": views.iter().enumerate().map(|(k, (cam, s, stages))| serde_json::json!({
            "dir": format!("view_{k:03}"), "camera": cam, "frame_seconds": s,
            "maps_reused": k > 0, "seconds_per_stage": stages,
        })).collect::<Vec<_>>(),
        "seconds": {"setup_medium_phase_tables": setup, "light_maps_once": maps, "sky_table_once": sky,
                    "mean_frame_with_maps_reused": if reused.is_empty() { None } else { Some(mean_reused) }},
        "frames_per_second_with_maps_reused": (!reused.is_empty()).then(|| 1.0 / mean_reused.max(1e-9)),
        "exposure": exposure,
    });
    nephele::io::atomic::write_atomic(&out.join("views.json"), |w| {
        Ok(serde_json::to_writer_pretty(w, &doc)?)
    })?;
    let (w, h) = (scene.camera.width, scene.camera.height);
    let others = if reused.is_empty() {
        String::new()
    } else {
        format!(
            ", the others {} each ({:.1} frames/s with the maps reused)",
            super::seconds(mean_reused),
            1.0 / mean_reused.max(1e-9)
        )
    };
    outln!(
        "{n} views of {w}×{h} pixels, {}: light maps {} once, the first frame {}{others}; wrote \
         {}/view_000 … view_{:03}, views.json",
        method_name(args.method.into()),
        super::seconds(maps + sky),
        super::seconds(views[0].1),
        out.display(),
        n - 1
    );
    Ok(())
}

/// The collector search's statistics per order group, in words (render.json has the counts).
fn print_search_stats(groups: &serde_json::Value) {
    let Some(groups) = groups.as_array() else {
        return;
    };
    outln!(
        "  collector search per order group (shares of the pixels searched; docs/collector.md):"
    );
    let f = |g: &serde_json::Value, k: &str| g[k].as_f64().unwrap_or(0.0);
    for g in groups.iter().filter(|g| f(g, "searches") > 0.0) {
        let n = f(g, "searches");
        let pct = |k: &str| 100.0 * f(g, k) / n;
        outln!(
            "  orders {:>2}+: {:.2} table reads a pixel, {:.1} % converged; held at the tables' \
             edge: thickness {:.1} %, sun angle {:.1} %, depth {:.1} %; depth set by the medium \
             behind the view point {:.1} %; cut above it to its depth to the sun {:.1} %; no \
             lit surface found {:.1} % (of which dark {:.2} %)",
            g["first_order"],
            f(g, "reads") / (n - f(g, "empty")).max(1.0),
            pct("converged"),
            pct("clamped_thickness"),
            pct("clamped_mu_l"),
            pct("clamped_depth"),
            pct("held_by_view"),
            pct("held_by_sun"),
            pct("empty"),
            pct("dark"),
        );
    }
}

/// Transparent huge pages off for this process (Linux; best effort). A render faults in its
/// light maps and images (~140 MB) at once, and the kernel's 2-MB pages made that slow and
/// irregular: on a 2-core machine the maps took 0.47 s on one core with them and 0.33 s
/// without, and the whole 320 × 240 command 0.90–1.07 s against 0.93–0.96 s, with the frames
/// and the path tracer unchanged (docs/collector.md, "Frame cost").
fn no_transparent_huge_pages() {
    #[cfg(target_os = "linux")]
    // SAFETY: prctl with PR_SET_THP_DISABLE reads no memory; it only sets a flag of the process.
    unsafe {
        libc::prctl(libc::PR_SET_THP_DISABLE, 1, 0, 0, 0);
    }
}
