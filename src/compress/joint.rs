//! Fits across thicknesses: every parameter θ_p of the form becomes a smooth function of the
//! slab thickness, θ_p(t) = Σ_{q<Q} β_pq L_q(s), s = 2 (ln t − ln t₀)/(ln t₁ − ln t₀) − 1 over the
//! tables' range [t₀, t₁] (L_q Legendre polynomials), and the β of one order group are fitted to
//! all its thicknesses at once — what makes thicknesses between the grid's interpolate (fits per
//! thickness do not: docs/compress.md). Same weights and ridge as [`super::fit`]; the normal
//! equations are accumulated from the sparse rows directly.

use super::fit::{for_each_row, DepthRanges, GroupFit, Row, MAX_REL_SE};
use super::form::LogAdditive;
use crate::slab::SlabTables;
use anyhow::{anyhow, Result};
use nalgebra::{DMatrix, DVector};
use nephele_runtime::fitting::{legendre, ln_t_position};
use rayon::prelude::*;

/// The fit of one order group over all thicknesses.
pub struct JointFit {
    /// Group index (≥ 1).
    pub group: usize,
    /// Legendre terms in ln t, Q.
    pub q: usize,
    /// β, parameter-major: β[p · Q + q].
    pub beta: Vec<f64>,
    /// Per thickness index, the fitted depth range per (μ_L, μ_V) pair (see [`GroupFit`]);
    /// a held-out thickness takes the intersection of its fitted neighbours'.
    pub u_range: Vec<Vec<(f64, f64)>>,
    /// Per thickness index, the largest T of the fitted cells per sun cosine (see
    /// [`GroupFit`]); a held-out thickness takes the larger of its fitted neighbours'.
    pub ceiling: Vec<Vec<f64>>,
    /// Cells fitted.
    pub cells: usize,
    /// ln of the thickness range the fit spans (where the group has enough usable cells);
    /// outside it the parameters are those of its ends.
    pub ln_t_range: (f64, f64),
}

/// s(t) ∈ [−1, 1] over the range (a, b) of ln t (held at ±1 outside), and L_0(s) … L_{Q−1}(s).
pub(crate) fn legendre_in_ln_t(range: (f64, f64), t: f64, q: usize) -> Vec<f64> {
    legendre(ln_t_position(range, t.ln()), q)[..q].to_vec()
}

/// The thicknesses the polynomials of group `g` span (not in `skip_t`, with ≥ 5 % of the largest
/// count of usable cells: a high order in a thin slab is thin on them and would make the
/// polynomials in ln t swing) and their ln t range.
pub(crate) fn spanned(
    tab: &SlabTables,
    g: usize,
    skip_t: &[usize],
) -> Result<(Vec<usize>, (f64, f64))> {
    let nt = tab.shape[1];
    let usable = |it: usize| {
        let start = tab.index(g, it, 0, 0, 0, 0);
        let n = tab.t.len() / (tab.shape[0] * nt);
        (start..start + n)
            .filter(|&i| tab.t[i] > 0.0 && tab.t_se[i] < MAX_REL_SE * tab.t[i])
            .count()
    };
    let counts: Vec<usize> = (0..nt).map(usable).collect();
    let most = counts.iter().copied().max().unwrap_or(0);
    let spanned: Vec<usize> = (0..nt)
        .filter(|&it| !skip_t.contains(&it) && counts[it] * 20 >= most && most > 0)
        .collect();
    match (spanned.first(), spanned.last()) {
        (Some(&a), Some(&b)) => {
            let range = (tab.thickness[a].ln(), tab.thickness[b].ln());
            Ok((spanned, range))
        }
        _ => Err(anyhow!("group {g}: no thickness with usable cells")),
    }
}

/// The normal equations of a joint fit: each row's features times L_q(s(t)) of its thickness.
pub(crate) struct NormalEquations {
    ata: DMatrix<f64>,
    aty: DVector<f64>,
    wide: Vec<(usize, f64)>,
    /// Rows added.
    pub cells: usize,
}

impl NormalEquations {
    /// For `n` parameters (form parameters × Q).
    pub fn new(n: usize) -> Self {
        Self {
            ata: DMatrix::zeros(n, n),
            aty: DVector::zeros(n),
            wide: Vec::new(),
            cells: 0,
        }
    }

    /// Adds one weighted row at a thickness whose Legendre values in ln t are `lq`.
    pub fn add(&mut self, r: &Row, lq: &[f64]) {
        let q = lq.len();
        self.wide.clear();
        for &(col, v) in r.features {
            self.wide.extend(
                lq.iter()
                    .enumerate()
                    .map(|(qi, l)| (col * q + qi, r.w * v * l)),
            );
        }
        let y = r.w * r.y;
        // The upper triangle of the outer product of the sparse row.
        for &(a, va) in &self.wide {
            self.aty[a] += va * y;
            for &(b, vb) in &self.wide {
                if b >= a {
                    self.ata[(a, b)] += va * vb;
                }
            }
        }
        self.cells += 1;
    }

    /// The least-squares parameters (ridge 10⁻¹⁰ of the mean diagonal, Cholesky).
    pub fn solve(mut self, what: &str) -> Result<Vec<f64>> {
        let n = self.aty.len();
        for a in 0..n {
            for b in 0..a {
                self.ata[(a, b)] = self.ata[(b, a)];
            }
        }
        let ridge = 1e-10 * (0..n).map(|i| self.ata[(i, i)]).sum::<f64>() / n as f64;
        for i in 0..n {
            self.ata[(i, i)] += ridge.max(1e-300);
        }
        let chol = self
            .ata
            .cholesky()
            .ok_or_else(|| anyhow!("{what}: normal equations not positive definite"))?;
        Ok(chol.solve(&self.aty).iter().copied().collect())
    }
}

/// The degree in ln t a group can carry: Q terms, but fewer than the thicknesses it spans (a
/// polynomial through every point would not smooth, and one with more terms than points is
/// undetermined: on a coarse grid with held-out thicknesses it swings).
pub(crate) fn effective_q(q: usize, spanned: usize) -> usize {
    q.min(spanned.saturating_sub(1)).max(1)
}

/// β fitted with `qe` terms per parameter, stored with `q` (the missing ones 0: the same
/// polynomial).
pub(crate) fn pad_q(beta: &[f64], qe: usize, q: usize) -> Vec<f64> {
    beta.chunks(qe)
        .flat_map(|b| b.iter().copied().chain(std::iter::repeat(0.0)).take(q))
        .collect()
}

/// The form's parameters at thickness `t` from their Legendre coefficients `beta`
/// (parameter-major, Q per parameter) over the ln t span `range`.
pub(crate) fn coef_at(beta: &[f64], q: usize, range: (f64, f64), t: f64) -> Vec<f64> {
    let lq = legendre_in_ln_t(range, t, q);
    beta.chunks(q)
        .map(|b| b.iter().zip(&lq).map(|(x, l)| x * l).sum())
        .collect()
}

/// Fits group `g` over every thickness not in `skip_t`, without the sun cosines in `skip_l`.
pub fn fit_joint(
    tab: &SlabTables,
    form: &LogAdditive,
    g: usize,
    q: usize,
    skip_t: &[usize],
    skip_l: &[usize],
) -> Result<JointFit> {
    let [_, nt, nl, _, nm, _] = tab.shape;
    let (spanned, ln_t_range) = spanned(tab, g, skip_t)?;
    let qe = effective_q(q, spanned.len());
    let mut ne = NormalEquations::new(form.n_params(nm, nl) * qe);
    let mut row = Vec::new();
    let mut ranges: Vec<DepthRanges> = (0..nt).map(|_| DepthRanges::new(nl * nm)).collect();
    for it in (0..nt).filter(|it| !skip_t.contains(it)) {
        let lq = legendre_in_ln_t(ln_t_range, tab.thickness[it], qe);
        let in_fit = spanned.contains(&it);
        // Depth ranges only where the polynomials span: beyond, their parameters are the
        // span's ends, not this thickness's (a stray usable cell of a high order in a thin
        // slab would light its whole pair with them).
        for_each_row(tab, form, g, it, skip_l, &mut row, |r| {
            if in_fit {
                ranges[it].add(&r);
                ne.add(&r, &lq);
            }
        });
    }
    let (mut u_range, mut ceiling): (Vec<_>, Vec<_>) =
        ranges.into_iter().map(|r| r.finish(nl)).unzip();
    let cells = ne.cells;
    let beta = pad_q(&ne.solve(&format!("group {g}"))?, qe, q);
    // Held-out thicknesses: the depth ranges both fitted neighbours cover.
    let fitted: Vec<usize> = (0..nt).filter(|it| !skip_t.contains(it)).collect();
    for it in skip_t.iter().copied() {
        let below = fitted.iter().rev().find(|&&f| f < it).or(fitted.first());
        let above = fitted.iter().find(|&&f| f > it).or(fitted.last());
        if let (Some(&a), Some(&b)) = (below, above) {
            u_range[it] = u_range[a]
                .iter()
                .zip(&u_range[b])
                .map(|(x, y)| (x.0.max(y.0), x.1.min(y.1)))
                .collect();
            ceiling[it] = ceiling[a]
                .iter()
                .zip(&ceiling[b])
                .map(|(x, y)| x.max(*y))
                .collect();
        }
    }
    Ok(JointFit {
        group: g,
        q,
        beta,
        u_range,
        ceiling,
        cells,
        ln_t_range,
    })
}

impl JointFit {
    /// The form's parameters at thickness index `it` (its thickness), as a per-thickness fit.
    pub fn at(&self, tab: &SlabTables, it: usize) -> GroupFit {
        GroupFit {
            group: self.group,
            it,
            coef: coef_at(&self.beta, self.q, self.ln_t_range, tab.thickness[it]),
            cells: self.cells,
            u_range: self.u_range[it].clone(),
            ceiling: self.ceiling[it].clone(),
        }
    }
}

/// Joint fits of every group of orders ≥ 2, in parallel over groups.
pub fn fit_joint_groups(
    tab: &SlabTables,
    form: &LogAdditive,
    q: usize,
    skip_t: &[usize],
    skip_l: &[usize],
) -> Result<Vec<JointFit>> {
    let groups: Vec<usize> = (1..tab.shape[0]).collect();
    groups
        .par_iter()
        .map(|&g| fit_joint(tab, form, g, q, skip_t, skip_l))
        .collect()
}

/// Joint fits of every group of orders ≥ 2, as per-thickness fits at every thickness (held-out
/// ones included).
pub fn fit_all_joint(
    tab: &SlabTables,
    form: &LogAdditive,
    q: usize,
    skip_t: &[usize],
    skip_l: &[usize],
) -> Result<Vec<GroupFit>> {
    let joint = fit_joint_groups(tab, form, q, skip_t, skip_l)?;
    Ok(joint
        .iter()
        .flat_map(|j| (0..tab.shape[1]).map(move |it| j.at(tab, it)))
        .collect())
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::compress::fit::predict_held_out;
    use crate::compress::fit::tests::{synthetic, worst_relative};

    /// Tables made by the form with parameters that do not depend on t: the joint fit gives
    /// them back at every thickness, the held-out one included.
    #[test]
    fn joint_fit_recovers_t_independent_tables_and_a_held_out_thickness() {
        let (tab, form, _) = synthetic(4);
        let fits = fit_all_joint(&tab, &form, 2, &[2], &[]).unwrap();
        assert_eq!(fits.len(), 4);
        let pred = predict_held_out(&tab, &form, &fits, &[]);
        let start = tab.index(1, 0, 0, 0, 0, 0);
        let end = tab.index(1, 3, 2, 5, 7, 3) + 1;
        let worst = worst_relative(&tab.t[start..end], &pred[start..end]);
        assert!(worst < 1e-6, "worst relative difference {worst}");
    }
}
