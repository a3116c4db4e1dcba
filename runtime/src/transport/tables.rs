//! The compressed transport tables as renderers use them: loaded in place from the bytes of a
//! `.ntt` container ([`crate::container`], docs/format.md), checked once, then evaluated at any
//! (d, t, μ_V, ψ_V, μ_L) without allocation: T per order group of orders ≥ 2 from the
//! log-additive form ([`super::log_additive`]) with its parameters read between the grid's
//! nodes, and order 1 in closed form ([`super::single`]) from the stored phase function.
//!
//! Arrays (all f32):
//!
//! | name | shape | content |
//! |---|---|---|
//! | `form` | [5] or [6] | J, K, Θ nodes, pairs (0/1), Q, and the interaction's A (0 if absent) |
//! | `group_first` | [G] | first order of each group |
//! | `mu_l_nodes` | [L] | sun cosines of the μ_L parameters |
//! | `mu_v_nodes` | [M] | view cosines of the μ_V parameters |
//! | `thickness` | [N] | thicknesses of the depth ranges |
//! | `ln_t_range` | [G, 2] | ln t span of each group's polynomials in ln t |
//! | `beta` | [G, P, Q] | the parameters' Legendre coefficients in s(ln t) |
//! | `u_range` | [G, N, L·M] | per thickness and (μ_L, μ_V) pair, the stretched depths fitted: [`U_STEPS`]-step integers lo · 4096 + hi (u = step/4095, widened outward; lo > hi: none) |
//! | `phase_theta` | [n] | phase function angles (degrees, increasing, 0 … 180) |
//! | `phase` | [n] | phase function p(θ) (sr⁻¹) |
//! | `collector_form` | [4] | optional: the collector form's J, K, Θ nodes, Q |
//! | `sigma_beta`, `cz_beta`, `cx_beta` | [G, P_s, Q] | with it: ln σ, c_z/σ̂, c_x/σ̂ ([`super::collector`]) |
//!
//! Files without the collector arrays load too; their [`Transport`] has c = 0, σ = 0.

use super::collector::{CollectorForm, Statistic};
use super::log_additive::{
    legendre, ln_boundary, Cell, Lerp, LogAdditive, MAX_CROSS, MAX_LEGENDRE,
};
use super::single::{single_scattering, PhaseValue};
use crate::container::{ArrayView, Container, FormatError};
use crate::phase::Cosine;
use crate::real::Real;

/// Most Legendre terms in ln t.
pub const MAX_Q: usize = MAX_LEGENDRE;
/// Most order groups.
pub const MAX_GROUPS: usize = 64;
/// Most azimuth harmonics of a loadable form (bounds the features of a point).
pub const MAX_HARMONICS: usize = 8;
/// Room for the features of one point: J ≤ 16 Legendre terms on two μ_V and two μ_L nodes,
/// γ and the pair terms on four (μ_V, μ_L) pairs, two Θ hats, K ≤ 8 harmonics, γ_L on two
/// μ_L nodes and 3 A² interaction products.
const MAX_FEATURES: usize = 16 * 4 + 4 * 3 + 4 + MAX_HARMONICS * 4 + 2 + 3 * MAX_CROSS * MAX_CROSS;

/// Most Legendre terms in depth and azimuth harmonics of a loadable collector form.
const MAX_COLLECTOR_LEGENDRE: usize = 8;
const MAX_COLLECTOR_HARMONICS: usize = 4;
/// Room for the features of a collector statistic at one point: at most two Θ blocks (4 values
/// each) and K + 2 depth blocks of J values on two μ_V and two μ_L nodes.
const MAX_C_FEATURES: usize = 8 + (MAX_COLLECTOR_HARMONICS + 2) * MAX_COLLECTOR_LEGENDRE * 4;

/// Transport of one order group at a point: T = L/E⊥ (sr⁻¹), the collector c = (c_x, c_z) and
/// its spread σ (mfp; spec 40).
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct Transport {
    /// T (sr⁻¹).
    pub t: f32,
    /// c_x (mfp), across the sun's horizontal travel.
    pub c_x: f32,
    /// c_z (mfp), along it.
    pub c_z: f32,
    /// σ (mfp).
    pub sigma: f32,
}

/// The collector part of the tables.
#[derive(Clone, Copy, Debug)]
struct CollectorPart<'a> {
    form: CollectorForm,
    q: usize,
    beta: [ArrayView<'a>; 3],
}

/// Validated compressed tables, borrowing the container's bytes.
#[derive(Clone, Copy, Debug)]
pub struct TransportTables<'a> {
    collector: Option<CollectorPart<'a>>,
    form: LogAdditive,
    q: usize,
    group_first: ArrayView<'a>,
    mu_l: ArrayView<'a>,
    mu_v: ArrayView<'a>,
    thickness: ArrayView<'a>,
    ln_t_range: ArrayView<'a>,
    beta: ArrayView<'a>,
    u_range: ArrayView<'a>,
    phase_theta: ArrayView<'a>,
    phase: ArrayView<'a>,
}

fn need<'a>(
    c: &Container<'a>,
    name: &'static str,
    len: usize,
) -> Result<ArrayView<'a>, FormatError> {
    let a = c.find(name).ok_or(FormatError::Missing(name))?;
    if a.len() != len || a.iter().any(|v| !v.is_finite()) {
        return Err(FormatError::BadArray(name));
    }
    Ok(a)
}

fn increasing(a: &ArrayView) -> bool {
    a.iter().zip(a.iter().skip(1)).all(|(x, y)| x < y)
}

impl<'a> TransportTables<'a> {
    /// Loads and checks every array (shapes, finiteness, increasing grids).
    pub fn from_bytes(bytes: &'a [u8]) -> Result<Self, FormatError> {
        let c = Container::from_bytes(bytes)?;
        let form_a = c.find("form").ok_or(FormatError::Missing("form"))?;
        let int = |i: usize| {
            form_a
                .get(i)
                .map(|v| v as usize)
                .ok_or(FormatError::BadArray("form"))
        };
        if !(5..=6).contains(&form_a.len())
            || form_a
                .iter()
                .any(|v| !(v >= 0.0 && v <= 4096.0 && v == (v as u32) as f32))
        {
            return Err(FormatError::BadArray("form"));
        }
        let form = LogAdditive {
            legendre: int(0)?,
            harmonics: int(1)?,
            theta_nodes: int(2)?,
            pairs: int(3)? == 1,
            cross: if form_a.len() == 6 { int(5)? } else { 0 },
        };
        let q = int(4)?;
        if !(1..=MAX_LEGENDRE).contains(&form.legendre)
            || form.theta_nodes < 2
            || form.harmonics > MAX_HARMONICS
            || form.cross > MAX_CROSS
            || !(1..=MAX_Q).contains(&q)
        {
            return Err(FormatError::BadArray("form"));
        }
        let count = |name: &'static str| {
            c.find(name)
                .map(|a| a.len())
                .ok_or(FormatError::Missing(name))
        };
        let (g, l, m, n) = (
            count("group_first")?,
            count("mu_l_nodes")?,
            count("mu_v_nodes")?,
            count("thickness")?,
        );
        if g == 0
            || l == 0
            || m == 0
            || n == 0
            || g > MAX_GROUPS
            || l > 1024
            || m > 1024
            || n > 1024
        {
            return Err(FormatError::BadArray("group_first"));
        }
        let p = form.n_params(m, l);
        let theta_len = count("phase_theta")?;
        let t = TransportTables {
            collector: collector_part(&c, g, m, l)?,
            form,
            q,
            group_first: need(&c, "group_first", g)?,
            mu_l: need(&c, "mu_l_nodes", l)?,
            mu_v: need(&c, "mu_v_nodes", m)?,
            thickness: need(&c, "thickness", n)?,
            ln_t_range: need(&c, "ln_t_range", 2 * g)?,
            beta: need(
                &c,
                "beta",
                g.checked_mul(p)
                    .and_then(|x| x.checked_mul(q))
                    .ok_or(FormatError::BadArray("beta"))?,
            )?,
            u_range: need(&c, "u_range", g * n * l * m)?,
            phase_theta: need(&c, "phase_theta", theta_len)?,
            phase: need(&c, "phase", theta_len)?,
        };
        for (a, name) in [
            (&t.mu_l, "mu_l_nodes"),
            (&t.mu_v, "mu_v_nodes"),
            (&t.thickness, "thickness"),
            (&t.phase_theta, "phase_theta"),
        ] {
            if !increasing(a) {
                return Err(FormatError::BadArray(name));
            }
        }
        let packed_max = (U_STEPS * U_STEPS - 1) as f32;
        if t.u_range
            .iter()
            .any(|v| !(v >= 0.0 && v <= packed_max && v == (v as u32) as f32))
        {
            return Err(FormatError::BadArray("u_range"));
        }
        if theta_len < 2 || t.phase.iter().any(|v| v < 0.0) {
            return Err(FormatError::BadArray("phase"));
        }
        Ok(t)
    }

    /// Number of order groups (of orders ≥ 2).
    pub fn groups(&self) -> usize {
        self.group_first.len()
    }

    /// First scattering order of group `g`.
    pub fn group_first_order(&self, g: usize) -> Option<f32> {
        self.group_first.get(g)
    }

    /// T = L/E⊥ (sr⁻¹) of group `g` at depth `d` of a slab of thickness `t` (mfp), view
    /// (`mu_v`, `psi_v` radians), sun `mu_l`; 0 where the tables resolve nothing. For several
    /// groups at one point, [`Self::transport_all`] shares the work.
    pub fn transport(&self, g: usize, d: f32, t: f32, mu_v: f32, psi_v: f32, mu_l: f32) -> f32 {
        let mut all = [0.0f32; MAX_GROUPS];
        self.transport_all(d, t, mu_v, psi_v, mu_l, &mut all);
        all.get(g).copied().unwrap_or(0.0)
    }

    /// T of every group at one point into `out[..groups()]` (the rest untouched): the features
    /// (geometry, single-scattering factor, scattering angle) are computed once, then each
    /// group is a dot product with its parameters at t.
    pub fn transport_all(&self, d: f32, t: f32, mu_v: f32, psi_v: f32, mu_l: f32, out: &mut [f32]) {
        let groups = self.groups().min(out.len());
        out[..groups].iter_mut().for_each(|v| *v = 0.0);
        if let Some(pt) = self.point(d, t, mu_v, psi_v, mu_l) {
            for (g, slot) in out[..groups].iter_mut().enumerate() {
                *slot = self.t_of(&pt, g);
            }
        }
    }

    /// T, c and σ of every group at one point into `out[..groups()]` (the rest untouched); c
    /// and σ are 0 where T is, or when the file holds no collector.
    pub fn evaluate_all(
        &self,
        d: f32,
        t: f32,
        mu_v: f32,
        psi_v: f32,
        mu_l: f32,
        out: &mut [Transport],
    ) {
        let groups = self.groups().min(out.len());
        out[..groups]
            .iter_mut()
            .for_each(|v| *v = Transport::default());
        let Some(pt) = self.point(d, t, mu_v, psi_v, mu_l) else {
            return;
        };
        let (nl, nm) = (self.mu_l.len(), self.mu_v.len());
        // The features are the same for every group: c_z's ℓ/σ̂ terms are computed with σ̂ = 1
        // and divided by the group's σ̂ after the dot product.
        let mut rows = [[(0u32, 0.0f32); MAX_C_FEATURES]; 3];
        let mut lens = [0usize; 3];
        if let Some(cp) = &self.collector {
            for ((stat, row), n) in Statistic::ALL.iter().zip(&mut rows).zip(&mut lens) {
                cp.form
                    .for_each_feature(*stat, &pt.cell, 1.0, nm, nl, |col, v| {
                        if *n < MAX_C_FEATURES {
                            row[*n] = (col as u32, v);
                            *n += 1;
                        }
                    });
            }
        }
        // The ℓ/σ̂ terms are c_z's last blocks: a suffix of its row.
        let split = self.collector.map_or(0, |cp| {
            let reach = cp.form.cz_reach_start(nm, nl) as u32;
            rows[1][..lens[1]].partition_point(|&(col, _)| col < reach)
        });
        for (g, slot) in out[..groups].iter_mut().enumerate() {
            slot.t = self.t_of(&pt, g);
            let Some(cp) = &self.collector else { continue };
            if !(slot.t > 0.0) {
                continue;
            }
            let lq = legendre_in(&self.ln_t_range, g, pt.ln_t, cp.q);
            let dot = |s: usize, row: &[(u32, f32)]| {
                let first = g * cp.form.n_params(Statistic::ALL[s], nm, nl);
                dot_at_t(&cp.beta[s], first, cp.q, &lq, row)
            };
            let sigma = Real::exp(dot(0, &rows[0][..lens[0]]));
            let (near, reach) = rows[1][..lens[1]].split_at(split);
            let cz = dot(1, near) + dot(1, reach) / sigma;
            slot.sigma = sigma;
            slot.c_z = sigma * cz;
            slot.c_x = sigma * dot(2, &rows[2][..lens[2]]);
        }
    }

    /// Whether the tables hold the collector (c, σ).
    pub fn has_collector(&self) -> bool {
        self.collector.is_some()
    }

    /// The features of T at a point, or None where every group is 0.
    fn point(&self, d: f32, t: f32, mu_v: f32, psi_v: f32, mu_l: f32) -> Option<Point> {
        if !(t > 0.0) || !(d >= 0.0 && d <= t) {
            return None;
        }
        let (nl, nm) = (self.mu_l.len(), self.mu_v.len());
        let cell = Cell {
            l: lerp(&self.mu_l, mu_l),
            mu_l,
            v: lerp(&self.mu_v, mu_v),
            mu_v,
            psi_v,
            u: stretched_u(d, t),
            d,
            t,
        };
        let offset = ln_boundary(&cell)?;
        let mut row = [(0u32, 0.0f32); MAX_FEATURES];
        let mut n = 0;
        let ok = self.form.for_each_feature(&cell, nm, nl, |col, v| {
            if n < MAX_FEATURES {
                row[n] = (col as u32, v);
                n += 1;
            }
        });
        ok.then(|| Point {
            cell,
            offset,
            row,
            n,
            near_t: lerp(&self.thickness, t),
            ln_t: Real::ln(t),
        })
    }

    /// T of group `g` at `pt`.
    fn t_of(&self, pt: &Point, g: usize) -> f32 {
        if !self.inside_fitted_depths(g, pt.near_t, &pt.cell) {
            return 0.0;
        }
        let (nl, nm) = (self.mu_l.len(), self.mu_v.len());
        let lq = legendre_in(&self.ln_t_range, g, pt.ln_t, self.q);
        let p = self.form.n_params(nm, nl);
        Real::exp(pt.offset + dot_at_t(&self.beta, g * p, self.q, &lq, &pt.row[..pt.n]))
    }

    /// Order 1 (single scattering of the sun beam, sr⁻¹) at the same point, albedo 1.
    pub fn order1(&self, d: f32, t: f32, mu_v: f32, psi_v: f32, mu_l: f32) -> f32 {
        single_scattering(&StoredPhase(self), 1.0, mu_l, t, d, mu_v, psi_v)
    }

    /// Whether u lies within the fitted depths of the thickness nodes `k` around t and of the
    /// (μ_L, μ_V) nodes the cell draws on.
    fn inside_fitted_depths(&self, g: usize, k: Lerp<f32>, c: &Cell<f32>) -> bool {
        let n = self.thickness.len();
        let (nl, nm) = (self.mu_l.len(), self.mu_v.len());
        [k.lo, k.hi].iter().all(|&it| {
            [c.l.lo, c.l.hi].iter().all(|&il| {
                [c.v.lo, c.v.hi].iter().all(|&m| {
                    let at = ((g * n + it) * nl + il) * nm + m;
                    match self.u_range.get(at) {
                        Some(v) => {
                            let (lo, hi) = unpack_u_range(v);
                            c.u >= lo - 1e-6 && c.u <= hi + 1e-6
                        }
                        None => false,
                    }
                })
            })
        })
    }

    /// p(θ) by linear interpolation of the stored table.
    fn phase_at(&self, theta_deg: f32) -> f32 {
        let n = self.phase_theta.len();
        let mut lo = 0;
        let mut hi = n - 1;
        while hi - lo > 1 {
            let mid = (lo + hi) / 2;
            if self.phase_theta.get(mid).unwrap_or(0.0) <= theta_deg {
                lo = mid
            } else {
                hi = mid
            }
        }
        let (a, b) = (
            self.phase_theta.get(lo).unwrap_or(0.0),
            self.phase_theta.get(hi).unwrap_or(180.0),
        );
        let (pa, pb) = (
            self.phase.get(lo).unwrap_or(0.0),
            self.phase.get(hi).unwrap_or(0.0),
        );
        let w = if b > a {
            ((theta_deg - a) / (b - a)).clamp(0.0, 1.0)
        } else {
            0.0
        };
        pa + w * (pb - pa)
    }
}

/// The features of T at one point.
struct Point {
    cell: Cell<f32>,
    offset: f32,
    row: [(u32, f32); MAX_FEATURES],
    n: usize,
    near_t: Lerp<f32>,
    ln_t: f32,
}

/// Σ_features v · Σ_k β[(first + col) · q + k] L_k: a dot product with the parameters at t.
fn dot_at_t(
    beta: &ArrayView,
    first: usize,
    q: usize,
    lq: &[f32; MAX_Q],
    row: &[(u32, f32)],
) -> f32 {
    let mut sum = 0.0;
    for &(col, v) in row {
        sum += v * coef_at_t(beta, first + col as usize, q, lq);
    }
    sum
}

/// Parameter `p` of a [G·P, Q] array at t: Σ_k β[p · q + k] L_k.
#[inline(always)]
fn coef_at_t(beta: &ArrayView, p: usize, q: usize, lq: &[f32; MAX_Q]) -> f32 {
    let Some(run) = beta.bytes().get(4 * p * q..4 * (p + 1) * q) else {
        return 0.0;
    };
    let mut coef = 0.0;
    for (b, l) in run.chunks_exact(4).zip(lq) {
        coef += f32::from_le_bytes([b[0], b[1], b[2], b[3]]) * l;
    }
    coef
}

/// L_0 … L_{q−1} of s ∈ [−1, 1], s the place of ln t in group g's span (`ranges`, [G, 2]).
fn legendre_in(ranges: &ArrayView, g: usize, ln_t: f32, q: usize) -> [f32; MAX_Q] {
    let (a, b) = (
        ranges.get(2 * g).unwrap_or(0.0),
        ranges.get(2 * g + 1).unwrap_or(0.0),
    );
    let s = if b > a {
        (2.0 * (ln_t - a) / (b - a) - 1.0).clamp(-1.0, 1.0)
    } else {
        0.0
    };
    legendre(s, q.min(MAX_Q))
}

/// The optional collector arrays, checked like the others.
fn collector_part<'a>(
    c: &Container<'a>,
    g: usize,
    m: usize,
    l: usize,
) -> Result<Option<CollectorPart<'a>>, FormatError> {
    let Some(sizes) = c.find("collector_form") else {
        return Ok(None);
    };
    let bad = FormatError::BadArray("collector_form");
    if sizes.len() != 4
        || sizes
            .iter()
            .any(|v| !(v >= 0.0 && v <= 512.0 && v == (v as u32) as f32))
    {
        return Err(bad);
    }
    let int = |i: usize| sizes.get(i).map_or(0, |v| v as usize);
    let form = CollectorForm {
        legendre: int(0),
        harmonics: int(1),
        theta_nodes: int(2),
    };
    let q = int(3);
    if !(1..=MAX_COLLECTOR_LEGENDRE).contains(&form.legendre)
        || form.theta_nodes < 2
        || form.harmonics > MAX_COLLECTOR_HARMONICS
        || !(1..=MAX_Q).contains(&q)
    {
        return Err(bad);
    }
    let mut beta = [None; 3];
    for (slot, (stat, name)) in
        beta.iter_mut().zip(
            Statistic::ALL
                .iter()
                .zip(["sigma_beta", "cz_beta", "cx_beta"]),
        )
    {
        *slot = Some(need(c, name, g * form.n_params(*stat, m, l) * q)?);
    }
    match beta {
        [Some(a), Some(b), Some(x)] => Ok(Some(CollectorPart {
            form,
            q,
            beta: [a, b, x],
        })),
        _ => Err(bad),
    }
}

/// Steps of the packed depth ranges: u = step / (U_STEPS − 1).
pub const U_STEPS: u32 = 4096;

/// A depth range (lo, hi) of stretched depths in [0, 1] as one exact f32: the steps
/// ⌊lo (U_STEPS − 1)⌋ · U_STEPS + ⌈hi (U_STEPS − 1)⌉ (widened outward by less than a step; an
/// empty range, lo > hi, stays empty).
pub fn pack_u_range(lo: f64, hi: f64) -> f32 {
    let top = (U_STEPS - 1) as f64;
    if !(lo <= hi) {
        return ((U_STEPS - 1) * U_STEPS) as f32;
    }
    // Truncation of non-negative values is the floor (no `floor` in core).
    let a = (lo * top).clamp(0.0, top) as u32;
    let x = (hi * top).clamp(0.0, top);
    let b = x as u32 + u32::from((x as u32 as f64) < x);
    (a * U_STEPS + b) as f32
}

/// The inverse of [`pack_u_range`].
pub fn unpack_u_range(v: f32) -> (f32, f32) {
    let v = v as u32;
    let top = (U_STEPS - 1) as f32;
    ((v / U_STEPS) as f32 / top, (v % U_STEPS) as f32 / top)
}

/// Where x sits among the values of `a` (held at the ends).
fn lerp(a: &ArrayView, x: f32) -> Lerp<f32> {
    let n = a.len();
    if n <= 1 || !(x > a.get(0).unwrap_or(0.0)) {
        return Lerp::at(0);
    }
    if x >= a.get(n - 1).unwrap_or(0.0) {
        return Lerp::at(n - 1);
    }
    let (mut lo, mut hi) = (0, n - 1);
    while hi - lo > 1 {
        let mid = (lo + hi) / 2;
        if a.get(mid).unwrap_or(0.0) <= x {
            lo = mid
        } else {
            hi = mid
        }
    }
    let (va, vb) = (a.get(lo).unwrap_or(0.0), a.get(hi).unwrap_or(1.0));
    Lerp {
        lo,
        hi,
        w: (x - va) / (vb - va),
    }
}

/// The stretched depth u ∈ [0, 1] of depth d in a slab of thickness t: the inverse of the slab
/// grid's planes d/t = (e^{βu} − 1)/(e^β − 1), β = 0.3 t^0.65 (nephele slab's default grid).
pub fn stretched_u(d: f32, t: f32) -> f32 {
    let beta = 0.3 * Real::exp(0.65 * Real::ln(t));
    if beta < 1e-6 {
        return d / t;
    }
    (Real::ln(1.0 + (Real::exp(beta) - 1.0) * d / t) / beta).clamp(0.0, 1.0)
}

/// The stored phase function, for order 1.
struct StoredPhase<'t, 'a>(&'t TransportTables<'a>);

impl PhaseValue<f32> for StoredPhase<'_, '_> {
    fn value(&self, c: Cosine<f32>) -> f32 {
        // θ from 1 − μ keeps the forward peak's digits: θ = 2 asin √((1 − μ)/2).
        let half = Real::sqrt((0.5 * c.one_minus_mu).max(0.0)).min(1.0);
        self.0
            .phase_at(2.0 * Real::asin(half) * (180.0 / core::f32::consts::PI))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Packed depth ranges contain the range packed, exceed it by less than a step, and an
    /// empty range stays empty.
    #[test]
    fn packed_depth_ranges_widen_by_less_than_a_step() {
        let step = 1.0 / (U_STEPS - 1) as f32;
        for j in 0..16 {
            for k in j..16 {
                let (lo, hi) = (j as f64 / 15.0, k as f64 / 15.0);
                let (a, b) = unpack_u_range(pack_u_range(lo, hi));
                assert!(a <= lo as f32 + 1e-7 && a > lo as f32 - step, "{lo} → {a}");
                assert!(b >= hi as f32 - 1e-7 && b < hi as f32 + step, "{hi} → {b}");
            }
        }
        let (a, b) = unpack_u_range(pack_u_range(0.7, 0.2));
        assert!(a > b);
        let (a, b) = unpack_u_range(pack_u_range(f64::INFINITY, f64::NEG_INFINITY));
        assert!(a > b);
    }
}
