//! One slice run to its stopping rule: rounds of batches in parallel (rayon), each batch with
//! its own random stream, folded into the accumulator in batch order — so the tables are the
//! same bits for any thread count.

use super::tally::{Accumulator, SliceTables};
use super::walk::{batch_rng, Slice};
use rayon::prelude::*;
use serde::{Deserialize, Serialize};

/// When a slice stops.
#[derive(Clone, Copy, Debug, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct StopRule {
    /// Photons per batch (the unit of the standard errors).
    pub batch_photons: u64,
    /// Batches per round (the unit of the stopping test; fixed, not the thread count).
    pub round_batches: u64,
    /// Batches before the first stopping test.
    pub min_batches: u64,
    /// Photon budget.
    pub max_photons: u64,
    /// Cells with T ≥ this fraction of the slice's largest T are tested …
    pub cell_fraction: f64,
    /// … against this relative standard error.
    pub target_rel_se: f64,
}

impl Default for StopRule {
    fn default() -> Self {
        Self {
            batch_photons: 10_000,
            round_batches: 16,
            min_batches: 32,
            max_photons: 100_000_000,
            cell_fraction: 0.01,
            target_rel_se: 0.02,
        }
    }
}

/// A finished slice.
pub struct SliceRun {
    /// The sums.
    pub acc: Accumulator,
    /// The tables.
    pub tables: SliceTables,
    /// Worst relative standard error over the tested cells.
    pub worst_rel_se: f64,
    /// Whether the target was met (else the budget ended it).
    pub converged: bool,
}

/// Runs `slice` (index `slice_index` in its run, for the random streams) until `rule` stops it;
/// `progress(photons, worst_rel_se)` after each round.
pub fn run_slice(slice: &Slice, seed: u64, slice_index: u64, rule: &StopRule, progress: &dyn Fn(u64, f64)) -> SliceRun {
    run_slice_from(slice, seed, slice_index, rule, Accumulator::new(slice.grid), &mut |acc, worst| {
        progress(acc.total.photons, worst)
    })
}

/// As [`run_slice`], continuing from `acc` (the sums after some rounds, e.g. from a
/// checkpoint: the result is the same bits as an uninterrupted run); `after_round` sees the
/// sums after every round that does not end the slice.
pub fn run_slice_from(
    slice: &Slice,
    seed: u64,
    slice_index: u64,
    rule: &StopRule,
    mut acc: Accumulator,
    after_round: &mut dyn FnMut(&Accumulator, f64),
) -> SliceRun {
    loop {
        let first = acc.batches;
        let batches: Vec<_> = (first..first + rule.round_batches)
            .into_par_iter()
            .map(|b| slice.run_batch(rule.batch_photons, &mut batch_rng(seed, slice_index, b)))
            .collect();
        batches.iter().for_each(|b| acc.add(b));
        let tables = acc.tables(slice.grid, slice.mu_l);
        let worst = tables.worst_relative_error(rule.cell_fraction);
        let converged = acc.batches >= rule.min_batches && worst <= rule.target_rel_se;
        if converged || acc.total.photons >= rule.max_photons {
            return SliceRun { acc, tables, worst_rel_se: worst, converged };
        }
        after_round(&acc, worst);
    }
}
