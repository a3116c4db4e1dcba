//! The main job (`nephele` without a subcommand, `cargo run --release`): the whole pipeline on
//! built-in configs — Mie tables and phase-model fits of the paper's setup, then the slab Monte
//! Carlo of 10 µm droplets (a quick preset, or the default tables with `--full`), then their
//! compression to the runtime's transport tables, then the ground-truth render of the default
//! cloud (fit-configs/scenes/cloud.json) — with a summary at the end.

use super::{compress as compress_cli, fit, slab};
use anyhow::Result;
use nephele::compress::run::{compress, Options};
use nephele::render::output::write_outputs;
use nephele::render::run::render;
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
    let t0 = Instant::now();
    fit::run_main_job()?;
    let fit_s = t0.elapsed().as_secs_f64();
    let (text, name, slab_out, comp_out) = preset(full);
    let cfg = slab::parse_config(text, name)?;
    eprintln!(
        "slab Monte Carlo ({name}{}) → {slab_out}",
        if full {
            ", ~17 min on 2 cores"
        } else {
            "; `-- --full` for the default tables"
        }
    );
    let t1 = Instant::now();
    slab::run_config(&cfg, Path::new(slab_out), None, 30.0, true)?;
    let slab_s = t1.elapsed().as_secs_f64();
    eprintln!("compression → {comp_out}");
    let t2 = Instant::now();
    // The quick grid is too coarse to leave two thicknesses and two sun cosines out of it.
    let opt = Options {
        held_out: full,
        ..Options::default()
    };
    let tables = Path::new(slab_out).join("tables.npz");
    let o = compress(&tables, Path::new(comp_out), &opt)?;
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
        "render of fit-configs/scenes/cloud.json → {}",
        render_out.display()
    );
    let scene = Scene::parse(include_str!("../../fit-configs/scenes/cloud.json"))?;
    let r = render(&scene, &|_| {})?;
    write_outputs(render_out, &scene, &r)?;
    println!(
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
    Ok(())
}
