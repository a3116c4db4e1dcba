//! A whole slab run: every slice (t, μ_L) of a config, one after the other (each parallel over
//! its batches), gathered into the 5D tables of spec 40 with shape
//! [group, t, μ_L, depth, μ_V, ψ_V].

use super::config::{PhaseSpec, SlabConfig};
use super::run::{run_slice, SliceRun};
use super::walk::Slice;
use crate::mie::polydisperse::{CONVERGED_DEFAULT, DEFAULT_WAVELENGTHS};
use crate::mie::MieJob;
use anyhow::{anyhow, Context, Result};
use nephele_runtime::phase::{HenyeyGreenstein, TabulatedTable};
use nephele_runtime::presets::{jendersie_deon, nephele_refit};
use nephele_runtime::PhaseFunction;
use serde::Serialize;
use std::time::Instant;

/// The phase function of a run, owned.
pub enum PhaseModel {
    /// A tabulated table (Mie or from a file).
    Table(TabulatedTable<f64>),
    /// An analytic model.
    Analytic(Box<dyn PhaseFunction<f64> + Sync>),
}

impl PhaseModel {
    /// Builds the phase function of `spec` (a Mie table is computed here, a few seconds).
    pub fn build(spec: &PhaseSpec) -> Result<Self> {
        let table = |th: &[f64], p: &[f64]| -> Result<Self> {
            let t = TabulatedTable::<f64>::from_phase(th, p).map_err(|e| anyhow!("tabulated phase function: {e:?}"))?;
            Ok(PhaseModel::Table(t))
        };
        match spec {
            PhaseSpec::Mie { diameter_um } => {
                let job = MieJob::paper(*diameter_um, CONVERGED_DEFAULT, DEFAULT_WAVELENGTHS);
                let tables = job.compute(&|_, _| {})?.0;
                let t = tables.first().context("Mie job gave no table")?;
                table(&t.theta_deg, &t.phase)
            }
            PhaseSpec::Table { path } => {
                let a = crate::io::npz::read_arrays(path, &["theta_deg", "phase"])?;
                table(&a[0], &a[1]).with_context(|| format!("'{}'", path.display()))
            }
            PhaseSpec::Hg { g } => Ok(PhaseModel::Analytic(Box::new(HenyeyGreenstein::new(*g)))),
            PhaseSpec::HgDraine { diameter_um, preset } => {
                let p = if preset == "nephele" { nephele_refit(*diameter_um) } else { jendersie_deon(*diameter_um) };
                Ok(PhaseModel::Analytic(Box::new(p.phase::<f64>())))
            }
        }
    }

    /// Runs `f` with the phase function as a trait object.
    pub fn with<R>(&self, f: impl FnOnce(&(dyn PhaseFunction<f64> + Sync)) -> R) -> R {
        match self {
            PhaseModel::Table(t) => f(&t.view()),
            PhaseModel::Analytic(b) => f(b.as_ref()),
        }
    }
}

/// What one slice reports besides its tables.
#[derive(Clone, Debug, Serialize)]
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

/// The results of every slice, in (t, μ_L) order.
pub struct SlabRun {
    /// Per slice: its report and its run.
    pub slices: Vec<(SliceReport, SliceRun)>,
    /// Depth planes per thickness.
    pub depths: Vec<Vec<f64>>,
}

/// Runs every slice of `cfg`; `progress(slice_done, slices, photons, worst_rel_se)` after each
/// round.
pub fn run_all(cfg: &SlabConfig, phase: &PhaseModel, progress: &dyn Fn(usize, usize, u64, f64)) -> Result<SlabRun> {
    cfg.validate()?;
    let total = cfg.thicknesses.len() * cfg.mu_l.len();
    let mut slices = Vec::with_capacity(total);
    let mut depths = Vec::new();
    for (it, &t) in cfg.thicknesses.iter().enumerate() {
        let grid = cfg.grid(t)?;
        depths.push(grid.depths.clone());
        for (im, &mu_l) in cfg.mu_l.iter().enumerate() {
            let index = (it * cfg.mu_l.len() + im) as u64;
            let t0 = Instant::now();
            let run = phase.with(|p| {
                let slice = Slice { grid: &grid, mu_l, albedo: cfg.albedo, phase: p };
                run_slice(&slice, cfg.seed, index, &cfg.stop, &|n, worst| progress(index as usize, total, n, worst))
            });
            let tot = &run.acc.total;
            let n = tot.photons as f64;
            let report = SliceReport {
                t,
                mu_l,
                photons: tot.photons,
                events: tot.events,
                worst_rel_se: run.worst_rel_se,
                converged: run.converged,
                reflected: tot.escaped_top / n,
                transmitted: tot.escaped_bottom / n,
                absorbed: tot.absorbed / n,
                seconds: t0.elapsed().as_secs_f64(),
            };
            slices.push((report, run));
        }
    }
    Ok(SlabRun { slices, depths })
}
