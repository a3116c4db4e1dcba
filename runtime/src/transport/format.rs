//! The `.ntt` layout of the compressed transport tables: the arrays' names, shapes and
//! limits, the checks of each array (the loader, `load.rs`, applies them in
//! [`super::TransportTables::from_bytes`]), and the packing of the fitted depth ranges. The
//! toolchain's writer uses the same names and limits
//! (`nephele_runtime::fitting`); the evaluation is in [`super::tables`].
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
//! | `beta` | [P, G, Q] | the parameters' Legendre coefficients in s(ln t), feature-major |
//! | `u_range` | [G, N, L·M] | per thickness and (μ_L, μ_V) pair, the stretched depths fitted: [`U_STEPS`]-step integers lo · 4096 + hi (u = step/4095, widened outward; lo > hi: none) |
//! | `t_ceiling` | [G, N, L] | optional: per thickness and sun cosine, the largest T of the fitted cells; T is capped at [`super::tables::CEILING_FACTOR`] × the largest of the nodes a point draws on |
//! | `phase_theta` | [n] | phase function nodes (degrees, increasing, 0 … 180); between them 2π p sin θ is linear in θ, as the tabulated model samples |
//! | `phase` | [n] | phase function p(θ) (sr⁻¹) |
//! | `collector_form` | [4] | optional: the collector form's J, K, Θ nodes, Q |
//! | `sigma_beta`, `cz_beta`, `cx_beta` | [P_s, G, Q] | with it: ln σ, c_z/σ̂, c_x/σ̂ ([`super::collector`]), feature-major as `beta` |
//! | `halo_edges` | [B + 1] | optional: the halo's annulus edges Θ (degrees from the transmitted beam, increasing from 0) |
//! | `halo_shape` | [2] | with it: the groups it covers (the first H ≤ G), the depth planes D (≥ 2) |
//! | `halo` | [H, N, L, D·B] | with it: h = ln(T_annulus / T̄_form) per plane d and annulus b at d·B + b (transport/halo.rs) |
//!
//! Files without the collector arrays load too; their [`super::Transport`] has c = 0, σ = 0.
//! Files without the halo arrays have T = the form's everywhere.

use super::collector::{CollectorForm, Statistic};
use super::halo::Halo;
use super::log_additive::{LogAdditive, MAX_LEGENDRE};
use crate::container::{ArrayView, Container, FormatError};

/// The names of the arrays of a `.ntt` (the table above), shared by the reader here and the
/// toolchain's writer.
pub mod names {
    /// J, K, Θ nodes, pairs, Q, A.
    pub const FORM: &str = "form";
    /// First order of each group.
    pub const GROUP_FIRST: &str = "group_first";
    /// Sun-cosine nodes.
    pub const MU_L_NODES: &str = "mu_l_nodes";
    /// View-cosine nodes.
    pub const MU_V_NODES: &str = "mu_v_nodes";
    /// Thicknesses of the depth ranges.
    pub const THICKNESS: &str = "thickness";
    /// ln t span per group.
    pub const LN_T_RANGE: &str = "ln_t_range";
    /// T's parameters' Legendre coefficients in s(ln t).
    pub const BETA: &str = "beta";
    /// Packed fitted depth ranges.
    pub const U_RANGE: &str = "u_range";
    /// The largest T of the fitted cells per group, thickness and sun cosine.
    pub const T_CEILING: &str = "t_ceiling";
    /// Optional: the halo's annulus edges (degrees from the beam).
    pub const HALO_EDGES: &str = "halo_edges";
    /// Optional: [groups covered, planes].
    pub const HALO_SHAPE: &str = "halo_shape";
    /// Optional: h = ln(T_annulus / T̄_form) over [group, thickness, μ_L, plane, annulus].
    pub const HALO: &str = "halo";
    /// Phase function angles (degrees).
    pub const PHASE_THETA: &str = "phase_theta";
    /// Phase function values (sr⁻¹).
    pub const PHASE: &str = "phase";
    /// The collector form's J, K, Θ nodes, Q.
    pub const COLLECTOR_FORM: &str = "collector_form";
    /// The collector's parameters, in the order of `Statistic::ALL` (ln σ, c_z, c_x).
    pub const COLLECTOR_BETA: [&str; 3] = ["sigma_beta", "cz_beta", "cx_beta"];
}

/// Most Legendre terms in ln t.
pub const MAX_Q: usize = MAX_LEGENDRE;

/// Most order groups.
pub const MAX_GROUPS: usize = 64;

/// nephele slab's default order groups by their first orders, order 1 first: 1, 2, 3–4, 5–6,
/// 7–8, 9–12, 13–18, 19–30, 31–∞ (a `.ntt` holds those of orders ≥ 2:
/// [`super::TransportTables::group_first_order`]).
pub const DEFAULT_GROUP_FIRST: [u32; 9] = [1, 2, 3, 5, 7, 9, 13, 19, 31];

/// Most nodes of each grid (sun cosines, view cosines, thicknesses).
pub const MAX_NODES: usize = 1024;

/// The collector part of the tables.
#[derive(Clone, Copy, Debug)]
pub(super) struct CollectorPart<'a> {
    pub(super) form: CollectorForm,
    pub(super) q: usize,
    pub(super) beta: [ArrayView<'a>; 3],
    pub(super) strides: [Strides; 3],
}

pub(super) fn need<'a>(
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

pub(super) fn increasing(a: &ArrayView) -> bool {
    a.iter().zip(a.iter().skip(1)).all(|(x, y)| x < y)
}

/// The T form's sizes and Q from the `form` array, within the runtime's limits.
pub(super) fn parse_form(c: &Container) -> Result<(LogAdditive, usize), FormatError> {
    let bad = FormatError::BadArray(names::FORM);
    let a = c
        .find(names::FORM)
        .ok_or(FormatError::Missing(names::FORM))?;
    if !(5..=6).contains(&a.len()) || !whole_numbers(&a, 4096.0) {
        return Err(bad);
    }
    let int = |i: usize| a.get(i).map_or(0, |v| v as usize);
    let form = LogAdditive {
        legendre: int(0),
        harmonics: int(1),
        theta_nodes: int(2),
        pairs: int(3) == 1,
        cross: if a.len() == 6 { int(5) } else { 0 },
    };
    let q = int(4);
    if form.check().is_err() || !(1..=MAX_Q).contains(&q) {
        return Err(bad);
    }
    Ok((form, q))
}

/// Where group g's Q coefficients of parameter p start in a β array, stored feature-major
/// [P, G, Q], so that one feature's coefficients for every group lie together and a point's
/// features are read once for all of them ([`Sums`]).
#[derive(Clone, Copy, Debug)]
pub(super) struct Strides {
    pub(super) param: usize,
    pub(super) group: usize,
}

impl Strides {
    /// The layout of `g` groups of parameters of `q` terms, feature-major: a parameter's
    /// coefficients for every group side by side.
    pub(super) fn of(g: usize, q: usize) -> Self {
        Self {
            param: g * q,
            group: q,
        }
    }

    /// The index of group `g`'s first coefficient of parameter `p`.
    #[inline(always)]
    pub(super) fn at(&self, g: usize, p: usize) -> usize {
        g * self.group + p * self.param
    }
}

/// The optional collector arrays, checked like the others.
pub(super) fn collector_part<'a>(
    c: &Container<'a>,
    g: usize,
    m: usize,
    l: usize,
) -> Result<Option<CollectorPart<'a>>, FormatError> {
    let Some(sizes) = c.find(names::COLLECTOR_FORM) else {
        return Ok(None);
    };
    let bad = FormatError::BadArray(names::COLLECTOR_FORM);
    if sizes.len() != 4 || !whole_numbers(&sizes, 512.0) {
        return Err(bad);
    }
    let int = |i: usize| sizes.get(i).map_or(0, |v| v as usize);
    let form = CollectorForm {
        legendre: int(0),
        harmonics: int(1),
        theta_nodes: int(2),
    };
    let q = int(3);
    if form.check().is_err() || !(1..=MAX_Q).contains(&q) {
        return Err(bad);
    }
    let mut beta = [None; 3];
    for (slot, (stat, name)) in beta
        .iter_mut()
        .zip(Statistic::ALL.iter().zip(names::COLLECTOR_BETA))
    {
        *slot = Some(need(c, name, g * form.n_params(*stat, m, l) * q)?);
    }
    let strides = [Strides::of(g, q); 3];
    match beta {
        [Some(a), Some(b), Some(x)] => Ok(Some(CollectorPart {
            form,
            q,
            beta: [a, b, x],
            strides,
        })),
        _ => Err(bad),
    }
}

/// Whether every value of `a` is a whole number in [0, `max`] (sizes stored as f32).
pub(super) fn whole_numbers(a: &ArrayView, max: f32) -> bool {
    a.iter()
        .all(|v| v >= 0.0 && v <= max && v == (v as u32) as f32)
}

/// A packed empty depth range (lo > hi).
pub(super) const EMPTY_RANGE: f32 = ((U_STEPS - 1) * U_STEPS) as f32;

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
    // × 1/4095 rather than ÷ 4095: a product is cheaper and the ranges were widened outward.
    let step = 1.0 / (U_STEPS - 1) as f32;
    ((v / U_STEPS) as f32 * step, (v % U_STEPS) as f32 * step)
}

/// The halo's arrays if the file has them: edges increasing from 0, at most `g` groups.
pub(super) fn halo_part<'a>(c: &Container<'a>, g: usize, n: usize, l: usize) -> Result<Option<Halo<'a>>, FormatError> {
    let Some(edges) = c.find(names::HALO_EDGES) else {
        return Ok(None);
    };
    let shape = need(c, names::HALO_SHAPE, 2)?;
    let (groups, planes) = (
        shape.get(0).unwrap_or(0.0) as usize,
        shape.get(1).unwrap_or(0.0) as usize,
    );
    let nb = edges.len().saturating_sub(1);
    if nb == 0 || edges.get(0) != Some(0.0) || !increasing(&edges) || groups > g || planes < 2 {
        return Err(FormatError::BadArray(names::HALO_EDGES));
    }
    let len = [groups, n, l, planes, nb]
        .iter()
        .try_fold(1usize, |acc, &k| acc.checked_mul(k))
        .ok_or(FormatError::BadArray(names::HALO))?;
    Ok(Some(Halo {
        edges,
        values: need(c, names::HALO, len)?,
        groups,
        planes,
    }))
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
