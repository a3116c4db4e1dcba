//! Weighted least squares of the form, per (order group, slab thickness): every cell with T > 0
//! and a relative standard error below 30 % weighs 1/max(rel SE, 0.2 %)² in ln T (so a cell's
//! weight is its precision: noise is not fitted), normal equations with a ridge of 10⁻¹⁰ of
//! their mean diagonal (the form has exact degeneracies, e.g. a₀(μ_V) + b₀(μ_L)), Cholesky.

use super::form::{Cell, Lerp, LogAdditive};
use super::tables::SlabTables;
use anyhow::{anyhow, Result};
use nalgebra::{DMatrix, DVector};
use rayon::prelude::*;

/// Cells noisier than this (relative SE) are left out of the fit.
const MAX_REL_SE: f64 = 0.3;
/// Floor of the relative SE in the weights (MC zero-variance accidents).
const MIN_REL_SE: f64 = 0.002;

/// The fit of one (group, thickness).
pub struct GroupFit {
    /// Group index (≥ 1: orders ≥ 2).
    pub group: usize,
    /// Thickness index.
    pub it: usize,
    /// The parameters.
    pub coef: Vec<f64>,
    /// Cells fitted.
    pub cells: usize,
    /// Per (μ_L, μ_V) pair (index il · nm + m): the range of stretched depth u the fitted cells
    /// cover. Beyond it the form gives 0 — the group's T there is below what the tables resolve
    /// (no photon, or a relative SE over 30 %) — rather than extrapolate its polynomials.
    pub u_range: Vec<(f64, f64)>,
}

/// Every (cell, flat table index) of (group `g`, thickness `it`) the form can represent, with
/// its offset ln B.
fn cells_of(tab: &SlabTables, form: &LogAdditive, it: usize) -> Vec<(Cell, [usize; 4], f64)> {
    let [_, _, nl, nd, nm, nk] = tab.shape;
    let mut out = Vec::new();
    for il in 0..nl {
        for j in 0..nd {
            for m in 0..nm {
                for k in 0..nk {
                    let c = Cell {
                        l: Lerp::at(il),
                        mu_l: tab.mu_l[il],
                        v: Lerp::at(m),
                        mu_v: tab.mu_v(m),
                        psi_v: tab.psi_v(k),
                        u: j as f64 / (nd - 1) as f64,
                        d: tab.depth[it * nd + j],
                        t: tab.thickness[it],
                    };
                    if let Some(off) = form.offset(&c) {
                        out.push((c, [il, j, m, k], off));
                    }
                }
            }
        }
    }
    out
}

/// Fits one (group, thickness).
pub fn fit_one(tab: &SlabTables, form: &LogAdditive, g: usize, it: usize) -> Result<GroupFit> {
    let [_, _, nl, _, nm, _] = tab.shape;
    let np = form.n_params(nm, nl);
    let mut ata = DMatrix::<f64>::zeros(np, np);
    let mut aty = DVector::<f64>::zeros(np);
    let mut row = Vec::new();
    let mut cells = 0;
    let mut u_range = vec![(f64::INFINITY, f64::NEG_INFINITY); nl * nm];
    // Rows are accumulated in blocks through a dense matrix product (fast), not one by one.
    let block = 2048;
    let mut a = DMatrix::<f64>::zeros(block, np);
    let mut y = DVector::<f64>::zeros(block);
    let mut filled = 0;
    let mut flush = |a: &mut DMatrix<f64>, y: &mut DVector<f64>, filled: &mut usize| {
        if *filled > 0 {
            let part = a.rows(0, *filled);
            ata += part.tr_mul(&part);
            aty += part.tr_mul(&y.rows(0, *filled));
            a.fill(0.0);
            *filled = 0;
        }
    };
    for (c, [il, j, m, k], off) in cells_of(tab, form, it) {
        let i = tab.index(g, it, il, j, m, k);
        let (t, se) = (tab.t[i], tab.t_se[i]);
        if !(t > 0.0 && se < MAX_REL_SE * t && form.features(&c, nm, nl, &mut row)) {
            continue;
        }
        let r = &mut u_range[il * nm + m];
        *r = (r.0.min(c.u), r.1.max(c.u));
        let w = 1.0 / (se / t).max(MIN_REL_SE);
        for &(col, v) in &row {
            a[(filled, col)] += w * v;
        }
        y[filled] = w * (t.ln() - off);
        filled += 1;
        cells += 1;
        if filled == block {
            flush(&mut a, &mut y, &mut filled);
        }
    }
    flush(&mut a, &mut y, &mut filled);
    let ridge = 1e-10 * (0..np).map(|i| ata[(i, i)]).sum::<f64>() / np as f64;
    for i in 0..np {
        ata[(i, i)] += ridge.max(1e-300);
    }
    let chol = ata.cholesky().ok_or_else(|| {
        anyhow!("group {g}, thickness {it}: normal equations not positive definite")
    })?;
    Ok(GroupFit {
        group: g,
        it,
        coef: chol.solve(&aty).iter().copied().collect(),
        cells,
        u_range,
    })
}

/// Fits every group of orders ≥ 2 at every thickness (in parallel).
pub fn fit_all(tab: &SlabTables, form: &LogAdditive) -> Result<Vec<GroupFit>> {
    let jobs: Vec<(usize, usize)> = (1..tab.shape[0])
        .flat_map(|g| (0..tab.shape[1]).map(move |it| (g, it)))
        .collect();
    jobs.par_iter()
        .map(|&(g, it)| fit_one(tab, form, g, it))
        .collect()
}

/// The form's T at every cell of (group, thickness) of `fit` (0 where it cannot represent one),
/// in the tables' layout [μ_L, depth, μ_V, ψ_V].
pub fn predict(tab: &SlabTables, form: &LogAdditive, fit: &GroupFit) -> Vec<f64> {
    let [_, _, nl, nd, nm, nk] = tab.shape;
    let mut out = vec![0.0; nl * nd * nm * nk];
    let mut row = Vec::new();
    for (c, [il, j, m, k], off) in cells_of(tab, form, fit.it) {
        let (lo, hi) = fit.u_range[il * nm + m];
        if c.u < lo || c.u > hi {
            continue; // beyond the depths where the tables hold a usable value: 0
        }
        if form.features(&c, nm, nl, &mut row) {
            let s: f64 = row.iter().map(|&(col, v)| v * fit.coef[col]).sum();
            out[((il * nd + j) * nm + m) * nk + k] = (off + s).exp();
        }
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::compress::SlabTables;

    /// A table made by the form itself from arbitrary parameters: the fit must give it back
    /// (its predictions, the parameters being defined up to the form's degeneracies).
    #[test]
    fn recovers_a_table_made_by_the_form() {
        let (nl, nd, nm, nk) = (3, 6, 8, 4);
        let depth: Vec<f64> = (0..nd).map(|j| 4.0 * j as f64 / (nd - 1) as f64).collect();
        let mut tab = SlabTables {
            shape: [2, 1, nl, nd, nm, nk],
            t: vec![0.0; 2 * nl * nd * nm * nk],
            t_se: vec![0.0; 2 * nl * nd * nm * nk],
            thickness: vec![4.0],
            mu_l: vec![0.3, 0.6, 0.9],
            depth,
            mu_v_edges: (0..=nm)
                .map(|i| -1.0 + 2.0 * i as f64 / nm as f64)
                .collect(),
            psi_v_edges: (0..=nk)
                .map(|i| std::f64::consts::PI * i as f64 / nk as f64)
                .collect(),
            group_first: vec![1.0, 2.0],
        };
        let form = LogAdditive {
            legendre: 3,
            harmonics: 2,
            theta_nodes: 6,
            pairs: false,
        };
        let np = form.n_params(nm, nl);
        let truth = GroupFit {
            group: 1,
            it: 0,
            coef: (0..np)
                .map(|i| 0.3 * ((i * 7919 % 101) as f64 / 101.0 - 0.5))
                .collect(),
            cells: 0,
            u_range: vec![(0.0, 1.0); nl * nm],
        };
        let made = predict(&tab, &form, &truth);
        let start = tab.index(1, 0, 0, 0, 0, 0);
        for (i, &v) in made.iter().enumerate() {
            tab.t[start + i] = v;
            tab.t_se[start + i] = 0.01 * v;
        }
        let fit = fit_one(&tab, &form, 1, 0).unwrap();
        assert!(fit.cells > 400, "{} cells", fit.cells);
        let back = predict(&tab, &form, &fit);
        let worst = made
            .iter()
            .zip(&back)
            .filter(|(a, _)| **a > 0.0)
            .map(|(a, b)| (b / a - 1.0).abs())
            .fold(0.0, f64::max);
        assert!(worst < 1e-6, "worst relative difference {worst}");
    }
}
