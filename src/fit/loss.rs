//! The fitting loss (Jendersie & d'Eon 2023, eq. 1) as a grid-independent integral:
//!
//!   E_AS = ∫₀^π |cos θ| sin θ (ln p(θ) − ln p_Mie(θ))² dθ
//!        ≈ Σᵢ Wᵢ (ln p(μᵢ) − ln p_Mie,ᵢ)²,  Wᵢ = |cos θᵢ| sin θᵢ Δθᵢ,
//!
//! with trapezoid weights Δθᵢ (radians) on the stage-1 angle grid (by default the 2251-angle
//! reference grid, 0.01° steps in the forward 5°). sin θ is the sphere's measure; |cos θ| lifts
//! the backward hemisphere and keeps the mean cosine honest. The paper writes the bare sum; the
//! Δθ makes the value independent of the grid. `log_l2` (weight sin θ only) is an ablation.
//!
//! ∂E/∂θ_k = Σᵢ 2 Wᵢ rᵢ ∂ ln p(μᵢ)/∂θ_k, rᵢ = ln p(μᵢ) − ln p_Mie,ᵢ, from the model's gradient.

use super::model::Fitting;
use super::model::Model;
use anyhow::{bail, Result};
use serde::{Deserialize, Serialize};

/// Which loss to minimise.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum Loss {
    /// E_AS: weight |cos θ| sin θ (the paper's).
    #[default]
    Eas,
    /// Unweighted-in-direction log L2: weight sin θ (an ablation).
    LogL2,
}

/// A Mie phase function prepared for the loss.
#[derive(Clone, Debug)]
pub struct Target {
    mu: Vec<f64>,
    weight: Vec<f64>,
    ln_mie: Vec<f64>,
}

impl Target {
    /// From a stage-1 table: angles (degrees, increasing, 0 … 180) and p_Mie (sr⁻¹, > 0).
    pub fn new(theta_deg: &[f64], phase: &[f64], loss: Loss) -> Result<Self> {
        if theta_deg.len() != phase.len() || theta_deg.len() < 3 {
            bail!("a Mie table needs ≥ 3 angles and one phase value per angle");
        }
        if let Some(i) = phase.iter().position(|p| !(*p > 0.0 && p.is_finite())) {
            bail!(
                "p_Mie({}°) = {} is not positive: ln p is undefined",
                theta_deg[i],
                phase[i]
            );
        }
        let th: Vec<f64> = theta_deg.iter().map(|t| t.to_radians()).collect();
        let n = th.len();
        let weight = (0..n)
            .map(|i| {
                let dtheta = 0.5 * (th[(i + 1).min(n - 1)] - th[i.saturating_sub(1)]);
                let w = match loss {
                    Loss::Eas => th[i].cos().abs() * th[i].sin(),
                    Loss::LogL2 => th[i].sin(),
                };
                w * dtheta
            })
            .collect();
        Ok(Self {
            mu: th.iter().map(|t| t.cos()).collect(),
            weight,
            ln_mie: phase.iter().map(|p| p.ln()).collect(),
        })
    }

    /// The loss of `model` at θ.
    pub fn loss(&self, model: Model, theta: &[f64]) -> f64 {
        let mut scratch = [0.0; 8];
        self.mu
            .iter()
            .zip(&self.weight)
            .zip(&self.ln_mie)
            .map(|((&mu, &w), &l)| {
                let r = model.ln_phase_grad(theta, mu, &mut scratch) - l;
                w * r * r
            })
            .sum()
    }

    /// The loss and its gradient with respect to θ (written into `grad`).
    pub fn loss_grad(&self, model: Model, theta: &[f64], grad: &mut [f64]) -> f64 {
        let n = theta.len();
        let mut d = [0.0; 8];
        grad.iter_mut().for_each(|g| *g = 0.0);
        let mut e = 0.0;
        for ((&mu, &w), &l) in self.mu.iter().zip(&self.weight).zip(&self.ln_mie) {
            let r = model.ln_phase_grad(theta, mu, &mut d[..n]) - l;
            e += w * r * r;
            for k in 0..n {
                grad[k] += 2.0 * w * r * d[k];
            }
        }
        e
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::mie::grid::reference_angles_deg;
    use nephele_runtime::phase::HenyeyGreenstein;
    use nephele_runtime::PhaseFunction;

    #[test]
    fn zero_at_the_generating_parameters_and_grid_independent() {
        let hg = HenyeyGreenstein::new(0.8);
        let coarse: Vec<f64> = (0..=180).map(|i| i as f64).collect();
        let fine = reference_angles_deg();
        let table =
            |th: &[f64]| -> Vec<f64> { th.iter().map(|t| hg.eval(t.to_radians().cos())).collect() };
        let t_fine = Target::new(&fine, &table(&fine), Loss::Eas).unwrap();
        assert!(t_fine.loss(Model::Hg, &[0.8]) < 1e-28);
        // A smooth misfit integrates to the same value on a 1° grid and the reference grid.
        let t_coarse = Target::new(&coarse, &table(&coarse), Loss::Eas).unwrap();
        let (a, b) = (
            t_coarse.loss(Model::Hg, &[0.7]),
            t_fine.loss(Model::Hg, &[0.7]),
        );
        assert!(
            (a / b - 1.0).abs() < 1e-3,
            "1° grid {a} vs reference grid {b}"
        );
        // ∫|cos θ| sin θ dθ = 1: a constant log-misfit c gives c² (to the trapezoid's O(h²) with
        // h = 0.1° = 1.7e-3 rad, ~1e-6 of it from the kink of |cos θ| at 90°).
        let flat = Target::new(&fine, &vec![1.0; fine.len()], Loss::Eas).unwrap();
        let iso = 1.0 / (4.0 * std::f64::consts::PI);
        let want = iso.ln().powi(2);
        let got = flat.loss(Model::Hg, &[0.0]);
        assert!((got / want - 1.0).abs() < 5e-6, "{got} vs {want}");
    }

    #[test]
    fn gradient_matches_differences() {
        let th = reference_angles_deg();
        let mie: Vec<f64> = th
            .iter()
            .map(|t| {
                let mu = t.to_radians().cos();
                0.7 * HenyeyGreenstein::new(0.95).eval(mu)
                    + 0.3 * HenyeyGreenstein::new(0.2).eval(mu)
            })
            .collect();
        let target = Target::new(&th, &mie, Loss::Eas).unwrap();
        let theta = [0.9, 0.4, 12.0, 0.35];
        let mut grad = [0.0; 4];
        target.loss_grad(Model::HgDraine, &theta, &mut grad);
        for k in 0..4 {
            let h = 1e-6 * theta[k];
            let (mut p, mut m) = (theta, theta);
            p[k] += h;
            m[k] -= h;
            let fd =
                (target.loss(Model::HgDraine, &p) - target.loss(Model::HgDraine, &m)) / (2.0 * h);
            assert!(
                (fd - grad[k]).abs() < 1e-6 * fd.abs().max(1e-3),
                "θ{k}: {} vs {fd}",
                grad[k]
            );
        }
    }
}
