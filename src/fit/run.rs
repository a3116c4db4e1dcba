//! A whole fit run over the Mie tables of a config: per-diameter optima of every model (coarse
//! grid + L-BFGS, then warm-start sweeps between neighbouring diameters), HG+Draine curves per
//! branch, and the paper's curves evaluated on the same tables.

use super::config::FitConfig;
use super::curves::{fit_points, polish_on_loss, Curve, CurveReport, Site};
use super::loss::Target;
use super::model::Fitting;
use super::model::Model;
use super::optimize::{minimise, Objective, Optimum};
use crate::mie::PhaseTable;
use anyhow::{bail, Result};
use nephele_runtime::presets::jendersie_deon;
use rayon::prelude::*;
use serde::Serialize;
use std::collections::BTreeMap;

/// One model against one Mie target.
struct ModelLoss<'a> {
    target: &'a Target,
    model: Model,
}

impl Objective for ModelLoss<'_> {
    fn loss_grad(&self, theta: &[f64], grad: &mut [f64]) -> f64 {
        self.target.loss_grad(self.model, theta, grad)
    }
    fn loss(&self, theta: &[f64]) -> f64 {
        self.target.loss(self.model, theta)
    }
}

/// L-BFGS starts taken from the coarse grid.
const GRID_STARTS: usize = 6;
/// Largest number of warm-start sweeps.
const MAX_SWEEPS: usize = 4;

/// One model's optimum at one diameter, as reported.
#[derive(Clone, Debug, Serialize)]
pub struct ModelFit {
    /// Parameters by name.
    pub params: BTreeMap<String, f64>,
    /// The optimiser's record (θ in model order, loss, gradient norms, evaluations, …).
    #[serde(flatten)]
    pub optimum: Optimum,
}

/// Everything fitted at one diameter.
#[derive(Clone, Debug, Serialize)]
pub struct DiameterFits {
    /// Median diameter (µm).
    pub d_um: f64,
    /// Per model.
    pub models: BTreeMap<String, ModelFit>,
    /// The paper's HG+Draine at this d (its branch formulas) and its loss on our table.
    pub paper: ParamsLoss,
}

/// HG+Draine parameters and their loss.
#[derive(Clone, Debug, Serialize)]
pub struct ParamsLoss {
    /// g_hg, g_d, alpha, w_d.
    pub params: BTreeMap<String, f64>,
    /// The loss on our Mie table.
    pub loss: f64,
}

/// A curve branch's result at one diameter.
#[derive(Clone, Debug, Serialize)]
pub struct CurvePoint {
    /// Diameter (µm).
    pub d_um: f64,
    /// Loss of the per-diameter HG+Draine optimum.
    pub loss_optimum: f64,
    /// Loss of our curve (after the joint polish).
    pub loss_curve: f64,
    /// Loss of the least-squares curve through the optima (step 1 only).
    pub loss_curve_step1: f64,
    /// Loss of the paper's curve.
    pub loss_paper: f64,
    /// loss_curve − loss_optimum.
    pub extra_loss: f64,
    /// extra_loss / loss_optimum.
    pub extra_loss_relative: f64,
    /// Our curve's parameters at d.
    pub params_curve: BTreeMap<String, f64>,
}

/// One fitted branch.
#[derive(Clone, Debug, Serialize)]
pub struct BranchReport {
    /// [lo, hi] (µm).
    pub range_um: [f64; 2],
    /// Our curves (after the joint polish), by parameter.
    pub curves: BTreeMap<String, CurveReport>,
    /// The least-squares curves through the optima (step 1).
    pub curves_step1: BTreeMap<String, CurveReport>,
    /// The joint polish's optimiser record (its θ are the internal coefficients).
    pub polish: Optimum,
    /// Which step-2 start won: "optima" (curves through our optima) or "paper" (the same forms
    /// through the paper's parameters).
    pub polish_start: String,
    /// Per diameter of the range.
    pub points: Vec<CurvePoint>,
    /// Diameters where our curve's loss ≤ the paper's, of all in the range.
    pub curve_beats_paper: [usize; 2],
    #[serde(skip)]
    /// The curves themselves, for figures.
    pub fitted: Vec<Curve>,
}

/// Everything a fit run found.
#[derive(Clone, Debug, Serialize)]
pub struct FitReport {
    /// Diameters (µm), increasing.
    pub diameters_um: Vec<f64>,
    /// Per diameter.
    pub fits: Vec<DiameterFits>,
    /// Warm-start sweeps run (each over all diameters and models).
    pub sweeps: usize,
    /// Per-diameter optima improved by the sweeps.
    pub improved_by_warm_starts: usize,
    /// Curve branches.
    pub branches: Vec<BranchReport>,
}

/// The HG+Draine parameter names, in θ order.
pub const HG_DRAINE_PARAMS: [&str; 4] = ["g_hg", "g_d", "alpha", "w_d"];

fn named(model: Model, theta: &[f64]) -> BTreeMap<String, f64> {
    model
        .param_names()
        .iter()
        .map(|n| n.to_string())
        .zip(theta.iter().copied())
        .collect()
}

/// The paper's blend at d as θ = [g_hg, g_d, α, w_d].
pub fn paper_theta(d_um: f64) -> [f64; 4] {
    let p = jendersie_deon(d_um);
    [p.g_hg, p.g_d, p.alpha, p.w_d]
}

/// Runs the fits on `tables` (one per diameter); `progress(done, total)` counts fits.
pub fn run(
    cfg: &FitConfig,
    tables: &[PhaseTable],
    progress: &(dyn Fn(usize, usize) + Sync),
) -> Result<(FitReport, Vec<Target>)> {
    cfg.validate()?;
    let models = cfg.models()?;
    let diameters: Vec<f64> = tables
        .iter()
        .map(|t| t.distribution.nominal_diameter_um())
        .collect();
    cfg.check_branches(&diameters)?;
    if diameters.windows(2).any(|w| w[1] <= w[0]) {
        bail!("fit diameters must be strictly increasing");
    }
    let targets: Vec<Target> = tables
        .iter()
        .map(|t| Target::new(&t.theta_deg, &t.phase, cfg.loss))
        .collect::<Result<_>>()?;
    let total = diameters.len() * models.len();
    let done = std::sync::atomic::AtomicUsize::new(0);
    // Global fits, parallel over diameters; at one diameter the models in order, each also
    // started from the embeddings of the simpler models' optima (Model::nested_starts), so a
    // model is never worse than a model it contains.
    let mut best: Vec<Vec<Optimum>> = (0..diameters.len())
        .into_par_iter()
        .map(|i| {
            let mut fitted: Vec<(Model, Optimum)> = Vec::with_capacity(models.len());
            for &m in &models {
                let obj = ModelLoss {
                    target: &targets[i],
                    model: m,
                };
                let nested: Vec<Vec<f64>> = fitted
                    .iter()
                    .flat_map(|(inner, o)| m.nested_starts(*inner, &o.params))
                    .collect();
                let grid = m.coarse_grid(cfg.alpha_max);
                let o = minimise(&obj, &m.bounds(cfg.alpha_max), &grid, GRID_STARTS, &nested);
                progress(
                    done.fetch_add(1, std::sync::atomic::Ordering::Relaxed) + 1,
                    total,
                );
                fitted.push((m, o));
            }
            fitted.into_iter().map(|(_, o)| o).collect()
        })
        .collect();
    let (sweeps, improved) = warm_start_sweeps(cfg, &models, &targets, &mut best);
    let fits = diameters
        .iter()
        .zip(&best)
        .zip(&targets)
        .map(|((&d, opts), target)| {
            let theta = paper_theta(d);
            DiameterFits {
                d_um: d,
                models: models
                    .iter()
                    .zip(opts)
                    .map(|(m, o)| {
                        (
                            m.json_name(),
                            ModelFit {
                                params: named(*m, &o.params),
                                optimum: o.clone(),
                            },
                        )
                    })
                    .collect(),
                paper: ParamsLoss {
                    params: named(Model::HgDraine, &theta),
                    loss: target.loss(Model::HgDraine, &theta),
                },
            }
        })
        .collect();
    let mut report = FitReport {
        diameters_um: diameters,
        fits,
        sweeps,
        improved_by_warm_starts: improved,
        branches: Vec::new(),
    };
    let hgd = models.iter().position(|m| *m == Model::HgDraine);
    for branch in &cfg.curves {
        let hgd = hgd.expect("validated: curves need hg_draine");
        report
            .branches
            .push(fit_branch(cfg, branch, &report, &targets, &best, hgd)?);
    }
    Ok((report, targets))
}

/// Re-polishes every (diameter, model) from its neighbours' optima until nothing improves;
/// each sweep reads only the previous sweep's results (the same bits for any thread count).
fn warm_start_sweeps(
    cfg: &FitConfig,
    models: &[Model],
    targets: &[Target],
    best: &mut [Vec<Optimum>],
) -> (usize, usize) {
    let n = targets.len();
    let mut improved_total = 0;
    for sweep in 1..=MAX_SWEEPS {
        let prev = best.to_vec();
        let next: Vec<Vec<Optimum>> = (0..n)
            .into_par_iter()
            .map(|i| {
                models
                    .iter()
                    .enumerate()
                    .map(|(k, &m)| {
                        let warm: Vec<Vec<f64>> = [i.wrapping_sub(1), i + 1]
                            .into_iter()
                            .filter(|&j| j < n)
                            .map(|j| prev[j][k].params.clone())
                            .collect();
                        if warm.is_empty() {
                            return prev[i][k].clone(); // a single diameter has no neighbours
                        }
                        let obj = ModelLoss {
                            target: &targets[i],
                            model: m,
                        };
                        let o = minimise(&obj, &m.bounds(cfg.alpha_max), &[], 0, &warm);
                        let mut kept = prev[i][k].clone();
                        kept.evaluations += o.evaluations;
                        if o.loss < kept.loss * (1.0 - 1e-9) {
                            let evals = kept.evaluations;
                            kept = o;
                            kept.evaluations = evals;
                        }
                        kept
                    })
                    .collect()
            })
            .collect();
        let improved = next
            .iter()
            .flatten()
            .zip(prev.iter().flatten())
            .filter(|(a, b)| a.loss < b.loss)
            .count();
        best.clone_from_slice(&next);
        improved_total += improved;
        if improved == 0 {
            return (sweep, improved_total);
        }
    }
    (MAX_SWEEPS, improved_total)
}

fn fit_branch(
    cfg: &FitConfig,
    branch: &super::config::BranchConfig,
    report: &FitReport,
    targets: &[Target],
    best: &[Vec<Optimum>],
    hgd: usize,
) -> Result<BranchReport> {
    let [lo, hi] = branch.range_um;
    let idx: Vec<usize> = (0..report.diameters_um.len())
        .filter(|&i| (lo..=hi).contains(&report.diameters_um[i]))
        .collect();
    let forms = branch.forms()?;
    let d: Vec<f64> = idx.iter().map(|&i| report.diameters_um[i]).collect();
    // Step 1 through our optima; the same forms through the paper's parameters as a second
    // start of step 2 (where the optima jump between modes, as below 1 µm, a curve through
    // them is a poor start and the paper's smoother path a better one).
    let through = |param: &dyn Fn(usize, usize) -> f64| -> Result<[Curve; 4]> {
        let curves: Vec<Curve> = (0..4)
            .map(|k| {
                fit_points(
                    forms[k],
                    &d,
                    &idx.iter().map(|&i| param(i, k)).collect::<Vec<_>>(),
                )
            })
            .collect::<Result<_>>()?;
        Ok(curves.try_into().expect("four curves"))
    };
    let step1 = through(&|i, k| best[i][hgd].params[k])?;
    let via_paper = through(&|i, k| paper_theta(report.diameters_um[i])[k])?;
    let sites: Vec<Site> = idx
        .iter()
        .map(|&i| Site {
            d: report.diameters_um[i],
            target: &targets[i],
            e_opt: best[i][hgd].loss,
        })
        .collect();
    let from_optima = polish_on_loss(step1.clone(), &sites, cfg.alpha_max);
    let from_paper = polish_on_loss(via_paper, &sites, cfg.alpha_max);
    let (polish_start, (curves, polish)) = if from_paper.1.loss < from_optima.1.loss {
        ("paper", from_paper)
    } else {
        ("optima", from_optima)
    };
    let bounds = Model::HgDraine.bounds(cfg.alpha_max);
    let at = |c: &[Curve; 4], d: f64| -> [f64; 4] {
        std::array::from_fn(|k| bounds[k].clamp(c[k].at(d)))
    };
    let points: Vec<CurvePoint> = sites
        .iter()
        .map(|s| {
            let theta = at(&curves, s.d);
            let loss_curve = s.target.loss(Model::HgDraine, &theta);
            CurvePoint {
                d_um: s.d,
                loss_optimum: s.e_opt,
                loss_curve,
                loss_curve_step1: s.target.loss(Model::HgDraine, &at(&step1, s.d)),
                loss_paper: s.target.loss(Model::HgDraine, &paper_theta(s.d)),
                extra_loss: loss_curve - s.e_opt,
                extra_loss_relative: (loss_curve - s.e_opt) / s.e_opt,
                params_curve: named(Model::HgDraine, &theta),
            }
        })
        .collect();
    let beats = points
        .iter()
        .filter(|p| p.loss_curve <= p.loss_paper)
        .count();
    let by_name = |c: &[Curve; 4]| -> BTreeMap<String, CurveReport> {
        HG_DRAINE_PARAMS
            .iter()
            .zip(c.iter())
            .map(|(n, c)| (n.to_string(), CurveReport::from(c)))
            .collect()
    };
    Ok(BranchReport {
        range_um: branch.range_um,
        curves: by_name(&curves),
        curves_step1: by_name(&step1),
        polish,
        polish_start: polish_start.to_string(),
        curve_beats_paper: [beats, points.len()],
        points,
        fitted: curves.to_vec(),
    })
}
