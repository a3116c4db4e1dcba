//! The log-additive form of spec 50 (the prototype's best, "the one to beat"), per order group
//! and slab thickness t:
//!
//!   ln T = ln B + Σ_j [a_j(μ_V) + b_j(μ_L)] P_j(2u − 1) + γ(μ_V) ln F₁
//!          + Σ_i h_i(Θ) [P0_i + P1_i (2u − 1)] + Σ_k [p_k(μ_V) + q_k(μ_L)] (s_V s_L)^k cos kψ_V,
//!
//! u the stretched depth (plane index / (planes − 1)), B the boundary factor (the share of the
//! optical path behind the viewpoint: 1 − e^{−(t−d)/μ_V} looking down at light going up,
//! 1 − e^{−d/|μ_V|} for light going down), F₁ the single-scattering depth factor (T₁ without its
//! phase function, [`nephele_runtime::transport::single_scattering`] with p = 1), h_i the hat
//! functions of nodes Θ_i = π (i/(n − 1))² (dense at the forward peak), s = sin of the polar
//! angles. Linear in its parameters: fitted by weighted least squares. With `pairs`, γ becomes
//! γ(μ_V, μ_L) and an offset and a depth slope per (μ_V, μ_L) pair are added.

use nephele_runtime::phase::HenyeyGreenstein;
use nephele_runtime::transport::{scattering_cosine, single_scattering};
use serde::{Deserialize, Serialize};
use std::f64::consts::PI;

/// Floor of ln F₁ as a feature (see [`LogAdditive::features`]).
pub const LN_F1_FLOOR: f64 = -10.0;

/// The form's sizes.
#[derive(Clone, Copy, Debug, Serialize, Deserialize)]
pub struct LogAdditive {
    /// Legendre terms in depth, J.
    pub legendre: usize,
    /// Azimuth harmonics, K.
    pub harmonics: usize,
    /// Θ nodes.
    pub theta_nodes: usize,
    /// Per-(μ_V, μ_L) γ, offset and slope.
    pub pairs: bool,
}

impl Default for LogAdditive {
    fn default() -> Self {
        Self {
            legendre: 6,
            harmonics: 3,
            theta_nodes: 24,
            pairs: false,
        }
    }
}

/// A position between two nodes of a parameter grid: weight 1 − w on `lo`, w on `hi`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Lerp {
    /// Lower node.
    pub lo: usize,
    /// Upper node.
    pub hi: usize,
    /// Weight of the upper node, in [0, 1].
    pub w: f64,
}

impl Lerp {
    /// Exactly on node `i`.
    pub fn at(i: usize) -> Self {
        Self {
            lo: i,
            hi: i,
            w: 0.0,
        }
    }

    /// `x` between the increasing `nodes` (held at the end nodes outside them).
    pub fn between(nodes: &[f64], x: f64) -> Self {
        let n = nodes.len();
        if n == 1 || x <= nodes[0] {
            return Self::at(0);
        }
        if x >= nodes[n - 1] {
            return Self::at(n - 1);
        }
        let hi = nodes.partition_point(|&v| v <= x).min(n - 1);
        let lo = hi - 1;
        Self {
            lo,
            hi,
            w: (x - nodes[lo]) / (nodes[hi] - nodes[lo]),
        }
    }

    /// (node, weight) pairs (one when on a node).
    fn parts(&self) -> impl Iterator<Item = (usize, f64)> + Clone {
        let two = self.w > 0.0 && self.hi != self.lo;
        [
            (self.lo, 1.0 - if two { self.w } else { 0.0 }),
            (self.hi, self.w),
        ]
        .into_iter()
        .take(if two { 2 } else { 1 })
    }
}

/// A cell as the form sees it: the sun and view between the nodes of the parameter grids.
#[derive(Clone, Copy, Debug)]
pub struct Cell {
    /// Where μ_L sits among the sun cosines of the tables.
    pub l: Lerp,
    /// Sun cosine.
    pub mu_l: f64,
    /// Where μ_V sits among the μ_V bin centres.
    pub v: Lerp,
    /// View cosine (bin centre).
    pub mu_v: f64,
    /// View azimuth (bin centre, radians).
    pub psi_v: f64,
    /// Stretched depth in [0, 1].
    pub u: f64,
    /// Depth (mfp).
    pub d: f64,
    /// Thickness (mfp).
    pub t: f64,
}

impl LogAdditive {
    /// Parameters per (group, t) for `nm` μ_V bins and `nl` sun cosines.
    pub fn n_params(&self, nm: usize, nl: usize) -> usize {
        let j = self.legendre * (nm + nl);
        let gamma = if self.pairs { nm * nl } else { nm };
        let pairs = if self.pairs { 2 * nm * nl } else { 0 };
        j + gamma + pairs + 2 * self.theta_nodes + self.harmonics * (nm + nl)
    }

    /// ln B of `c`, or None where the form says T = 0 (no medium behind the viewpoint).
    pub fn offset(&self, c: &Cell) -> Option<f64> {
        let path = if c.mu_v > 0.0 { c.t - c.d } else { c.d };
        let b = -(-path / c.mu_v.abs()).exp_m1();
        (b > 0.0).then(|| b.ln())
    }

    /// The features of `c` as (column, value) pairs, into `out` (cleared first); false where the
    /// cell cannot be represented (F₁ = 0).
    pub fn features(&self, c: &Cell, nm: usize, nl: usize, out: &mut Vec<(usize, f64)>) -> bool {
        out.clear();
        let f1 = 4.0
            * PI
            * single_scattering(
                &HenyeyGreenstein::new(0.0),
                1.0,
                c.mu_l,
                c.t,
                c.d,
                c.mu_v,
                c.psi_v,
            );
        if f1.is_nan() || f1 <= 0.0 {
            return false;
        }
        // Deep in a thick slab F₁ falls like e^{−d/μ_L} (e^{−500} at t = 128, μ_L = 1/4) while
        // the multiply scattered T does not: held at LN_F1_FLOOR, ln F₁ cannot lever the fit
        // there (nor blow up between thicknesses).
        let ln_f1 = f1.ln().max(LN_F1_FLOOR);
        let x = 2.0 * c.u - 1.0;
        let mut col = 0;
        let (v, l) = (c.v.parts(), c.l.parts());
        let both = |out: &mut Vec<(usize, f64)>, col: usize, val: f64| {
            out.extend(v.clone().map(|(m, w)| (col + m, w * val)));
            out.extend(l.clone().map(|(il, w)| (col + nm + il, w * val)));
        };
        for p in legendre(x, self.legendre) {
            both(out, col, p);
            col += nm + nl;
        }
        let pairs: Vec<(usize, f64)> =
            c.v.parts()
                .flat_map(|(m, wm)| c.l.parts().map(move |(il, wl)| (m * nl + il, wm * wl)))
                .collect();
        if self.pairs {
            out.extend(pairs.iter().map(|&(p, w)| (col + p, w * ln_f1)));
            col += nm * nl;
            out.extend(pairs.iter().map(|&(p, w)| (col + 2 * p, w)));
            out.extend(pairs.iter().map(|&(p, w)| (col + 2 * p + 1, w * x)));
            col += 2 * nm * nl;
        } else {
            out.extend(v.clone().map(|(m, w)| (col + m, w * ln_f1)));
            col += nm;
        }
        let theta = scattering_angle(c);
        for (i, h) in self.theta_hats(theta) {
            out.push((col + 2 * i, h));
            out.push((col + 2 * i + 1, h * x));
        }
        col += 2 * self.theta_nodes;
        let s = ((1.0 - c.mu_v * c.mu_v) * (1.0 - c.mu_l * c.mu_l))
            .max(0.0)
            .sqrt();
        for k in 1..=self.harmonics {
            both(out, col, s.powi(k as i32) * (k as f64 * c.psi_v).cos());
            col += nm + nl;
        }
        true
    }

    /// The (at most two) hat functions that are not zero at `theta`.
    fn theta_hats(&self, theta: f64) -> Vec<(usize, f64)> {
        let n = self.theta_nodes;
        let node = |i: usize| PI * (i as f64 / (n - 1) as f64).powi(2);
        let i = (1..n).find(|&i| node(i) >= theta).unwrap_or(n - 1);
        let (a, b) = (node(i - 1), node(i));
        let w = ((theta - a) / (b - a)).clamp(0.0, 1.0);
        vec![(i - 1, 1.0 - w), (i, w)]
    }
}

/// P_0(x) … P_{n−1}(x) by the three-term recurrence.
fn legendre(x: f64, n: usize) -> Vec<f64> {
    let mut p = Vec::with_capacity(n);
    for j in 0..n {
        p.push(match j {
            0 => 1.0,
            1 => x,
            _ => ((2 * j - 1) as f64 * x * p[j - 1] - (j - 1) as f64 * p[j - 2]) / j as f64,
        });
    }
    p
}

/// The scattering angle Θ (radians) between the sun and the view of `c`.
fn scattering_angle(c: &Cell) -> f64 {
    let cos = scattering_cosine(c.mu_l, c.mu_v, c.psi_v);
    2.0 * (0.5 * cos.one_minus_mu).sqrt().min(1.0).asin()
}
