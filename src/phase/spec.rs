//! A phase function as a config or a scene names it: Mie by diameter, HG, HG+Draine from a
//! preset, any runtime model by name, or a table from a file — checked here, built by
//! [`super::Phase`].

use super::model::{build, Model, ModelParams, Preset};
use anyhow::{bail, Context, Result};
use serde::{Deserialize, Serialize};
use std::path::PathBuf;

/// A phase function as configs and scenes name it (`"phase": {"kind": …}`).
#[derive(Clone, Debug, Serialize, Deserialize)]
#[serde(tag = "kind", rename_all = "snake_case", deny_unknown_fields)]
pub enum PhaseSpec {
    /// A stage-1 Mie table in the paper's setup (water, σ = 0.25, 400–700 nm) at this median
    /// diameter (µm), sampled exactly by the tabulated model.
    Mie {
        /// Median diameter (µm; also `diameter`).
        #[serde(alias = "diameter")]
        diameter_um: f64,
        /// One phase function per linear-sRGB channel (the renderer only) instead of the mean.
        #[serde(default, skip_serializing_if = "std::ops::Not::not")]
        rgb: bool,
    },
    /// Henyey–Greenstein (for validation against DISORT).
    Hg {
        /// Asymmetry g.
        g: f64,
    },
    /// HG + Draine from a diameter preset: jendersie_deon (default) or nephele.
    #[serde(alias = "hg-draine")]
    HgDraine {
        /// Median diameter (µm; also `diameter`).
        #[serde(alias = "diameter")]
        diameter_um: f64,
        /// The preset.
        #[serde(default)]
        preset: Preset,
    },
    /// Any analytic model of nephele-runtime by name, with its parameters (as `nephele phase
    /// --model`): {"kind": "runtime", "model": "draine", "params": {"g": 0.8, "alpha": 1}}.
    Runtime {
        /// The model.
        model: Model,
        /// Its parameters.
        #[serde(default)]
        params: ModelParams,
    },
    /// A `nephele mie` phase.npz (its `theta_deg` and `phase`, or `phase_rgb`).
    Table {
        /// Path of the npz.
        path: PathBuf,
        /// Read `phase_rgb` (n × 3), one phase function per channel (the renderer only).
        #[serde(default, skip_serializing_if = "std::ops::Not::not")]
        rgb: bool,
    },
}

impl Default for PhaseSpec {
    fn default() -> Self {
        PhaseSpec::Mie {
            diameter_um: 10.0,
            rgb: false,
        }
    }
}

impl PhaseSpec {
    /// Whether there is one phase function per RGB channel.
    pub fn is_rgb(&self) -> bool {
        matches!(
            self,
            PhaseSpec::Mie { rgb: true, .. } | PhaseSpec::Table { rgb: true, .. }
        )
    }

    /// Checks the parameters, naming the first bad one.
    pub fn validate(&self) -> Result<()> {
        match self {
            PhaseSpec::Mie { diameter_um, .. } | PhaseSpec::HgDraine { diameter_um, .. }
                if !(*diameter_um > 0.0 && *diameter_um <= 1e4) =>
            {
                bail!("phase.diameter_um = {diameter_um} must be in (0, 10000]")
            }
            PhaseSpec::Hg { g } if !(g.abs() < 1.0) => bail!("phase.g = {g} must be in (−1, 1)"),
            PhaseSpec::Runtime { model, params } => build(*model, params)
                .map(|_| ())
                .context("phase (kind runtime)"),
            _ => Ok(()),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Configs may write names in either spelling and `diameter` for `diameter_um`.
    #[test]
    fn both_spellings_and_the_diameter_alias_parse() {
        for text in [
            r#"{"kind": "hg_draine", "diameter_um": 10, "preset": "jendersie_deon"}"#,
            r#"{"kind": "hg_draine", "diameter": 10, "preset": "jendersie-deon"}"#,
        ] {
            let spec: PhaseSpec = serde_json::from_str(text).unwrap();
            assert!(matches!(
                spec,
                PhaseSpec::HgDraine {
                    diameter_um: 10.0,
                    preset: Preset::JendersieDeon
                }
            ));
        }
        let runtime: PhaseSpec = serde_json::from_str(
            r#"{"kind": "runtime", "model": "two-term-hg", "params": {"g": 0.8, "g2": -0.2, "w": 0.9}}"#,
        )
        .unwrap();
        assert!(runtime.validate().is_ok());
        let bad: PhaseSpec = serde_json::from_str(
            r#"{"kind": "runtime", "model": "hg", "params": {"g": 0.8, "w": 0.9}}"#,
        )
        .unwrap();
        let e = format!("{:#}", bad.validate().unwrap_err());
        assert!(e.contains("does not take w"), "{e}");
    }
}
