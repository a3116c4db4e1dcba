//! A phase function built from its spec and owned: a tabulated table (Mie, computed here, or
//! read from a file) or an analytic model, one per linear-sRGB channel where the spec asks.

use super::model::build;
use super::spec::PhaseSpec;
use crate::mie::cache;
use crate::mie::output::channels;
use crate::mie::polydisperse::{CONVERGED_DEFAULT, DEFAULT_WAVELENGTHS};
use crate::mie::MieJob;
use anyhow::{anyhow, bail, ensure, Context, Result};
use nephele_runtime::phase::{HenyeyGreenstein, TabulatedTable};
use nephele_runtime::PhaseFunction;

/// The phase function of a run, owned.
pub enum Phase {
    /// A tabulated table (Mie or from a file) and the p(θ) it was built from.
    Table(TabulatedTable<f64>, Source),
    /// An analytic model.
    Analytic(Box<dyn PhaseFunction<f64> + Sync>),
}

impl Phase {
    /// Builds the phase function of `spec` (a Mie table is computed here, a few seconds, or
    /// read from the cache of earlier runs: [`crate::mie::cache`]); a
    /// per-channel (rgb) spec is an error here, see `build_channels`.
    pub fn build(spec: &PhaseSpec) -> Result<Self> {
        let mut models = Self::build_channels(spec)?;
        if models.len() != 1 {
            bail!("phase.rgb: one phase function is needed here, not one per channel");
        }
        Ok(models.remove(0))
    }

    /// The phase functions of `spec`: one per linear-sRGB channel when it asks for them (rgb),
    /// else one.
    pub fn build_channels(spec: &PhaseSpec) -> Result<Vec<Self>> {
        let (theta, columns) = match spec {
            PhaseSpec::Mie { diameter_um, rgb } => {
                let job = MieJob::paper(*diameter_um, CONVERGED_DEFAULT, DEFAULT_WAVELENGTHS);
                let t = cache::first_table(&job, cache::default_dir().as_deref(), || {
                    let mut tables = job.compute(&|_, _| {})?.0;
                    ensure!(!tables.is_empty(), "Mie job gave no table");
                    let t = tables.swap_remove(0);
                    Ok(cache::CachedPhase {
                        theta_deg: t.theta_deg,
                        phase: t.phase,
                        phase_rgb: t.phase_rgb,
                    })
                })?;
                let columns = if *rgb {
                    channels(&t.phase_rgb)
                } else {
                    vec![t.phase]
                };
                (t.theta_deg, columns)
            }
            PhaseSpec::Table { path, rgb } => crate::mie::output::read_phase(path, *rgb)?,
            PhaseSpec::Hg { g } => {
                return Ok(vec![Phase::Analytic(Box::new(HenyeyGreenstein::new(*g)))])
            }
            PhaseSpec::HgDraine {
                diameter_um,
                preset,
            } => {
                let p = preset.at(*diameter_um);
                return Ok(vec![Phase::Analytic(Box::new(p.phase::<f64>()))]);
            }
            PhaseSpec::Runtime { model, params } => {
                return Ok(vec![Phase::Analytic(build(*model, params)?.0)]);
            }
        };
        let file = match spec {
            PhaseSpec::Table { path, .. } => format!("'{}'", path.display()),
            _ => "the Mie table".to_string(),
        };
        columns
            .into_iter()
            .map(|phase| {
                let theta_deg = theta.clone();
                Self::from_source(Source { theta_deg, phase }).with_context(|| file.clone())
            })
            .collect()
    }

    /// Runs `f` with the phase function as a trait object.
    pub fn with<R>(&self, f: impl FnOnce(&(dyn PhaseFunction<f64> + Sync)) -> R) -> R {
        // (Not via with_all: callers use this per evaluation, and with_all allocates.)
        match self {
            Phase::Table(t, _) => f(&t.view()),
            Phase::Analytic(b) => f(b.as_ref()),
        }
    }

    /// Runs `f` with all of `models` as trait objects.
    pub fn with_all<R>(
        models: &[Self],
        f: impl FnOnce(&[&(dyn PhaseFunction<f64> + Sync)]) -> R,
    ) -> R {
        let views: Vec<_> = models
            .iter()
            .map(|m| match m {
                Phase::Table(t, _) => Some(t.view()),
                Phase::Analytic(_) => None,
            })
            .collect();
        let refs: Vec<&(dyn PhaseFunction<f64> + Sync)> = models
            .iter()
            .zip(&views)
            .map(|(m, v)| match (m, v) {
                (_, Some(v)) => v as &(dyn PhaseFunction<f64> + Sync),
                (Phase::Analytic(b), None) => b.as_ref(),
                (Phase::Table(..), None) => unreachable!("every table has its view"),
            })
            .collect();
        f(&refs)
    }
}

/// The p(θ) a table was built from: what a run stores so that later stages rebuild the very
/// same table without the Mie computation or the file.
#[derive(Clone, Debug, PartialEq)]
pub struct Source {
    /// Angles (degrees, 0 … 180).
    pub theta_deg: Vec<f64>,
    /// p (sr⁻¹) there.
    pub phase: Vec<f64>,
}

impl Phase {
    /// The table `source` describes (as [`Phase::build`] makes it from a spec).
    pub fn from_source(source: Source) -> Result<Self> {
        let t = TabulatedTable::<f64>::from_phase(&source.theta_deg, &source.phase)
            .map_err(|e| anyhow!("tabulated phase function: {e:?}"))?;
        Ok(Phase::Table(t, source))
    }

    /// The p(θ) of a tabulated phase function; None for an analytic one.
    pub fn source(&self) -> Option<&Source> {
        match self {
            Phase::Table(_, s) => Some(s),
            Phase::Analytic(_) => None,
        }
    }
}
