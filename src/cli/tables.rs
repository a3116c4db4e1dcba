//! `nephele tables`: transport tables for another droplet size in one command — the slab Monte
//! Carlo of Mie droplets of diameter D on a preset grid, then its compression — ready for
//! `nephele render --method collector --tables DIR` (docs/tutorial.md).

use super::{compress as compress_cli, slab};
use anyhow::{Context, Result};
use clap::{Args, ValueEnum};
use nephele::compress::run::Options;
use nephele::render::scene::Scene;
use std::path::{Path, PathBuf};
use std::time::Instant;

/// Options of `nephele tables`.
#[derive(Args, Debug)]
pub struct TablesArgs {
    /// Median droplet diameter (µm) of the paper's setup: water, lognormal σ = 0.25,
    /// 400–700 nm (the shipped tables: 10).
    #[arg(long, value_name = "MICRONS", value_parser = super::positive_f64)]
    pub diameter: f64,
    /// The slab grid: quick (t = 1…16 mfp, 4 sun cosines; about a minute on 2 cores) or
    /// default (t = 0.5…128 mfp, 8 sun cosines, the shipped tables' grid; about 20 minutes).
    #[arg(long, value_enum, default_value = "quick")]
    pub grid: GridPreset,
    /// A scene the tables are for: warns when it is optically thicker than the grid's
    /// thickest slab (the collector then holds its searches there).
    #[arg(long, value_name = "FILE")]
    pub scene: Option<PathBuf>,
    /// Output folder: the compressed tables (transport.ntt, manifest.json, report.json) at
    /// its top, for `--tables DIR`; the slab run in DIR/slab (checkpointed: a rerun resumes).
    #[arg(long)]
    pub out: PathBuf,
}

/// The slab grids `nephele tables` offers.
#[derive(Clone, Copy, Debug, PartialEq, Eq, ValueEnum)]
pub enum GridPreset {
    /// fit-configs/slab-pipeline.json's grid.
    Quick,
    /// fit-configs/slab-default.json's grid, the shipped tables'.
    Default,
}

impl GridPreset {
    /// The preset's config text, its name, and the minutes it took for 10 µm droplets on the
    /// 2-core reference machine (Mie, slab and compression).
    fn config(self) -> (&'static str, &'static str, f64) {
        match self {
            Self::Quick => (
                include_str!("../../fit-configs/slab-pipeline.json"),
                "fit-configs/slab-pipeline.json",
                1.0,
            ),
            Self::Default => (
                include_str!("../../fit-configs/slab-default.json"),
                "fit-configs/slab-default.json",
                20.0,
            ),
        }
    }
}

impl GridPreset {
    /// The slab's share of the command's time (the rest is the compression's), as measured for
    /// 10 µm droplets on 2 cores.
    fn slab_share(self) -> f64 {
        match self {
            Self::Quick => 0.8,
            Self::Default => 0.92,
        }
    }
}

/// Runs `nephele tables`.
pub fn run(a: TablesArgs) -> Result<()> {
    let d = a.diameter;
    let (text, name, minutes) = a.grid.config();
    let mut cfg = slab::parse_config(text, name)?;
    cfg.phase = nephele::phase::PhaseSpec::Mie {
        diameter_um: d,
        rgb: false,
    };
    cfg.description = describe(&cfg.description, d);
    cfg.validate()
        .with_context(|| format!("--diameter {d} (µm)"))?;
    let t_max = cfg.thicknesses.iter().copied().fold(0.0, f64::max);
    if let Some(path) = &a.scene {
        if let Some(w) = thicker_than_grid(&Scene::load(path)?, path, t_max, a.grid) {
            eprintln!("warning: {w}");
        }
    }
    nephele::io::check_output_dir(&a.out)?;
    let threads = rayon::current_num_threads();
    eprintln!(
        "tables for d = {d} µm on the {} grid ({name}: t ≤ {t_max} mfp, {} sun cosines) → {}; \
         about {} on {threads} threads (measured {minutes:.0} min for 10 µm on 2 cores; the \
         Mie step grows with the diameter and is cached in ~/.cache/nephele)",
        a.grid
            .to_possible_value()
            .map_or("?".into(), |v| v.get_name().to_string()),
        cfg.mu_l.len(),
        a.out.display(),
        duration(60.0 * minutes * 2.0 / threads as f64),
    );
    let t0 = Instant::now();
    let slab_dir = a.out.join("slab");
    eprintln!(
        "steps: 1/2 the Mie phase function and the slab Monte Carlo → {}; 2/2 the compression \
         → {}",
        slab_dir.display(),
        a.out.display()
    );
    // One bar for both steps, shared by their measured times (the slab's, 10 µm, 2 cores).
    let bar = super::progress::work_bar("tables", 1000);
    let slab_share = (1000.0 * a.grid.slab_share()) as u64;
    let show = |span, step| super::progress::Show::Share {
        bar: &bar,
        span,
        step,
    };
    slab::run_config_showing(
        &cfg,
        &slab_dir,
        (None, 30.0, true),
        &show((0, slab_share), "1/2 slab"),
    )?;
    // The quick grid is too coarse to leave two thicknesses and two sun cosines out of it.
    let opt = Options {
        held_out: a.grid == GridPreset::Default,
        ..Options::default()
    };
    let tables = slab_dir.join("tables.npz");
    let step = show((slab_share, 1000), "2/2 compression");
    let o = compress_cli::compress_showing(&tables, &a.out, &opt, &step)?;
    bar.finish_and_clear();
    compress_cli::print_outcome(&o, &a.out);
    outln!(
        "tables for d = {d} µm written to {} in {}: render with `nephele render --method \
         collector --tables {}` and a scene whose phase is {{\"kind\": \"mie\", \"diameter_um\": \
         {d}}}",
        a.out.display(),
        super::seconds(t0.elapsed().as_secs_f64()),
        a.out.display()
    );
    Ok(())
}

/// "45 s", "3 min".
fn duration(s: f64) -> String {
    if s < 90.0 {
        format!("{s:.0} s")
    } else {
        format!("{:.0} min", s / 60.0)
    }
}

/// The preset's description with its droplet size replaced by `d`.
fn describe(preset: &str, d: f64) -> String {
    let named = preset.replace("d = 10 um", &format!("d = {d} um"));
    format!("{named} Made by `nephele tables --diameter {d}`.")
}

/// A warning when `scene` is optically thicker than the grid's thickest slab `t_max` (mfp).
fn thicker_than_grid(scene: &Scene, path: &Path, t_max: f64, grid: GridPreset) -> Option<String> {
    let tau = scene.optical_size();
    if tau <= t_max {
        return None;
    }
    let wider = match grid {
        GridPreset::Quick => "; --grid default reaches 128 mfp",
        GridPreset::Default => "",
    };
    Some(format!(
        "the scene '{}' is up to {tau:.0} mean free paths across (sigma_t × its extent) and the \
         grid's thickest slab is {t_max} mfp: the collector holds its searches there, and \
         render.json counts them{wider}",
        path.display()
    ))
}
