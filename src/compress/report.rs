//! How well a compressed form reproduces the tables: per order group and for the sum of the
//! groups of orders ≥ 2, the T-weighted relative RMS error
//!
//!   E = √( Σ T (T̂/T − 1)² / Σ T )
//!
//! over the cells with T > 0 and relative SE < 30 %, next to the tables' own noise on the same
//! cells, N = √( Σ T (SE/T)² / Σ T ) (a form that follows the tables to their noise has E ≈ N);
//! and the worst cells among those holding ≥ 1 % of their slice's largest T.

use crate::slab::SlabTables;
use serde::Serialize;

/// One cell named in a report.
#[derive(Clone, Debug, Serialize)]
pub struct WorstCell {
    /// Group index.
    pub group: usize,
    /// Thickness (mfp).
    pub t: f64,
    /// Sun cosine.
    pub mu_l: f64,
    /// Depth (mfp).
    pub depth: f64,
    /// View cosine (bin centre).
    pub mu_v: f64,
    /// View azimuth (bin centre, degrees).
    pub psi_v_deg: f64,
    /// Table value and its standard error.
    pub t_table: f64,
    /// See `t_table`.
    pub t_se: f64,
    /// The form's value.
    pub t_form: f64,
}

/// The error of one group (or of the sum of groups).
#[derive(Clone, Debug, Serialize)]
pub struct GroupError {
    /// Group index, or None for the sum of the groups of orders ≥ 2.
    pub group: Option<usize>,
    /// First order of the group.
    pub first_order: Option<f64>,
    /// T-weighted relative RMS error E.
    pub rel_rms: f64,
    /// The tables' T-weighted relative RMS noise N on the same cells.
    pub noise: f64,
    /// Cells measured.
    pub cells: usize,
    /// E per thickness.
    pub rel_rms_by_t: Vec<f64>,
    /// E per (thickness, sun cosine) slice, [t, μ_L] row-major (NaN: no cell measured).
    pub rel_rms_by_slice: Vec<f64>,
    /// The five largest relative errors among cells ≥ 1 % of their slice's maximum.
    pub worst: Vec<WorstCell>,
}

/// E and N of `pred` (the form's T over the whole table layout, groups ≥ 1 filled) for group
/// `group`, or for the sum of groups ≥ 1 when `group` is None.
pub fn group_error(tab: &SlabTables, pred: &[f64], group: Option<usize>) -> GroupError {
    group_error_on(tab, pred, group, &|_, _| true)
}

/// As [`group_error`], on the slices (t index, μ_L index) that `include` accepts only.
pub fn group_error_on(
    tab: &SlabTables,
    pred: &[f64],
    group: Option<usize>,
    include: &dyn Fn(usize, usize) -> bool,
) -> GroupError {
    let [ng, nt, nl, nd, nm, nk] = tab.shape;
    let groups: Vec<usize> = match group {
        Some(g) => vec![g],
        None => (1..ng).collect(),
    };
    let value = |v: &[f64], it: usize, rest: usize| -> f64 {
        groups
            .iter()
            .map(|&g| v[(g * nt + it) * nl * nd * nm * nk + rest])
            .sum()
    };
    let se_of = |it: usize, rest: usize| -> f64 {
        groups
            .iter()
            .map(|&g| tab.t_se[(g * nt + it) * nl * nd * nm * nk + rest].powi(2))
            .sum::<f64>()
            .sqrt()
    };
    let per_slice = nl * nd * nm * nk;
    let (mut e, mut n, mut w, mut cells) = (0.0, 0.0, 0.0, 0);
    let mut by_t = Vec::new();
    let mut by_slice = vec![(0.0, 0.0); nt * nl];
    let mut worst: Vec<(f64, WorstCell)> = Vec::new();
    for it in 0..nt {
        let (mut et, mut wt) = (0.0, 0.0);
        let slice_max = (0..per_slice)
            .map(|r| value(&tab.t, it, r))
            .fold(0.0, f64::max);
        for cell in cells_of_thickness(tab, it, include) {
            let r = cell.r;
            let (t, se, f) = (value(&tab.t, it, r), se_of(it, r), value(pred, it, r));
            if !(t > 0.0 && se < 0.3 * t) {
                continue;
            }
            let rel = f / t - 1.0;
            let slice = &mut by_slice[it * nl + cell.il];
            slice.0 += t * rel * rel;
            slice.1 += t;
            e += t * rel * rel;
            n += t * (se / t).powi(2);
            w += t;
            et += t * rel * rel;
            wt += t;
            cells += 1;
            if t >= 0.01 * slice_max {
                let [t_slab, mu_l, depth, mu_v, psi_v_deg] = cell.coords(tab);
                worst.push((
                    rel.abs(),
                    WorstCell {
                        group: group.unwrap_or(usize::MAX),
                        t: t_slab,
                        mu_l,
                        depth,
                        mu_v,
                        psi_v_deg,
                        t_table: t,
                        t_se: se,
                        t_form: f,
                    },
                ));
            }
        }
        by_t.push(if wt > 0.0 { (et / wt).sqrt() } else { 0.0 });
    }
    worst.sort_by(|a, b| b.0.total_cmp(&a.0));
    GroupError {
        group,
        first_order: group.map(|g| tab.group_first[g]),
        rel_rms: if w > 0.0 { (e / w).sqrt() } else { 0.0 },
        noise: if w > 0.0 { (n / w).sqrt() } else { 0.0 },
        cells,
        rel_rms_by_t: by_t,
        rel_rms_by_slice: by_slice
            .iter()
            .map(|&(e, w)| if w > 0.0 { (e / w).sqrt() } else { f64::NAN })
            .collect(),
        worst: worst.into_iter().take(5).map(|(_, c)| c).collect(),
    }
}

/// One collector cell named in a report.
#[derive(Clone, Debug, Serialize)]
pub struct WorstCollectorCell {
    /// Where: thickness (mfp), sun cosine, depth (mfp), view cosine, view azimuth (degrees).
    pub at: [f64; 5],
    /// Table (c_x, c_z, σ) (mfp).
    pub table: [f64; 3],
    /// The form's (c_x, c_z, σ).
    pub form: [f64; 3],
    /// |ĉ − c|/σ.
    pub c_error_in_sigma: f64,
}

/// The collector error of one group: T-weighted RMS over the cells where T and σ are usable
/// (relative SE < 30 %) and the form gives T > 0.
#[derive(Clone, Debug, Serialize)]
pub struct CollectorError {
    /// Group index.
    pub group: usize,
    /// First order of the group.
    pub first_order: f64,
    /// √(Σ T (σ̂/σ − 1)² / Σ T).
    pub sigma_rel: f64,
    /// The tables' relative noise of σ on the same cells.
    pub sigma_noise: f64,
    /// √(Σ T |ĉ − c|²/σ² / Σ T): the collector's error in units of σ.
    pub c_in_sigma: f64,
    /// The same for c_x and c_z apart.
    pub cx_in_sigma: f64,
    /// See `cx_in_sigma`.
    pub cz_in_sigma: f64,
    /// The tables' noise of c in units of σ, √(Σ T (SE_x² + SE_z²)/σ² / Σ T).
    pub c_noise: f64,
    /// Cells measured.
    pub cells: usize,
    /// Cells where T is usable but the form gives T = 0 (left out).
    pub cells_without_form: usize,
    /// `c_in_sigma` per thickness.
    pub c_in_sigma_by_t: Vec<f64>,
    /// The five largest |ĉ − c|/σ among cells ≥ 1 % of their slice's largest T.
    pub worst: Vec<WorstCollectorCell>,
}

/// The collector error of group `g` from `pred` = (σ̂, ĉ_x, ĉ_z) over the table layout (NaN
/// where the form gives none), on the slices (t index, μ_L index) that `include` accepts.
pub fn collector_error_on(
    tab: &SlabTables,
    pred: &[Vec<f64>; 3],
    g: usize,
    include: &dyn Fn(usize, usize) -> bool,
) -> CollectorError {
    let [_, nt, nl, nd, nm, nk] = tab.shape;
    let c = &tab.collector;
    let per_slice = nl * nd * nm * nk;
    let mut acc = [0.0; 6]; // T·(σ rel², σ noise², c², cx², cz², c noise²)
    let (mut w, mut cells, mut without) = (0.0, 0, 0);
    let mut by_t = Vec::new();
    let mut worst: Vec<WorstCollectorCell> = Vec::new();
    for it in 0..nt {
        let start = (g * nt + it) * per_slice;
        let slice_max = tab.t[start..start + per_slice]
            .iter()
            .copied()
            .fold(0.0, f64::max);
        let (mut et, mut wt) = (0.0, 0.0);
        for cell in cells_of_thickness(tab, it, include) {
            let i = start + cell.r;
            let (t, s) = (tab.t[i], c.sigma[i]);
            let usable = t > 0.0
                && tab.t_se[i] < 0.3 * t
                && s > 0.0
                && c.sigma_se[i] < 0.3 * s
                && c.cx[i].is_finite()
                && c.cz[i].is_finite();
            if !usable {
                continue;
            }
            let [ps, px, pz] = [pred[0][i], pred[1][i], pred[2][i]];
            if !ps.is_finite() {
                without += 1;
                continue;
            }
            let (dx, dz) = ((px - c.cx[i]) / s, (pz - c.cz[i]) / s);
            let terms = [
                (ps / s - 1.0).powi(2),
                (c.sigma_se[i] / s).powi(2),
                dx * dx + dz * dz,
                dx * dx,
                dz * dz,
                (c.cx_se[i].powi(2) + c.cz_se[i].powi(2)) / (s * s),
            ];
            for (a, v) in acc.iter_mut().zip(terms) {
                *a += t * v;
            }
            w += t;
            et += t * terms[2];
            wt += t;
            cells += 1;
            if t >= 0.01 * slice_max {
                worst.push(WorstCollectorCell {
                    at: cell.coords(tab),
                    table: [c.cx[i], c.cz[i], s],
                    form: [px, pz, ps],
                    c_error_in_sigma: terms[2].sqrt(),
                });
                worst.sort_by(|a, b| b.c_error_in_sigma.total_cmp(&a.c_error_in_sigma));
                worst.truncate(5);
            }
        }
        by_t.push(if wt > 0.0 { (et / wt).sqrt() } else { 0.0 });
    }
    let rms = |a: f64| if w > 0.0 { (a / w).sqrt() } else { 0.0 };
    CollectorError {
        group: g,
        first_order: tab.group_first[g],
        sigma_rel: rms(acc[0]),
        sigma_noise: rms(acc[1]),
        c_in_sigma: rms(acc[2]),
        cx_in_sigma: rms(acc[3]),
        cz_in_sigma: rms(acc[4]),
        c_noise: rms(acc[5]),
        cells,
        cells_without_form: without,
        c_in_sigma_by_t: by_t,
        worst,
    }
}

/// A cell of one thickness: its offset `r` in the [μ_L, depth, μ_V, ψ_V] slice of thickness
/// `it`, and r's parts.
#[derive(Clone, Copy, Debug)]
struct CellAt {
    it: usize,
    r: usize,
    il: usize,
    j: usize,
    m: usize,
    k: usize,
}

impl CellAt {
    /// (t, μ_L, depth, μ_V, ψ_V in degrees) of the cell, as reports name it.
    fn coords(&self, tab: &SlabTables) -> [f64; 5] {
        let nd = tab.shape[3];
        [
            tab.thickness[self.it],
            tab.mu_l[self.il],
            tab.depth[self.it * nd + self.j],
            tab.mu_v(self.m),
            tab.psi_v(self.k).to_degrees(),
        ]
    }
}

/// The cells of thickness `it`, in layout order, of the slices (t index, μ_L index) that
/// `include` accepts: the one walk over the tables that the error reports share.
fn cells_of_thickness<'a>(
    tab: &SlabTables,
    it: usize,
    include: &'a dyn Fn(usize, usize) -> bool,
) -> impl Iterator<Item = CellAt> + 'a {
    let [_, _, nl, nd, nm, nk] = tab.shape;
    (0..nl * nd * nm * nk)
        .map(move |r| CellAt {
            it,
            r,
            il: r / (nd * nm * nk),
            j: r / (nm * nk) % nd,
            m: r / nk % nm,
            k: r % nk,
        })
        .filter(move |c| include(c.it, c.il))
}
