//! Fits of the collector form ([`nephele_runtime::fitting::collector`], equations there) to
//! the tables' c_x, c_z and σ, per order group and jointly across thicknesses (the same
//! polynomials in ln t and span as the group's T, [`super::joint`]). First ln σ, weighted by
//! 1/max(rel SE, 0.2 %) like T; then c_z/σ̂ and c_x/σ̂ with σ̂ the fitted σ, weighted by
//! σ̂/max(SE, 0.002 σ̂): the residuals are the error in units of σ that the report gives. Cells
//! enter where T is usable (as for T's fit) and σ's relative SE is below 30 %.

use super::fit::{cells_of, fitted_range, GroupFit, Row, MAX_REL_SE, MIN_REL_SE};
use super::form::{Cell, Lerp};
use super::joint::{coef_at, effective_q, legendre_in_ln_t, pad_q, NormalEquations};
use crate::slab::SlabTables;
use anyhow::Result;
use nephele_runtime::fitting::{CollectorForm, Statistic};

/// The collector fit of one group over all thicknesses.
pub struct CollectorFit {
    /// Group index (≥ 1).
    pub group: usize,
    /// Legendre terms in ln t.
    pub q: usize,
    /// ln t span (the group's T fit's).
    pub ln_t_range: (f64, f64),
    /// β of ln σ, c_z/σ̂, c_x/σ̂ (parameter-major, Q per parameter).
    pub beta: [Vec<f64>; 3],
    /// Cells fitted.
    pub cells: usize,
}

/// A usable cell of thickness `it`: its form cell, flat table index.
fn usable_cells(tab: &SlabTables, g: usize, it: usize, skip_l: &[usize]) -> Vec<(Cell, usize)> {
    let c = &tab.collector;
    cells_of(tab, it)
        .into_iter()
        .filter(|(_, [il, ..], _)| !skip_l.contains(il))
        .map(|(cell, [il, j, m, k], _)| (cell, tab.index(g, it, il, j, m, k)))
        .filter(|&(_, i)| {
            let (t, s) = (tab.t[i], c.sigma[i]);
            t > 0.0
                && tab.t_se[i] < MAX_REL_SE * t
                && s > 0.0
                && c.sigma_se[i] < MAX_REL_SE * s
                && c.cx[i].is_finite()
                && c.cz[i].is_finite()
        })
        .collect()
}

/// Fits group `g` at the thicknesses `fit_t` (those T's fit spans), without the sun cosines
/// `skip_l`, with polynomials of `q` terms over `ln_t_range`.
pub fn fit_collector(
    tab: &SlabTables,
    form: &CollectorForm,
    g: usize,
    q: usize,
    (fit_t, ln_t_range): (&[usize], (f64, f64)),
    skip_l: &[usize],
) -> Result<CollectorFit> {
    let [_, _, nl, _, nm, _] = tab.shape;
    let c = &tab.collector;
    let cells: Vec<Vec<(Cell, usize)>> = fit_t
        .iter()
        .map(|&it| usable_cells(tab, g, it, skip_l))
        .collect();
    let qe = effective_q(q, fit_t.len());
    let lq = |it: usize| legendre_in_ln_t(ln_t_range, tab.thickness[it], qe);
    let mut row = Vec::new();
    let mut solve = |stat: Statistic, target: &dyn Fn(&Cell, usize, usize) -> (f64, f64, f64)| {
        let mut ne = NormalEquations::new(form.n_params(stat, nm, nl) * qe);
        for (&it, cells) in fit_t.iter().zip(&cells) {
            let l = lq(it);
            for (cell, i) in cells {
                let (sigma, y, w) = target(cell, *i, it);
                row.clear();
                form.for_each_feature(stat, cell, sigma, nm, nl, |col, v| row.push((col, v)));
                let r = Row {
                    pair: 0,
                    u: cell.u,
                    features: &row,
                    w,
                    y,
                    t: 0.0,
                };
                ne.add(&r, &l);
            }
        }
        let n = ne.cells;
        let beta = ne.solve(&format!("group {g}, {stat:?}"))?;
        Ok::<_, anyhow::Error>((pad_q(&beta, qe, q), n))
    };
    let (ln_sigma, n) = solve(Statistic::LnSigma, &|_, i, _| {
        let w = 1.0 / (c.sigma_se[i] / c.sigma[i]).max(MIN_REL_SE);
        (0.0, c.sigma[i].ln(), w)
    })?;
    let sigma_coef: Vec<Vec<f64>> = (0..tab.shape[1])
        .map(|it| coef_at(&ln_sigma, q, ln_t_range, tab.thickness[it]))
        .collect();
    let sigma_hat = |cell: &Cell, it: usize| {
        let coef = &sigma_coef[it];
        form.value(Statistic::LnSigma, cell, 0.0, nm, nl, |k| coef[k])
            .exp()
    };
    let ratio = |v: &[f64], se: &[f64], cell: &Cell, i: usize, it: usize| {
        let s = sigma_hat(cell, it);
        (s, v[i] / s, 1.0 / (se[i] / s).max(MIN_REL_SE))
    };
    let (cz, _) = solve(Statistic::Cz, &|cell, i, it| {
        ratio(&c.cz, &c.cz_se, cell, i, it)
    })?;
    let (cx, _) = solve(Statistic::Cx, &|cell, i, it| {
        ratio(&c.cx, &c.cx_se, cell, i, it)
    })?;
    Ok(CollectorFit {
        group: g,
        q,
        ln_t_range,
        beta: [ln_sigma, cz, cx],
        cells: n,
    })
}

impl CollectorFit {
    /// The parameters of ln σ, c_z/σ̂, c_x/σ̂ at thickness `t`.
    pub fn at(&self, t: f64) -> [Vec<f64>; 3] {
        [0, 1, 2].map(|s| coef_at(&self.beta[s], self.q, self.ln_t_range, t))
    }
}

/// The fitted (σ, c_x, c_z) (mfp) at cell `c` from the parameters `coef` at its thickness.
pub fn predict_at(
    form: &CollectorForm,
    coef: &[Vec<f64>; 3],
    c: &Cell,
    nm: usize,
    nl: usize,
) -> [f64; 3] {
    let sigma = form
        .value(Statistic::LnSigma, c, 0.0, nm, nl, |k| coef[0][k])
        .exp();
    let cz = sigma * form.value(Statistic::Cz, c, sigma, nm, nl, |k| coef[1][k]);
    let cx = sigma * form.value(Statistic::Cx, c, sigma, nm, nl, |k| coef[2][k]);
    [sigma, cx, cz]
}

/// (σ, c_x, c_z) of the form over the whole table layout where `t_pred` (the form's T) is
/// positive, NaN elsewhere; the sun cosine of index il read at `l_of(il)` among the nodes.
pub fn predict_collector(
    tab: &SlabTables,
    form: &CollectorForm,
    fits: &[CollectorFit],
    (t_fits, t_pred): (&[GroupFit], &[f64]),
    l_of: &dyn Fn(usize) -> Lerp,
) -> [Vec<f64>; 3] {
    let [_, nt, nl, _, nm, _] = tab.shape;
    let mut out = [0, 1, 2].map(|_| vec![f64::NAN; tab.t.len()]);
    for fit in fits {
        for it in 0..nt {
            let coef = fit.at(tab.thickness[it]);
            let t_fit = t_fits.iter().find(|f| f.group == fit.group && f.it == it);
            for (mut cell, [il, j, m, k], _) in cells_of(tab, it) {
                let i = tab.index(fit.group, it, il, j, m, k);
                if t_pred[i] > 0.0 {
                    cell.l = l_of(il);
                    // Held within T's fitted depths, as the runtime reads it.
                    if let Some(r) = t_fit.and_then(|f| fitted_range(f, &cell, nm)) {
                        cell.u = r.held(cell.u);
                    }
                    let v = predict_at(form, &coef, &cell, nm, nl);
                    for (o, v) in out.iter_mut().zip(v) {
                        o[i] = v;
                    }
                }
            }
        }
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::compress::fit::tests::synthetic;

    /// Collector tables made by the form itself from parameters that do not depend on t: the
    /// joint fit gives them back (σ, c_x, c_z) at every thickness.
    #[test]
    fn recovers_collector_tables_made_by_the_form() {
        let (mut tab, _, _) = synthetic(3);
        let [_, nt, nl, _, nm, _] = tab.shape;
        let form = CollectorForm {
            legendre: 2,
            harmonics: 1,
            theta_nodes: 5,
        };
        let coef: [Vec<f64>; 3] = [0, 1, 2].map(|s| {
            (0..form.n_params(Statistic::ALL[s], nm, nl))
                .map(|i| 0.2 * (((i + 7 * s) * 7919 % 97) as f64 / 97.0 - 0.5))
                .collect()
        });
        let n = tab.t.len();
        let values: Vec<(usize, [f64; 3])> = (0..nt)
            .flat_map(|it| {
                cells_of(&tab, it)
                    .into_iter()
                    .map(move |(cell, [il, j, m, k], _)| (it, cell, [il, j, m, k]))
            })
            .map(|(it, cell, [il, j, m, k])| {
                let i = tab.index(1, it, il, j, m, k);
                (i, predict_at(&form, &coef, &cell, nm, nl))
            })
            .collect();
        let c = &mut tab.collector;
        c.sigma = vec![f64::NAN; n];
        c.cx = vec![f64::NAN; n];
        c.cz = vec![f64::NAN; n];
        for (i, [s, x, z]) in values {
            (c.sigma[i], c.cx[i], c.cz[i]) = (s, x, z);
        }
        c.sigma_se = c.sigma.iter().map(|s| 0.01 * s).collect();
        c.cx_se = c.sigma_se.clone();
        c.cz_se = c.sigma_se.clone();
        let span: Vec<usize> = (0..nt).collect();
        let range = (tab.thickness[0].ln(), tab.thickness[nt - 1].ln());
        let fit = fit_collector(&tab, &form, 1, 2, (&span, range), &[]).unwrap();
        let pred = predict_collector(&tab, &form, &[fit], (&[], &tab.t), &Lerp::at);
        let mut worst = 0.0f64;
        let mut compared = 0;
        for i in 0..n {
            let s = tab.collector.sigma[i];
            if s > 0.0 && pred[0][i].is_finite() {
                worst = worst
                    .max((pred[0][i] / s - 1.0).abs())
                    .max((pred[1][i] - tab.collector.cx[i]).abs() / s)
                    .max((pred[2][i] - tab.collector.cz[i]).abs() / s);
                compared += 1;
            }
        }
        assert!(compared > 500, "{compared} cells");
        // The ridge (10⁻¹⁰ of the mean diagonal) on the form's exact degeneracies leaves ~10⁻⁶
        // in σ̂, which c inherits through its target and its ℓ/σ̂ features.
        assert!(worst < 1e-5, "worst difference {worst}");
    }
}
