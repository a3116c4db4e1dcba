//! The reference form (docs/compress.md): Bouthors et al.'s structure for T — an amplitude that factors
//! into a view part A(t, μ_V) and a light part X(t, μ_L), a skewed Gaussian in depth whose peak
//! moves with μ_V and μ_L, a table P(t, Θ) for the remaining anisotropy and azimuth terms —
//! written in ln T so that it is linear in its parameters and fitted like ours:
//!
//!   ln T = ln B + a(μ_V) + x(μ_L) + [b_V(μ_V) + b_L(μ_L)] x̂ + c₂ P₂(x̂) + c₃ P₃(x̂)
//!          + Σ_i h_i(Θ) p_i + Σ_k [e_k(μ_V) + f_k(μ_L)] (s_V s_L)^k cos kψ_V,
//!
//! x̂ = 2u − 1. The Gaussian −(u − B₁ − B₂)²/2C² gives the slope (B₁ + B₂)/C², additive in
//! μ_V and μ_L, and the width c₂ = −1/2C²; c₃ skews it; its cross term B₁B₂/C² is what the
//! factored amplitude A·X leaves out, as Bouthors et al.'s form does. Fitted per (group,
//! thickness) — each parameter a 2D table in (t, μ_V), (t, μ_L) or (t, Θ), the most generous
//! reading — and measured on the fitted slices only: it is the baseline the log-additive form
//! is compared with, not a shipped form.

use super::fit::for_each_row_of;
use super::form::Cell;
use super::joint::NormalEquations;
use crate::slab::SlabTables;
use anyhow::Result;
use nephele_runtime::fitting::{legendre, theta_hats};
use rayon::prelude::*;

/// Θ nodes of the reference form's P table.
const THETA_NODES: usize = 24;
/// Azimuth terms.
const HARMONICS: usize = 3;

/// Parameters per (group, thickness) for `nm` view and `nl` sun cosines.
pub fn n_params(nm: usize, nl: usize) -> usize {
    2 * (nm + nl) + 2 + 2 * THETA_NODES + HARMONICS * (nm + nl)
}

/// The features of cell `c` (on the grid's nodes) into `row`.
fn features(c: &Cell, nm: usize, nl: usize, row: &mut Vec<(usize, f64)>) -> bool {
    row.clear();
    let x = 2.0 * c.u - 1.0;
    let (m, il) = (c.v.lo, c.l.lo);
    row.extend([(m, 1.0), (nm + il, 1.0)]);
    let slope = nm + nl;
    row.extend([(slope + m, x), (slope + nm + il, x)]);
    let p = legendre(x, 4);
    let shape = 2 * (nm + nl);
    row.extend([(shape, p[2]), (shape + 1, p[3])]);
    let table = shape + 2;
    // The Θ hats with their depth slopes, of which the reference keeps the constants only.
    theta_hats(THETA_NODES, c, 1.0, table, &mut |col, v, j| {
        if j == 0 {
            row.push((col, v));
        }
    });
    let azimuth = table + 2 * THETA_NODES;
    let (mu_v, mu_l) = (c.at.mu_v, c.at.mu_l);
    let s = ((1.0 - mu_v * mu_v) * (1.0 - mu_l * mu_l))
        .clamp(0.0, 1.0)
        .sqrt();
    for k in 0..HARMONICS {
        let v = s.powi(k as i32 + 1) * ((k + 1) as f64 * c.at.psi_v).cos();
        let col = azimuth + k * (nm + nl);
        row.extend([(col + m, v), (col + nm + il, v)]);
    }
    true
}

/// T of the reference form over the whole table layout, fitted per (group ≥ 1, thickness) to
/// the usable cells; 0 outside each (μ_L, μ_V) pair's fitted depths (as for our form).
pub fn fit_and_predict(tab: &SlabTables) -> Result<Vec<f64>> {
    let [ng, nt, nl, nd, nm, nk] = tab.shape;
    let np = n_params(nm, nl);
    let slice = nl * nd * nm * nk;
    let feats = |c: &Cell, row: &mut Vec<(usize, f64)>| features(c, nm, nl, row);
    let jobs: Vec<(usize, usize)> = (1..ng)
        .flat_map(|g| (0..nt).map(move |it| (g, it)))
        .collect();
    let parts: Vec<Vec<f64>> = jobs
        .par_iter()
        .map(|&(g, it)| {
            let mut ne = NormalEquations::new(np);
            let mut row = Vec::new();
            let mut u_range = vec![(f64::INFINITY, f64::NEG_INFINITY); nl * nm];
            for_each_row_of(tab, &feats, g, it, &[], &mut row, |r| {
                let range = &mut u_range[r.pair];
                *range = (range.0.min(r.u), range.1.max(r.u));
                ne.add(&r, &[1.0]);
            });
            let mut pred = vec![0.0; slice];
            if ne.cells == 0 {
                return Ok(pred);
            }
            let coef = ne.solve(&format!("reference form, group {g}, thickness {it}"))?;
            for_each_cell(tab, it, |c, r, off| {
                let (lo, hi) = u_range[c.l.lo * nm + c.v.lo];
                if c.u >= lo && c.u <= hi && features(c, nm, nl, &mut row) {
                    let s: f64 = row.iter().map(|&(col, v)| v * coef[col]).sum();
                    pred[r] = (off + s).exp();
                }
            });
            Ok(pred)
        })
        .collect::<Result<_>>()?;
    let mut pred = vec![0.0; tab.t.len()];
    for ((g, it), part) in jobs.iter().zip(parts) {
        let start = (g * nt + it) * slice;
        pred[start..start + slice].copy_from_slice(&part);
    }
    Ok(pred)
}

/// Calls `f(cell, index within the slice, ln B)` for every representable cell of thickness it.
fn for_each_cell(tab: &SlabTables, it: usize, mut f: impl FnMut(&Cell, usize, f64)) {
    let [_, _, _, nd, nm, nk] = tab.shape;
    let cells = super::fit::cells_of(tab, it);
    for (c, [il, j, m, k], off) in cells {
        f(&c, ((il * nd + j) * nm + m) * nk + k, off);
    }
}
