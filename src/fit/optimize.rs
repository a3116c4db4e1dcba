//! Minimising a smooth loss over bounded parameters: the bounds become smooth maps θ = T(u) of
//! unconstrained u ([`Bound`]), and L-BFGS (argmin, More–Thuente line search) polishes from
//! several starts with the analytic gradient ∂E/∂u = ∂E/∂θ · T′(u).

use super::model::Bound;
use argmin::core::{CostFunction, Executor, Gradient, State, TerminationReason};
use argmin::solver::linesearch::MoreThuenteLineSearch;
use argmin::solver::quasinewton::LBFGS;
use serde::Serialize;

/// A loss with its gradient, in the bounded parameters θ.
pub trait Objective: Sync {
    /// E(θ) and ∂E/∂θ (into `grad`).
    fn loss_grad(&self, theta: &[f64], grad: &mut [f64]) -> f64;
    /// E(θ) alone.
    fn loss(&self, theta: &[f64]) -> f64 {
        let mut g = vec![0.0; theta.len()];
        self.loss_grad(theta, &mut g)
    }
}

/// The outcome of one minimisation.
#[derive(Clone, Debug, Serialize)]
pub struct Optimum {
    /// The parameters θ at the optimum (in the model's order; `params` names them).
    #[serde(rename = "theta")]
    pub params: Vec<f64>,
    /// The loss there.
    pub loss: f64,
    /// |∂E/∂θ| there (Euclidean norm; entries at a bound are not excluded).
    pub grad_norm: f64,
    /// |∂E/∂u| there, in the unconstrained variables L-BFGS works in.
    pub grad_norm_free: f64,
    /// Loss (and gradient) evaluations, coarse-grid start included.
    pub evaluations: u64,
    /// L-BFGS iterations of the polish that won.
    pub iterations: u64,
    /// Whether that polish met its tolerance (rather than an iteration limit or a line-search
    /// failure).
    pub converged: bool,
    /// argmin's termination reason for it.
    pub termination: String,
}

/// Largest L-BFGS iterations per polish.
pub const MAX_ITERS: u64 = 400;

struct Free<'a, O> {
    objective: &'a O,
    bounds: &'a [Bound],
}

impl<O: Objective> Free<'_, O> {
    fn theta(&self, u: &[f64]) -> Vec<f64> {
        u.iter()
            .zip(self.bounds)
            .map(|(u, b)| b.to_param(*u))
            .collect()
    }
}

impl<O: Objective> CostFunction for Free<'_, O> {
    type Param = Vec<f64>;
    type Output = f64;
    fn cost(&self, u: &Vec<f64>) -> Result<f64, argmin::core::Error> {
        finite(self.objective.loss(&self.theta(u)), u)
    }
}

impl<O: Objective> Gradient for Free<'_, O> {
    type Param = Vec<f64>;
    type Gradient = Vec<f64>;
    fn gradient(&self, u: &Vec<f64>) -> Result<Vec<f64>, argmin::core::Error> {
        let mut g = vec![0.0; u.len()];
        finite(self.objective.loss_grad(&self.theta(u), &mut g), u)?;
        finite(g.iter().sum(), u)?;
        Ok(g.iter()
            .zip(u.iter().zip(self.bounds))
            .map(|(g, (u, b))| g * b.slope(*u))
            .collect())
    }
}

/// A non-finite loss stops the polish with an error (reported, the best start kept) instead of
/// letting argmin's More–Thuente search, which has no iteration cap, chase NaN comparisons.
fn finite(loss: f64, u: &[f64]) -> Result<f64, argmin::core::Error> {
    if loss.is_finite() {
        Ok(loss)
    } else {
        Err(argmin::core::Error::msg(format!(
            "loss {loss} at u = {u:?}"
        )))
    }
}

/// L-BFGS from θ₀ (moved inside its bounds), at most [`MAX_ITERS`] iterations.
pub fn polish<O: Objective>(objective: &O, bounds: &[Bound], theta0: &[f64]) -> Optimum {
    polish_iters(objective, bounds, theta0, MAX_ITERS)
}

/// L-BFGS from θ₀ (moved inside its bounds), at most `max_iters` iterations.
pub fn polish_iters<O: Objective>(
    objective: &O,
    bounds: &[Bound],
    theta0: &[f64],
    max_iters: u64,
) -> Optimum {
    let free = Free { objective, bounds };
    let u0: Vec<f64> = theta0
        .iter()
        .zip(bounds)
        .map(|(t, b)| b.to_free(*t))
        .collect();
    let solver = LBFGS::new(MoreThuenteLineSearch::new(), 8)
        .with_tolerance_grad(1e-10)
        .and_then(|s| s.with_tolerance_cost(1e-15));
    let run = solver.and_then(|s| {
        Executor::new(free, s)
            .configure(|state| state.param(u0.clone()).max_iters(max_iters))
            .run()
    });
    let free = Free { objective, bounds };
    let (u, iterations, evaluations, termination, converged) = match run {
        Ok(res) => {
            let st = res.state();
            let counts = st.get_func_counts();
            let evals = counts.get("cost_count").copied().unwrap_or(0)
                + counts.get("gradient_count").copied().unwrap_or(0);
            let reason = st.get_termination_reason();
            let converged = matches!(reason, Some(TerminationReason::SolverConverged));
            let u = st.get_best_param().cloned().unwrap_or_else(|| u0.clone());
            let text = reason.map_or("none".to_string(), |r| r.text().to_string());
            (u, st.get_iter(), evals, text, converged)
        }
        // The line search gives up when it cannot decrease further: at a (numerical) optimum
        // or in a flat region. Report it; the caller keeps the best start.
        Err(e) => (u0.clone(), 0, 0, format!("error: {e}"), false),
    };
    finish(&free, &u, evaluations, iterations, converged, termination)
}

fn finish<O: Objective>(
    free: &Free<'_, O>,
    u: &[f64],
    evaluations: u64,
    iterations: u64,
    converged: bool,
    termination: String,
) -> Optimum {
    let theta = free.theta(u);
    let mut g = vec![0.0; u.len()];
    let loss = free.objective.loss_grad(&theta, &mut g);
    let grad_norm = g.iter().map(|x| x * x).sum::<f64>().sqrt();
    let grad_norm_free = g
        .iter()
        .zip(u.iter().zip(free.bounds))
        .map(|(g, (u, b))| (g * b.slope(*u)).powi(2))
        .sum::<f64>()
        .sqrt();
    // A polish that stopped on its cost tolerance with a tiny gradient has converged too.
    let converged = converged || grad_norm_free <= 1e-7 * loss.max(1e-12).sqrt();
    Optimum {
        params: theta,
        loss,
        grad_norm,
        grad_norm_free,
        evaluations: evaluations + 1,
        iterations,
        converged,
        termination,
    }
}

/// The `n` lowest grid points that differ from every lower chosen one by at least
/// [`MIN_SEPARATION`] in some unconstrained coordinate u: the best few points of a grid tend to
/// sit in one basin, and a start in each of several basins is what finds the global minimum.
fn diverse_best<'a>(
    scored: &[(f64, &'a Vec<f64>)],
    bounds: &[Bound],
    n: usize,
) -> Vec<&'a Vec<f64>> {
    let free = |t: &[f64]| -> Vec<f64> {
        t.iter()
            .zip(bounds)
            .map(|(t, b)| b.to_free(b.clamp(*t)))
            .collect()
    };
    let mut chosen: Vec<(&Vec<f64>, Vec<f64>)> = Vec::with_capacity(n);
    for (_, t) in scored {
        if chosen.len() == n {
            break;
        }
        let u = free(t);
        let apart = |c: &Vec<f64>| {
            c.iter()
                .zip(&u)
                .any(|(a, b)| (a - b).abs() >= MIN_SEPARATION)
        };
        if chosen.iter().all(|(_, c)| apart(c)) {
            chosen.push((t, u));
        }
    }
    chosen.into_iter().map(|(t, _)| t).collect()
}

/// Least separation of two starts in u (g = 0.88 and 0.96 are 0.57 apart, α = 3 and 10 are 1.2).
const MIN_SEPARATION: f64 = 0.5;

/// The global-ish minimum: the loss on every point of `grid`, L-BFGS from `n_best` mutually
/// distant best of them and from every `warm` start, the best result kept (ties to the
/// earliest: deterministic). Needs at least one start (a non-empty grid with `n_best` ≥ 1, or a
/// warm start).
pub fn minimise<O: Objective>(
    objective: &O,
    bounds: &[Bound],
    grid: &[Vec<f64>],
    n_best: usize,
    warm: &[Vec<f64>],
) -> Optimum {
    let mut scored: Vec<(f64, &Vec<f64>)> = grid
        .iter()
        .map(|t| {
            let inside: Vec<f64> = t.iter().zip(bounds).map(|(t, b)| b.clamp(*t)).collect();
            (objective.loss(&inside), t)
        })
        .collect();
    scored.sort_by(|a, b| a.0.total_cmp(&b.0));
    let starts = diverse_best(&scored, bounds, n_best)
        .into_iter()
        .chain(warm.iter());
    let mut best: Option<Optimum> = None;
    let mut evaluations = grid.len() as u64;
    for start in starts {
        let o = polish(objective, bounds, start);
        evaluations += o.evaluations;
        if best.as_ref().is_none_or(|b| o.loss < b.loss) {
            best = Some(o);
        }
    }
    let mut best = best.expect("at least one start");
    best.evaluations = evaluations;
    best
}
