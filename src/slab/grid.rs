//! The cells of the canonical tables (docs/slab.md): tally planes in depth, view-direction bins in
//! (μ_V, ψ_V) and groups of scattering orders.
//!
//! - μ_V = cosine of the light's direction with the upward normal (> 0 going up).
//! - ψ_V = azimuth of that direction from the sun beam's horizontal travel direction, folded to
//!   [0, π] by mirror symmetry; a bin [ψ₁, ψ₂] therefore covers ±[ψ₁, ψ₂], solid angle
//!   ΔΩ = 2 Δμ Δψ.
//! - Planes are stretched toward the lit face for thick slabs: with s = d/t and u uniform on
//!   [0, 1], s = (e^{βu} − 1)/(e^β − 1), β = 0.3 t^0.65 (0.3 at t = 1, 4.5 at t = 64): at t = 64
//!   the orders 1–8 live within ~10 mfp of the lit face. The law is the runtime's (its
//!   constants, and its inverse for the tables' lookups), as are the default order groups.

use super::aureole::Aureole;
use super::lanes::{count_edges, floor_index, Lane, LANES};
use anyhow::{bail, Result};
use nephele_runtime::fitting::{STRETCH_EXPONENT, STRETCH_SCALE};

pub use nephele_runtime::fitting::DEFAULT_GROUP_FIRST;

/// The default order groups: 1, 2, 3–4, 5–6, 7–8, 9–12, 13–18, 19–30, 31–∞ (inclusive bounds;
/// `u32::MAX` is ∞), from their first orders, the runtime's [`DEFAULT_GROUP_FIRST`].
pub const DEFAULT_GROUPS: [(u32, u32); 9] = {
    let first = DEFAULT_GROUP_FIRST;
    let mut groups = [(0, 0); 9];
    let mut i = 0;
    while i < 9 {
        let last = if i + 1 < 9 {
            first[i + 1] - 1
        } else {
            u32::MAX
        };
        groups[i] = (first[i], last);
        i += 1;
    }
    groups
};

/// Default of [`SlabGrid::grazing_mu`].
pub const DEFAULT_GRAZING_MU: f64 = 0.01;

/// Orders up to this are looked up in a table; higher orders fall in the last group.
const ORDER_TABLE: usize = 256;

/// Depth planes, direction bins and order groups of one slice (t, μ_L).
#[derive(Clone, Debug)]
pub struct SlabGrid {
    /// Tally depths in mfp, increasing, from 0 (lit face) to t (far face).
    pub depths: Vec<f64>,
    /// μ_V bin edges, increasing, from −1 to 1.
    pub mu_edges: Vec<f64>,
    /// ψ_V bin edges (radians), increasing, from 0 to π.
    pub psi_edges: Vec<f64>,
    /// Order groups (first, last), consecutive from order 1.
    pub groups: Vec<(u32, u32)>,
    /// Crossings with |μ| below this weigh 2/`grazing_mu` instead of 1/|μ| (0: never; see
    /// [`SlabGrid::crossing_weight`]).
    pub grazing_mu: f64,
    group_of_order: Vec<u8>,
    psi_cos: Vec<f64>,
    /// Bins per unit of μ when the μ_V bins are equal.
    mu_uniform: Option<f64>,
    /// Cones around the transmitted beam, tallied apart (empty: none).
    pub aureole: Aureole,
}

impl SlabGrid {
    /// A grid; errors name what is wrong.
    pub fn new(
        depths: Vec<f64>,
        mu_edges: Vec<f64>,
        psi_edges: Vec<f64>,
        groups: Vec<(u32, u32)>,
    ) -> Result<Self> {
        let increasing =
            |v: &[f64]| v.windows(2).all(|w| w[0] < w[1]) && v.iter().all(|x| x.is_finite());
        if depths.len() < 2 || depths[0] != 0.0 || !increasing(&depths) {
            bail!("depth planes must increase from 0 (the lit face) to t, at least two");
        }
        if mu_edges.len() < 2
            || mu_edges[0] != -1.0
            || mu_edges[mu_edges.len() - 1] != 1.0
            || !increasing(&mu_edges)
        {
            bail!("mu_V bin edges must increase from -1 to 1");
        }
        let pi = std::f64::consts::PI;
        if psi_edges.len() < 2
            || psi_edges[0] != 0.0
            || psi_edges[psi_edges.len() - 1] != pi
            || !increasing(&psi_edges)
        {
            bail!("psi_V bin edges must increase from 0 to pi");
        }
        if groups.is_empty()
            || groups.len() > 255
            || groups[0].0 != 1
            || groups[groups.len() - 1].1 != u32::MAX
        {
            bail!("order groups must start at order 1 and end at infinity");
        }
        if groups.iter().any(|g| g.0 > g.1) || groups.windows(2).any(|w| w[1].0 != w[0].1 + 1) {
            bail!("order groups must be consecutive, each first ≤ last");
        }
        let group_of_order = (0..=ORDER_TABLE as u32)
            .map(|k| {
                groups
                    .iter()
                    .position(|g| g.0 <= k && k <= g.1)
                    .unwrap_or(0) as u8
            })
            .collect();
        let psi_cos = psi_edges.iter().map(|p| p.cos()).collect();
        let n_mu = (mu_edges.len() - 1) as f64;
        // Equal bins only if the edges are exactly where the multiplication puts them.
        let uniform = mu_edges
            .iter()
            .enumerate()
            .all(|(i, e)| *e == -1.0 + 2.0 * i as f64 / n_mu);
        let mu_uniform = uniform.then_some(0.5 * n_mu);
        Ok(Self {
            depths,
            mu_edges,
            psi_edges,
            groups,
            grazing_mu: DEFAULT_GRAZING_MU,
            group_of_order,
            psi_cos,
            mu_uniform,
            aureole: Aureole::default(),
        })
    }

    /// The default grid for thickness `t`: 16 stretched planes, 16 μ_V bins, 12 ψ_V bins,
    /// nine order groups.
    pub fn default_for(t: f64) -> Result<Self> {
        let pi = std::f64::consts::PI;
        Self::new(
            stretched_depths(t, 16),
            (0..=16).map(|i| -1.0 + 2.0 * i as f64 / 16.0).collect(),
            (0..=12).map(|i| pi * i as f64 / 12.0).collect(),
            DEFAULT_GROUPS.to_vec(),
        )
    }

    /// [`Self::default_for`] with the aureole annuli every config's grid tallies
    /// ([`super::aureole::DEFAULT_AUREOLE_DEG`], `aureole_deg`'s default): the grid a walk with
    /// all of a table's tallies runs on.
    pub fn default_with_annuli(t: f64) -> Result<Self> {
        let mut grid = Self::default_for(t)?;
        grid.aureole = Aureole::new(super::aureole::DEFAULT_AUREOLE_DEG.to_vec())?;
        Ok(grid)
    }

    /// The slab thickness (mfp).
    pub fn thickness(&self) -> f64 {
        self.depths[self.depths.len() - 1]
    }

    /// Number of cells: groups × planes × μ_V bins × ψ_V bins.
    pub fn n_cells(&self) -> usize {
        self.groups.len() * self.depths.len() * self.n_mu() * self.n_psi()
    }

    /// Number of μ_V bins.
    pub fn n_mu(&self) -> usize {
        self.mu_edges.len() - 1
    }

    /// Number of ψ_V bins.
    pub fn n_psi(&self) -> usize {
        self.psi_edges.len() - 1
    }

    /// The group of scattering order `k` ≥ 1.
    #[inline]
    pub fn group(&self, k: u32) -> usize {
        self.group_of_order[(k as usize).min(ORDER_TABLE)] as usize
    }

    /// The μ_V bin of `mu` (edges belong to the bin above; 1 to the last).
    #[inline]
    pub fn mu_bin(&self, mu: f64) -> usize {
        match self.mu_uniform {
            // Equal bins (the default): one multiplication instead of a search.
            Some(per_unit) => (((mu + 1.0) * per_unit) as usize).min(self.n_mu() - 1),
            None => bin(&self.mu_edges, mu),
        }
    }

    /// [`Self::mu_bin`] of every lane, side by side (the same bins).
    #[inline(always)]
    pub fn mu_bins(&self, mu: &Lane<f64>) -> Lane<usize> {
        let last = self.n_mu() - 1;
        match self.mu_uniform {
            // Converted side by side ([`floor_index`]). A plain loop, not `array::from_fn`:
            // LLVM compiled that apart from the walk's vector variants, in baseline scalar
            // code, and called it at every step.
            Some(per_unit) => {
                let mut m = [0; LANES];
                for l in 0..LANES {
                    m[l] = floor_index((mu[l] + 1.0) * per_unit, last);
                }
                m
            }
            None => count_edges(&self.mu_edges[1..=last], |e, l| e <= mu[l]),
        }
    }

    /// The ψ_V bin of `psi` ∈ [0, π].
    #[inline]
    pub fn psi_bin(&self, psi: f64) -> usize {
        bin(&self.psi_edges, psi)
    }

    /// For each ψ_V bin k: (Δψ_k/π, mean of sin ψ, mean of cos ψ over the bin) — what a
    /// crossing turned to an azimuth uniform in the bin contributes on average.
    pub fn psi_bin_means(&self) -> Vec<[f64; 3]> {
        self.psi_edges
            .windows(2)
            .map(|e| {
                let w = e[1] - e[0];
                [
                    w / std::f64::consts::PI,
                    (e[0].cos() - e[1].cos()) / w,
                    (e[1].sin() - e[0].sin()) / w,
                ]
            })
            .collect()
    }

    /// The weight w/|μ| of a crossing with 1/|μ| = `inv_mu`, except below |μ| = ε =
    /// `grazing_mu` where it is 2w/ε. The plain 1/|μ| weight has an infinite variance at the
    /// horizon (∫ L/|μ| dμ diverges at 0); with the cap it is finite. The crossings with |μ| < ε
    /// number ∝ ∫₀^ε L μ dμ, so 2/ε gives ∫₀^ε L dμ exactly when L is linear in μ up to a bias
    /// of L′ε²/6 — relative to a horizon bin of width Δμ, (L′/L) ε²/(6Δμ): 1.3e-4 · L′/L for
    /// ε = 0.01 and Δμ = 1/8 (the MCNP grazing-angle treatment of surface flux, with a small ε).
    #[inline]
    pub fn crossing_weight(&self, weight: f64, inv_mu: f64) -> f64 {
        if inv_mu * self.grazing_mu > 1.0 {
            weight * (2.0 / self.grazing_mu)
        } else {
            weight * inv_mu
        }
    }

    /// Whether μ_V bin `m` touches the horizon μ_V = 0, where the 1/|μ| crossing estimator has
    /// unbounded variance (its error shrinks only like √(ln N / N)).
    pub fn is_horizon(&self, m: usize) -> bool {
        self.mu_edges[m] <= 0.0 && self.mu_edges[m + 1] >= 0.0
    }

    /// Solid angle (sr) of direction bin (m, k), both mirror halves.
    pub fn solid_angle(&self, m: usize, k: usize) -> f64 {
        2.0 * (self.mu_edges[m + 1] - self.mu_edges[m])
            * (self.psi_edges[k + 1] - self.psi_edges[k])
    }

    /// Number of aureole cells: groups × planes × annuli.
    pub fn n_aureole_cells(&self) -> usize {
        self.groups.len() * self.depths.len() * self.aureole.n_bins()
    }

    /// Flat index of aureole cell (group, plane, annulus).
    #[inline]
    pub fn aureole_cell(&self, group: usize, plane: usize, b: usize) -> usize {
        (group * self.depths.len() + plane) * self.aureole.n_bins() + b
    }

    /// Flat index of cell (group, plane, μ bin, ψ bin). Planes are the fastest index: the
    /// crossings of one flight share (group, μ, ψ) and land on neighbouring cells.
    #[inline]
    pub fn cell(&self, group: usize, plane: usize, m: usize, k: usize) -> usize {
        ((group * self.n_mu() + m) * self.n_psi() + k) * self.depths.len() + plane
    }

    /// (group, plane, μ bin, ψ bin) of a flat cell index.
    pub fn cell_parts(&self, cell: usize) -> (usize, usize, usize, usize) {
        let planes = self.depths.len();
        let (rest, plane) = (cell / planes, cell % planes);
        let (rest, k) = (rest / self.n_psi(), rest % self.n_psi());
        (rest / self.n_mu(), plane, rest % self.n_mu(), k)
    }

    /// The ψ_V bin of the horizontal direction (x, z) ≠ 0, without an arctangent: cos ψ_V =
    /// z/√(x² + z²) decreases with ψ_V, so the bin is found among the edges' cosines.
    #[inline]
    pub fn psi_bin_of(&self, x: f64, z: f64) -> usize {
        let r = (x * x + z * z).sqrt();
        if r == 0.0 {
            return 0;
        }
        // Bin k holds cos ψ = z/r ∈ (cos ψ_{k+1}, cos ψ_k]; edges inside (0, π) only; compared
        // as z against r cos ψ_k, without a division. The edges' cosines decrease, so the bin is
        // the count of those at or above z/r: counted without a branch (a binary search's
        // branches go either way at random, a mispredicted jump each).
        let inner = &self.psi_cos[1..self.psi_cos.len() - 1];
        inner.iter().map(|e| (*e * r >= z) as usize).sum()
    }

    /// [`Self::psi_bin_of`] of every lane's (x, z), side by side (the same bins; 0 where
    /// x² + z² = 0).
    #[inline(always)]
    pub fn psi_bins_of(&self, x: &Lane<f64>, z: &Lane<f64>) -> Lane<usize> {
        let r: Lane<f64> = std::array::from_fn(|l| (x[l] * x[l] + z[l] * z[l]).sqrt());
        let inner = &self.psi_cos[1..self.psi_cos.len() - 1];
        let n = count_edges(inner, |e, l| e * r[l] >= z[l]);
        std::array::from_fn(|l| if r[l] == 0.0 { 0 } else { n[l] })
    }
}

/// The bin of `x` among increasing `edges` (edges belong to the bin above), counted without a
/// branch as in [`SlabGrid::psi_bin_of`].
fn bin(edges: &[f64], x: f64) -> usize {
    edges[1..edges.len() - 1]
        .iter()
        .map(|e| (*e <= x) as usize)
        .sum()
}

/// `n` ≥ 2 planes from 0 to t, stretched toward the lit face (module docs).
pub fn stretched_depths(t: f64, n: usize) -> Vec<f64> {
    (0..n)
        .map(|j| match j {
            0 => 0.0,
            _ if j == n - 1 => t,
            _ => stretched_depth(t, j as f64 / (n - 1) as f64),
        })
        .collect()
}

/// The depth (mfp) at stretched depth u ∈ [0, 1] of a slab of thickness t:
/// t (e^{βu} − 1)/(e^β − 1), β = 0.3 t^0.65 (module docs): the runtime's law
/// ([`nephele_runtime::fitting::STRETCH_SCALE`]; its inverse is the runtime's `stretched_u`).
pub fn stretched_depth(t: f64, u: f64) -> f64 {
    let beta = STRETCH_SCALE * t.powf(STRETCH_EXPONENT);
    t * (beta * u).exp_m1() / beta.exp_m1()
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::slab::lanes::LANES;

    /// Each of `values` against `one` of it, bit for bit, through `lanes` of sets of lanes.
    fn lanes_match<T: Copy + std::fmt::Debug>(
        values: &[T],
        fill: T,
        lanes: impl Fn(&[T; LANES]) -> [usize; LANES],
        one: impl Fn(T) -> usize,
    ) {
        for chunk in values.chunks(LANES) {
            let mut v = [fill; LANES];
            v[..chunk.len()].copy_from_slice(chunk);
            let got = lanes(&v);
            for l in 0..LANES {
                assert_eq!(got[l], one(v[l]), "{:?}", v[l]);
            }
        }
    }

    /// The lanes' μ_V bins (equal and unequal edges) and ψ_V bins are each direction's own:
    /// at every edge ±1 ulp, ±1, ±0, the axes, (0, 0), vanishing r and sweeps.
    #[test]
    fn lane_bins_are_each_directions_own() {
        let equal = SlabGrid::default_for(8.0).unwrap();
        let unequal = SlabGrid::new(
            equal.depths.clone(),
            vec![-1.0, -0.6, -0.1, 0.0, 0.05, 0.3, 0.9, 1.0],
            vec![0.0, 0.2, 1.0, 1.6, 3.0, std::f64::consts::PI],
            DEFAULT_GROUPS.to_vec(),
        )
        .unwrap();
        for g in [&equal, &unequal] {
            let mut mu = vec![
                -1.0,
                1.0,
                0.0,
                -0.0,
                1.0f64.next_down(),
                (-1.0f64).next_up(),
            ];
            for &e in &g.mu_edges {
                mu.extend([e, e.next_up(), e.next_down()]);
            }
            mu.extend((0..3001).map(|i| -1.0 + 2.0 * i as f64 / 3000.0));
            lanes_match(&mu, 0.0, |v| g.mu_bins(v), |m| g.mu_bin(m));
            let mut xz = vec![(0.0, 0.0), (0.0, 1.0), (0.0, -1.0), (1.0, 0.0), (-1.0, 0.0)];
            xz.extend([
                (1e-300, 0.0),
                (0.0, 1e-300),
                (-1e-200, 1e-200),
                (5e-324, -5e-324),
            ]);
            for &c in &g.psi_cos {
                let s = (1.0 - c * c).max(0.0).sqrt();
                for (x, z) in [(s, c), (-s, c), (s, c.next_up()), (s, c.next_down())] {
                    xz.extend([(x, z), (x * 1e-3, z * 1e-3)]);
                }
            }
            xz.extend((0..2000).map(|i| (i as f64 * 0.0031).sin_cos()));
            let lanes = |v: &[(f64, f64); LANES]| g.psi_bins_of(&v.map(|p| p.0), &v.map(|p| p.1));
            lanes_match(&xz, (0.0, 1.0), lanes, |(x, z)| g.psi_bin_of(x, z));
        }
    }

    #[test]
    fn bins_groups_and_planes() {
        let g = SlabGrid::default_for(64.0).unwrap();
        assert_eq!(
            (
                g.mu_bin(-1.0),
                g.mu_bin(-0.875),
                g.mu_bin(0.99),
                g.mu_bin(1.0)
            ),
            (0, 1, 15, 15)
        );
        for i in 0..=2000 {
            let mu = -1.0 + i as f64 / 1000.0;
            assert_eq!(g.mu_bin(mu), bin(&g.mu_edges, mu), "μ = {mu}");
        }
        assert_eq!((g.psi_bin(0.0), g.psi_bin(std::f64::consts::PI)), (0, 11));
        // 1.5707 and 3.14159 are test angles just short of π/2 and π, not those constants.
        #[allow(clippy::approx_constant)]
        for psi in [0.0f64, 0.1, 0.3, 1.0, 1.5707, 2.0, 3.0, 3.14159] {
            assert_eq!(
                g.psi_bin_of(psi.sin(), psi.cos()),
                g.psi_bin(psi),
                "ψ = {psi}"
            );
            assert_eq!(
                g.psi_bin_of(-psi.sin(), psi.cos()),
                g.psi_bin(psi),
                "ψ = −{psi}"
            );
        }
        for (k, [share, s, c]) in g.psi_bin_means().into_iter().enumerate() {
            // Against the midpoint rule on 1000 points.
            let (lo, hi) = (g.psi_edges[k], g.psi_edges[k + 1]);
            let psi = |i: usize| lo + (i as f64 + 0.5) / 1000.0 * (hi - lo);
            let ms: f64 = (0..1000).map(|i| psi(i).sin()).sum::<f64>() / 1000.0;
            let mc: f64 = (0..1000).map(|i| psi(i).cos()).sum::<f64>() / 1000.0;
            assert!((s - ms).abs() < 1e-6 && (c - mc).abs() < 1e-6, "bin {k}");
            assert!((share - 1.0 / 12.0).abs() < 1e-14);
        }
        // Crossing weights: 1/|μ| down to |μ| = ε = 0.01, 2/ε below.
        assert_eq!(g.crossing_weight(0.5, 1.0 / 0.02), 0.5 / 0.02);
        assert_eq!(g.crossing_weight(0.5, 1.0 / 0.005), 0.5 * 200.0);
        let mut plain = g.clone();
        plain.grazing_mu = 0.0;
        assert_eq!(plain.crossing_weight(1.0, 1e6), 1e6);
        let c = g.cell(3, 7, 11, 5);
        assert_eq!(g.cell_parts(c), (3, 7, 11, 5));
        let groups: Vec<usize> = [1, 2, 3, 4, 5, 8, 9, 12, 13, 30, 31, 1000]
            .iter()
            .map(|&k| g.group(k))
            .collect();
        assert_eq!(groups, [0, 1, 2, 2, 3, 4, 5, 5, 6, 7, 8, 8]);
        assert_eq!(
            DEFAULT_GROUPS,
            [
                (1, 1),
                (2, 2),
                (3, 4),
                (5, 6),
                (7, 8),
                (9, 12),
                (13, 18),
                (19, 30),
                (31, u32::MAX)
            ]
        );
        // Stretched: at t = 64 half the planes lie within the first ~10 mfp.
        assert_eq!(g.depths[0], 0.0);
        assert_eq!(g.depths[15], 64.0);
        assert!(g.depths[7] < 10.0, "{:?}", g.depths);
        let total: f64 = (0..16)
            .flat_map(|m| (0..12).map(move |k| (m, k)))
            .map(|(m, k)| g.solid_angle(m, k))
            .sum();
        assert!((total - 4.0 * std::f64::consts::PI).abs() < 1e-12);
        assert!(SlabGrid::new(
            vec![0.0, 1.0],
            vec![-1.0, 1.0],
            vec![0.0, 3.0],
            DEFAULT_GROUPS.to_vec()
        )
        .is_err());
    }
}
