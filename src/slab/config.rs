//! A slab run's config (fit-configs/slab-*.json): the grids (docs/slab.md), the phase function,
//! the seed and the stopping rule. Unknown keys and impossible values are errors.

use super::grid::{stretched_depths, SlabGrid, DEFAULT_GROUP_FIRST};
use super::run::StopRule;
use crate::phase::PhaseSpec;
use anyhow::{bail, Result};
use serde::{Deserialize, Serialize};
use std::f64::consts::PI;

/// Everything a slab run needs.
#[derive(Clone, Debug, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct SlabConfig {
    /// Free text.
    #[serde(default)]
    pub description: String,
    /// Slab thicknesses t (mfp), increasing.
    #[serde(default = "default_thicknesses")]
    pub thicknesses: Vec<f64>,
    /// Sun cosines μ_L in (0, 1], increasing.
    #[serde(default = "default_mu_l")]
    pub mu_l: Vec<f64>,
    /// Depth planes per slab (stretched toward the lit face, both faces included).
    #[serde(default = "sixteen")]
    pub planes: usize,
    /// Equal μ_V bins over [−1, 1].
    #[serde(default = "sixteen")]
    pub mu_v_bins: usize,
    /// Equal ψ_V bins over [0, π].
    #[serde(default = "twelve")]
    pub psi_v_bins: usize,
    /// First order of each group (the last group runs to ∞).
    #[serde(default = "default_group_starts")]
    pub group_starts: Vec<u32>,
    /// The phase function.
    #[serde(default)]
    pub phase: PhaseSpec,
    /// Single-scattering albedo in (0, 1].
    #[serde(default = "one")]
    pub albedo: f64,
    /// Crossings with |μ| below this weigh 2/grazing_mu instead of 1/|μ| (bounded variance at
    /// the horizon, bias ≈ (L′/L) ε²/(6Δμ); 0 keeps the plain estimator); at most half the
    /// narrowest μ_V bin.
    #[serde(default = "default_grazing")]
    pub grazing_mu: f64,
    /// Edges (degrees) of the cones around the transmitted beam tallied apart, the aureole
    /// (src/slab/aureole.rs); empty: none.
    #[serde(default = "default_aureole")]
    pub aureole_deg: Vec<f64>,
    /// Seed of every random stream.
    #[serde(default = "one_u64")]
    pub seed: u64,
    /// When each slice stops.
    #[serde(default)]
    pub stop: StopRule,
}

fn default_thicknesses() -> Vec<f64> {
    vec![0.5, 1.0, 2.0, 4.0, 8.0, 16.0, 32.0, 64.0, 128.0]
}
fn default_mu_l() -> Vec<f64> {
    (1..=8).map(|k| k as f64 / 8.0).collect()
}
fn default_group_starts() -> Vec<u32> {
    DEFAULT_GROUP_FIRST.to_vec()
}
fn default_grazing() -> f64 {
    super::grid::DEFAULT_GRAZING_MU
}
fn default_aureole() -> Vec<f64> {
    super::aureole::DEFAULT_AUREOLE_DEG.to_vec()
}
fn sixteen() -> usize {
    16
}
fn twelve() -> usize {
    12
}
fn one() -> f64 {
    1.0
}
fn one_u64() -> u64 {
    1
}

impl Default for SlabConfig {
    fn default() -> Self {
        serde_json::from_str("{}").expect("every key has a default")
    }
}

impl SlabConfig {
    /// Checks every value; the message names the key.
    pub fn validate(&self) -> Result<()> {
        let increasing = |v: &[f64]| v.windows(2).all(|w| w[0] < w[1]);
        if self.thicknesses.is_empty()
            || !increasing(&self.thicknesses)
            || self
                .thicknesses
                .iter()
                .any(|t| !(t.is_finite() && *t > 0.0 && *t <= 1e4))
        {
            bail!("thicknesses must be increasing, each in (0, 10000] mfp");
        }
        if self.mu_l.is_empty()
            || !increasing(&self.mu_l)
            || self.mu_l.iter().any(|m| !(*m > 0.0 && *m <= 1.0))
        {
            bail!("mu_l must be increasing, each in (0, 1]");
        }
        if !(2..=1024).contains(&self.planes)
            || !(1..=1024).contains(&self.mu_v_bins)
            || !(1..=1024).contains(&self.psi_v_bins)
        {
            bail!("planes must be in 2..=1024, mu_v_bins and psi_v_bins in 1..=1024");
        }
        if self.group_starts.first() != Some(&1)
            || self.group_starts.windows(2).any(|w| w[0] >= w[1])
            || self.group_starts.len() > 255
        {
            bail!("group_starts must begin with 1 and increase (at most 255 groups)");
        }
        if !(self.albedo > 0.0 && self.albedo <= 1.0) {
            bail!("albedo = {} must be in (0, 1]", self.albedo);
        }
        if !(self.grazing_mu >= 0.0 && self.grazing_mu <= 1.0 / self.mu_v_bins.max(1) as f64) {
            bail!(
                "grazing_mu = {} must be in [0, {}] (half a μ_V bin)",
                self.grazing_mu,
                1.0 / self.mu_v_bins.max(1) as f64
            );
        }
        let s = &self.stop;
        if s.batch_photons == 0
            || s.round_batches < 2
            || s.min_batches < 2
            || s.max_photons < s.batch_photons * s.round_batches
        {
            bail!("stop: batch_photons ≥ 1, round_batches ≥ 2, min_batches ≥ 2, max_photons ≥ one round of batches");
        }
        if !(s.target_rel_se >= 0.0 && (0.0..=1.0).contains(&s.cell_fraction)) {
            bail!("stop: target_rel_se ≥ 0 and cell_fraction in [0, 1]");
        }
        self.phase.validate()?;
        if self.phase.is_rgb() {
            bail!("phase.rgb: the slab tables are monochrome; leave rgb out (the channel mean)");
        }
        self.grid(self.thicknesses[0]).map(|_| ())
    }

    /// The order groups as (first, last).
    pub fn groups(&self) -> Vec<(u32, u32)> {
        let s = &self.group_starts;
        (0..s.len())
            .map(|i| (s[i], s.get(i + 1).map_or(u32::MAX, |n| n - 1)))
            .collect()
    }

    /// Bytes a run holds at its peak, an upper estimate: for the slice under way its
    /// accumulator (Σ v and Σ v vᵀ: 14 f64 a cell) and a round of batch tallies (4 f64 a cell
    /// each), and every slice's tables (T, its error, c and σ: at most 8 f64 a cell) until they
    /// are written.
    pub fn footprint_bytes(&self) -> Result<f64> {
        let t_max = self.thicknesses.iter().copied().fold(0.0, f64::max);
        let cells = self.grid(t_max)?.n_cells() as f64;
        let slices = (self.thicknesses.len() * self.mu_l.len()) as f64;
        let round = self.stop.round_batches as f64;
        Ok(8.0 * cells * (14.0 + 4.0 * round + 8.0 * slices))
    }

    /// Refuses a run larger than `available` bytes, with its estimate.
    pub fn check_memory(&self, available: f64) -> Result<()> {
        let need = self.footprint_bytes()?;
        if need > available {
            bail!(
                "this slab run needs about {} of memory, more than the {} available ({} cells a \
                 slice: planes × mu_v_bins × psi_v_bins × order groups, {} slices); use fewer \
                 planes, mu_v_bins, psi_v_bins, order groups or slices",
                crate::io::text::bytes(need),
                crate::io::text::bytes(available),
                self.grid(self.thicknesses[0])?.n_cells(),
                self.thicknesses.len() * self.mu_l.len()
            );
        }
        Ok(())
    }

    /// The grid of the slab of thickness `t`.
    pub fn grid(&self, t: f64) -> Result<SlabGrid> {
        let (nm, np) = (self.mu_v_bins, self.psi_v_bins);
        let mut grid = SlabGrid::new(
            stretched_depths(t, self.planes),
            (0..=nm)
                .map(|i| -1.0 + 2.0 * i as f64 / nm as f64)
                .collect(),
            (0..=np)
                .map(|i| {
                    if i == np {
                        PI
                    } else {
                        PI * i as f64 / np as f64
                    }
                })
                .collect(),
            self.groups(),
        )?;
        grid.grazing_mu = self.grazing_mu;
        grid.aureole = super::aureole::Aureole::new(self.aureole_deg.clone())?;
        Ok(grid)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_run_larger_than_memory_is_refused_with_its_estimate() {
        let text = include_str!("../../fit-configs/slab-default.json");
        let mut cfg: SlabConfig = serde_json::from_str(text).unwrap();
        let need = cfg.footprint_bytes().unwrap();
        // The default run: 72 slices of 16 planes × 16 × 12 bins × 10 groups.
        assert!(need > 1e7 && need < 1e9, "{need}");
        assert!(cfg.check_memory(need).is_ok());
        cfg.planes = 1024;
        let err = cfg.check_memory(8e9).unwrap_err().to_string();
        assert!(err.contains("more than the 8 GB available"), "{err}");
        assert!(err.contains("use fewer"), "{err}");
    }
}
