//! The analytic phase models of nephele-runtime by name and parameters: what `nephele phase
//! --model` tabulates and what a slab config or a scene names as `{"kind": "runtime", "model":
//! …, "params": {…}}`. Parameters are checked here, each against the range where the model is
//! a phase function, and a parameter the model does not take is an error, not ignored.
//!
//! Names: kebab-case on the command line (`hg-draine`), snake_case in JSON (`hg_draine`); both
//! spellings are accepted everywhere, and JSON outputs write snake_case.

use anyhow::{bail, Context, Result};
use nephele_runtime::phase::{
    Draine, HenyeyGreenstein, Rayleigh, ReynoldsMcCormick, Schlick, TwoTermHg, VonMisesFisher, Xlf,
    XLF_G_MAX,
};
use nephele_runtime::presets::{jendersie_deon, nephele_refit, HgDraineParams};
use nephele_runtime::PhaseFunction;
use serde::{Deserialize, Serialize};
use serde_json::json;
use std::str::FromStr;

/// The models of nephele-runtime.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, PartialOrd, Ord, Serialize, Deserialize)]
#[serde(rename_all = "snake_case", try_from = "String")]
pub enum Model {
    /// Henyey–Greenstein (g).
    Hg,
    /// w HG(g) + (1 − w) HG(g2): two-term HG (g, g2, w = the weight of the first lobe).
    TwoTermHg,
    /// Cornette–Shanks (g): Draine with α = 1.
    CornetteShanks,
    /// Draine (g, alpha).
    Draine,
    /// HG + Draine blend (Jendersie & d'Eon 2023): (1 − w_d) HG(g_hg) + w_d Draine(g_d, α), from
    /// a diameter (and a preset) or from g_hg, g_d, alpha, w_d.
    HgDraine,
    /// Rayleigh (no parameter).
    Rayleigh,
    /// Reynolds–McCormick (g, alpha > 0; α = 1/2 is HG).
    ReynoldsMccormick,
    /// Schlick (k).
    Schlick,
    /// von Mises–Fisher (kappa).
    Vmf,
    /// Xiao-Lei Fan's function, normalised (g, |g| ≤ 0.476955 where it stays non-negative).
    Xlf,
    /// A Mie table (`nephele phase --table phase.npz` from `nephele mie`).
    Tabulated,
}

/// The HG+Draine diameter presets of nephele-runtime.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case", try_from = "String")]
pub enum Preset {
    /// `presets::jendersie_deon`: the paper's curves and its supplement's branches.
    #[default]
    JendersieDeon,
    /// `presets::nephele_refit`: nephele's refit on the same Mie setup.
    Nephele,
}

/// A name in kebab-case and its value, for parsing either spelling.
fn parse_name<T: Copy>(kind: &str, s: &str, names: &[(T, &str)]) -> Result<T> {
    let kebab = s.trim().replace('_', "-");
    names
        .iter()
        .find(|(_, n)| *n == kebab)
        .map(|(v, _)| *v)
        .with_context(|| {
            let valid: Vec<&str> = names.iter().map(|(_, n)| *n).collect();
            format!(
                "unknown {kind} `{s}` (valid: {}; snake_case works too)",
                valid.join(", ")
            )
        })
}

impl Model {
    /// Every model with its command-line name, in the order of `--help`.
    pub const NAMES: [(Model, &'static str); 11] = [
        (Model::Hg, "hg"),
        (Model::TwoTermHg, "two-term-hg"),
        (Model::CornetteShanks, "cornette-shanks"),
        (Model::Draine, "draine"),
        (Model::HgDraine, "hg-draine"),
        (Model::Rayleigh, "rayleigh"),
        (Model::ReynoldsMccormick, "reynolds-mccormick"),
        (Model::Schlick, "schlick"),
        (Model::Vmf, "vmf"),
        (Model::Xlf, "xlf"),
        (Model::Tabulated, "tabulated"),
    ];

    /// The command-line name (kebab-case).
    pub fn name(self) -> &'static str {
        Self::NAMES
            .iter()
            .find(|(m, _)| *m == self)
            .map_or("?", |(_, n)| n)
    }

    /// The JSON name (snake_case), as configs and outputs write it.
    pub fn json_name(self) -> String {
        self.name().replace('-', "_")
    }

    /// A label for figures and tables.
    pub fn label(self) -> &'static str {
        match self {
            Model::Hg => "HG",
            Model::TwoTermHg => "two-term HG",
            Model::CornetteShanks => "Cornette-Shanks",
            Model::Draine => "Draine",
            Model::HgDraine => "HG+Draine",
            Model::Rayleigh => "Rayleigh",
            Model::ReynoldsMccormick => "Reynolds-McCormick",
            Model::Schlick => "Schlick",
            Model::Vmf => "von Mises-Fisher",
            Model::Xlf => "XLF",
            Model::Tabulated => "tabulated",
        }
    }

    /// The parameters this model takes (the names of [`ModelParams`]' fields).
    pub fn takes(self) -> &'static [&'static str] {
        match self {
            Model::Hg | Model::CornetteShanks | Model::Xlf => &["g"],
            Model::Draine | Model::ReynoldsMccormick => &["g", "alpha"],
            Model::TwoTermHg => &["g", "g2", "w"],
            Model::HgDraine => &["g_hg", "g_d", "alpha", "w_d", "diameter", "preset"],
            Model::Schlick => &["k"],
            Model::Vmf => &["kappa"],
            Model::Rayleigh => &[],
            Model::Tabulated => &[],
        }
    }
}

impl FromStr for Model {
    type Err = anyhow::Error;
    fn from_str(s: &str) -> Result<Self> {
        parse_name("model", s, &Self::NAMES)
    }
}

impl TryFrom<String> for Model {
    type Error = anyhow::Error;
    fn try_from(s: String) -> Result<Self> {
        s.parse()
    }
}

impl Preset {
    /// Every preset with its command-line name.
    pub const NAMES: [(Preset, &'static str); 2] = [
        (Preset::JendersieDeon, "jendersie-deon"),
        (Preset::Nephele, "nephele"),
    ];

    /// The parameters of the preset's curves at diameter `d` (µm).
    pub fn at(self, d: f64) -> HgDraineParams {
        match self {
            Preset::JendersieDeon => jendersie_deon(d),
            Preset::Nephele => nephele_refit(d),
        }
    }
}

impl FromStr for Preset {
    type Err = anyhow::Error;
    fn from_str(s: &str) -> Result<Self> {
        parse_name("preset", s, &Self::NAMES)
    }
}

impl TryFrom<String> for Preset {
    type Error = anyhow::Error;
    fn try_from(s: String) -> Result<Self> {
        s.parse()
    }
}

/// A model's parameters (each model takes the ones [`Model::takes`] names; any other one given
/// is an error).
#[derive(Clone, Debug, Default, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct ModelParams {
    /// Asymmetry g (HG, Draine, Cornette–Shanks, Reynolds–McCormick, XLF; the first lobe of
    /// two-term HG).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub g: Option<f64>,
    /// The second lobe's g of two-term HG.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub g2: Option<f64>,
    /// Draine α ≥ 0 (also HG+Draine's); Reynolds–McCormick α > 0.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub alpha: Option<f64>,
    /// The first lobe's weight in [0, 1] of two-term HG.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub w: Option<f64>,
    /// HG+Draine: the HG lobe's g.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub g_hg: Option<f64>,
    /// HG+Draine: the Draine lobe's g.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub g_d: Option<f64>,
    /// HG+Draine: the Draine lobe's weight in [0, 1].
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub w_d: Option<f64>,
    /// Schlick k in (−1, 1).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub k: Option<f64>,
    /// von Mises–Fisher κ ≥ 0.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub kappa: Option<f64>,
    /// Droplet diameter (µm) for an HG+Draine preset (also `diameter_um`).
    #[serde(
        default,
        alias = "diameter_um",
        skip_serializing_if = "Option::is_none"
    )]
    pub diameter: Option<f64>,
    /// Which diameter curves `diameter` uses (default jendersie_deon).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub preset: Option<Preset>,
}

impl ModelParams {
    /// The names of the parameters given.
    fn given(&self) -> Vec<&'static str> {
        let set = [
            ("g", self.g.is_some()),
            ("g2", self.g2.is_some()),
            ("alpha", self.alpha.is_some()),
            ("w", self.w.is_some()),
            ("g_hg", self.g_hg.is_some()),
            ("g_d", self.g_d.is_some()),
            ("w_d", self.w_d.is_some()),
            ("k", self.k.is_some()),
            ("kappa", self.kappa.is_some()),
            ("diameter", self.diameter.is_some()),
            ("preset", self.preset.is_some()),
        ];
        set.iter().filter(|(_, on)| *on).map(|(n, _)| *n).collect()
    }

    /// Refuses a parameter `m` does not take, and HG+Draine's two ways mixed.
    pub fn check_for(&self, m: Model) -> Result<()> {
        let takes = m.takes();
        if let Some(extra) = self.given().into_iter().find(|n| !takes.contains(n)) {
            bail!(
                "model {} does not take {extra} (it takes: {})",
                m.name(),
                if takes.is_empty() {
                    "nothing".to_string()
                } else {
                    takes.join(", ")
                }
            );
        }
        let explicit = [self.g_hg, self.g_d, self.alpha, self.w_d];
        if m == Model::HgDraine && self.diameter.is_some() && explicit.iter().any(Option::is_some) {
            bail!("model hg-draine takes either diameter (and preset) or g_hg, g_d, alpha, w_d, not both");
        }
        if self.preset.is_some() && self.diameter.is_none() {
            bail!("preset needs a diameter");
        }
        Ok(())
    }
}

fn need(v: Option<f64>, name: &str, m: Model) -> Result<f64> {
    v.with_context(|| format!("model {} needs {name}", m.name()))
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
    p.check_for(m)?;
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
            let preset = p.preset.unwrap_or_default();
            let lobe_g = |v, name| in_range(need(v, name, m)?, name, -1.0, 1.0, true);
            let hd = match p.diameter {
                Some(d) => preset.at(in_range(d, "diameter", 0.0, 1e4, true)?),
                None => HgDraineParams {
                    g_hg: lobe_g(p.g_hg, "g_hg")?,
                    g_d: lobe_g(p.g_d, "g_d")?,
                    alpha: in_range(need(p.alpha, "alpha", m)?, "alpha", 0.0, 1e6, false)?,
                    w_d: in_range(need(p.w_d, "w_d", m)?, "w_d", 0.0, 1.0, false)?,
                },
            };
            let echo = json!({ "g_hg": hd.g_hg, "g_d": hd.g_d, "alpha": hd.alpha, "w_d": hd.w_d, "diameter_um": p.diameter, "preset": p.diameter.map(|_| preset) });
            (Box::new(hd.phase::<f64>()), echo)
        }
        Model::Tabulated => {
            bail!("model tabulated is built from its table (`nephele phase --table`, or kind \"table\" in a config)")
        }
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use nephele_runtime::phase::HenyeyGreenstein;

    fn params(g: Option<f64>, alpha: Option<f64>) -> ModelParams {
        ModelParams {
            g,
            alpha,
            ..ModelParams::default()
        }
    }

    /// Names and parameters reach the right model; missing or out-of-range ones are errors.
    #[test]
    fn models_are_built_from_their_names_and_parameters() {
        let (hg, _) = build(Model::Hg, &params(Some(0.7), None)).unwrap();
        let (cs, _) = build(Model::CornetteShanks, &params(Some(0.7), None)).unwrap();
        let (draine, _) = build(Model::Draine, &params(Some(0.7), Some(1.0))).unwrap();
        for mu in [-0.9, 0.0, 0.5, 0.99] {
            assert_eq!(hg.eval(mu), HenyeyGreenstein::new(0.7).eval(mu));
            assert_eq!(
                cs.eval(mu),
                draine.eval(mu),
                "Cornette–Shanks is Draine at α = 1"
            );
        }
        let err = |m, p: &ModelParams| build(m, p).err().unwrap().to_string();
        assert!(err(Model::Schlick, &ModelParams::default()).contains("model schlick needs k"));
        assert!(err(Model::Hg, &params(Some(1.2), None)).contains("g must lie in"));
        assert!(
            err(Model::HgDraine, &ModelParams::default()).contains("model hg-draine needs g_hg")
        );
    }

    /// A parameter the model does not take is an error naming it, and so are HG+Draine's two
    /// ways mixed and a preset without a diameter.
    #[test]
    fn parameters_that_do_not_apply_are_refused() {
        let err = |m, p: &ModelParams| build(m, p).err().unwrap().to_string();
        let kappa = ModelParams {
            g: Some(0.5),
            kappa: Some(3.0),
            ..ModelParams::default()
        };
        assert!(err(Model::Hg, &kappa).contains("model hg does not take kappa"));
        let mixed = ModelParams {
            diameter: Some(10.0),
            g_hg: Some(0.5),
            ..ModelParams::default()
        };
        assert!(err(Model::HgDraine, &mixed).contains("either diameter"));
        let old_names = ModelParams {
            diameter: Some(10.0),
            g: Some(0.5),
            ..ModelParams::default()
        };
        assert!(err(Model::HgDraine, &old_names).contains("does not take g "));
        let preset = ModelParams {
            g: Some(0.5),
            preset: Some(Preset::Nephele),
            ..ModelParams::default()
        };
        assert!(err(Model::Hg, &preset).contains("does not take preset"));
    }

    /// Both spellings of every name parse, in Rust and in JSON; JSON writes snake_case.
    #[test]
    fn names_parse_in_kebab_and_snake_case() {
        for (m, name) in Model::NAMES {
            assert_eq!(name.parse::<Model>().unwrap(), m);
            assert_eq!(name.replace('-', "_").parse::<Model>().unwrap(), m);
            let json = serde_json::to_string(&m).unwrap();
            assert_eq!(json, format!("\"{}\"", name.replace('-', "_")));
            assert_eq!(
                serde_json::from_str::<Model>(&format!("\"{name}\"")).unwrap(),
                m
            );
        }
        for (p, name) in Preset::NAMES {
            assert_eq!(name.parse::<Preset>().unwrap(), p);
            assert_eq!(name.replace('-', "_").parse::<Preset>().unwrap(), p);
        }
        let e = "hg-drain".parse::<Model>().unwrap_err().to_string();
        assert!(
            e.contains("unknown model `hg-drain`") && e.contains("hg-draine"),
            "{e}"
        );
    }
}
