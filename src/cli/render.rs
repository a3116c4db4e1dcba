//! `nephele render`: renders a scene with the ground-truth path tracer.

use anyhow::Result;
use clap::Args;
use indicatif::{ProgressBar, ProgressStyle};
use nephele::render::output::write_outputs;
use nephele::render::run::render;
use nephele::render::scene::Scene;
use std::path::PathBuf;

/// Options of `nephele render`.
#[derive(Args, Debug)]
pub struct RenderArgs {
    /// Scene (JSON; keys in fit-configs/scenes/README.md).
    #[arg(long, value_name = "FILE")]
    pub scene: PathBuf,
    /// Output directory: beauty.png, beauty.exr, beauty.npy, groups.npy, unscattered.npy,
    /// transmittance.npy, opacity.npy, render.json. [default: outputs/render]
    #[arg(long, value_name = "DIR")]
    pub out: Option<PathBuf>,
    /// Samples per pixel, overriding the scene's (per pass with a time budget).
    #[arg(long)]
    pub spp: Option<u32>,
    /// Wall-clock budget in seconds, overriding the scene's: passes of spp samples per pixel
    /// while the next one fits.
    #[arg(long, value_name = "SECONDS")]
    pub time_budget: Option<f64>,
    /// Most steps of the sun-lobe walks and directions of their MIS window (variance reduction
    /// for forward peaks, docs/render.md), overriding the scene's (default 16): 0 is plain
    /// next-event estimation, up to 32.
    #[arg(long, value_name = "K")]
    pub sun_lobe_steps: Option<usize>,
}

/// Runs `nephele render`.
pub fn run(args: RenderArgs) -> Result<()> {
    let mut scene = Scene::load(&args.scene)?;
    if let Some(spp) = args.spp {
        scene.spp = spp;
    }
    if let Some(budget) = args.time_budget {
        scene.time_budget_s = Some(budget);
    }
    if let Some(k) = args.sun_lobe_steps {
        scene.sun_lobe_steps = k;
    }
    scene.validate()?;
    let out = args.out.unwrap_or_else(|| PathBuf::from("outputs/render"));
    let bar = ProgressBar::new(1000).with_style(
        ProgressStyle::with_template("render [{bar:30}] {percent:>3}% ({elapsed}, eta {eta})")
            .expect("static template"),
    );
    let r = render(&scene, &|done| bar.set_position((done * 1000.0) as u64))?;
    bar.finish_and_clear();
    write_outputs(&out, &scene, &r)?;
    println!(
        "{}×{} pixels, {} spp: {} camera paths in {:.1} s ({:.0} paths/s); wrote {}/beauty.png, \
         beauty.exr, beauty.npy, groups.npy, unscattered.npy, transmittance.npy, opacity.npy, \
         render.json",
        r.width,
        r.height,
        r.spp,
        r.paths,
        r.seconds,
        r.paths as f64 / r.seconds.max(1e-9),
        out.display()
    );
    Ok(())
}
