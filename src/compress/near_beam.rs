//! The compressed tables near the transmitted beam, where the halo of the low orders lives
//! (src/slab/aureole.rs): the runtime's T, read from the `.ntt` just written, averaged over
//! each aureole annulus and over each view bin within [`NEAR_BEAM_DEG`] of the beam, against
//! the slab run's tallies there. A bin average is compared with a bin average, so the halo's
//! energy counts wherever in the bin the form puts it.

use crate::slab::aureole::{bin_extent, view_near_beam};
use crate::slab::output::AureoleTables;
use crate::slab::SlabTables;
use nephele_runtime::transport::{SlabPoint, Transport, TransportTables};
use serde::Serialize;
use std::f64::consts::PI;

/// The view bins compared: those that come within this angle of the transmitted beam, whose
/// bin average holds the halo.
pub const NEAR_BEAM_DEG: f64 = 6.5;

/// Which view bins going down come within an angle of the beam, per (μ_L, μ_V, ψ_V).
pub struct NearBeam {
    near: Vec<bool>,
    nm: usize,
    nk: usize,
}

impl NearBeam {
    /// The bins of `tab` going down that come within `angle` (radians) of the beam.
    pub fn within(tab: &SlabTables, angle: f64) -> Self {
        let [_, _, nl, _, nm, nk] = tab.shape;
        let mut near = vec![false; nl * nm * nk];
        let e = (&tab.mu_v_edges, &tab.psi_v_edges);
        for (il, &mu_l) in tab.mu_l.iter().enumerate() {
            let beam = mu_l.acos();
            for m in 0..nm {
                // The polar angles of the bin's views going down, against the beam's.
                let (a, b) = ((-e.0[m]).acos(), (-e.0[m + 1]).acos());
                if e.0[m] >= 0.0 || beam < a - angle || beam > b + angle {
                    continue;
                }
                for k in 0..nk {
                    let psi = (e.1[k], e.1[k + 1]);
                    let (lo, _) = bin_extent(mu_l, (e.0[m], e.0[m + 1]), psi);
                    near[(il * nm + m) * nk + k] = lo < angle;
                }
            }
        }
        Self { near, nm, nk }
    }

    /// Whether bin (μ_L il, μ_V m, ψ_V k) comes within the angle.
    pub fn holds(&self, il: usize, m: usize, k: usize) -> bool {
        self.near[(il * self.nm + m) * self.nk + k]
    }
}

/// Quadrature points across an annulus (or a bin) in each of its two directions.
const POINTS: usize = 8;

/// The error of one group (or of the sum of orders ≥ 2) over a set of cells near the beam.
#[derive(Clone, Debug, Default, Serialize)]
pub struct NearBeamError {
    /// Group index, or None for the sum of orders ≥ 2.
    pub group: Option<usize>,
    /// Cells compared (T > 0 in the tables, finite standard error).
    pub cells: usize,
    /// Σ form / Σ tables − 1.
    pub bias: f64,
    /// T-weighted relative RMS error, √(Σ T (f/T − 1)² / Σ T).
    pub rel_rms: f64,
    /// The tables' own T-weighted relative RMS noise on the same cells.
    pub noise: f64,
}

/// Near the beam: per group then the sum, over the aureole's annuli and over the view bins.
#[derive(Clone, Debug, Serialize)]
pub struct NearBeamCheck {
    /// What is measured.
    pub definition: &'static str,
    /// Over the annuli (none if the tables have no aureole).
    pub annuli: Vec<NearBeamError>,
    /// Over the view bins within [`NEAR_BEAM_DEG`] of the beam.
    pub bins: Vec<NearBeamError>,
}

/// Sums of one group's comparison.
#[derive(Clone, Copy, Default)]
struct Sums {
    cells: usize,
    t: f64,
    form: f64,
    err2: f64,
    noise2: f64,
}

impl Sums {
    fn add(&mut self, t: f64, se: f64, form: f64) {
        if t > 0.0 && se.is_finite() {
            self.cells += 1;
            self.t += t;
            self.form += form;
            self.err2 += t * (form / t - 1.0).powi(2);
            self.noise2 += t * (se / t).powi(2);
        }
    }

    fn error(&self, group: Option<usize>) -> NearBeamError {
        let t = self.t.max(f64::MIN_POSITIVE);
        NearBeamError {
            group,
            cells: self.cells,
            bias: self.form / t - 1.0,
            rel_rms: (self.err2 / t).sqrt(),
            noise: (self.noise2 / t).sqrt(),
        }
    }
}

/// The check of `rt` against `tab` (and its aureole, if the run tallied one) for the groups of
/// orders ≥ 2 (the runtime's groups are the tables' from 1 on).
pub fn near_beam_check(tab: &SlabTables, rt: &TransportTables) -> NearBeamCheck {
    let aureole = tab.aureole.as_ref();
    let [ng, nt, nl, nd, nm, nk] = tab.shape;
    let mut annuli = vec![Sums::default(); ng];
    let mut bins = vec![Sums::default(); ng];
    let near = NearBeam::within(tab, NEAR_BEAM_DEG.to_radians());
    let mut all = vec![Transport::default(); ng - 1];
    let mut mean = vec![0.0; ng - 1];
    if let Some(a) = aureole {
        each_annulus(tab, a, rt, a.annuli.n_bins(), |[it, il, j, b], mean| {
            for g in 1..ng {
                let i = a.index(&tab.shape, g, it, il, j, b);
                annuli[g].add(a.t[i], a.t_se[i], mean[g - 1]);
            }
        });
    }
    for (it, il, j) in
        (0..nt).flat_map(|it| (0..nl).flat_map(move |il| (0..nd).map(move |j| (it, il, j))))
    {
        let at = tab.point(it, il, j, 0, 0);
        for (m, k) in (0..nm).flat_map(|m| (0..nk).map(move |k| (m, k))) {
            if !near.holds(il, m, k) {
                continue;
            }
            let (mu, psi) = (&tab.mu_v_edges, &tab.psi_v_edges);
            average(rt, &mut all, &mut mean, |p, q| {
                let mu_v = mu[m] + (mu[m + 1] - mu[m]) * p;
                let psi_v = psi[k] + (psi[k + 1] - psi[k]) * q;
                (SlabPoint { mu_v, psi_v, ..at }, 1.0)
            });
            for g in 1..ng {
                let i = tab.index(g, it, il, j, m, k);
                bins[g].add(tab.t[i], tab.t_se[i], mean[g - 1]);
            }
        }
    }
    // Each group's cells, then the cells of every group of orders ≥ 2 pooled.
    let errors = |s: &[Sums]| -> Vec<NearBeamError> {
        let mut pooled = Sums::default();
        for x in &s[1..] {
            pooled.cells += x.cells;
            pooled.t += x.t;
            pooled.form += x.form;
            pooled.err2 += x.err2;
            pooled.noise2 += x.noise2;
        }
        (1..ng)
            .map(|g| s[g].error(Some(g)))
            .chain([pooled.error(None)])
            .collect()
    };
    NearBeamCheck {
        definition: "the runtime's T from transport.ntt averaged over each aureole annulus (8 angles x 8 turns about the beam, weighted by sin theta) and over each view bin within NEAR_BEAM_DEG of the beam (8 x 8 points), against the slab tables' tallies there; per group of orders >= 2, then all of them pooled (cells of every group together)",
        annuli: if aureole.is_some() {
            errors(&annuli)
        } else {
            Vec::new()
        },
        bins: errors(&bins),
    }
}

/// Groups of orders ≥ 2 the halo covers (orders 2 … 18): the form of the higher orders is
/// within +9 … +27 % on the annuli, and two more groups would add a third to the table.
pub const HALO_GROUPS: usize = 6;

/// The halo's reach (degrees from the beam): the annuli out to it. Beyond it the form's bins
/// hold the light well enough, and a ratio taken at the nodes does not carry between them at
/// the far face of thick slabs (docs/compress.md, "The halo term").
const HALO_DEG: f64 = 6.5;

/// The largest |h| stored: e^30 ≈ 10¹³, within f32 for any T the form gives near the beam
/// (order 2's form there is 10⁻⁴ … 10⁻⁸ of the halo's tally on the inner annuli).
const H_MAX: f64 = 30.0;

/// The halo correction a `.ntt` stores (nephele_runtime's `transport::halo`).
pub struct HaloTable {
    /// Annulus edges (degrees).
    pub edges_deg: Vec<f64>,
    /// Groups covered (the first ones of orders ≥ 2).
    pub groups: usize,
    /// Depth planes.
    pub planes: usize,
    /// h = ln(T_annulus / T̄_form) over [group, thickness, μ_L, plane, annulus]; where the
    /// annulus is cut by the horizon or its tally has no light or is too noisy (relative SE ≥
    /// 30 %), the mean of its neighbours' (filled outward).
    pub values: Vec<f32>,
}

/// The halo of `tab`'s aureole against the form of `rt` (which has none).
pub fn halo_table(tab: &SlabTables, aur: &AureoleTables, rt: &TransportTables) -> HaloTable {
    let [ng, nt, nl, nd, ..] = tab.shape;
    // The annuli out to HALO_DEG.
    let nb = (0..aur.annuli.n_bins())
        .take_while(|&b| aur.annuli.edges_deg[b + 1] <= HALO_DEG + 1e-9)
        .count()
        .max(1);
    let groups = HALO_GROUPS.min(ng - 1);
    let mut values = vec![0.0f32; groups * nt * nl * nd * nb];
    let mut known = vec![false; values.len()];
    each_annulus(tab, aur, rt, nb, |[it, il, j, b], mean| {
        for g in 0..groups {
            let i = aur.index(&tab.shape, g + 1, it, il, j, b);
            let (t, se) = (aur.t[i], aur.t_se[i]);
            if t > 0.0 && se < 0.3 * t && mean[g] > 0.0 {
                let h = (t / mean[g]).ln().clamp(-H_MAX, H_MAX);
                let k = (((g * nt + it) * nl + il) * nd + j) * nb + b;
                (values[k], known[k]) = (h as f32, true);
            }
        }
    });
    fill_from_neighbours(&mut values, &mut known, [groups, nt, nl, nd, nb]);
    HaloTable {
        edges_deg: aur.annuli.edges_deg[..=nb].to_vec(),
        groups,
        planes: nd,
        values,
    }
}

/// Gives every entry of `values` [group, t, μ_L, plane, annulus] not `known` the mean of its
/// known neighbours (±1 node in t, μ_L and plane), pass after pass until all are known (or
/// none of a group's annulus is). The halo is read linearly between nodes: where the walk left
/// an annulus without light or too noisy (order 2 at the far face of thick slabs) or cut by
/// the horizon, h = 0 would pull its neighbours' halo halfway back to the form's hole (order 2
/// −85 % at the far face of a 10 mfp slab, between nodes, before this fill).
fn fill_from_neighbours(values: &mut [f32], known: &mut [bool], [ng, nt, nl, nd, nb]: [usize; 5]) {
    let at = |g: usize, it: usize, il: usize, j: usize, b: usize| {
        (((g * nt + it) * nl + il) * nd + j) * nb + b
    };
    for (g, b) in (0..ng).flat_map(|g| (0..nb).map(move |b| (g, b))) {
        loop {
            let mut found = Vec::new();
            for (it, il, j) in
                (0..nt).flat_map(|it| (0..nl).flat_map(move |il| (0..nd).map(move |j| (it, il, j))))
            {
                if known[at(g, it, il, j, b)] {
                    continue;
                }
                let near = [
                    (it > 0).then(|| at(g, it - 1, il, j, b)),
                    (it + 1 < nt).then(|| at(g, it + 1, il, j, b)),
                    (il > 0).then(|| at(g, it, il - 1, j, b)),
                    (il + 1 < nl).then(|| at(g, it, il + 1, j, b)),
                    (j > 0).then(|| at(g, it, il, j - 1, b)),
                    (j + 1 < nd).then(|| at(g, it, il, j + 1, b)),
                ];
                let (n, sum) = near
                    .iter()
                    .flatten()
                    .filter(|&&k| known[k])
                    .fold((0, 0.0f64), |(n, s), &k| (n + 1, s + values[k] as f64));
                if n > 0 {
                    found.push((at(g, it, il, j, b), (sum / n as f64) as f32));
                }
            }
            if found.is_empty() {
                break;
            }
            for (k, v) in found {
                (values[k], known[k]) = (v, true);
            }
        }
    }
}

/// `f([it, il, j, b], means)` for every (thickness, sun cosine, plane) of `tab` and each of
/// the first `nb` annuli of `aur` that lies whole below the horizon, `means` every runtime
/// group's T averaged over the annulus ([`POINTS`] angles × [`POINTS`] turns about the beam,
/// weighted by sin Θ).
fn each_annulus(
    tab: &SlabTables,
    aur: &AureoleTables,
    rt: &TransportTables,
    nb: usize,
    mut f: impl FnMut([usize; 4], &[f64]),
) {
    let [_, nt, nl, nd, ..] = tab.shape;
    let mut all = vec![Transport::default(); rt.groups()];
    let mut mean = vec![0.0; rt.groups()];
    for (it, il, j) in
        (0..nt).flat_map(|it| (0..nl).flat_map(move |il| (0..nd).map(move |j| (it, il, j))))
    {
        let at = tab.point(it, il, j, 0, 0);
        let mu_l = tab.mu_l[il];
        for b in (0..nb).filter(|&b| aur.annuli.whole(mu_l, b)) {
            let (lo, hi) = (aur.annuli.edges_deg[b], aur.annuli.edges_deg[b + 1]);
            average(rt, &mut all, &mut mean, |p, q| {
                let theta = (lo + (hi - lo) * p).to_radians();
                let (mu_v, psi_v) = view_near_beam(mu_l, theta, 2.0 * PI * q);
                (SlabPoint { mu_v, psi_v, ..at }, theta.sin())
            });
            f([it, il, j, b], &mean);
        }
    }
}

/// The mean of every group's T over a cell: `point(p, q)` gives the point at fractions (p, q)
/// ∈ (0, 1)² of the cell's two directions and its quadrature weight; midpoints, [`POINTS`]².
fn average(
    rt: &TransportTables,
    all: &mut [Transport],
    mean: &mut [f64],
    point: impl Fn(f64, f64) -> (SlabPoint<f64>, f64),
) {
    mean.iter_mut().for_each(|m| *m = 0.0);
    let mut weight = 0.0;
    for a in 0..POINTS {
        for b in 0..POINTS {
            let f = |i: usize| (i as f64 + 0.5) / POINTS as f64;
            let (at, w) = point(f(a), f(b));
            let at32 = at.to_f32();
            rt.evaluate_all(&at32, all);
            for (m, t) in mean.iter_mut().zip(all.iter()) {
                *m += w * t.t as f64;
            }
            weight += w;
        }
    }
    mean.iter_mut().for_each(|m| *m /= weight);
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::compress::fit::tests::synthetic;

    #[test]
    fn the_bins_near_the_beam_are_those_around_it() {
        // 8 μ_V bins of 1/4, 4 ψ_V bins of 45°, sun cosines 0.3, 0.6, 0.9.
        let (tab, _, _) = synthetic(1);
        let near = NearBeam::within(&tab, NEAR_BEAM_DEG.to_radians());
        // Under μ_L = 0.6 the beam (μ_V = −0.6, ψ_V = 0) lies in μ_V bin 1 ([−0.75, −0.5]).
        assert!(near.holds(1, 1, 0));
        assert!(!near.holds(1, 1, 2) && !near.holds(1, 6, 0) && !near.holds(1, 3, 0));
        let held = (0..3 * 8 * 4).filter(|i| near.near[*i]).count();
        assert!((3..=8).contains(&held), "{held} bins held");
    }
}
