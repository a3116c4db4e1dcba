//! Weighted least squares of the form, per (order group, slab thickness): every cell with T > 0
//! and a relative standard error below 30 % weighs 1/max(rel SE, 0.2 %)² in ln T (so a cell's
//! weight is its precision: noise is not fitted), normal equations with a ridge of 10⁻¹⁰ of
//! their mean diagonal (the form has exact degeneracies, e.g. a₀(μ_V) + b₀(μ_L)), Cholesky.

use super::form::{features, ln_boundary, Cell, Lerp, LogAdditive};
use crate::slab::SlabTables;
use anyhow::{anyhow, Result};
use nalgebra::{DMatrix, DVector};
use nephele_runtime::fitting::{FittedDepths, CEILING_FACTOR};
use rayon::prelude::*;

/// Cells noisier than this (relative SE) are left out of the fit.
pub(crate) const MAX_REL_SE: f64 = 0.3;
/// Floor of the relative SE in the weights (MC zero-variance accidents).
pub(crate) const MIN_REL_SE: f64 = 0.002;

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
    /// cover. Beyond it the form's depth polynomials are not extrapolated but continued from
    /// the range's end ([`nephele_runtime::fitting::depth_polynomial`]); a pair without
    /// fitted cells has an empty range (lo > hi).
    pub u_range: Vec<(f64, f64)>,
    /// Per sun cosine, the largest T of the fitted cells (0: none): the form's T is capped at
    /// [`CEILING_FACTOR`] times the largest of the nodes a point draws on.
    pub ceiling: Vec<f64>,
}

/// Fewest fitted cells (of a pair's depths × azimuths) for a (μ_L, μ_V) pair's depth range to
/// count: a stray usable cell or two of a group where it is mostly noise would otherwise let
/// the form's value there stand for the pair's other depths.
pub const MIN_PAIR_CELLS: usize = 4;

/// The fitted depth range of every (μ_L, μ_V) pair of one thickness, accumulated cell by cell.
pub(crate) struct DepthRanges {
    range: Vec<(f64, f64)>,
    cells: Vec<usize>,
    top: Vec<f64>,
}

impl DepthRanges {
    /// For `pairs` pairs, all empty.
    pub fn new(pairs: usize) -> Self {
        Self {
            range: vec![(f64::INFINITY, f64::NEG_INFINITY); pairs],
            cells: vec![0; pairs],
            top: vec![0.0; pairs],
        }
    }

    /// A fitted cell `r`.
    pub fn add(&mut self, r: &Row) {
        let range = &mut self.range[r.pair];
        *range = (range.0.min(r.u), range.1.max(r.u));
        self.cells[r.pair] += 1;
        self.top[r.pair] = self.top[r.pair].max(r.t);
    }

    /// The ranges, empty (lo > hi) where a pair has fewer than [`MIN_PAIR_CELLS`] cells, and
    /// per sun cosine (`nl` of them) the largest T of those pairs' fitted cells (0: none).
    pub fn finish(self, nl: usize) -> (Vec<(f64, f64)>, Vec<f64>) {
        let nm = self.range.len() / nl.max(1);
        let mut ceiling = vec![0.0f64; nl];
        let mut ranges = Vec::with_capacity(self.range.len());
        for (pair, (r, n)) in self.range.into_iter().zip(self.cells).enumerate() {
            if n >= MIN_PAIR_CELLS {
                ranges.push(r);
                ceiling[pair / nm] = ceiling[pair / nm].max(self.top[pair]);
            } else {
                ranges.push((f64::INFINITY, f64::NEG_INFINITY));
            }
        }
        (ranges, ceiling)
    }
}

/// Every cell (and its [μ_L, depth, μ_V, ψ_V] indices) of thickness `it` with medium behind
/// the viewpoint, with its offset ln B (geometry only: the same for every form).
pub(crate) fn cells_of(tab: &SlabTables, it: usize) -> Vec<(Cell, [usize; 4], f64)> {
    let [_, _, nl, nd, nm, nk] = tab.shape;
    let mut out = Vec::new();
    for il in 0..nl {
        for j in 0..nd {
            for m in 0..nm {
                for k in 0..nk {
                    let c = Cell::new(
                        tab.point(it, il, j, m, k),
                        Lerp::at(il),
                        Lerp::at(m),
                        j as f64 / (nd - 1) as f64,
                    );
                    if let Some(off) = ln_boundary(&c.at) {
                        out.push((c, [il, j, m, k], off));
                    }
                }
            }
        }
    }
    out
}

/// One row of the weighted least squares: a usable cell's features, weight and target.
pub(crate) struct Row<'r> {
    /// Index il · nm + m of its (μ_L, μ_V) pair.
    pub pair: usize,
    /// Its stretched depth.
    pub u: f64,
    /// Its features (column, value).
    pub features: &'r [(usize, f64)],
    /// 1/max(rel SE, floor).
    pub w: f64,
    /// ln T − ln B.
    pub y: f64,
    /// T.
    pub t: f64,
}

/// Calls `f` with the row of every cell of (group `g`, thickness `it`) that enters a fit: T > 0,
/// relative SE below [`MAX_REL_SE`], representable by the form, its sun cosine not in `skip_l`.
pub(crate) fn for_each_row(
    tab: &SlabTables,
    form: &LogAdditive,
    g: usize,
    it: usize,
    skip_l: &[usize],
    row: &mut Vec<(usize, f64)>,
    f: impl FnMut(Row),
) {
    let [_, _, nl, _, nm, _] = tab.shape;
    let feats = |c: &Cell, row: &mut Vec<(usize, f64)>| features(form, c, nm, nl, row);
    for_each_row_of(tab, &feats, g, it, skip_l, row, f)
}

/// As [`for_each_row`], for any form linear in ln T − ln B whose features `feats` gives
/// (false: the form cannot represent the cell).
pub(crate) fn for_each_row_of(
    tab: &SlabTables,
    feats: &dyn Fn(&Cell, &mut Vec<(usize, f64)>) -> bool,
    g: usize,
    it: usize,
    skip_l: &[usize],
    row: &mut Vec<(usize, f64)>,
    mut f: impl FnMut(Row),
) {
    let nm = tab.shape[4];
    for (c, [il, j, m, k], off) in cells_of(tab, it) {
        if skip_l.contains(&il) {
            continue;
        }
        let i = tab.index(g, it, il, j, m, k);
        let (t, se) = (tab.t[i], tab.t_se[i]);
        if !(t > 0.0 && se < MAX_REL_SE * t && feats(&c, row)) {
            continue;
        }
        f(Row {
            pair: il * nm + m,
            u: c.u,
            features: row,
            w: 1.0 / (se / t).max(MIN_REL_SE),
            y: t.ln() - off,
            t,
        });
    }
}

/// Fits one (group, thickness), leaving out the sun cosines of index in `skip_l` (held out).
pub fn fit_one(
    tab: &SlabTables,
    form: &LogAdditive,
    g: usize,
    it: usize,
    skip_l: &[usize],
) -> Result<GroupFit> {
    let [_, _, nl, _, nm, _] = tab.shape;
    let np = form.n_params(nm, nl);
    let mut ata = DMatrix::<f64>::zeros(np, np);
    let mut aty = DVector::<f64>::zeros(np);
    let mut row = Vec::new();
    let mut cells = 0;
    let mut u_range = DepthRanges::new(nl * nm);
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
    for_each_row(tab, form, g, it, skip_l, &mut row, |r| {
        u_range.add(&r);
        for &(col, v) in r.features {
            a[(filled, col)] += r.w * v;
        }
        y[filled] = r.w * r.y;
        filled += 1;
        cells += 1;
        if filled == block {
            flush(&mut a, &mut y, &mut filled);
        }
    });
    flush(&mut a, &mut y, &mut filled);
    let (u_range, ceiling) = u_range.finish(nl);
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
        ceiling,
    })
}

/// Fits every group of orders ≥ 2 at every thickness but those of index in `skip_t`, without
/// the sun cosines of index in `skip_l` (in parallel).
pub fn fit_all(
    tab: &SlabTables,
    form: &LogAdditive,
    skip_t: &[usize],
    skip_l: &[usize],
) -> Result<Vec<GroupFit>> {
    let jobs: Vec<(usize, usize)> = (1..tab.shape[0])
        .flat_map(|g| (0..tab.shape[1]).map(move |it| (g, it)))
        .filter(|(_, it)| !skip_t.contains(it))
        .collect();
    jobs.par_iter()
        .map(|&(g, it)| fit_one(tab, form, g, it, skip_l))
        .collect()
}

/// The form's T at every cell of (group, thickness) of `fit` (0 where it cannot represent one),
/// in the tables' layout [μ_L, depth, μ_V, ψ_V].
pub fn predict(tab: &SlabTables, form: &LogAdditive, fit: &GroupFit) -> Vec<f64> {
    predict_ln(tab, form, fit, fit.it, &|il| Lerp::at(il))
        .into_iter()
        .map(|v| v.map_or(0.0, f64::exp))
        .collect()
}

/// ln T of the form with the parameters of `fit`, at the cells of thickness `it_geom` (its
/// depths, boundary and single-scattering factors), the sun cosine of index il taken at
/// `l_of(il)` among the parameter nodes; None where the form says 0.
pub fn predict_ln(
    tab: &SlabTables,
    form: &LogAdditive,
    fit: &GroupFit,
    it_geom: usize,
    l_of: &dyn Fn(usize) -> Lerp,
) -> Vec<Option<f64>> {
    let [_, _, nl, nd, nm, nk] = tab.shape;
    let mut out = vec![None; nl * nd * nm * nk];
    for (mut c, [il, j, m, k], _) in cells_of(tab, it_geom) {
        c.l = l_of(il);
        // The depth polynomials read within the fitted depths, as the runtime reads them.
        let Some(range) = fitted_range(fit, &c, nm) else {
            continue;
        };
        if let Some(v) = form.ln_t_in_range(&c, (nm, nl), |col| fit.coef[col], &range) {
            let mut top = 0.0f64;
            c.l.each(|l, _| top = top.max(fit.ceiling[l]));
            out[((il * nd + j) * nm + m) * nk + k] = Some(v.min((CEILING_FACTOR * top).ln()));
        }
    }
    out
}

/// The depths `fit` had cells at around `c` (its μ_L nodes, its own μ_V node).
pub fn fitted_range(fit: &GroupFit, c: &Cell, nm: usize) -> Option<FittedDepths<f64>> {
    let mut ranges = Vec::with_capacity(2);
    c.l.each(|l, w| {
        let (lo, hi) = fit.u_range[l * nm + c.v.lo];
        ranges.push((w, lo, hi));
    });
    FittedDepths::of(ranges)
}

/// Where sun cosine il sits among the fitted ones (all but `skip_l`): its own node, or between
/// its fitted neighbours.
pub fn held_out_l<'a>(tab: &'a SlabTables, skip_l: &[usize]) -> impl Fn(usize) -> Lerp + use<'a> {
    let kept_l: Vec<usize> = (0..tab.shape[2])
        .filter(|il| !skip_l.contains(il))
        .collect();
    let kept_mu: Vec<f64> = kept_l.iter().map(|&il| tab.mu_l[il]).collect();
    move |il: usize| {
        let p = Lerp::between(&kept_mu, tab.mu_l[il]);
        Lerp {
            lo: kept_l[p.lo],
            hi: kept_l[p.hi],
            w: p.w,
        }
    }
}

/// The form's T over the whole table layout from fits that left out the thicknesses `skip_t`
/// and the sun cosines `skip_l`: a held-out thickness by interpolating ln T linearly in ln t
/// between the nearest fitted thicknesses (each evaluated at the held-out geometry), a held-out
/// sun cosine by interpolating the μ_L parameters between its fitted neighbours.
pub fn predict_held_out(
    tab: &SlabTables,
    form: &LogAdditive,
    fits: &[GroupFit],
    skip_l: &[usize],
) -> Vec<f64> {
    let [_, nt, nl, nd, nm, nk] = tab.shape;
    let slice = nl * nd * nm * nk;
    let mut pred = vec![0.0; tab.t.len()];
    let l_of = held_out_l(tab, skip_l);
    for g in 1..tab.shape[0] {
        let of_t: Vec<Option<&GroupFit>> = (0..nt)
            .map(|it| fits.iter().find(|f| f.group == g && f.it == it))
            .collect();
        let fitted: Vec<usize> = (0..nt).filter(|&it| of_t[it].is_some()).collect();
        for it in 0..nt {
            let ln = |fit: &GroupFit| predict_ln(tab, form, fit, it, &l_of);
            let values: Vec<Option<f64>> = match of_t[it] {
                Some(f) => ln(f),
                None => {
                    let ln_t: Vec<f64> = fitted.iter().map(|&i| tab.thickness[i].ln()).collect();
                    let p = Lerp::between(&ln_t, tab.thickness[it].ln());
                    // Each neighbour's fit read at this thickness, capped by the larger of
                    // the two neighbours' ceilings (its own is another thickness's).
                    let (fa, fb) = (of_t[fitted[p.lo]].unwrap(), of_t[fitted[p.hi]].unwrap());
                    let top: Vec<f64> = fa
                        .ceiling
                        .iter()
                        .zip(&fb.ceiling)
                        .map(|(x, y)| x.max(*y))
                        .collect();
                    let capped = |f: &GroupFit| GroupFit {
                        coef: f.coef.clone(),
                        u_range: f.u_range.clone(),
                        ceiling: top.clone(),
                        ..*f
                    };
                    let (a, b) = (ln(&capped(fa)), ln(&capped(fb)));
                    a.iter()
                        .zip(&b)
                        .map(|(x, y)| Some((1.0 - p.w) * (*x)? + p.w * (*y)?))
                        .collect()
                }
            };
            let start = (g * nt + it) * slice;
            for (dst, v) in pred[start..start + slice].iter_mut().zip(values) {
                *dst = v.map_or(0.0, f64::exp);
            }
        }
    }
    pred
}

#[cfg(test)]
pub(crate) mod tests {
    use super::*;
    use crate::compress::SlabTables;

    /// Tables of `nt` thicknesses made by the form from the same arbitrary parameters at every
    /// thickness.
    pub(crate) fn synthetic(nt: usize) -> (SlabTables, LogAdditive, GroupFit) {
        let (nl, nd, nm, nk) = (3, 6, 8, 4);
        let thickness: Vec<f64> = (0..nt).map(|i| 2.0 * 2f64.powi(i as i32)).collect();
        let depth = thickness
            .iter()
            .flat_map(|&t| (0..nd).map(move |j| t * j as f64 / (nd - 1) as f64))
            .collect();
        let n = 2 * nt * nl * nd * nm * nk;
        let mut tab = SlabTables {
            shape: [2, nt, nl, nd, nm, nk],
            t: vec![0.0; n],
            t_se: vec![0.0; n],
            thickness,
            mu_l: vec![0.3, 0.6, 0.9],
            depth,
            mu_v_edges: (0..=nm)
                .map(|i| -1.0 + 2.0 * i as f64 / nm as f64)
                .collect(),
            psi_v_edges: (0..=nk)
                .map(|i| std::f64::consts::PI * i as f64 / nk as f64)
                .collect(),
            group_first: vec![1.0, 2.0],
            collector: Default::default(),
            phase: None,
            aureole: None,
        };
        let form = LogAdditive {
            legendre: 3,
            harmonics: 2,
            theta_nodes: 6,
            pairs: false,
            cross: 2,
        };
        let np = form.n_params(nm, nl);
        let mut truth = GroupFit {
            group: 1,
            it: 0,
            coef: (0..np)
                .map(|i| 0.3 * ((i * 7919 % 101) as f64 / 101.0 - 0.5))
                .collect(),
            cells: 0,
            u_range: vec![(0.0, 1.0); nl * nm],
            ceiling: vec![f64::INFINITY; nl],
        };
        for it in 0..nt {
            truth.it = it;
            let start = tab.index(1, it, 0, 0, 0, 0);
            for (i, v) in predict(&tab, &form, &truth).into_iter().enumerate() {
                tab.t[start + i] = v;
                tab.t_se[start + i] = 0.01 * v;
            }
        }
        truth.it = 0;
        (tab, form, truth)
    }

    pub(crate) fn worst_relative(a: &[f64], b: &[f64]) -> f64 {
        a.iter()
            .zip(b)
            .filter(|(x, _)| **x > 0.0)
            .map(|(x, y)| (y / x - 1.0).abs())
            .fold(0.0, f64::max)
    }

    /// A held-out thickness of tables whose parameters do not change with t comes back exactly
    /// from its neighbours (the interpolation path and the held-out geometry are right).
    #[test]
    fn a_held_out_thickness_of_a_t_independent_form_comes_back() {
        let (tab, form, _) = synthetic(3);
        let fits = fit_all(&tab, &form, &[1], &[]).unwrap();
        assert_eq!(fits.len(), 2);
        let pred = predict_held_out(&tab, &form, &fits, &[]);
        let start = tab.index(1, 1, 0, 0, 0, 0);
        let n = 3 * 6 * 8 * 4;
        let worst = worst_relative(&tab.t[start..start + n], &pred[start..start + n]);
        assert!(worst < 1e-6, "worst relative difference {worst}");
    }

    /// A table made by the form itself from arbitrary parameters: the fit must give it back
    /// (its predictions, the parameters being defined up to the form's degeneracies).
    #[test]
    fn recovers_a_table_made_by_the_form() {
        let (tab, form, truth) = synthetic(1);
        let made = predict(&tab, &form, &truth);
        let fit = fit_one(&tab, &form, 1, 0, &[]).unwrap();
        assert!(fit.cells > 400, "{} cells", fit.cells);
        let worst = worst_relative(&made, &predict(&tab, &form, &fit));
        assert!(worst < 1e-6, "worst relative difference {worst}");
    }
}
