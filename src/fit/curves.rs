//! Diameter → parameter curves of HG+Draine over a diameter range, in the paper's functional
//! forms (or others, per parameter in the config):
//!
//! | form | θ(d) | coefficients |
//! |---|---|---|
//! | `exp_rational` | exp(A − B/(d + C)) | A, B, C |
//! | `exp_rational_no_offset` | exp(−B/(d + C)) | B, C |
//! | `poly_ln_d_K` | Σₖ cₖ (ln d − L₀)ᵏ, k ≤ K, L₀ the mean ln d of the range | c0 … cK |
//! | `constant` | c0 | c0 |
//!
//! The paper's g_HG = exp(−a/(d − b)) is `exp_rational_no_offset` with B = a, C = −b;
//! g_D = exp(−a/(d + b) − c) and w_D = exp(−a/(d − b) − c) are `exp_rational` (A = −c), and
//! α = exp(a − b/(d + c)) is `exp_rational` as written. Internally C = e^s − d_min so that the
//! pole stays left of the range.
//!
//! Two steps. (1) Each parameter alone by least squares (in ln θ for the exp forms, in θ for
//! the others) through the per-diameter optima — what the paper did. (2) All coefficients
//! together by minimising the total loss over the total optimum, Σ_d E_AS(θ(d); d) / Σ_d
//! E_opt(d), with L-BFGS and the chain rule through the loss gradient, from the step-1 curves
//! and from the same forms fitted through the paper's parameters (the better kept): the curve
//! is judged by the loss it gives, not by how close its parameters are to the optima (the loss
//! is flat along some parameter combinations and steep along others).

use super::loss::Target;
use super::model::Fitting;
use super::model::{Bound, Model};
use super::optimize::{minimise, polish_iters, Objective, Optimum};
use anyhow::{bail, Result};
use rayon::prelude::*;
use serde::Serialize;
use std::collections::BTreeMap;

/// A functional form θ(d).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Form {
    /// exp(A − B/(d + C)).
    ExpRational,
    /// exp(−B/(d + C)).
    ExpRationalNoOffset,
    /// Polynomial in ln d − L₀ of the given degree.
    PolyLnD(usize),
    /// A constant.
    Constant,
}

/// The form names a config may use, for error messages.
pub const FORM_NAMES: &str =
    "exp_rational, exp_rational_no_offset, poly_ln_d_1 … poly_ln_d_5, constant";

impl Form {
    /// Parses a config name.
    pub fn parse(name: &str) -> Result<Form> {
        Ok(match name {
            "exp_rational" => Form::ExpRational,
            "exp_rational_no_offset" => Form::ExpRationalNoOffset,
            "constant" => Form::Constant,
            _ => match name.strip_prefix("poly_ln_d_").and_then(|k| k.parse().ok()) {
                Some(k) if (1..=5).contains(&k) => Form::PolyLnD(k),
                _ => bail!("unknown curve form `{name}` (valid: {FORM_NAMES})"),
            },
        })
    }

    /// The config name.
    pub fn name(self) -> String {
        match self {
            Form::ExpRational => "exp_rational".into(),
            Form::ExpRationalNoOffset => "exp_rational_no_offset".into(),
            Form::PolyLnD(k) => format!("poly_ln_d_{k}"),
            Form::Constant => "constant".into(),
        }
    }

    pub(crate) fn n_coef(self) -> usize {
        match self {
            Form::ExpRational => 3,
            Form::ExpRationalNoOffset => 2,
            Form::PolyLnD(k) => k + 1,
            Form::Constant => 1,
        }
    }

    fn is_exp(self) -> bool {
        matches!(self, Form::ExpRational | Form::ExpRationalNoOffset)
    }
}

/// One fitted curve θ(d).
#[derive(Clone, Debug)]
pub struct Curve {
    /// Its form.
    pub form: Form,
    /// Smallest diameter of the range (µm): the exp forms keep their pole left of it.
    pub d_min: f64,
    /// L₀ of the polynomial forms.
    pub ln_d0: f64,
    /// Internal coefficients ([A, B, s] or [B, s] with C = e^s − d_min; polynomial cₖ).
    coef: Vec<f64>,
}

impl Curve {
    /// θ(d).
    pub fn at(&self, d: f64) -> f64 {
        let mut g = vec![0.0; self.coef.len()];
        self.eval_grad(&self.coef, d, &mut g)
    }

    /// θ(d; c) and ∂θ/∂c.
    fn eval_grad(&self, c: &[f64], d: f64, grad: &mut [f64]) -> f64 {
        match self.form {
            Form::ExpRational | Form::ExpRationalNoOffset => {
                let (a, b, s) = match self.form {
                    Form::ExpRational => (c[0], c[1], c[2]),
                    _ => (0.0, c[0], c[1]),
                };
                let x = 1.0 / (d - self.d_min + s.exp());
                let v = (a - b * x).exp();
                let (db, ds) = (-v * x, v * b * x * x * s.exp());
                match self.form {
                    Form::ExpRational => grad.copy_from_slice(&[v, db, ds]),
                    _ => grad.copy_from_slice(&[db, ds]),
                }
                v
            }
            Form::PolyLnD(_) | Form::Constant => {
                let l = d.ln() - self.ln_d0;
                let mut pow = 1.0;
                let mut v = 0.0;
                for (k, ck) in c.iter().enumerate() {
                    grad[k] = pow;
                    v += ck * pow;
                    pow *= l;
                }
                v
            }
        }
    }

    /// The coefficients as reported (A, B, C or c0 …, with L0).
    pub fn coefficients(&self) -> BTreeMap<String, f64> {
        let c = &self.coef;
        let mut out = BTreeMap::new();
        match self.form {
            Form::ExpRational => {
                out.insert("A".into(), c[0]);
                out.insert("B".into(), c[1]);
                out.insert("C".into(), c[2].exp() - self.d_min);
            }
            Form::ExpRationalNoOffset => {
                out.insert("B".into(), c[0]);
                out.insert("C".into(), c[1].exp() - self.d_min);
            }
            Form::PolyLnD(_) | Form::Constant => {
                for (k, v) in c.iter().enumerate() {
                    out.insert(format!("c{k}"), *v);
                }
                out.insert("L0".into(), self.ln_d0);
            }
        }
        out
    }

    /// θ(d) as a formula with the numbers in (d in µm).
    pub fn expression(&self) -> String {
        let k = self.coefficients();
        // "x - c" written with the sign folded in: "x + 0.5" rather than "x - -0.5".
        let minus = |x: &str, c: f64| {
            if c < 0.0 {
                format!("{x} + {:.6}", -c)
            } else {
                format!("{x} - {c:.6}")
            }
        };
        match self.form {
            Form::ExpRational => {
                let sign = if k["B"] < 0.0 { '+' } else { '-' };
                format!(
                    "exp({:.6} {sign} {:.6}/({}))",
                    k["A"],
                    k["B"].abs(),
                    minus("d", -k["C"])
                )
            }
            Form::ExpRationalNoOffset => format!("exp(-{:.6}/({}))", k["B"], minus("d", -k["C"])),
            Form::PolyLnD(_) | Form::Constant => {
                let x = minus("ln d", self.ln_d0);
                let terms: Vec<String> = self
                    .coef
                    .iter()
                    .enumerate()
                    .map(|(i, c)| match i {
                        0 => format!("{c:.6}"),
                        1 => format!("{c:+.6}*({x})"),
                        _ => format!("{c:+.6}*({x})^{i}"),
                    })
                    .collect();
                terms.join(" ")
            }
        }
    }
}

/// Least squares of one form through (d, θ) points: in ln θ for exp forms, θ otherwise.
struct PointFit<'a> {
    curve: &'a Curve,
    d: &'a [f64],
    y: &'a [f64],
}

impl Objective for PointFit<'_> {
    fn loss_grad(&self, c: &[f64], grad: &mut [f64]) -> f64 {
        let mut g = vec![0.0; c.len()];
        grad.iter_mut().for_each(|x| *x = 0.0);
        let mut sse = 0.0;
        for (&d, &y) in self.d.iter().zip(self.y) {
            let v = self.curve.eval_grad(c, d, &mut g);
            // ln θ for the exp forms: ∂ ln v = ∂v / v.
            let (r, scale) = if self.curve.form.is_exp() {
                (v.ln() - y, 1.0 / v)
            } else {
                (v - y, 1.0)
            };
            sse += r * r;
            for k in 0..c.len() {
                grad[k] += 2.0 * r * g[k] * scale;
            }
        }
        sse
    }
}

/// Step 1: the least-squares curve of `form` through the points (d, θ).
pub fn fit_points(form: Form, d: &[f64], theta: &[f64]) -> Result<Curve> {
    let d_min = d.iter().copied().fold(f64::INFINITY, f64::min);
    let ln_d0 = d.iter().map(|d| d.ln()).sum::<f64>() / d.len() as f64;
    if form.is_exp() && theta.iter().any(|t| *t <= 0.0) {
        bail!("form {} needs positive values", form.name());
    }
    let y: Vec<f64> = if form.is_exp() {
        theta.iter().map(|t| t.ln()).collect()
    } else {
        theta.to_vec()
    };
    let mut curve = Curve {
        form,
        d_min,
        ln_d0,
        coef: vec![0.0; form.n_coef()],
    };
    let starts = starts(form, d, &y, d_min);
    let obj = PointFit {
        curve: &curve,
        d,
        y: &y,
    };
    let bounds = vec![Bound::Free; form.n_coef()];
    let best = minimise(&obj, &bounds, &starts, 3, &[]);
    curve.coef = best.params;
    Ok(curve)
}

/// Starting coefficients: for the exp forms, the closed-form regression of ln θ on
/// x = 1/(d + C) over a scan of C; for the polynomials, the mean.
fn starts(form: Form, d: &[f64], y: &[f64], d_min: f64) -> Vec<Vec<f64>> {
    let n = d.len() as f64;
    let ybar = y.iter().sum::<f64>() / n;
    if !form.is_exp() {
        let mut c = vec![0.0; form.n_coef()];
        c[0] = ybar;
        return vec![c];
    }
    let d_max = d.iter().copied().fold(0.0, f64::max);
    (0..200)
        .map(|i| {
            let s = (1e-3 * d_min).ln() + ((30.0 * d_max) / (1e-3 * d_min)).ln() * i as f64 / 199.0;
            let x: Vec<f64> = d.iter().map(|d| 1.0 / (d - d_min + s.exp())).collect();
            if form == Form::ExpRational {
                let xbar = x.iter().sum::<f64>() / n;
                let sxy: f64 = x.iter().zip(y).map(|(x, y)| (x - xbar) * (y - ybar)).sum();
                let sxx: f64 = x.iter().map(|x| (x - xbar).powi(2)).sum();
                let b = -sxy / sxx.max(1e-300);
                vec![ybar + b * xbar, b, s]
            } else {
                let sxy: f64 = x.iter().zip(y).map(|(x, y)| x * y).sum();
                let sxx: f64 = x.iter().map(|x| x * x).sum();
                vec![-sxy / sxx, s]
            }
        })
        .collect()
}

/// One diameter of a branch, for the joint polish.
pub struct Site<'a> {
    /// Diameter (µm).
    pub d: f64,
    /// Its Mie target.
    pub target: &'a Target,
    /// The per-diameter optimum of HG+Draine there.
    pub e_opt: f64,
}

/// Step 2: the total loss of four HG+Draine curves over the total optimum,
/// Σ_d E_AS(θ(d); d) / Σ_d E_opt(d) (≥ 1).
struct JointLoss<'a> {
    curves: &'a [Curve; 4],
    sites: &'a [Site<'a>],
    bounds: Vec<Bound>,
}

impl JointLoss<'_> {
    fn split<'c>(&self, c: &'c [f64]) -> Vec<&'c [f64]> {
        let mut out = Vec::new();
        let mut at = 0;
        for curve in self.curves {
            out.push(&c[at..at + curve.coef.len()]);
            at += curve.coef.len();
        }
        out
    }
}

impl Objective for JointLoss<'_> {
    fn loss_grad(&self, c: &[f64], grad: &mut [f64]) -> f64 {
        let parts = self.split(c);
        // One scale for all sites: a per-site 1/E_opt would let the smallest droplets, whose
        // optima reach 10⁻⁶, outweigh the rest by orders of magnitude.
        let scale = 1.0 / self.sites.iter().map(|s| s.e_opt).sum::<f64>();
        // Per site in parallel, summed in order: the same bits whatever the thread count.
        let per_site: Vec<(f64, Vec<f64>)> = self
            .sites
            .par_iter()
            .map(|site| {
                let mut dtheta_dc: Vec<Vec<f64>> = Vec::with_capacity(4);
                let mut theta = [0.0; 4];
                for k in 0..4 {
                    let mut g = vec![0.0; parts[k].len()];
                    let raw = self.curves[k].eval_grad(parts[k], site.d, &mut g);
                    theta[k] = self.bounds[k].clamp(raw);
                    if theta[k] != raw {
                        g.iter_mut().for_each(|x| *x = 0.0);
                    }
                    dtheta_dc.push(g);
                }
                let mut de = [0.0; 4];
                let e = site.target.loss_grad(Model::HgDraine, &theta, &mut de);
                let g: Vec<f64> = (0..4)
                    .flat_map(|k| {
                        dtheta_dc[k]
                            .iter()
                            .map(move |x| x * de[k] * scale)
                            .collect::<Vec<_>>()
                    })
                    .collect();
                (e * scale, g)
            })
            .collect();
        grad.iter_mut().for_each(|x| *x = 0.0);
        let mut total = 0.0;
        for (e, g) in &per_site {
            total += e;
            for (a, b) in grad.iter_mut().zip(g) {
                *a += b;
            }
        }
        total
    }
}

/// Largest L-BFGS iterations of the joint polish.
const CURVE_MAX_ITERS: u64 = 4000;

/// Step 2 from the step-1 curves: returns the polished curves and the optimiser's report.
pub fn polish_on_loss(
    curves: [Curve; 4],
    sites: &[Site<'_>],
    alpha_max: f64,
) -> ([Curve; 4], Optimum) {
    let c0: Vec<f64> = curves.iter().flat_map(|c| c.coef.clone()).collect();
    let joint = JointLoss {
        curves: &curves,
        sites,
        bounds: Model::HgDraine.bounds(alpha_max),
    };
    let free = vec![Bound::Free; c0.len()];
    // 12–16 coefficients along narrow valleys: more iterations than a per-diameter fit.
    let best = polish_iters(&joint, &free, &c0, CURVE_MAX_ITERS);
    let mut out = curves.clone();
    let mut at = 0;
    for curve in out.iter_mut() {
        let n = curve.coef.len();
        curve.coef = best.params[at..at + n].to_vec();
        at += n;
    }
    (out, best)
}

/// A curve as written to fits.json.
#[derive(Clone, Debug, Serialize)]
pub struct CurveReport {
    /// Form name.
    pub form: String,
    /// The formula with its numbers.
    pub expression: String,
    /// The coefficients by name.
    pub coefficients: BTreeMap<String, f64>,
}

impl From<&Curve> for CurveReport {
    fn from(c: &Curve) -> Self {
        Self {
            form: c.form.name(),
            expression: c.expression(),
            coefficients: c.coefficients(),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn recovers_a_known_exp_rational_curve() {
        // The paper's α(d) sampled at 5…50 µm is an exp_rational with A, B, C = 3.62489,
        // 8.29288, 5.52825.
        let d: Vec<f64> = (5..=50).map(|d| d as f64).collect();
        let a: Vec<f64> = d
            .iter()
            .map(|d| (3.62489 - 8.29288 / (d + 5.52825)).exp())
            .collect();
        let c = fit_points(Form::ExpRational, &d, &a).unwrap();
        let k = c.coefficients();
        assert!((k["A"] - 3.62489).abs() < 1e-4, "{k:?}");
        assert!((k["B"] - 8.29288).abs() < 1e-3, "{k:?}");
        assert!((k["C"] - 5.52825).abs() < 1e-3, "{k:?}");
        let g: Vec<f64> = d
            .iter()
            .map(|d| (-0.0990567 / (d - 1.67154)).exp())
            .collect();
        let c = fit_points(Form::ExpRationalNoOffset, &d, &g).unwrap();
        assert!(
            (c.coefficients()["C"] + 1.67154).abs() < 1e-3,
            "{:?}",
            c.coefficients()
        );
    }

    #[test]
    fn polynomial_in_ln_d() {
        let d: Vec<f64> = (1..=20).map(|i| 0.1 * 1.2f64.powi(i)).collect();
        let y: Vec<f64> = d
            .iter()
            .map(|d| 0.3 + 0.1 * d.ln() - 0.02 * d.ln().powi(2))
            .collect();
        let c = fit_points(Form::PolyLnD(2), &d, &y).unwrap();
        for (d, y) in d.iter().zip(&y) {
            assert!((c.at(*d) - y).abs() < 1e-7, "{} vs {y}", c.at(*d));
        }
        assert!(Form::parse("poly_ln_d_9").is_err());
        assert!(Form::parse("cubic")
            .unwrap_err()
            .to_string()
            .contains("exp_rational"));
    }
}
