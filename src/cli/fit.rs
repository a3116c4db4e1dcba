//! `nephele fit`: Mie tables for a config's diameters, then every model fitted to them.

use super::mie::{compute_with_bar, write_outputs as write_mie, MieArgs};
use anyhow::{Context, Result};
use clap::Args;
use nephele::fit::output::write_fits;
use nephele::fit::{figures, run::FitReport, FitConfig};
use nephele::mie::PhaseTable;
use serde::{Deserialize, Serialize};
use serde_json::json;
use std::path::{Path, PathBuf};
use std::time::Instant;

/// Options of `nephele fit`.
#[derive(Args, Debug, Clone)]
pub struct FitArgs {
    /// Fit config (JSON): {"description": …, "mie": {keys of `nephele mie --config`},
    /// "fit": {"models", "loss", "alpha_max", "curves", "figure_diameters_um"}}; see
    /// fit-configs/README.md.
    #[arg(long, value_name = "FILE")]
    config: PathBuf,
    /// Output directory. [default: outputs/fit]
    #[arg(long, value_name = "DIR")]
    out: Option<PathBuf>,
    /// Do not draw the figures.
    #[arg(long)]
    no_plot: bool,
}

/// A fit config file.
#[derive(Debug, Clone, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct FitFile {
    /// Free text.
    #[serde(default)]
    description: String,
    /// The Mie tables: the keys of `nephele mie --config` (diameter list/range, sigma, …).
    mie: MieArgs,
    /// What to fit.
    #[serde(default)]
    fit: FitConfig,
}

impl FitFile {
    /// Reads and validates a config file.
    pub fn load(path: &Path) -> Result<Self> {
        let text = std::fs::read_to_string(path)
            .with_context(|| format!("cannot read config '{}'", path.display()))?;
        let file: FitFile =
            serde_json::from_str(&text).with_context(|| format!("config '{}'", path.display()))?;
        file.fit
            .validate()
            .with_context(|| format!("config '{}'", path.display()))?;
        let job = file
            .mie
            .job()
            .with_context(|| format!("config '{}': mie", path.display()))?;
        let diameters: Vec<f64> = job
            .distributions
            .iter()
            .map(|d| d.nominal_diameter_um())
            .collect();
        file.fit
            .check_branches(&diameters)
            .with_context(|| format!("config '{}'", path.display()))?;
        Ok(file)
    }
}

/// Runs `nephele fit`.
pub fn run(args: FitArgs) -> Result<()> {
    let file = FitFile::load(&args.config)?;
    let out = args.out.unwrap_or_else(|| PathBuf::from("outputs/fit"));
    nephele::io::check_output_dir(&out)?;
    let mie_out = out.join("mie");
    run_file(&file, &out, &mie_out, !args.no_plot)
}

/// The main job: Mie + fits of fit-configs/paper.json (embedded) into outputs/fit, and the Mie
/// tables at the figure diameters (5, 10, 20, 50 µm) into outputs/mie.
pub fn run_main_job() -> Result<()> {
    let text = include_str!("../../fit-configs/paper.json");
    let file: FitFile = serde_json::from_str(text).context("embedded fit-configs/paper.json")?;
    file.fit.validate()?;
    eprintln!(
        "step 1: the paper's setup (water n = 1.333, σ = 0.25, 400–700 nm), d = 5…50 µm: Mie \
         tables, then HG, two-term HG, Cornette–Shanks, Draine and HG+Draine fits"
    );
    run_file(
        &file,
        Path::new("outputs/fit"),
        Path::new("outputs/mie"),
        true,
    )
}

fn run_file(file: &FitFile, out: &Path, mie_out: &Path, plot: bool) -> Result<()> {
    let job = file.mie.job()?;
    let t0 = Instant::now();
    let (tables, stats, mie_s) = compute_with_bar(&job)?;
    let t1 = Instant::now();
    let bar = super::progress::work_bar("fit", 0);
    let (report, _targets) = nephele::fit::run(&file.fit, &tables, &|done, total| {
        bar.set_length(total as u64);
        bar.set_position(done as u64);
        bar.set_message(format!("{done}/{total} fits"));
    })?;
    bar.finish_and_clear();
    let fit_s = t1.elapsed().as_secs_f64();
    let t2 = Instant::now();
    let timings =
        json!({ "mie_s": mie_s, "fit_s": fit_s, "threads": rayon::current_num_threads() });
    let config = serde_json::to_value(file)?;
    let spin = super::progress::spinner("fit", "writing the fits and figures");
    write_fits(&config, &file.fit, &tables, &report, timings, out, plot)?;
    // The Mie tables of the figure diameters, as `nephele mie` writes them.
    let mut shown: Vec<PhaseTable> = Vec::new();
    for &d in &file.fit.figure_diameters_um {
        let i = figures::nearest(&report, d);
        if !shown
            .iter()
            .any(|t| t.distribution == tables[i].distribution)
        {
            shown.push(tables[i].clone());
        }
    }
    write_mie(&job, &file.mie, &shown, &stats, mie_s, mie_out)?;
    spin.finish_and_clear();
    print_summary(&report, &file.fit, out);
    eprintln!(
        "Mie {mie_s:.1} s, fits {fit_s:.1} s, writing {:.1} s; total {:.1} s",
        t2.elapsed().as_secs_f64(),
        t0.elapsed().as_secs_f64()
    );
    Ok(())
}

fn print_summary(report: &FitReport, cfg: &FitConfig, out: &Path) {
    let models = cfg.models().unwrap_or_default();
    let mut head = format!("{:>8}", "d (µm)");
    for m in &models {
        head += &format!(" {:>12}", m.label());
    }
    head += &format!(" {:>12} {:>12}", "paper curve", "our curve");
    outln!("{head}");
    // One screen: about ten rows (every row is in fits.json).
    let stride = report.fits.len().div_ceil(10).max(1);
    let last = report.fits.len() - 1;
    for (i, f) in report.fits.iter().enumerate() {
        if i % stride != 0 && i != last {
            continue;
        }
        let mut row = format!("{:>8.3}", f.d_um);
        for m in &models {
            let o = &f.models[&m.json_name()].optimum;
            row += &format!(" {:>11.4e}{}", o.loss, if o.converged { ' ' } else { '*' });
        }
        let ours = report
            .branches
            .iter()
            .flat_map(|b| b.points.iter())
            .find(|p| p.d_um == report.diameters_um[i])
            .map_or("-".to_string(), |p| format!("{:.4e}", p.loss_curve));
        row += &format!(" {:>12.4e} {:>12}", f.paper.loss, ours);
        outln!("{row}");
    }
    let not_converged: usize = report
        .fits
        .iter()
        .flat_map(|f| f.models.values())
        .filter(|m| !m.optimum.converged)
        .count();
    outln!(
        "loss per model at its per-diameter optimum ({} marked * did not meet the convergence test); \
         warm-start sweeps: {}, optima improved by them: {}",
        not_converged, report.sweeps, report.improved_by_warm_starts
    );
    for b in &report.branches {
        let worst = b
            .points
            .iter()
            .map(|p| p.extra_loss_relative)
            .fold(0.0, f64::max);
        outln!(
            "curves {:?} µm: loss ≤ the paper's curves at {}/{} diameters; largest extra loss over the optimum {:.1}%",
            b.range_um,
            b.curve_beats_paper[0],
            b.curve_beats_paper[1],
            100.0 * worst
        );
        for (name, c) in &b.curves {
            outln!("  {name:>6}(d) = {}", c.expression);
        }
    }
    outln!("wrote {}/fits.json, fits.npz and figures", out.display());
}
