//! `nephele slab`: the canonical transport tables of a slab config.

use anyhow::{bail, Context, Result};
use clap::Args;
use indicatif::{ProgressBar, ProgressStyle};
use nephele::io::plot::{panels_plot, Panel, Series, Style};
use nephele::io::{AtomicFiles, Npz};
use nephele::phase::Phase;
use nephele::slab::checkpoint::Checkpoint;
use nephele::slab::tables::{merge, run_all, Control, SlabRun};
use nephele::slab::SlabConfig;
use serde_json::json;
use std::path::{Path, PathBuf};
use std::time::Instant;

/// Options of `nephele slab`.
#[derive(Args, Debug, Clone)]
pub struct SlabArgs {
    /// Slab config (JSON; keys in fit-configs/README.md): thicknesses, mu_l, planes, mu_v_bins,
    /// psi_v_bins, group_starts, phase, albedo, seed, stop.
    #[arg(long, value_name = "FILE")]
    config: PathBuf,
    /// Output directory; its checkpoint/ subdirectory holds finished slices and the slice in
    /// progress, and a rerun resumes from it. [default: outputs/slab]
    #[arg(long, value_name = "DIR")]
    out: Option<PathBuf>,
    /// Run only the slices s with s mod N = K-1 ("K/N", 1 ≤ K ≤ N) and keep their sums in
    /// DIR/checkpoint for `nephele merge` (e.g. one Slurm array task per K).
    #[arg(long, value_name = "K/N")]
    shard: Option<String>,
    /// Least seconds between two checkpoints of the slice in progress.
    #[arg(long, value_name = "S", default_value_t = 30.0)]
    save_every: f64,
    /// Do not draw the figure.
    #[arg(long)]
    no_plot: bool,
}

/// Options of `nephele merge`.
#[derive(Args, Debug, Clone)]
pub struct MergeArgs {
    /// The slab config every shard ran.
    #[arg(long, value_name = "FILE")]
    config: PathBuf,
    /// Where the merged tables go. [default: outputs/slab]
    #[arg(long, value_name = "DIR")]
    out: Option<PathBuf>,
    /// The shards' output directories (`nephele slab --shard K/N --out DIR`).
    #[arg(value_name = "SHARD_DIR", required = true)]
    shards: Vec<PathBuf>,
    /// Do not draw the figure.
    #[arg(long)]
    no_plot: bool,
}

fn load_config(path: &Path) -> Result<SlabConfig> {
    let text = std::fs::read_to_string(path)
        .with_context(|| format!("cannot read config '{}'", path.display()))?;
    parse_config(&text, &path.display().to_string())
}

/// A slab config from its JSON text (`name` for messages), validated.
pub fn parse_config(text: &str, name: &str) -> Result<SlabConfig> {
    let cfg: SlabConfig = serde_json::from_str(text).with_context(|| format!("config '{name}'"))?;
    cfg.validate().with_context(|| format!("config '{name}'"))?;
    Ok(cfg)
}

fn parse_shard(s: &str) -> Result<(usize, usize)> {
    let parsed = s.split_once('/').and_then(|(k, n)| {
        Some((
            k.trim().parse::<usize>().ok()?,
            n.trim().parse::<usize>().ok()?,
        ))
    });
    match parsed {
        Some((k, n)) if 1 <= k && k <= n => Ok((k - 1, n)),
        _ => bail!("--shard '{s}' must be K/N with 1 ≤ K ≤ N"),
    }
}

/// Runs `nephele slab`.
pub fn run(args: SlabArgs) -> Result<()> {
    let cfg = load_config(&args.config)?;
    let shard = args.shard.as_deref().map(parse_shard).transpose()?;
    if !(args.save_every >= 0.0) {
        bail!("--save-every must be ≥ 0 seconds");
    }
    let out = args.out.unwrap_or_else(|| PathBuf::from("outputs/slab"));
    run_config(&cfg, &out, shard, args.save_every, !args.no_plot)
}

/// Runs the slab Monte Carlo of `cfg` into `out` (checkpointed there; one shard (K − 1, N) of
/// it, or all), then writes the tables (and the figure if `plot`).
pub fn run_config(
    cfg: &SlabConfig,
    out: &Path,
    shard: Option<(usize, usize)>,
    save_every: f64,
    plot: bool,
) -> Result<()> {
    let t0 = Instant::now();
    let phase = Phase::build(&cfg.phase)?;
    let phase_s = t0.elapsed().as_secs_f64();
    let checkpoint = Checkpoint::open(&out.join("checkpoint"), cfg)?;
    let control = Control {
        shard,
        checkpoint: Some(&checkpoint),
        save_every_s: save_every,
    };
    let total = cfg.thicknesses.len() * cfg.mu_l.len();
    let bar = ProgressBar::new(total as u64).with_style(
        ProgressStyle::with_template(
            "slab [{bar:30}] {pos}/{len} slices ({elapsed}, eta {eta}) {msg}",
        )
        .expect("static template"),
    );
    let t1 = Instant::now();
    let run = run_all(cfg, &phase, &control, &|slice, _, photons, worst| {
        bar.set_position(slice as u64);
        let rate = photons as f64 / t1.elapsed().as_secs_f64().max(1e-9);
        bar.set_message(format!(
            "slice {}: {photons} photons, worst rel. error {:.2} %, {:.2} M photons/s",
            slice + 1,
            100.0 * worst,
            rate / 1e6
        ));
    })?;
    bar.finish_and_clear();
    let mc_s = t1.elapsed().as_secs_f64();
    if let Some((k, n)) = shard {
        summary(&run, mc_s);
        println!(
            "shard {}/{n}: sums in {}; merge all shards with `nephele merge --config … SHARD_DIR…`",
            k + 1,
            out.join("checkpoint").display()
        );
        return Ok(());
    }
    let timings =
        json!({"phase_s": phase_s, "monte_carlo_s": mc_s, "threads": rayon::current_num_threads()});
    write_tables(cfg, &run, out, plot, timings)?;
    checkpoint.remove()?;
    summary(&run, mc_s);
    println!("wrote {}/tables.npz, tables.json", out.display());
    Ok(())
}

/// Runs `nephele merge`.
pub fn merge_shards(args: MergeArgs) -> Result<()> {
    let cfg = load_config(&args.config)?;
    let shards = args
        .shards
        .iter()
        .map(|d| Checkpoint::existing(&d.join("checkpoint"), &cfg))
        .collect::<Result<Vec<_>>>()?;
    let run = merge(&cfg, &shards)?;
    let out = args.out.unwrap_or_else(|| PathBuf::from("outputs/slab"));
    let seconds: f64 = run.done().map(|(r, _)| r.seconds).sum();
    let timings = json!({"monte_carlo_s_summed_over_shards": seconds, "shards": args.shards.len()});
    write_tables(&cfg, &run, &out, !args.no_plot, timings)?;
    summary(&run, seconds);
    println!(
        "merged {} shards into {}/tables.npz, tables.json",
        args.shards.len(),
        out.display()
    );
    Ok(())
}

fn write_tables(
    cfg: &SlabConfig,
    run: &SlabRun,
    out: &Path,
    plot: bool,
    timings: serde_json::Value,
) -> Result<()> {
    std::fs::create_dir_all(out).with_context(|| format!("cannot create '{}'", out.display()))?;
    let mut set = AtomicFiles::new();
    set.write(&out.join("tables.json"), |w| {
        serde_json::to_writer_pretty(&mut *w, &report(cfg, run, timings))?;
        Ok(())
    })?;
    set.write(&out.join("tables.npz"), |w| arrays(cfg, run).write_to(w))?;
    if plot {
        set.write_via_path(&out.join("slab.png"), |p| figure(p, cfg, run))?;
    }
    set.commit()
}

fn report(cfg: &SlabConfig, run: &SlabRun, timings: serde_json::Value) -> serde_json::Value {
    let slices: Vec<_> = run.done().map(|(r, _)| r).collect();
    json!({
        "version": nephele::VERSION,
        "git_commit": option_env!("NEPHELE_GIT_COMMIT"),
        "config": cfg,
        "seed": cfg.seed,
        "shape": "[group, t, mu_L, depth, mu_V, psi_V]",
        "units": {"T": "L / E_perp (1/sr), E_perp the sun's irradiance on a surface facing it", "cx, cz, sigma": "mean free paths; c = collector entry point minus the viewpoint's projection, z along the sun's horizontal travel, x across", "flux_up, flux_down": "diffuse flux / E_perp"},
        "photons": slices.iter().map(|s| s.photons).sum::<u64>(),
        "events": slices.iter().map(|s| s.events).sum::<u64>(),
        "converged_slices": slices.iter().filter(|s| s.converged).count(),
        "slices": slices,
        "timings": timings,
    })
}

/// The 5D tables and their grids.
fn arrays(cfg: &SlabConfig, run: &SlabRun) -> Npz {
    let (nt, nl, np) = (cfg.thicknesses.len(), cfg.mu_l.len(), cfg.planes);
    let (ng, nm, nk) = (cfg.group_starts.len(), cfg.mu_v_bins, cfg.psi_v_bins);
    let n = ng * nt * nl * np * nm * nk;
    let names = [
        "T", "T_se", "cx", "cx_se", "cz", "cz_se", "sigma", "sigma_se",
    ];
    let mut out: Vec<Vec<f64>> = vec![vec![f64::NAN; n]; names.len()];
    let mut flux = [
        vec![0.0; nt * nl * np],
        vec![0.0; nt * nl * np],
        vec![0.0; nt * nl * np],
        vec![0.0; nt * nl * np],
    ];
    for (s, (report, slice)) in run
        .slices
        .iter()
        .enumerate()
        .filter_map(|(s, x)| Some((s, x.as_ref()?)))
    {
        let (it, il) = (s / nl, s % nl);
        let grid = cfg.grid(report.t).expect("validated");
        let t = &slice.tables;
        let src = [
            &t.t,
            &t.t_se,
            &t.cx,
            &t.cx_se,
            &t.cz,
            &t.cz_se,
            &t.sigma,
            &t.sigma_se,
        ];
        for c in 0..grid.n_cells() {
            let (g, j, m, k) = grid.cell_parts(c);
            let at = ((((g * nt + it) * nl + il) * np + j) * nm + m) * nk + k;
            for (dst, v) in out.iter_mut().zip(src) {
                dst[at] = v[c];
            }
        }
        let tot = &slice.acc.total;
        let per = report.mu_l / tot.photons as f64;
        for j in 0..np {
            let at = (it * nl + il) * np + j;
            flux[0][at] = per * tot.up[j];
            flux[1][at] = per * tot.down[j];
            flux[2][at] = (-run.depths[it][j] / report.mu_l).exp();
            flux[3][at] = tot.direct[j] / tot.photons as f64;
        }
    }
    let mut z = Npz::new();
    let shape = [ng, nt, nl, np, nm, nk];
    for (name, data) in names.iter().zip(&out) {
        z.add(name, &shape, data);
    }
    z.add("flux_up", &[nt, nl, np], &flux[0]);
    z.add("flux_down", &[nt, nl, np], &flux[1]);
    z.add("direct", &[nt, nl, np], &flux[2]);
    z.add("direct_mc", &[nt, nl, np], &flux[3]);
    z.add("thickness", &[nt], &cfg.thicknesses);
    z.add("mu_l", &[nl], &cfg.mu_l);
    z.add("depth", &[nt, np], &run.depths.concat());
    let grid = cfg.grid(cfg.thicknesses[0]).expect("validated");
    z.add("mu_v_edges", &[nm + 1], &grid.mu_edges);
    z.add("psi_v_edges", &[nk + 1], &grid.psi_edges);
    let groups = cfg.groups();
    let first: Vec<f64> = groups.iter().map(|g| g.0 as f64).collect();
    let last: Vec<f64> = groups
        .iter()
        .map(|g| {
            if g.1 == u32::MAX {
                f64::INFINITY
            } else {
                g.1 as f64
            }
        })
        .collect();
    z.add("group_first", &[ng], &first);
    z.add("group_last", &[ng], &last);
    z
}

/// T (up and down), c_z and σ against depth per order group, for the slice nearest t = 8,
/// μ_L = 0.5, in the view bins nearest straight up / down and ψ_V = 0.
fn figure(path: &Path, cfg: &SlabConfig, run: &SlabRun) -> Result<()> {
    let nearest = |v: &[f64], x: f64| {
        (0..v.len())
            .min_by(|&a, &b| (v[a] - x).abs().total_cmp(&(v[b] - x).abs()))
            .unwrap_or(0)
    };
    let (it, il) = (nearest(&cfg.thicknesses, 8.0), nearest(&cfg.mu_l, 0.5));
    let (report, slice) = run.slices[it * cfg.mu_l.len() + il]
        .as_ref()
        .context("slice not run")?;
    let grid = cfg.grid(report.t)?;
    let d = &grid.depths;
    let (up, down) = (grid.n_mu() - 1, 0);
    let label = |g: usize| {
        let (a, b) = grid.groups[g];
        match (a, b) {
            (a, u32::MAX) => format!("orders ≥ {a}"),
            (a, b) if a == b => format!("order {a}"),
            (a, b) => format!("orders {a}–{b}"),
        }
    };
    let column = |v: &[f64], g: usize, m: usize| -> Vec<f64> {
        (0..d.len()).map(|j| v[grid.cell(g, j, m, 0)]).collect()
    };
    let t = &slice.tables;
    let data: Vec<Vec<(String, Vec<f64>)>> =
        [(&t.t, up), (&t.t, down), (&t.cz, down), (&t.sigma, down)]
            .iter()
            .map(|(v, m)| {
                (0..grid.groups.len())
                    .map(|g| (label(g), column(v, g, *m)))
                    .collect()
            })
            .collect();
    let titles = [
        format!(
            "T, light going up (μ_V bin nearest 1), t = {}, μ_L = {}",
            report.t, report.mu_l
        ),
        "T, light going down (μ_V bin nearest −1)".to_string(),
        "collector mean c_z, light going down".to_string(),
        "collector width σ, light going down".to_string(),
    ];
    let y_labels = ["T = L/E⊥ (1/sr)", "T = L/E⊥ (1/sr)", "c_z (mfp)", "σ (mfp)"];
    let panels: Vec<Panel> = data
        .iter()
        .enumerate()
        .map(|(i, series)| Panel {
            title: titles[i].clone(),
            x_label: "depth d (mfp)".into(),
            y_label: y_labels[i].into(),
            log_y: i < 2,
            log_x: false,
            series: series
                .iter()
                .enumerate()
                .map(|(g, (l, y))| Series {
                    label: l.clone(),
                    x: d,
                    y,
                    style: Style::Line,
                    colour: g + 1,
                })
                .collect(),
        })
        .collect();
    panels_plot(path, (1600, 1200), 2, &panels)
}

fn summary(run: &SlabRun, seconds: f64) {
    println!(
        "{:>8} {:>6} {:>12} {:>10} {:>10} {:>10} {:>10} {:>10}",
        "t", "mu_L", "photons", "R", "T", "worst se", "horizon", "converged"
    );
    for (r, _) in run.done() {
        println!(
            "{:>8} {:>6} {:>12} {:>10.5} {:>10.5} {:>9.2}% {:>9.2}% {:>10}",
            r.t,
            r.mu_l,
            r.photons,
            r.reflected,
            r.transmitted,
            100.0 * r.worst_rel_se,
            100.0 * r.worst_rel_se_horizon,
            r.converged
        );
    }
    let events: u64 = run.done().map(|(r, _)| r.events).sum();
    println!("{events} scattering events in {seconds:.1} s");
}
