//! A whole slab run: every slice (t, μ_L) of a config, one after the other (each parallel over
//! its batches), gathered into the 5D tables with shape
//! [group, t, μ_L, depth, μ_V, ψ_V].

use super::checkpoint::Checkpoint;
use super::config::SlabConfig;
use super::grid::SlabGrid;
use super::run::{run_slice_from, SliceReport, SliceRun};
use super::tally::Accumulator;
use super::walk::Slice;
use crate::phase::Phase;
use anyhow::{Context, Result};
use std::time::Instant;

/// The results of every slice, in (t, μ_L) order (`None`: another shard's).
pub struct SlabRun {
    /// Per slice: its report and its run.
    pub slices: Vec<Option<(SliceReport, SliceRun)>>,
    /// Depth planes per thickness.
    pub depths: Vec<Vec<f64>>,
}

impl SlabRun {
    /// The slices this run holds.
    pub fn done(&self) -> impl Iterator<Item = &(SliceReport, SliceRun)> {
        self.slices.iter().flatten()
    }
}

/// How a run is split and made safe to interrupt.
pub struct Control<'a> {
    /// Run only slices s with s mod n = k: `Some((k, n))`.
    pub shard: Option<(usize, usize)>,
    /// Where finished slices and the slice in progress are saved (and resumed from).
    pub checkpoint: Option<&'a Checkpoint>,
    /// Least seconds between two saves of the slice in progress.
    pub save_every_s: f64,
}

/// Runs the slices of `cfg` (this shard's, resuming from the checkpoint if any);
/// `progress(slice, slices, photons, worst_rel_se)` after each round.
pub fn run_all(
    cfg: &SlabConfig,
    phase: &Phase,
    control: &Control,
    progress: &dyn Fn(usize, usize, u64, f64),
) -> Result<SlabRun> {
    let total = cfg.thicknesses.len() * cfg.mu_l.len();
    for_each_slice(cfg, |s, grid, mu_l| {
        let mine = control.shard.is_none_or(|(k, n)| s % n == k);
        if !mine {
            return Ok(None);
        }
        let run = run_one(cfg, phase, control, grid, s, mu_l, &|n, w| {
            progress(s, total, n, w)
        })?;
        Ok(Some(run))
    })
}

/// Calls `f(s, grid, mu_l)` for every slice s of `cfg` in (t, μ_L) order and gathers the results.
fn for_each_slice(
    cfg: &SlabConfig,
    mut f: impl FnMut(usize, &SlabGrid, f64) -> Result<Option<(SliceReport, SliceRun)>>,
) -> Result<SlabRun> {
    cfg.validate()?;
    let mut slices = Vec::new();
    let mut depths = Vec::new();
    for (it, &t) in cfg.thicknesses.iter().enumerate() {
        let grid = cfg.grid(t)?;
        depths.push(grid.depths.clone());
        for (im, &mu_l) in cfg.mu_l.iter().enumerate() {
            slices.push(f(it * cfg.mu_l.len() + im, &grid, mu_l)?);
        }
    }
    Ok(SlabRun { slices, depths })
}

/// The tables and verdict of a slice from its sums.
fn judged(cfg: &SlabConfig, grid: &SlabGrid, mu_l: f64, acc: Accumulator) -> SliceRun {
    let (tables, worst, worst_horizon, converged) = cfg.stop.judge(&acc, grid, mu_l);
    SliceRun {
        acc,
        tables,
        worst_rel_se: worst,
        worst_rel_se_horizon: worst_horizon,
        converged,
    }
}

/// Slice `s`: from the checkpoint if finished there, else run (resuming its saved rounds).
fn run_one(
    cfg: &SlabConfig,
    phase: &Phase,
    control: &Control,
    grid: &SlabGrid,
    s: usize,
    mu_l: f64,
    progress: &dyn Fn(u64, f64),
) -> Result<(SliceReport, SliceRun)> {
    if let Some(cp) = control.checkpoint {
        if let Some((report, acc)) = cp.finished(s, grid)? {
            return Ok((report, judged(cfg, grid, mu_l, acc)));
        }
    }
    let (start, spent) = match control.checkpoint {
        Some(cp) => cp
            .current(s, grid)?
            .unwrap_or((Accumulator::new(grid), 0.0)),
        None => (Accumulator::new(grid), 0.0),
    };
    let t0 = Instant::now();
    let mut last_save = Instant::now();
    let mut save_error = None;
    let run = phase.with(|p| {
        let slice = Slice {
            grid,
            mu_l,
            albedo: cfg.albedo,
            phase: p,
        };
        run_slice_from(
            &slice,
            cfg.seed,
            s as u64,
            &cfg.stop,
            start,
            &mut |acc, worst| {
                progress(acc.total.photons, worst);
                if let Some(cp) = control.checkpoint {
                    if last_save.elapsed().as_secs_f64() >= control.save_every_s
                        && save_error.is_none()
                    {
                        save_error = cp
                            .save_current(s, acc, spent + t0.elapsed().as_secs_f64())
                            .err();
                        last_save = Instant::now();
                    }
                }
            },
        )
    });
    if let Some(e) = save_error {
        return Err(e.context("saving a checkpoint"));
    }
    let tot = &run.acc.total;
    let n = tot.photons as f64;
    let report = SliceReport {
        t: grid.thickness(),
        mu_l,
        photons: tot.photons,
        events: tot.events,
        worst_rel_se: run.worst_rel_se,
        worst_rel_se_horizon: run.worst_rel_se_horizon,
        converged: run.converged,
        reflected: tot.escaped_top / n,
        transmitted: tot.escaped_bottom / n,
        absorbed: tot.absorbed / n,
        seconds: spent + t0.elapsed().as_secs_f64(),
    };
    if let Some(cp) = control.checkpoint {
        cp.finish(s, &report, &run.acc)?;
    }
    Ok((report, run))
}

/// Gathers the slices of several shards' directories into one run (every slice exactly once).
pub fn merge(cfg: &SlabConfig, shards: &[Checkpoint]) -> Result<SlabRun> {
    for_each_slice(cfg, |s, grid, mu_l| {
        let where_ = || format!("slice {s} (t = {}, mu_L = {mu_l})", grid.thickness());
        let mut found = None;
        for cp in shards {
            if let Some((report, acc)) = cp.finished(s, grid)? {
                if found.is_some() {
                    anyhow::bail!("{} is in more than one shard", where_());
                }
                found = Some((report, judged(cfg, grid, mu_l, acc)));
            }
        }
        let found = found
            .with_context(|| format!("{} is in no shard: did every shard finish?", where_()))?;
        Ok(Some(found))
    })
}
