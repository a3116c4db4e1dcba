//! Coverage: how much of the tables' light the form loses. The errors of [`super::report`] are
//! measured on the cells the fit used (T > 0, relative SE < 30 %); a renderer asks for every
//! geometry, so this measures on **every** cell with light — the horizon bins, the cells next to
//! the faces, the noisy ones — the share of the light in cells where the form gives 0 or is off
//! by more than a factor [`FACTOR`] ("dropped"), per group and for the sum of orders ≥ 2, per
//! (t, μ_L) slice, with the worst cells named. [`domain_check`] draws the sample of the tables a
//! renderer-side test checks the shipped `.ntt` against, between the grid's nodes too.

use super::report::WorstCell;
use crate::io::Npz;
use crate::slab::SlabTables;
use rand::{Rng, SeedableRng};
use rand_xoshiro::Xoshiro256PlusPlus;
use serde::Serialize;

/// A cell is dropped when the form is 0 there or off by more than this factor either way.
pub const FACTOR: f64 = 2.0;

/// The coverage of one group (or of the sum of the groups of orders ≥ 2).
#[derive(Clone, Debug, Serialize)]
pub struct Coverage {
    /// Group index, or None for the sum.
    pub group: Option<usize>,
    /// First order of the group.
    pub first_order: Option<f64>,
    /// Share of its light (Σ T over every cell with T > 0) in cells where the form is 0.
    pub zero: f64,
    /// Share of its light in cells where the form is 0 or off by more than [`FACTOR`].
    pub dropped: f64,
    /// The largest share of one (t, μ_L) slice's light of orders ≥ 2 that it drops, and where.
    pub worst_slice: SliceShare,
    /// Cells holding ≥ 1 % of their slice's largest T (this group's) where the form is 0.
    pub zero_cells_over_1pct: usize,
    /// T-weighted relative RMS error over every cell with T > 0 (nothing skipped).
    pub rel_rms_all: f64,
    /// The tables' T-weighted relative RMS noise on the same cells.
    pub noise_all: f64,
    /// √max(0, E² − N²): the error the noise does not explain.
    pub rel_rms_all_net: f64,
    /// Cells with T > 0.
    pub cells: usize,
    /// The five dropped cells with the most light.
    pub worst: Vec<WorstCell>,
}

/// A share of one slice's light.
#[derive(Clone, Copy, Debug, Default, Serialize)]
pub struct SliceShare {
    /// Thickness (mfp).
    pub t: f64,
    /// Sun cosine.
    pub mu_l: f64,
    /// The share.
    pub share: f64,
}

/// Whether the form's `got` drops the table's `want` (> 0).
pub fn dropped(want: f64, got: f64) -> bool {
    !(got > 0.0) || got > FACTOR * want || got * FACTOR < want
}

/// Coverage of `pred` (the form over the tables' layout, groups ≥ 1) for group `group`, or for
/// the sum of the groups ≥ 1 when None.
pub fn coverage(tab: &SlabTables, pred: &[f64], group: Option<usize>) -> Coverage {
    let [ng, nt, nl, nd, nm, nk] = tab.shape;
    let slice = nd * nm * nk;
    let groups: Vec<usize> = group.map_or_else(|| (1..ng).collect(), |g| vec![g]);
    let (mut light, mut zero, mut lost, mut e2, mut n2) = (0.0, 0.0, 0.0, 0.0, 0.0);
    let (mut cells, mut zero_cells) = (0, 0);
    let mut worst_slice = SliceShare::default();
    let mut worst: Vec<WorstCell> = Vec::new();
    for it in 0..nt {
        for il in 0..nl {
            let at = |g: usize| tab.index(g, it, il, 0, 0, 0);
            let value = |i: usize| {
                groups.iter().fold((0.0, 0.0, 0.0), |(t, v, p), &g| {
                    let k = at(g) + i;
                    (t + tab.t[k], v + tab.t_se[k].powi(2), p + pred[k])
                })
            };
            let all: f64 = (1..ng)
                .map(|g| tab.t[at(g)..at(g) + slice].iter().sum::<f64>())
                .sum();
            let top = (0..slice).map(|i| value(i).0).fold(0.0, f64::max);
            let mut slice_lost = 0.0;
            for i in (0..slice).filter(|&i| value(i).0 > 0.0) {
                let (t, var, p) = value(i);
                cells += 1;
                light += t;
                e2 += t * (p / t - 1.0).powi(2);
                n2 += var / t;
                if p <= 0.0 {
                    zero += t;
                    zero_cells += usize::from(t >= 0.01 * top);
                }
                if dropped(t, p) {
                    lost += t;
                    slice_lost += t;
                    let (j, m, k) = (i / (nm * nk), i / nk % nm, i % nk);
                    let pt = tab.point(it, il, j, m, k);
                    worst.push(WorstCell {
                        group: group.unwrap_or(0),
                        t: pt.thickness,
                        mu_l: pt.mu_l,
                        depth: pt.depth,
                        mu_v: pt.mu_v,
                        psi_v_deg: pt.psi_v.to_degrees(),
                        t_table: t,
                        t_se: var.sqrt(),
                        t_form: p,
                    });
                }
            }
            let share = if all > 0.0 { slice_lost / all } else { 0.0 };
            if share > worst_slice.share {
                worst_slice = SliceShare {
                    t: tab.thickness[it],
                    mu_l: tab.mu_l[il],
                    share,
                };
            }
        }
    }
    worst.sort_by(|a, b| b.t_table.total_cmp(&a.t_table));
    worst.truncate(5);
    let share = |v: f64| if light > 0.0 { v / light } else { 0.0 };
    let (e, n) = (share(e2).sqrt(), share(n2).sqrt());
    Coverage {
        group,
        first_order: group.map(|g| tab.group_first[g]),
        zero: share(zero),
        dropped: share(lost),
        worst_slice,
        zero_cells_over_1pct: zero_cells,
        rel_rms_all: e,
        noise_all: n,
        rel_rms_all_net: (e * e - n * n).max(0.0).sqrt(),
        cells,
        worst,
    }
}

/// The slice of `slices` with the largest share (the default where there is none).
pub fn worst_slice(slices: &[SliceShare]) -> SliceShare {
    slices.iter().fold(SliceShare::default(), |w, s| {
        if s.share > w.share {
            *s
        } else {
            w
        }
    })
}

/// The light of orders ≥ 2 every group drops together, per (t, μ_L) slice (t outer).
pub fn slices_of_all(tab: &SlabTables, pred: &[f64]) -> Vec<SliceShare> {
    let [ng, nt, nl, nd, nm, nk] = tab.shape;
    let slice = nd * nm * nk;
    let mut out = Vec::with_capacity(nt * nl);
    for it in 0..nt {
        for il in 0..nl {
            let (mut all, mut lost) = (0.0, 0.0);
            for g in 1..ng {
                let at = tab.index(g, it, il, 0, 0, 0);
                for k in at..at + slice {
                    all += tab.t[k];
                    if tab.t[k] > 0.0 && dropped(tab.t[k], pred[k]) {
                        lost += tab.t[k];
                    }
                }
            }
            out.push(SliceShare {
                t: tab.thickness[it],
                mu_l: tab.mu_l[il],
                share: if all > 0.0 { lost / all } else { 0.0 },
            });
        }
    }
    out
}

/// Two indices bracketing `x` among increasing `nodes` (one twice outside them).
fn around(nodes: &[f64], x: f64) -> [usize; 2] {
    let n = nodes.len();
    let hi = nodes.partition_point(|&v| v < x).min(n - 1);
    [hi.saturating_sub(usize::from(nodes[hi] > x)), hi]
}

/// The sample a renderer-side test checks a `.ntt` against (domain_check.npz), drawn from the
/// slab tables with a fixed seed: `n` random cells with T > 0 of any group (horizon, faces and
/// noisy cells included) — `cells` [n, 8]: group, t, μ_L, d, μ_V, ψ_V (the cell's centre), T,
/// SE — and `n` random points of the whole domain between the grid's nodes — `points` [n, 5]:
/// t (log-uniform), μ_L, d (uniform in stretched depth), μ_V, ψ_V — with the smallest and
/// largest table value per group over the 32 cells around each (the two thicknesses, sun
/// cosines, depth planes, μ_V and ψ_V bin centres that bracket it): `lo`, `hi` [n, groups].
pub fn domain_check(tab: &SlabTables, n: usize) -> Npz {
    let [ng, nt, nl, nd, nm, nk] = tab.shape;
    let mut rng = Xoshiro256PlusPlus::seed_from_u64(17);
    let mut cells = Vec::with_capacity(8 * n);
    while cells.len() < 8 * n {
        let (g, it, il) = (
            rng.random_range(1..ng),
            rng.random_range(0..nt),
            rng.random_range(0..nl),
        );
        let (j, m, k) = (
            rng.random_range(0..nd),
            rng.random_range(0..nm),
            rng.random_range(0..nk),
        );
        let i = tab.index(g, it, il, j, m, k);
        if tab.t[i] > 0.0 {
            let p = tab.point(it, il, j, m, k);
            cells.extend([
                g as f64,
                p.thickness,
                p.mu_l,
                p.depth,
                p.mu_v,
                p.psi_v,
                tab.t[i],
                tab.t_se[i],
            ]);
        }
    }
    let ln_t: Vec<f64> = tab.thickness.iter().map(|t| t.ln()).collect();
    let mu_v: Vec<f64> = (0..nm).map(|m| tab.mu_v(m)).collect();
    let psi_v: Vec<f64> = (0..nk).map(|k| tab.psi_v(k)).collect();
    let planes: Vec<f64> = (0..nd).map(|j| j as f64 / (nd - 1) as f64).collect();
    let (mut points, mut lo_all, mut hi_all) = (Vec::new(), Vec::new(), Vec::new());
    for _ in 0..n {
        let lt = rng.random_range(ln_t[0]..=ln_t[nt - 1]);
        let mu_l = rng.random_range(tab.mu_l[0]..=1.0);
        let u: f64 = rng.random();
        let (mv, psi) = (
            rng.random_range(-1.0..=1.0),
            rng.random_range(0.0..=std::f64::consts::PI),
        );
        let t = lt.exp();
        let d = crate::slab::grid::stretched_depth(t, u).clamp(0.0, t);
        let (mut lo, mut hi) = (vec![f64::INFINITY; ng - 1], vec![0.0f64; ng - 1]);
        for it in around(&ln_t, lt) {
            for il in around(&tab.mu_l, mu_l) {
                for j in around(&planes, u) {
                    for m in around(&mu_v, mv) {
                        for k in around(&psi_v, psi) {
                            for g in 1..ng {
                                let v = tab.t[tab.index(g, it, il, j, m, k)];
                                lo[g - 1] = lo[g - 1].min(v);
                                hi[g - 1] = hi[g - 1].max(v);
                            }
                        }
                    }
                }
            }
        }
        points.extend([t, mu_l, d, mv, psi]);
        lo_all.extend(lo);
        hi_all.extend(hi);
    }
    let mut npz = Npz::new();
    npz.add("cells", &[n, 8], &cells)
        .add("points", &[n, 5], &points)
        .add("lo", &[n, ng - 1], &lo_all)
        .add("hi", &[n, ng - 1], &hi_all);
    npz
}
