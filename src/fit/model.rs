//! The models fitted to Mie, as functions of a parameter vector θ: ln p(μ; θ)
//! and its gradient ∂ ln p/∂θ in closed form, bounds and the smooth maps that enforce them.
//!
//! Values come from the runtime's evaluators (`HenyeyGreenstein::eval`, `phase_draine`); only
//! the derivatives are written here. With t = 1 + g² − 2gμ and N = 1 + α(1 + 2g²)/3:
//!
//!   ∂ ln HG/∂g = −2g/(1 − g²) − 3(g − μ)/t,
//!   ∂ ln D/∂g  = ∂ ln HG/∂g − 4αg/(3N),      ∂ ln D/∂α = μ²/(1 + αμ²) − (1 + 2g²)/(3N),
//!
//! and for a blend p = (1 − w) a + w b: ∂ ln p/∂θ_a = (1 − w) a ∂ ln a/∂θ_a / p,
//! ∂ ln p/∂θ_b = w b ∂ ln b/∂θ_b / p, ∂ ln p/∂w = (b − a)/p.

pub use crate::phase::Model;
use crate::phase::{build, Boxed, ModelParams};
use nephele_runtime::phase::{phase_draine, HenyeyGreenstein};
use nephele_runtime::PhaseFunction;

/// The models `nephele fit` fits (those of [`crate::phase::Model`] that it has gradients for),
/// in the order of reports.
pub const FITTED: [Model; 5] = [
    Model::Hg,
    Model::TwoTermHg,
    Model::CornetteShanks,
    Model::Draine,
    Model::HgDraine,
];

/// The largest |g| a fit may reach (HG at g = 0.999999 peaks at 2·10¹², still finite).
pub const G_MAX: f64 = 1.0 - 1e-6;

/// Where a parameter lives, and the smooth map from an unconstrained u onto it.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Bound {
    /// (−G, G) by θ = G tanh u, G = [`G_MAX`]: tanh rounds to exactly ±1 for |u| > 19, where
    /// HG's normalisation 1 − g² vanishes and ln p = −∞; a line search that wanders there
    /// must still see a finite loss.
    Symmetric,
    /// (lo, hi) by θ = lo + (hi − lo)/(1 + e^{−u}).
    Interval(f64, f64),
    /// Unbounded: θ = u.
    Free,
}

impl Bound {
    /// θ(u).
    pub fn to_param(self, u: f64) -> f64 {
        match self {
            Bound::Symmetric => G_MAX * u.tanh(),
            Bound::Interval(lo, hi) => lo + (hi - lo) / (1.0 + (-u).exp()),
            Bound::Free => u,
        }
    }

    /// dθ/du.
    pub fn slope(self, u: f64) -> f64 {
        match self {
            Bound::Symmetric => G_MAX * (1.0 - u.tanh().powi(2)),
            Bound::Interval(lo, hi) => {
                let s = 1.0 / (1.0 + (-u).exp());
                (hi - lo) * s * (1.0 - s)
            }
            Bound::Free => 1.0,
        }
    }

    /// u(θ), for θ strictly inside the bound (clamped 1e-12 inside otherwise).
    pub fn to_free(self, theta: f64) -> f64 {
        match self {
            Bound::Symmetric => (theta / G_MAX).clamp(-1.0 + 1e-12, 1.0 - 1e-12).atanh(),
            Bound::Interval(lo, hi) => {
                let s = ((theta - lo) / (hi - lo)).clamp(1e-12, 1.0 - 1e-12);
                (s / (1.0 - s)).ln()
            }
            Bound::Free => theta,
        }
    }

    /// θ moved strictly inside the bound (by 1e-9 of its width).
    pub fn clamp(self, theta: f64) -> f64 {
        let (lo, hi) = match self {
            Bound::Symmetric => (-G_MAX, G_MAX),
            Bound::Interval(lo, hi) => (lo, hi),
            Bound::Free => return theta,
        };
        let eps = 1e-9 * (hi - lo);
        theta.clamp(lo + eps, hi - eps)
    }
}

/// What fitting needs of a model: θ's names and bounds, starts, ln p and its gradient. Only the
/// [`FITTED`] models have them (configs refuse the others): another model has no parameters
/// here, and ln p = NaN. Implemented for [`Model`].
pub trait Fitting: Sized {
    /// Parses a config name (either spelling) of a fitted model; the error lists the valid ones.
    fn fitted_from_name(name: &str) -> anyhow::Result<Model>;
    /// The names of θ's components.
    fn param_names(self) -> &'static [&'static str];
    /// The bounds of θ; α ∈ (0, `alpha_max`).
    fn bounds(self, alpha_max: f64) -> Vec<Bound>;
    /// Starts for this model built from the optimum θ of a simpler model it contains (or
    /// nearly contains): HG+Draine holds HG (w_D → 0), Draine (w_D → 1) and two-term HG
    /// (α → 0); Draine holds Cornette–Shanks (α = 1) and HG (α → 0). A small second lobe is
    /// added in a few directions, since that is where the extra freedom usually pays.
    fn nested_starts(self, inner: Model, t: &[f64]) -> Vec<Vec<f64>>;
    /// A coarse grid of θ covering droplet-like shapes, the global start of the fits.
    fn coarse_grid(self, alpha_max: f64) -> Vec<Vec<f64>>;
    /// ln p(μ; θ), writing ∂ ln p/∂θ into `grad` (θ.len() entries).
    fn ln_phase_grad(self, theta: &[f64], mu: f64, grad: &mut [f64]) -> f64;
    /// The runtime's evaluator for θ (for figures and the sampler), built by
    /// [`crate::phase::build`].
    fn phase(self, theta: &[f64]) -> anyhow::Result<Boxed>;
}

impl Fitting for Model {
    fn fitted_from_name(name: &str) -> anyhow::Result<Model> {
        let valid = || FITTED.map(|m| m.json_name()).join(", ");
        let m: Model = name
            .parse()
            .map_err(|_| anyhow::anyhow!("unknown model `{name}` (valid: {})", valid()))?;
        anyhow::ensure!(
            FITTED.contains(&m),
            "model `{name}` is not fitted (fitted models: {})",
            valid()
        );
        Ok(m)
    }

    fn param_names(self) -> &'static [&'static str] {
        match self {
            Model::Hg | Model::CornetteShanks => &["g"],
            Model::TwoTermHg => &["g1", "g2", "w"],
            Model::Draine => &["g", "alpha"],
            Model::HgDraine => &["g_hg", "g_d", "alpha", "w_d"],
            _ => &[],
        }
    }

    fn bounds(self, alpha_max: f64) -> Vec<Bound> {
        let alpha = Bound::Interval(0.0, alpha_max);
        let w = Bound::Interval(0.0, 1.0);
        match self {
            Model::Hg | Model::CornetteShanks => vec![Bound::Symmetric],
            Model::TwoTermHg => vec![Bound::Symmetric, Bound::Symmetric, w],
            Model::Draine => vec![Bound::Symmetric, alpha],
            Model::HgDraine => vec![Bound::Symmetric, Bound::Symmetric, alpha, w],
            _ => Vec::new(),
        }
    }

    fn nested_starts(self, inner: Model, t: &[f64]) -> Vec<Vec<f64>> {
        let a0 = 1e-3; // α → 0: Draine → HG
        match (self, inner) {
            (Model::Draine, Model::Hg) => vec![vec![t[0], a0]],
            (Model::Draine, Model::CornetteShanks) => vec![vec![t[0], 1.0]],
            (Model::HgDraine, Model::Hg) => [-0.5, 0.0, 0.5]
                .iter()
                .map(|&g_d| vec![t[0], g_d, 10.0, 0.05])
                .collect(),
            (Model::HgDraine, Model::TwoTermHg) => {
                vec![vec![t[0], t[1], a0, 1.0 - t[2]], vec![t[1], t[0], a0, t[2]]]
            }
            (Model::HgDraine, Model::CornetteShanks) => vec![vec![0.0, t[0], 1.0, 0.98]],
            (Model::HgDraine, Model::Draine) => [-0.5, 0.0, 0.5]
                .iter()
                .map(|&g_hg| vec![g_hg, t[0], t[1], 0.98])
                .collect(),
            _ => Vec::new(),
        }
    }

    fn coarse_grid(self, alpha_max: f64) -> Vec<Vec<f64>> {
        let gs = |lo: f64, hi: f64, n: usize| -> Vec<f64> {
            (0..n)
                .map(|i| lo + (hi - lo) * i as f64 / (n - 1) as f64)
                .collect()
        };
        let alphas: Vec<f64> = [0.01, 0.3, 1.0, 3.0, 10.0, 30.0, 100.0, 250.0]
            .into_iter()
            .map(|a: f64| a.min(0.98 * alpha_max))
            .collect();
        let forward = [0.5, 0.7, 0.8, 0.88, 0.93, 0.96, 0.98, 0.99, 0.995];
        let mut grid = Vec::new();
        match self {
            Model::Hg | Model::CornetteShanks => {
                grid.extend(gs(-0.9, 0.99, 64).into_iter().map(|g| vec![g]))
            }
            Model::TwoTermHg => {
                for &g1 in &forward {
                    for g2 in gs(-0.8, 0.6, 8) {
                        for w in gs(0.3, 0.97, 7) {
                            grid.push(vec![g1, g2, w]);
                        }
                    }
                }
            }
            Model::Draine => {
                for g in gs(-0.8, 0.99, 24) {
                    for &a in &alphas {
                        grid.push(vec![g, a]);
                    }
                }
            }
            // Small droplets have optima far from the large-droplet shape: a backward HG lobe of
            // weight 0.01 beside a forward Draine lobe (0.85 µm), or a faint backward Draine lobe
            // (2.5 µm); SciPy from random starts found them when this grid lacked g_HG < 0.5 and
            // w_D > 0.8 (scripts/check_fit.py).
            Model::HgDraine => {
                let g_hgs = [-0.6, -0.3, 0.0, 0.3].iter().chain(&forward);
                for &g_hg in g_hgs {
                    for g_d in gs(-0.8, 0.9, 8) {
                        for &a in &alphas {
                            for w in [0.02, 0.05, 0.15, 0.3, 0.45, 0.6, 0.8, 0.95, 0.99] {
                                grid.push(vec![g_hg, g_d, a, w]);
                            }
                        }
                    }
                }
            }
            _ => {}
        }
        grid
    }

    #[inline]
    fn ln_phase_grad(self, theta: &[f64], mu: f64, grad: &mut [f64]) -> f64 {
        match self {
            Model::Hg => {
                let (p, dg) = hg_lobe(theta[0], mu);
                grad[0] = dg;
                p.ln()
            }
            Model::CornetteShanks => {
                let (p, dg, _) = draine_lobe(theta[0], 1.0, mu);
                grad[0] = dg;
                p.ln()
            }
            Model::Draine => {
                let (p, dg, da) = draine_lobe(theta[0], theta[1], mu);
                grad[0] = dg;
                grad[1] = da;
                p.ln()
            }
            Model::TwoTermHg => {
                // p = w HG(g1) + (1 − w) HG(g2)
                let w = theta[2];
                let (a, da) = hg_lobe(theta[0], mu);
                let (b, db) = hg_lobe(theta[1], mu);
                let p = w * a + (1.0 - w) * b;
                grad[0] = w * a * da / p;
                grad[1] = (1.0 - w) * b * db / p;
                grad[2] = (a - b) / p;
                p.ln()
            }
            Model::HgDraine => {
                let w = theta[3];
                let (a, da) = hg_lobe(theta[0], mu);
                let (b, dbg, dba) = draine_lobe(theta[1], theta[2], mu);
                let p = (1.0 - w) * a + w * b;
                grad[0] = (1.0 - w) * a * da / p;
                grad[1] = w * b * dbg / p;
                grad[2] = w * b * dba / p;
                grad[3] = (b - a) / p;
                p.ln()
            }
            _ => f64::NAN,
        }
    }

    fn phase(self, theta: &[f64]) -> anyhow::Result<Boxed> {
        let p = |i: usize| theta.get(i).copied();
        let params = match self {
            Model::Hg | Model::CornetteShanks => ModelParams {
                g: p(0),
                ..ModelParams::default()
            },
            Model::Draine => ModelParams {
                g: p(0),
                alpha: p(1),
                ..ModelParams::default()
            },
            Model::TwoTermHg => ModelParams {
                g: p(0),
                g2: p(1),
                w: p(2),
                ..ModelParams::default()
            },
            Model::HgDraine => ModelParams {
                g_hg: p(0),
                g_d: p(1),
                alpha: p(2),
                w_d: p(3),
                ..ModelParams::default()
            },
            _ => ModelParams::default(),
        };
        Ok(build(self, &params)?.0)
    }
}

/// HG(g, μ) and ∂ ln HG/∂g.
#[inline]
fn hg_lobe(g: f64, mu: f64) -> (f64, f64) {
    let p = HenyeyGreenstein::new(g).eval(mu);
    // t = 1 + g² − 2gμ, written to keep its digits in the peak (as the runtime does).
    let t = if g >= 0.0 {
        (1.0 - g) * (1.0 - g) + 2.0 * g * (1.0 - mu)
    } else {
        (1.0 + g) * (1.0 + g) - 2.0 * g * (1.0 + mu)
    };
    (p, -2.0 * g / ((1.0 - g) * (1.0 + g)) - 3.0 * (g - mu) / t)
}

/// Draine(g, α, μ), ∂ ln D/∂g and ∂ ln D/∂α.
#[inline]
fn draine_lobe(g: f64, alpha: f64, mu: f64) -> (f64, f64, f64) {
    let p = phase_draine(g, alpha, mu);
    let (_, dg_hg) = hg_lobe(g, mu);
    let norm = 1.0 + alpha * (1.0 + 2.0 * g * g) / 3.0;
    let q = 1.0 + alpha * mu * mu;
    (
        p,
        dg_hg - 4.0 * alpha * g / (3.0 * norm),
        mu * mu / q - (1.0 + 2.0 * g * g) / (3.0 * norm),
    )
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn gradients_match_central_differences() {
        let cases: [(Model, Vec<f64>); 5] = [
            (Model::Hg, vec![0.83]),
            (Model::CornetteShanks, vec![-0.4]),
            (Model::Draine, vec![0.6, 17.0]),
            (Model::TwoTermHg, vec![0.9, -0.3, 0.8]),
            (Model::HgDraine, vec![0.97, 0.5, 18.0, 0.44]),
        ];
        for (m, theta) in cases {
            for mu in [-1.0, -0.3, 0.0, 0.5, 0.99, 1.0] {
                let mut grad = vec![0.0; theta.len()];
                let mut scratch = grad.clone();
                m.ln_phase_grad(&theta, mu, &mut grad);
                for k in 0..theta.len() {
                    let h = 1e-6 * theta[k].abs().max(1e-3);
                    let (mut tp, mut tm) = (theta.clone(), theta.clone());
                    tp[k] += h;
                    tm[k] -= h;
                    let fd = (m.ln_phase_grad(&tp, mu, &mut scratch)
                        - m.ln_phase_grad(&tm, mu, &mut scratch))
                        / (2.0 * h);
                    assert!(
                        (fd - grad[k]).abs() <= 1e-6 * fd.abs().max(1.0),
                        "{m:?} θ{k} at μ = {mu}: analytic {} vs difference {fd}",
                        grad[k]
                    );
                }
            }
        }
    }

    #[test]
    fn bounds_round_trip() {
        for b in [
            Bound::Symmetric,
            Bound::Interval(0.0, 250.0),
            Bound::Interval(0.0, 1.0),
        ] {
            for u in [-5.0, -0.3, 0.0, 2.0, 7.0] {
                let t = b.to_param(u);
                assert!((b.to_free(t) - u).abs() < 1e-8, "{b:?} u = {u}");
                let h = 1e-6;
                let fd = (b.to_param(u + h) - b.to_param(u - h)) / (2.0 * h);
                assert!((fd - b.slope(u)).abs() < 1e-7 * fd.abs().max(1.0));
            }
        }
    }
}
