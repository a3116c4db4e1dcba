//! The analytic phase models of nephele-runtime by name and parameters: what `nephele phase
//! --model` tabulates and what a slab config or a scene names as `{"kind": "runtime", "model":
//! …, "params": {…}}`. Parameters are checked here, each against the range where the model is
//! a phase function.

use anyhow::{bail, Context, Result};
use clap::ValueEnum;
use nephele_runtime::phase::{
    Draine, HenyeyGreenstein, Rayleigh, ReynoldsMcCormick, Schlick, TwoTermHg, VonMisesFisher, Xlf,
    XLF_G_MAX,
};
use nephele_runtime::presets::{jendersie_deon, nephele_refit, HgDraineParams};
use nephele_runtime::PhaseFunction;
use serde::{Deserialize, Serialize};
use serde_json::json;

/// The models of nephele-runtime.
#[derive(Clone, Copy, Debug, PartialEq, Eq, ValueEnum, Serialize, Deserialize)]
#[serde(rename_all = "kebab-case")]
pub enum Model {
    /// Henyey–Greenstein (--g).
    Hg,
    /// Draine (--g, --alpha).
    Draine,
    /// Cornette–Shanks (--g): Draine with α = 1.
    CornetteShanks,
    /// Rayleigh (no parameter).
    Rayleigh,
    /// Reynolds–McCormick (--g, --alpha > 0; α = 1/2 is HG).
    ReynoldsMccormick,
    /// Schlick (--k).
    Schlick,
    /// von Mises–Fisher (--kappa).
    Vmf,
    /// Xiao-Lei Fan's function, normalised (--g, |g| ≤ 0.476955 where it stays non-negative).
    Xlf,
    /// w HG(g) + (1 − w) HG(g2) (--g, --g2, --w).
    TwoTermHg,
    /// HG + Draine blend (Jendersie & d'Eon), from --diameter (and --preset) or from --g, --g2 (g_D), --alpha, --w (w_D).
    HgDraine,
    /// A Mie table (--table phase.npz from `nephele mie`).
    Tabulated,
}

/// The HG+Draine diameter presets of nephele-runtime.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, ValueEnum, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum Preset {
    /// `presets::jendersie_deon`: the paper's curves and its supplement's branches.
    #[default]
    JendersieDeon,
    /// `presets::nephele_refit`: nephele's refit on the same Mie setup.
    Nephele,
}

/// A model's parameters (each model reads the ones it needs; see `Model`).
#[derive(Clone, Debug, Default, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct ModelParams {
    /// Asymmetry g (HG, Draine, Cornette–Shanks, Reynolds–McCormick, XLF, first lobe of
    /// two-term HG, HG lobe of HG+Draine).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub g: Option<f64>,
    /// Second g (two-term HG; the Draine lobe's g of HG+Draine).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub g2: Option<f64>,
    /// Draine α ≥ 0; Reynolds–McCormick α > 0.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub alpha: Option<f64>,
    /// Lobe weight in [0, 1] (first lobe of two-term HG; the Draine lobe of HG+Draine).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub w: Option<f64>,
    /// Schlick k in (−1, 1).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub k: Option<f64>,
    /// von Mises–Fisher κ ≥ 0.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub kappa: Option<f64>,
    /// Droplet diameter (µm) for an HG+Draine preset.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub diameter: Option<f64>,
    /// Which diameter curves `diameter` uses.
    #[serde(default)]
    pub preset: Preset,
}

fn need(v: Option<f64>, name: &str, model: Model) -> Result<f64> {
    v.with_context(|| format!("model {model:?} needs {name}"))
}

fn in_range(v: f64, name: &str, lo: f64, hi: f64, open: bool) -> Result<f64> {
    let ok = if open {
        v > lo && v < hi
    } else {
        v >= lo && v <= hi
    };
    if !(v.is_finite() && ok) {
        let (l, r) = if open { ("(", ")") } else { ("[", "]") };
        bail!("{name} must lie in {l}{lo}, {hi}{r}, got {v}");
    }
    Ok(v)
}

/// An analytic phase function.
pub type Boxed = Box<dyn PhaseFunction<f64> + Sync>;

/// The model with these parameters, and the parameters it used as JSON.
pub fn build(m: Model, p: &ModelParams) -> Result<(Boxed, serde_json::Value)> {
    let g = || in_range(need(p.g, "g", m)?, "g", -1.0, 1.0, true);
    Ok(match m {
        Model::Hg => (Box::new(HenyeyGreenstein::new(g()?)), json!({ "g": g()? })),
        Model::Draine => {
            let a = in_range(need(p.alpha, "alpha", m)?, "alpha", 0.0, 1e6, false)?;
            (
                Box::new(Draine::new(g()?, a)),
                json!({ "g": g()?, "alpha": a }),
            )
        }
        Model::CornetteShanks => (
            Box::new(Draine::cornette_shanks(g()?)),
            json!({ "g": g()? }),
        ),
        Model::Rayleigh => (Box::new(Rayleigh), json!({})),
        Model::ReynoldsMccormick => {
            let a = in_range(need(p.alpha, "alpha", m)?, "alpha", 0.0, 1e3, true)?;
            (
                Box::new(ReynoldsMcCormick::new(g()?, a)),
                json!({ "g": g()?, "alpha": a }),
            )
        }
        Model::Schlick => {
            let k = in_range(need(p.k, "k", m)?, "k", -1.0, 1.0, true)?;
            (Box::new(Schlick::new(k)), json!({ "k": k }))
        }
        Model::Vmf => {
            let k = in_range(need(p.kappa, "kappa", m)?, "kappa", 0.0, 1e7, false)?;
            (Box::new(VonMisesFisher::new(k)), json!({ "kappa": k }))
        }
        Model::Xlf => {
            let gv = g()?;
            let xlf = Xlf::new(gv).with_context(|| {
                format!(
                    "g must satisfy |g| ≤ {XLF_G_MAX} for xlf (it turns negative beyond), got {gv}"
                )
            })?;
            (Box::new(xlf), json!({ "g": gv, "normalised": true }))
        }
        Model::TwoTermHg => {
            let g2 = in_range(need(p.g2, "g2", m)?, "g2", -1.0, 1.0, true)?;
            let w = in_range(need(p.w, "w", m)?, "w", 0.0, 1.0, false)?;
            (
                Box::new(TwoTermHg::two_term(g()?, g2, w)),
                json!({ "g": g()?, "g2": g2, "w": w }),
            )
        }
        Model::HgDraine => {
            let hd = match p.diameter {
                Some(d) => {
                    let d = in_range(d, "diameter", 0.0, 1e4, true)?;
                    match p.preset {
                        Preset::JendersieDeon => jendersie_deon(d),
                        Preset::Nephele => nephele_refit(d),
                    }
                }
                None => HgDraineParams {
                    g_hg: g()?,
                    g_d: in_range(need(p.g2, "g2", m)?, "g2", -1.0, 1.0, true)?,
                    alpha: in_range(need(p.alpha, "alpha", m)?, "alpha", 0.0, 1e6, false)?,
                    w_d: in_range(need(p.w, "w", m)?, "w", 0.0, 1.0, false)?,
                },
            };
            let echo = json!({ "g_hg": hd.g_hg, "g_d": hd.g_d, "alpha": hd.alpha, "w_d": hd.w_d, "diameter_um": p.diameter, "preset": p.diameter.map(|_| p.preset) });
            (Box::new(hd.phase::<f64>()), echo)
        }
        Model::Tabulated => bail!("a tabulated model is built from its table (kind \"table\")"),
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use nephele_runtime::phase::HenyeyGreenstein;

    /// Names and parameters reach the right model; missing or out-of-range ones are errors.
    #[test]
    fn models_are_built_from_their_names_and_parameters() {
        let params = ModelParams {
            g: Some(0.7),
            alpha: Some(1.0),
            ..ModelParams::default()
        };
        let (hg, _) = build(Model::Hg, &params).unwrap();
        let (cs, _) = build(Model::CornetteShanks, &params).unwrap();
        let (draine, _) = build(Model::Draine, &params).unwrap();
        for mu in [-0.9, 0.0, 0.5, 0.99] {
            assert_eq!(hg.eval(mu), HenyeyGreenstein::new(0.7).eval(mu));
            assert_eq!(
                cs.eval(mu),
                draine.eval(mu),
                "Cornette–Shanks is Draine at α = 1"
            );
        }
        let err = |m, p: &ModelParams| build(m, p).err().unwrap().to_string();
        assert!(err(Model::Schlick, &params).contains("needs k"));
        let bad = ModelParams {
            g: Some(1.2),
            ..ModelParams::default()
        };
        assert!(err(Model::Hg, &bad).contains("g must lie in"));
    }
}
