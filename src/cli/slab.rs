//! `nephele slab`: the canonical transport tables of a slab config.

use super::progress::Show;
use anyhow::{bail, Context, Result};
use clap::Args;
use nephele::phase::Phase;
use nephele::slab::checkpoint::Checkpoint;
use nephele::slab::output::write_tables;
use nephele::slab::tables::{merge, run_all, Control, SlabRun};
use nephele::slab::SlabConfig;
use serde_json::json;
use std::path::{Path, PathBuf};
use std::time::Instant;

/// Options of `nephele slab`.
#[derive(Args, Debug, Clone)]
pub struct SlabArgs {
    /// Slab config (JSON; keys in fit-configs/README.md): thicknesses, mu_l, planes, mu_v_bins,
    /// psi_v_bins, group_starts, phase, albedo, grazing_mu, aureole_deg, seed, stop.
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
    nephele::io::check_output_dir(&out)?;
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
    run_config_showing(cfg, out, (shard, save_every, plot), &Show::Own("slab"))
}

/// [`run_config`] with its progress shown by `show` (`nephele tables` shares one bar among its
/// steps).
pub(super) fn run_config_showing(
    cfg: &SlabConfig,
    out: &Path,
    (shard, save_every, plot): (Option<(usize, usize)>, f64, bool),
    show: &Show,
) -> Result<()> {
    if let Some(bytes) = nephele::io::available_memory() {
        cfg.check_memory(bytes)?;
    }
    let t0 = Instant::now();
    let shown = show.start();
    shown.set(None, "the phase function");
    let phase = Phase::build(&cfg.phase)?;
    let phase_s = t0.elapsed().as_secs_f64();
    let checkpoint = Checkpoint::open(&out.join("checkpoint"), cfg)?;
    let control = Control {
        shard,
        checkpoint: Some(&checkpoint),
        save_every_s: save_every,
    };
    let total = cfg.thicknesses.len() * cfg.mu_l.len();
    let t1 = Instant::now();
    shown.set(Some(0.0), "");
    let run = run_all(cfg, &phase, &control, &|slice, _, photons, worst| {
        // The bar moves within a slice, by the stopping test's estimate.
        let within = cfg.stop.fraction_done(photons, worst);
        let rate = photons as f64 / t1.elapsed().as_secs_f64().max(1e-9);
        let msg = format!(
            "slice {}/{total}: {photons} photons, worst rel. error {:.2} %, {:.2} M photons/s",
            slice + 1,
            100.0 * worst,
            rate / 1e6
        );
        shown.set(Some((slice as f64 + within) / total as f64), &msg);
    })?;
    let mc_s = t1.elapsed().as_secs_f64();
    if let Some((k, n)) = shard {
        drop(shown);
        summary(&run, mc_s);
        outln!(
            "shard {}/{n}: sums in {}; merge all shards with `nephele merge --config … SHARD_DIR…`",
            k + 1,
            out.join("checkpoint").display()
        );
        return Ok(());
    }
    let timings =
        json!({"phase_s": phase_s, "monte_carlo_s": mc_s, "threads": rayon::current_num_threads()});
    shown.set(Some(1.0), "writing the tables");
    write_tables(cfg, &run, Some(&phase), out, plot, timings)?;
    drop(shown);
    checkpoint.remove()?;
    summary(&run, mc_s);
    outln!("wrote {}/tables.npz, tables.json", out.display());
    Ok(())
}

/// Runs `nephele merge`.
pub fn merge_shards(args: MergeArgs) -> Result<()> {
    let cfg = load_config(&args.config)?;
    let spin = super::progress::spinner("merge", "reading the shards");
    let shards = args
        .shards
        .iter()
        .map(|d| Checkpoint::existing(&d.join("checkpoint"), &cfg))
        .collect::<Result<Vec<_>>>()?;
    let run = merge(&cfg, &shards)?;
    // The shards sampled this phase function; its table is stored with the tables where it
    // can be built here (else the compressor builds it from the config).
    spin.set_message("the phase function");
    let phase = Phase::build(&cfg.phase)
        .map_err(|e| {
            spin.suspend(|| {
                eprintln!("warning: the phase table is not stored with the tables: {e:#}")
            })
        })
        .ok();
    let out = args.out.unwrap_or_else(|| PathBuf::from("outputs/slab"));
    let seconds: f64 = run.done().map(|(r, _)| r.seconds).sum();
    let timings = json!({"monte_carlo_s_summed_over_shards": seconds, "shards": args.shards.len()});
    spin.set_message("writing the tables");
    write_tables(&cfg, &run, phase.as_ref(), &out, !args.no_plot, timings)?;
    spin.finish_and_clear();
    summary(&run, seconds);
    outln!(
        "merged {} shards into {}/tables.npz, tables.json",
        args.shards.len(),
        out.display()
    );
    Ok(())
}

fn summary(run: &SlabRun, seconds: f64) {
    outln!(
        "{:>8} {:>6} {:>12} {:>10} {:>10} {:>10} {:>10} {:>10}",
        "t",
        "mu_L",
        "photons",
        "R",
        "T",
        "worst se",
        "horizon",
        "converged"
    );
    for (r, _) in run.done() {
        outln!(
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
    outln!("{events} scattering events in {seconds:.1} s");
}
