//! The analytic phase models by name and named parameters: the one table of them, which the
//! toolchain's configs and command line, the C ABI and the Python module all read. Each
//! parameter is checked against the range where its model is a phase function; a parameter the
//! model does not take is an error, not ignored.
//!
//! Names are kebab-case (`hg-draine`); snake_case (`hg_draine`) is accepted everywhere.

use super::{
    Cosine, Draine, HenyeyGreenstein, HgDraine, PhaseFunction, Rayleigh, ReynoldsMcCormick,
    Schlick, Tabulated, TwoTermHg, VonMisesFisher, Xlf, XLF_G_MAX,
};
use crate::frame::Vec3;
use crate::presets::{jendersie_deon, nephele_refit, HgDraineParams, FIT_MAX_DIAMETER_UM};
use crate::real::Real;
use core::fmt;

/// The phase models of the runtime, by name.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, PartialOrd, Ord)]
#[cfg_attr(
    feature = "serde",
    derive(serde::Serialize, serde::Deserialize),
    serde(rename_all = "snake_case", try_from = "String")
)]
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
    /// A table p(θ) (a Mie table): built from its arrays ([`super::TabulatedTable`]), not from
    /// named numbers.
    Tabulated,
}

/// The HG+Draine diameter presets ([`crate::presets`]).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
#[cfg_attr(
    feature = "serde",
    derive(serde::Serialize, serde::Deserialize),
    serde(rename_all = "snake_case", try_from = "String")
)]
pub enum Preset {
    /// [`jendersie_deon`]: the paper's curves and its supplement's branches.
    #[default]
    JendersieDeon,
    /// [`nephele_refit`]: nephele's refit on the same Mie setup.
    Nephele,
}

/// A name that is none of a list's (`kind` is "model" or "preset").
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct UnknownName {
    /// "model" or "preset".
    pub kind: &'static str,
    /// The valid names, kebab-case.
    pub valid: &'static [&'static str],
}

impl fmt::Display for UnknownName {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        self.describe(f, None)
    }
}

/// The value in `names` whose name is `s` in kebab- or snake_case.
fn by_name<T: Copy>(s: &str, names: &[(T, &str)]) -> Option<T> {
    let s = s.trim();
    names.iter().find(|(_, n)| same_name(s, n)).map(|(v, _)| *v)
}

/// `s` is `kebab` with any of its hyphens written as underscores.
fn same_name(s: &str, kebab: &str) -> bool {
    s.len() == kebab.len()
        && s.bytes()
            .zip(kebab.bytes())
            .all(|(a, b)| a == b || (a == b'_' && b == b'-'))
}

const MODEL_NAMES: [&str; 11] = [
    "hg",
    "two-term-hg",
    "cornette-shanks",
    "draine",
    "hg-draine",
    "rayleigh",
    "reynolds-mccormick",
    "schlick",
    "vmf",
    "xlf",
    "tabulated",
];

impl Model {
    /// Every model with its name (kebab-case), in the order of the command line's help.
    pub const NAMES: [(Model, &'static str); 11] = [
        (Model::Hg, MODEL_NAMES[0]),
        (Model::TwoTermHg, MODEL_NAMES[1]),
        (Model::CornetteShanks, MODEL_NAMES[2]),
        (Model::Draine, MODEL_NAMES[3]),
        (Model::HgDraine, MODEL_NAMES[4]),
        (Model::Rayleigh, MODEL_NAMES[5]),
        (Model::ReynoldsMccormick, MODEL_NAMES[6]),
        (Model::Schlick, MODEL_NAMES[7]),
        (Model::Vmf, MODEL_NAMES[8]),
        (Model::Xlf, MODEL_NAMES[9]),
        (Model::Tabulated, MODEL_NAMES[10]),
    ];

    /// The model named `s` (kebab- or snake_case).
    pub fn from_name(s: &str) -> Result<Self, UnknownName> {
        by_name(s, &Self::NAMES).ok_or(UnknownName {
            kind: "model",
            valid: &MODEL_NAMES,
        })
    }

    /// The name, kebab-case.
    pub fn name(self) -> &'static str {
        MODEL_NAMES[self as usize]
    }

    /// The name in snake_case, as JSON writes it.
    #[cfg(feature = "std")]
    pub fn json_name(self) -> std::string::String {
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

    /// The parameters this model takes (the names of [`Params`]' fields).
    pub fn takes(self) -> &'static [&'static str] {
        match self {
            Model::Hg | Model::CornetteShanks | Model::Xlf => &["g"],
            Model::Draine | Model::ReynoldsMccormick => &["g", "alpha"],
            Model::TwoTermHg => &["g", "g2", "w"],
            Model::HgDraine => &["g_hg", "g_d", "alpha", "w_d", "diameter", "preset"],
            Model::Schlick => &["k"],
            Model::Vmf => &["kappa"],
            Model::Rayleigh | Model::Tabulated => &[],
        }
    }
}

impl core::str::FromStr for Model {
    type Err = UnknownName;
    fn from_str(s: &str) -> Result<Self, UnknownName> {
        Model::from_name(s)
    }
}

const PRESET_NAMES: [&str; 2] = ["jendersie-deon", "nephele"];

impl Preset {
    /// Every preset with its name (kebab-case).
    pub const NAMES: [(Preset, &'static str); 2] = [
        (Preset::JendersieDeon, PRESET_NAMES[0]),
        (Preset::Nephele, PRESET_NAMES[1]),
    ];

    /// The preset named `s` (kebab- or snake_case).
    pub fn from_name(s: &str) -> Result<Self, UnknownName> {
        by_name(s, &Self::NAMES).ok_or(UnknownName {
            kind: "preset",
            valid: &PRESET_NAMES,
        })
    }

    /// The name, kebab-case.
    pub fn name(self) -> &'static str {
        PRESET_NAMES[self as usize]
    }

    /// The parameters of the preset's curves at diameter `d` (µm).
    pub fn at(self, d: f64) -> HgDraineParams {
        match self {
            Preset::JendersieDeon => jendersie_deon(d),
            Preset::Nephele => nephele_refit(d),
        }
    }
}

/// A model's parameters by name (each model takes the ones [`Model::takes`] names).
#[derive(Clone, Copy, Debug, Default, PartialEq)]
#[cfg_attr(
    feature = "serde",
    derive(serde::Serialize, serde::Deserialize),
    serde(deny_unknown_fields)
)]
pub struct Params {
    /// Asymmetry g (HG, Draine, Cornette–Shanks, Reynolds–McCormick, XLF; the first lobe of
    /// two-term HG).
    #[cfg_attr(
        feature = "serde",
        serde(default, skip_serializing_if = "Option::is_none")
    )]
    pub g: Option<f64>,
    /// The second lobe's g of two-term HG.
    #[cfg_attr(
        feature = "serde",
        serde(default, skip_serializing_if = "Option::is_none")
    )]
    pub g2: Option<f64>,
    /// Draine α ≥ 0 (also HG+Draine's); Reynolds–McCormick α > 0.
    #[cfg_attr(
        feature = "serde",
        serde(default, skip_serializing_if = "Option::is_none")
    )]
    pub alpha: Option<f64>,
    /// The first lobe's weight in [0, 1] of two-term HG.
    #[cfg_attr(
        feature = "serde",
        serde(default, skip_serializing_if = "Option::is_none")
    )]
    pub w: Option<f64>,
    /// HG+Draine: the HG lobe's g.
    #[cfg_attr(
        feature = "serde",
        serde(default, skip_serializing_if = "Option::is_none")
    )]
    pub g_hg: Option<f64>,
    /// HG+Draine: the Draine lobe's g.
    #[cfg_attr(
        feature = "serde",
        serde(default, skip_serializing_if = "Option::is_none")
    )]
    pub g_d: Option<f64>,
    /// HG+Draine: the Draine lobe's weight in [0, 1].
    #[cfg_attr(
        feature = "serde",
        serde(default, skip_serializing_if = "Option::is_none")
    )]
    pub w_d: Option<f64>,
    /// Schlick k in (−1, 1).
    #[cfg_attr(
        feature = "serde",
        serde(default, skip_serializing_if = "Option::is_none")
    )]
    pub k: Option<f64>,
    /// von Mises–Fisher κ ≥ 0.
    #[cfg_attr(
        feature = "serde",
        serde(default, skip_serializing_if = "Option::is_none")
    )]
    pub kappa: Option<f64>,
    /// Droplet diameter (µm, 0 < d ≤ [`FIT_MAX_DIAMETER_UM`]) for an HG+Draine preset (also
    /// `diameter_um`).
    #[cfg_attr(
        feature = "serde",
        serde(
            default,
            alias = "diameter_um",
            skip_serializing_if = "Option::is_none"
        )
    )]
    pub diameter: Option<f64>,
    /// Which diameter curves `diameter` uses (default jendersie_deon).
    #[cfg_attr(
        feature = "serde",
        serde(default, skip_serializing_if = "Option::is_none")
    )]
    pub preset: Option<Preset>,
}

/// Why named parameters give no phase function.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum ParamError {
    /// `name` is no parameter of any model.
    Unknown(Model),
    /// The model does not take this parameter.
    DoesNotTake(Model, &'static str),
    /// The model needs this parameter.
    Needs(Model, &'static str),
    /// A value outside its range: name, value, range.
    Range(&'static str, f64, Interval),
    /// HG+Draine given both a diameter and lobe parameters.
    Mixed,
    /// A preset without a diameter.
    PresetNeedsDiameter,
    /// XLF's g beyond ±[`XLF_G_MAX`].
    XlfG(f64),
    /// `tabulated` asked of named numbers.
    Tabulated,
}

impl fmt::Display for ParamError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match *self {
            ParamError::Unknown(m) => write!(
                f,
                "model {} takes no such parameter (it takes: {})",
                m.name(),
                Takes(m)
            ),
            ParamError::DoesNotTake(m, p) => write!(
                f,
                "model {} does not take {p} (it takes: {})",
                m.name(),
                Takes(m)
            ),
            ParamError::Needs(m, p) => write!(f, "model {} needs {p}", m.name()),
            ParamError::Range(name, v, r) => write!(f, "{name} must lie in {r}, got {v}"),
            ParamError::Mixed => write!(
                f,
                "model hg-draine takes either diameter (and preset) or g_hg, g_d, alpha, w_d, \
                 not both"
            ),
            ParamError::PresetNeedsDiameter => write!(f, "preset needs a diameter"),
            ParamError::XlfG(g) => write!(
                f,
                "g must satisfy |g| ≤ {XLF_G_MAX} for xlf (it turns negative beyond), got {g}"
            ),
            ParamError::Tabulated => write!(
                f,
                "model tabulated is built from its table (p at angles θ), not from numbers"
            ),
        }
    }
}

/// A model's parameter list, "nothing" when empty.
struct Takes(Model);

impl fmt::Display for Takes {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        let takes = self.0.takes();
        if takes.is_empty() {
            return write!(f, "nothing");
        }
        for (i, n) in takes.iter().enumerate() {
            write!(f, "{}{n}", if i > 0 { ", " } else { "" })?;
        }
        Ok(())
    }
}

impl UnknownName {
    /// "unknown model `given` (valid: …)".
    pub fn naming<'a>(&'a self, given: &'a str) -> impl fmt::Display + 'a {
        struct Naming<'a>(&'a UnknownName, &'a str);
        impl fmt::Display for Naming<'_> {
            fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
                self.0.describe(f, Some(self.1))
            }
        }
        Naming(self, given)
    }

    fn describe(&self, f: &mut fmt::Formatter<'_>, given: Option<&str>) -> fmt::Result {
        write!(f, "unknown {}", self.kind)?;
        if let Some(g) = given {
            write!(f, " `{g}`")?;
        }
        write!(f, " (valid: ")?;
        for (i, n) in self.valid.iter().enumerate() {
            write!(f, "{}{n}", if i > 0 { ", " } else { "" })?;
        }
        write!(f, "; snake_case works too)")
    }
}

#[cfg(feature = "std")]
impl std::error::Error for ParamError {}
#[cfg(feature = "std")]
impl std::error::Error for UnknownName {}

#[cfg(feature = "serde")]
impl TryFrom<std::string::String> for Model {
    type Error = std::string::String;
    fn try_from(s: std::string::String) -> Result<Self, Self::Error> {
        Model::from_name(&s).map_err(|e| std::format!("{}", e.naming(&s)))
    }
}

#[cfg(feature = "serde")]
impl TryFrom<std::string::String> for Preset {
    type Error = std::string::String;
    fn try_from(s: std::string::String) -> Result<Self, Self::Error> {
        Preset::from_name(&s).map_err(|e| std::format!("{}", e.naming(&s)))
    }
}

impl Params {
    /// The names of the parameters given.
    fn given(&self) -> impl Iterator<Item = &'static str> + '_ {
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
        set.into_iter().filter(|(_, on)| *on).map(|(n, _)| n)
    }

    /// Sets the number named `name` (as [`Model::takes`] writes it, or `diameter_um`) for
    /// model `m`: a name `m` does not take is an error.
    pub fn set(&mut self, m: Model, name: &str, value: f64) -> Result<(), ParamError> {
        let slot = match name {
            "g" => &mut self.g,
            "g2" => &mut self.g2,
            "alpha" => &mut self.alpha,
            "w" => &mut self.w,
            "g_hg" => &mut self.g_hg,
            "g_d" => &mut self.g_d,
            "w_d" => &mut self.w_d,
            "k" => &mut self.k,
            "kappa" => &mut self.kappa,
            "diameter" | "diameter_um" => &mut self.diameter,
            _ => return Err(ParamError::Unknown(m)),
        };
        *slot = Some(value);
        Ok(())
    }

    /// Refuses a parameter `m` does not take, and HG+Draine's two ways mixed.
    pub fn check_for(&self, m: Model) -> Result<(), ParamError> {
        if let Some(extra) = self.given().find(|n| !m.takes().contains(n)) {
            return Err(ParamError::DoesNotTake(m, extra));
        }
        let explicit = [self.g_hg, self.g_d, self.alpha, self.w_d];
        if m == Model::HgDraine && self.diameter.is_some() && explicit.iter().any(Option::is_some) {
            return Err(ParamError::Mixed);
        }
        if self.preset.is_some() && self.diameter.is_none() {
            return Err(ParamError::PresetNeedsDiameter);
        }
        Ok(())
    }
}

/// A parameter's range: from `lo` to `hi`, each end in it or not.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Interval {
    /// The lowest end.
    pub lo: f64,
    /// The highest end.
    pub hi: f64,
    /// Whether `lo` itself is out.
    pub lo_open: bool,
    /// Whether `hi` itself is out.
    pub hi_open: bool,
}

impl Interval {
    const fn open(lo: f64, hi: f64) -> Self {
        Self {
            lo,
            hi,
            lo_open: true,
            hi_open: true,
        }
    }

    const fn closed(lo: f64, hi: f64) -> Self {
        Self {
            lo,
            hi,
            lo_open: false,
            hi_open: false,
        }
    }

    /// `v` is finite and inside.
    pub fn holds(&self, v: f64) -> bool {
        let above = if self.lo_open {
            v > self.lo
        } else {
            v >= self.lo
        };
        let below = if self.hi_open {
            v < self.hi
        } else {
            v <= self.hi
        };
        v.is_finite() && above && below
    }
}

impl fmt::Display for Interval {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        let l = if self.lo_open { "(" } else { "[" };
        let r = if self.hi_open { ")" } else { "]" };
        write!(f, "{l}{}, {}{r}", self.lo, self.hi)
    }
}

/// `v` (named `name`, needed by `m`) when `range` holds it.
fn in_range(
    m: Model,
    v: Option<f64>,
    name: &'static str,
    range: Interval,
) -> Result<f64, ParamError> {
    let v = v.ok_or(ParamError::Needs(m, name))?;
    if range.holds(v) {
        Ok(v)
    } else {
        Err(ParamError::Range(name, v, range))
    }
}

/// An asymmetry parameter's range: (−1, 1).
const ASYMMETRY: Interval = Interval::open(-1.0, 1.0);
/// A lobe weight's range: [0, 1].
const WEIGHT: Interval = Interval::closed(0.0, 1.0);
/// Draine's α: [0, 10⁶].
const DRAINE_ALPHA: Interval = Interval::closed(0.0, 1e6);
/// Reynolds–McCormick's α: (0, 10³).
const RMC_ALPHA: Interval = Interval::open(0.0, 1e3);
/// von Mises–Fisher's κ: [0, 10⁷].
const KAPPA: Interval = Interval::closed(0.0, 1e7);
/// A droplet diameter (µm): (0, [`FIT_MAX_DIAMETER_UM`]], where the presets were fitted.
const DIAMETER: Interval = Interval {
    lo: 0.0,
    hi: FIT_MAX_DIAMETER_UM,
    lo_open: true,
    hi_open: false,
};

/// One of the runtime's analytic models, built from its name and parameters by [`build`].
#[derive(Clone, Copy, Debug)]
pub enum Named<F> {
    /// Henyey–Greenstein.
    Hg(HenyeyGreenstein<F>),
    /// Two-term HG.
    TwoTermHg(TwoTermHg<F>),
    /// Draine (and Cornette–Shanks).
    Draine(Draine<F>),
    /// HG + Draine.
    HgDraine(HgDraine<F>),
    /// Rayleigh.
    Rayleigh(Rayleigh),
    /// Reynolds–McCormick.
    ReynoldsMccormick(ReynoldsMcCormick<F>),
    /// Schlick.
    Schlick(Schlick<F>),
    /// von Mises–Fisher.
    Vmf(VonMisesFisher<F>),
    /// XLF.
    Xlf(Xlf<F>),
}

/// `model` with `params` (all checked), and the parameters it used: HG+Draine from a diameter
/// gives its lobes' g_hg, g_d, alpha, w_d beside the diameter and the preset.
pub fn build<F: Real>(model: Model, params: &Params) -> Result<(Named<F>, Params), ParamError> {
    params.check_for(model)?;
    let m = model;
    let p = params;
    let g = || in_range(m, p.g, "g", ASYMMETRY);
    let of = F::of;
    let mut used = Params::default();
    let named = match m {
        Model::Hg | Model::CornetteShanks => {
            let g = g()?;
            used.g = Some(g);
            if m == Model::Hg {
                Named::Hg(HenyeyGreenstein::new(of(g)))
            } else {
                Named::Draine(Draine::cornette_shanks(of(g)))
            }
        }
        Model::Draine | Model::ReynoldsMccormick => {
            let range = if m == Model::Draine {
                DRAINE_ALPHA
            } else {
                RMC_ALPHA
            };
            let (g, a) = (g()?, in_range(m, p.alpha, "alpha", range)?);
            (used.g, used.alpha) = (Some(g), Some(a));
            if m == Model::Draine {
                Named::Draine(Draine::new(of(g), of(a)))
            } else {
                Named::ReynoldsMccormick(ReynoldsMcCormick::new(of(g), of(a)))
            }
        }
        Model::Rayleigh => Named::Rayleigh(Rayleigh),
        Model::Schlick => {
            let k = in_range(m, p.k, "k", ASYMMETRY)?;
            used.k = Some(k);
            Named::Schlick(Schlick::new(of(k)))
        }
        Model::Vmf => {
            let k = in_range(m, p.kappa, "kappa", KAPPA)?;
            used.kappa = Some(k);
            Named::Vmf(VonMisesFisher::new(of(k)))
        }
        Model::Xlf => {
            let gv = g()?;
            used.g = Some(gv);
            Named::Xlf(Xlf::new(of(gv)).ok_or(ParamError::XlfG(gv))?)
        }
        Model::TwoTermHg => {
            let g = g()?;
            let g2 = in_range(m, p.g2, "g2", ASYMMETRY)?;
            let w = in_range(m, p.w, "w", WEIGHT)?;
            (used.g, used.g2, used.w) = (Some(g), Some(g2), Some(w));
            Named::TwoTermHg(TwoTermHg::two_term(of(g), of(g2), of(w)))
        }
        Model::HgDraine => {
            let hd = hg_draine(p)?;
            used = Params {
                g_hg: Some(hd.g_hg),
                g_d: Some(hd.g_d),
                alpha: Some(hd.alpha),
                w_d: Some(hd.w_d),
                diameter: p.diameter,
                preset: p.diameter.map(|_| p.preset.unwrap_or_default()),
                ..Params::default()
            };
            Named::HgDraine(hd.phase())
        }
        Model::Tabulated => return Err(ParamError::Tabulated),
    };
    Ok((named, used))
}

/// HG+Draine's lobes: from a diameter by a preset, or given one by one.
fn hg_draine(p: &Params) -> Result<HgDraineParams, ParamError> {
    let m = Model::HgDraine;
    if p.diameter.is_some() {
        let d = in_range(m, p.diameter, "diameter", DIAMETER)?;
        return Ok(p.preset.unwrap_or_default().at(d));
    }
    Ok(HgDraineParams {
        g_hg: in_range(m, p.g_hg, "g_hg", ASYMMETRY)?,
        g_d: in_range(m, p.g_d, "g_d", ASYMMETRY)?,
        alpha: in_range(m, p.alpha, "alpha", DRAINE_ALPHA)?,
        w_d: in_range(m, p.w_d, "w_d", WEIGHT)?,
    })
}

/// `$e` on the model inside `$self`, whichever it is.
macro_rules! each {
    ($self:expr, $m:ident => $e:expr) => {
        match $self {
            Named::Hg($m) => $e,
            Named::TwoTermHg($m) => $e,
            Named::Draine($m) => $e,
            Named::HgDraine($m) => $e,
            Named::Rayleigh($m) => $e,
            Named::ReynoldsMccormick($m) => $e,
            Named::Schlick($m) => $e,
            Named::Vmf($m) => $e,
            Named::Xlf($m) => $e,
        }
    };
}

impl<F: Real> PhaseFunction<F> for Named<F> {
    fn eval(&self, mu: F) -> F {
        each!(self, m => m.eval(mu))
    }
    fn pdf(&self, mu: F) -> F {
        each!(self, m => m.pdf(mu))
    }
    fn sample_mu(&self, xi: F) -> F {
        each!(self, m => m.sample_mu(xi))
    }
    fn sample_cosine(&self, xi: F) -> Cosine<F> {
        each!(self, m => m.sample_cosine(xi))
    }
    fn sample_cosines(&self, xi: &[F], out: &mut [Cosine<F>]) {
        each!(self, m => m.sample_cosines(xi, out))
    }
    fn pdf_cosine(&self, c: Cosine<F>) -> F {
        each!(self, m => m.pdf_cosine(c))
    }
    fn mean_cosine(&self) -> Option<F> {
        each!(self, m => m.mean_cosine())
    }
    fn as_tabulated(&self) -> Option<Tabulated<'_, F>> {
        None
    }
    fn sample(&self, xi1: F, xi2: F, wi: Vec3<F>) -> (Vec3<F>, F) {
        each!(self, m => m.sample(xi1, xi2, wi))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn params(g: Option<f64>, alpha: Option<f64>) -> Params {
        Params {
            g,
            alpha,
            ..Params::default()
        }
    }

    /// Names and parameters reach the right model; Cornette–Shanks is Draine at α = 1.
    #[test]
    fn models_are_built_from_their_names_and_parameters() {
        let (hg, _) = build::<f64>(Model::Hg, &params(Some(0.7), None)).unwrap();
        let (cs, _) = build::<f64>(Model::CornetteShanks, &params(Some(0.7), None)).unwrap();
        let (dr, _) = build::<f64>(Model::Draine, &params(Some(0.7), Some(1.0))).unwrap();
        for mu in [-0.9, 0.0, 0.5, 0.99] {
            assert_eq!(hg.eval(mu), HenyeyGreenstein::new(0.7).eval(mu));
            assert_eq!(cs.eval(mu), dr.eval(mu));
        }
        let by_diameter = Params {
            diameter: Some(10.0),
            ..Params::default()
        };
        let (_, used) = build::<f32>(Model::HgDraine, &by_diameter).unwrap();
        assert_eq!(used.g_hg, Some(jendersie_deon(10.0).g_hg));
        assert_eq!(used.preset, Some(Preset::JendersieDeon));
    }

    /// Missing, out-of-range and foreign parameters are errors that name them.
    #[test]
    fn bad_parameters_are_named() {
        let err = |m, p: &Params| std::format!("{}", build::<f64>(m, p).unwrap_err());
        assert_eq!(
            err(Model::Schlick, &Params::default()),
            "model schlick needs k"
        );
        assert!(err(Model::Hg, &params(Some(1.2), None)).contains("g must lie in (-1, 1)"));
        assert!(err(Model::Hg, &params(Some(f64::NAN), None)).contains("got NaN"));
        let kappa = Params {
            g: Some(0.5),
            kappa: Some(3.0),
            ..Params::default()
        };
        assert!(err(Model::Hg, &kappa).contains("model hg does not take kappa (it takes: g)"));
        let big = Params {
            diameter: Some(80.0),
            ..Params::default()
        };
        assert!(err(Model::HgDraine, &big).contains("diameter must lie in (0, 50]"));
        let zero = Params {
            diameter: Some(0.0),
            ..Params::default()
        };
        assert!(err(Model::HgDraine, &zero).contains("got 0"));
        let mut p = Params::default();
        assert_eq!(
            p.set(Model::Hg, "q", 1.0),
            Err(ParamError::Unknown(Model::Hg))
        );
        assert!(err(Model::Tabulated, &p).contains("built from its table"));
    }

    /// Both spellings of every name parse.
    #[test]
    fn names_parse_in_kebab_and_snake_case() {
        for (m, name) in Model::NAMES {
            assert_eq!(m.name(), name);
            assert_eq!(Model::from_name(name), Ok(m));
            assert_eq!(Model::from_name(&name.replace('-', "_")), Ok(m));
        }
        for (p, name) in Preset::NAMES {
            assert_eq!(p.name(), name);
            assert_eq!(Preset::from_name(&name.replace('-', "_")), Ok(p));
        }
        let e = std::format!("{}", Model::from_name("hg-drain").unwrap_err());
        assert!(
            e.starts_with("unknown model (valid: hg, two-term-hg"),
            "{e}"
        );
    }
}
