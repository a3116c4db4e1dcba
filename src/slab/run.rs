//! One slice run to its stopping rule: rounds of batches in parallel (rayon), each batch with
//! its own random stream, folded into the accumulator in batch order — so the tables are the
//! same bits for any thread count.

use super::grid::SlabGrid;
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
    /// Leave the μ_V bins touching the horizon out of the test (their error is reported apart):
    /// the 1/|μ| estimator there has unbounded variance and would hold every slice to its budget.
    pub exclude_horizon: bool,
}

impl StopRule {
    /// An estimate of the share of a slice done after `photons` with the worst tested relative
    /// error `worst`: the larger of the budget's share and (target/worst)², the share of the
    /// photons the test needs as errors fall like 1/√N. Below 1 until the slice stops (for a
    /// progress display).
    pub fn fraction_done(&self, photons: u64, worst: f64) -> f64 {
        let budget = photons as f64 / self.max_photons.max(1) as f64;
        let by_error = if worst.is_finite() && worst > 0.0 {
            (self.target_rel_se / worst).powi(2)
        } else {
            0.0
        };
        budget.max(by_error).clamp(0.0, 0.99)
    }

    /// The tables of `acc`, the worst relative errors (tested cells, horizon cells when not
    /// tested) and whether the slice has converged.
    pub fn judge(
        &self,
        acc: &Accumulator,
        grid: &SlabGrid,
        mu_l: f64,
    ) -> (SliceTables, f64, f64, bool) {
        let tables = acc.tables(grid, mu_l);
        let skip = |c: usize| self.exclude_horizon && grid.is_horizon(grid.cell_parts(c).2);
        let (worst, horizon) = tables.worst_relative_error(self.cell_fraction, &skip);
        let converged = acc.batches >= self.min_batches && worst <= self.target_rel_se;
        (tables, worst, horizon, converged)
    }
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
            exclude_horizon: true,
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
    /// Worst relative standard error over the horizon bins when they are not tested (else 0).
    pub worst_rel_se_horizon: f64,
    /// Whether the target was met (else the budget ended it).
    pub converged: bool,
}

/// Runs `slice` (index `slice_index` in its run, for the random streams) until `rule` stops it;
/// `progress(photons, worst_rel_se)` after each round.
pub fn run_slice(
    slice: &Slice,
    seed: u64,
    slice_index: u64,
    rule: &StopRule,
    progress: &dyn Fn(u64, f64),
) -> SliceRun {
    run_slice_from(
        slice,
        seed,
        slice_index,
        rule,
        Accumulator::new(slice.grid),
        &mut |acc, worst| progress(acc.total.photons, worst),
    )
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
        let (tables, worst, worst_horizon, converged) = rule.judge(&acc, slice.grid, slice.mu_l);
        if converged || acc.total.photons >= rule.max_photons {
            return SliceRun {
                acc,
                tables,
                worst_rel_se: worst,
                worst_rel_se_horizon: worst_horizon,
                converged,
            };
        }
        after_round(&acc, worst);
    }
}

/// What one slice reports besides its tables.
#[derive(Clone, Debug, Serialize, Deserialize)]
pub struct SliceReport {
    /// Thickness (mfp).
    pub t: f64,
    /// Sun cosine.
    pub mu_l: f64,
    /// Photons walked.
    pub photons: u64,
    /// Scattering events.
    pub events: u64,
    /// Worst relative standard error over the tested cells.
    pub worst_rel_se: f64,
    /// Worst relative standard error over the horizon bins, when the test leaves them out.
    pub worst_rel_se_horizon: f64,
    /// Whether the target was met (else the photon budget stopped it).
    pub converged: bool,
    /// Fractions of the incident photons leaving by the lit face / the far face, and absorbed.
    pub reflected: f64,
    /// See `reflected`.
    pub transmitted: f64,
    /// See `reflected`.
    pub absorbed: f64,
    /// Wall-clock seconds.
    pub seconds: f64,
}

#[cfg(test)]
mod tests {
    use super::StopRule;

    /// A slice's progress: the budget's share or (target/worst)², whichever is further, never
    /// 1 before the slice stops, 0 before any error is known.
    #[test]
    fn a_slice_progresses_by_its_budget_or_its_error() {
        let stop = StopRule {
            max_photons: 1_000_000,
            target_rel_se: 0.01,
            ..StopRule::default()
        };
        assert_eq!(stop.fraction_done(0, f64::INFINITY), 0.0);
        assert!((stop.fraction_done(250_000, f64::NAN) - 0.25).abs() < 1e-12);
        assert!((stop.fraction_done(10_000, 0.02) - 0.25).abs() < 1e-12);
        assert_eq!(stop.fraction_done(10_000, 0.005), 0.99);
    }
}
