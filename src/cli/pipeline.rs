//! The main job (`nephele` without a subcommand, `cargo run --release`): the whole pipeline on
//! built-in configs — Mie tables and phase-model fits of the paper's setup, then the slab Monte
//! Carlo of 10 µm droplets (a quick preset, or the default tables with `--full`), then their
//! compression to the runtime's transport tables, then the ground-truth render of the default
//! cloud (fit-configs/scenes/cloud.json), the same cloud by the collector renderer on the
//! shipped tables and their comparison — with a summary at the end.

use super::{compress as compress_cli, fit, slab};
use anyhow::Result;
use nephele::compress::run::Options;
use nephele::render::compare::compare;
use nephele::render::fast::{render_fast, FastOptions};
use nephele::render::output::write_outputs;
use nephele::render::path::{render, Settings};
use nephele::render::scene::Scene;
use std::path::Path;
use std::time::Instant;

/// The slab preset of the main job: (config text, its name, tables dir, compressed dir).
fn preset(full: bool) -> (&'static str, &'static str, &'static str, &'static str) {
    if full {
        (
            include_str!("../../fit-configs/slab-default.json"),
            "fit-configs/slab-default.json",
            "outputs/slab",
            "outputs/transport/mie10um",
        )
    } else {
        (
            include_str!("../../fit-configs/slab-pipeline.json"),
            "fit-configs/slab-pipeline.json",
            "outputs/slab-quick",
            "outputs/transport/quick",
        )
    }
}

/// Runs the main job.
pub fn run(full: bool) -> Result<()> {
    announce(full);
    let t0 = Instant::now();
    fit::run_main_job()?;
    let fit_s = t0.elapsed().as_secs_f64();
    let (text, name, slab_out, comp_out) = preset(full);
    let cfg = slab::parse_config(text, name)?;
    eprintln!(
        "step 2: slab Monte Carlo ({name}{}) → {slab_out}",
        if full {
            ", ~17 min on 2 cores"
        } else {
            "; `-- --full` for the default tables"
        }
    );
    let t1 = Instant::now();
    slab::run_config(&cfg, Path::new(slab_out), None, 30.0, true)?;
    let slab_s = t1.elapsed().as_secs_f64();
    eprintln!("step 2: compression → {comp_out}");
    let t2 = Instant::now();
    // The quick grid is too coarse to leave two thicknesses and two sun cosines out of it.
    let opt = Options {
        held_out: full,
        ..Options::default()
    };
    let tables = Path::new(slab_out).join("tables.npz");
    let o = compress_cli::compress_with_spinner(&tables, Path::new(comp_out), &opt)?;
    compress_cli::print_outcome(&o, Path::new(comp_out));
    let comp_s = t2.elapsed().as_secs_f64();
    if full {
        eprintln!(
            "to ship these tables (nephele_runtime::embedded), copy transport.ntt, manifest.json, \
             report.json and domain_check.npz from {comp_out} into runtime/tables/mie10um/"
        );
    }
    let sum = o.errors.last().map_or(f64::NAN, |e| e.rel_rms);
    let render_out = Path::new("outputs/render/cloud");
    eprintln!(
        "step 3: render of fit-configs/scenes/cloud.json → {}",
        render_out.display()
    );
    let file = include_str!("../../fit-configs/scenes/cloud.json");
    let (scene, settings) = (Scene::parse(file)?, Settings::parse(file)?);
    let bar = super::progress::work_bar("render", 1000);
    let r = render(&scene, &settings, &|done| {
        bar.set_position((done * 1000.0) as u64)
    })?;
    bar.finish_and_clear();
    write_outputs(render_out, &scene, &r)?;
    let headline = collector_beside(&scene, render_out)?;
    outln!(
        "\nmain job done in {:.0} s: Mie + fits {fit_s:.0} s → outputs/fit, outputs/mie; slab {slab_s:.0} s \
         → {slab_out}; compression {comp_s:.0} s → {comp_out} (sum of groups ≥ 2 within {:.1} % \
         T-weighted RMS of the tables{}); render {:.0} s ({} spp) → {}/beauty.png",
        t0.elapsed().as_secs_f64(),
        100.0 * sum,
        o.ntt
            .as_ref()
            .map_or(String::new(), |n| format!("; transport.ntt {:.0} KB", n.bytes as f64 / 1024.0)),
        r.seconds,
        r.spp,
        render_out.display(),
    );
    outln!("{headline}");
    Ok(())
}

/// What the main job is about to do, and where, before any of it is spent.
fn announce(full: bool) {
    let (_, name, slab_out, comp_out) = preset(full);
    let here = std::env::current_dir().map_or("the current folder".into(), |d| {
        format!("'{}'", d.join("outputs").display())
    });
    eprintln!(
        "nephele {}: the main job ({}; `nephele --help` lists the commands), writing into {here}:\n\
         \x20 1. Mie tables and phase-model fits of the paper's setup → outputs/mie, outputs/fit\n\
         \x20 2. slab tables of 10 µm droplets ({name}) → {slab_out}, compressed → {comp_out}\n\
         \x20 3. the default cloud path-traced → outputs/render/cloud, by the collector → \
         outputs/render/cloud-collector, compared → outputs/compare/cloud",
        nephele::VERSION,
        if full { "about 20 min on 2 cores" } else { "about 2 min on 2 cores" }
    );
}

/// The default cloud by the collector renderer (the shipped tables) beside its path-traced
/// render in `reference`, compared: the headline numbers.
fn collector_beside(scene: &Scene, reference: &Path) -> Result<String> {
    let out = Path::new("outputs/render/cloud-collector");
    let cmp = Path::new("outputs/compare/cloud");
    eprintln!(
        "collector render → {}; comparison → {}",
        out.display(),
        cmp.display()
    );
    let tables = nephele_runtime::embedded::mie_10um();
    let c = render_fast(scene, &tables, &FastOptions::default(), &|_| {})?;
    write_outputs(out, scene, &c)?;
    let report = compare(reference, &[out.to_path_buf()], cmp)?;
    let cand = &report.candidates[0];
    let stat = |name: &str| {
        cand.quantities
            .iter()
            .find(|q| q.quantity == name)
            .and_then(|q| q.regions.get("opaque"))
    };
    let (Some(ms), Some(o1), Some(b)) = (stat("orders >= 2"), stat("order 1"), stat("beauty"))
    else {
        anyhow::bail!("the comparison has no opaque pixels");
    };
    Ok(format!(
        "collector renderer: {:.2} s a frame vs the path tracer's {:.0} s; over opaque pixels, \
         orders ≥ 2 bias {:+.1} %, relative RMSE {:.1} % (the reference's own noise {:.1} %, \
         corrected {:.1} %), order 1 bias {:+.1} %, beauty bias {:+.1} %, PSNR {:.1} dB; {} → \
         {}/panel.png, report.json (docs/collector.md)",
        c.seconds,
        report.reference_seconds,
        100.0 * ms.bias,
        100.0 * ms.rel_rmse,
        100.0 * ms.reference_noise,
        100.0 * ms.rel_rmse_corrected,
        100.0 * o1.bias,
        100.0 * b.bias,
        cand.psnr_db,
        super::compare::worth(cand.equal_quality.as_ref()),
        cmp.display()
    ))
}
