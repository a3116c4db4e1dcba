//! The `fit` section of a fit config (fit-configs/*.json): which models, which loss, which
//! curves. Unknown keys, impossible names and bad ranges are errors that say what is valid.

use super::curves::Form;
use super::loss::Loss;
use super::model::Fitting;
use super::model::{Model, FITTED};
use anyhow::{bail, Context, Result};
use serde::{Deserialize, Serialize};

/// What to fit and how.
#[derive(Clone, Debug, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct FitConfig {
    /// Model names (see [`Model::name`]).
    #[serde(default = "default_models")]
    pub models: Vec<String>,
    /// The loss minimised (and reported).
    #[serde(default)]
    pub loss: Loss,
    /// Upper bound of Draine's α (the paper's small-droplet branches sit at 250).
    #[serde(default = "default_alpha_max")]
    pub alpha_max: f64,
    /// Diameter ranges over which HG+Draine curves are fitted, each with its forms.
    #[serde(default)]
    pub curves: Vec<BranchConfig>,
    /// Diameters (µm) shown in the phase-function figure (the nearest fitted ones are used).
    #[serde(default = "default_figure_diameters")]
    pub figure_diameters_um: Vec<f64>,
}

/// One curve branch: a closed diameter range and the form of each HG+Draine parameter.
#[derive(Clone, Debug, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct BranchConfig {
    /// [d_lo, d_hi] in µm, inclusive.
    pub range_um: [f64; 2],
    /// Form of g_HG(d).
    pub g_hg: String,
    /// Form of g_D(d).
    pub g_d: String,
    /// Form of α(d).
    pub alpha: String,
    /// Form of w_D(d).
    pub w_d: String,
}

fn default_models() -> Vec<String> {
    FITTED.iter().map(|m| m.json_name()).collect()
}

fn default_alpha_max() -> f64 {
    250.0
}

fn default_figure_diameters() -> Vec<f64> {
    vec![5.0, 10.0, 20.0, 50.0]
}

impl Default for FitConfig {
    fn default() -> Self {
        Self {
            models: default_models(),
            loss: Loss::Eas,
            alpha_max: default_alpha_max(),
            curves: Vec::new(),
            figure_diameters_um: default_figure_diameters(),
        }
    }
}

impl BranchConfig {
    /// The four forms, in the order g_HG, g_D, α, w_D.
    pub fn forms(&self) -> Result<[Form; 4]> {
        let f = |name: &str, what: &str| {
            Form::parse(name)
                .with_context(|| format!("curve of {what} over {:?} µm", self.range_um))
        };
        Ok([
            f(&self.g_hg, "g_hg")?,
            f(&self.g_d, "g_d")?,
            f(&self.alpha, "alpha")?,
            f(&self.w_d, "w_d")?,
        ])
    }
}

impl FitConfig {
    /// The models, parsed, in report order, without repeats.
    pub fn models(&self) -> Result<Vec<Model>> {
        if self.models.is_empty() {
            bail!(
                "fit.models is empty (valid: {})",
                default_models().join(", ")
            );
        }
        let mut out = self
            .models
            .iter()
            .map(|n| Model::fitted_from_name(n))
            .collect::<Result<Vec<_>>>()?;
        out.sort();
        out.dedup();
        Ok(out)
    }

    /// Checks that every curve branch holds more fitted diameters than its largest form has
    /// coefficients (else the least squares would be exact or underdetermined).
    pub fn check_branches(&self, diameters_um: &[f64]) -> Result<()> {
        for b in &self.curves {
            let [lo, hi] = b.range_um;
            let n = diameters_um
                .iter()
                .filter(|d| (lo..=hi).contains(*d))
                .count();
            let need = b.forms()?.iter().map(|f| f.n_coef()).max().unwrap_or(1) + 1;
            if n < need {
                bail!("fit.curves range_um {:?} holds {n} of the fitted diameters; its forms need at least {need}", b.range_um);
            }
        }
        Ok(())
    }

    /// Checks everything that can be checked without the diameters.
    pub fn validate(&self) -> Result<()> {
        let models = self.models()?;
        if !(self.alpha_max.is_finite() && self.alpha_max > 1.0 && self.alpha_max <= 1e4) {
            bail!("fit.alpha_max = {} must be in (1, 10000]", self.alpha_max);
        }
        if !self.curves.is_empty() && !models.contains(&Model::HgDraine) {
            bail!("fit.curves are curves of HG+Draine: add \"hg_draine\" to fit.models");
        }
        for b in &self.curves {
            let [lo, hi] = b.range_um;
            if !(lo.is_finite() && hi.is_finite() && 0.0 < lo && lo < hi) {
                bail!(
                    "fit.curves range_um {:?} must be 0 < lo < hi (µm)",
                    b.range_um
                );
            }
            b.forms()?;
        }
        if let Some(d) = self
            .figure_diameters_um
            .iter()
            .find(|d| !(**d > 0.0 && d.is_finite()))
        {
            bail!("fit.figure_diameters_um: {d} is not a positive diameter");
        }
        Ok(())
    }
}
