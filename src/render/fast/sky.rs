//! The sky term of the fast renderers: light of a constant sky scattered in the cloud, from the
//! slab tables (docs/collector.md). A slab under a sky of radiance L_sky on its lit face is the
//! tables integrated over sun directions (E⊥ = L_sky dΩ per direction):
//!
//!   S_g(d, t, μ_V) = ∫₀¹ dμ_L ∫₀^{2π} dφ T_g(d, t, μ_V, φ, μ_L)      (dimensionless),
//!
//! and the sky all around the cloud (as the path tracer has it) lights both faces: the radiance
//! of group g is L_sky [S_g(d, t, μ_V) + S_g(t − d, t, −μ_V)]. Every method reads it in the view
//! ray's own slab, seen face-on from its near face ([`SkyTable::view_slab`]): d = 0, μ_V = 1,
//! so only t varies. Sun cosines under the tables' smallest (0.125) read the tables there.
//! Order 1 is S₀ with the closed-form single scattering of the tables' phase function.
//!
//! S of the face-on slab is tabulated once per render at [`N_T`] thicknesses, linear in ln t
//! between them: 6 Gauss–Legendre sun cosines × 8 azimuths (midpoints on [0, π], mirror
//! symmetry) per face and node.

use nephele_runtime::transport::leakage::lateral_orders;
use nephele_runtime::transport::{SlabPoint, TransportTables};
use rayon::prelude::*;

/// Thicknesses of the face-on table, evenly spaced in ln t over the tables' range (0.5 … 128,
/// 0.79 apart). Linear interpolation between them is coarse where S bends fastest, t = 3 … 16:
/// at t = 9.2 it puts S₀ 40 % above the integral there and orders 3–4's share at 0.086 against
/// 0.048 (32 nodes agree with 16 within 0.01 of the light per group). Measured against the path
/// tracer on five sky-only scenes, 32 nodes were no closer (mean |bias| per group 17.9 %
/// against 16.8 %): the face-on slab's own error dominates, so the table stays as it was.
const N_T: usize = 8;
/// Gauss–Legendre nodes and weights on [−1, 1], 6 points.
pub(super) const GAUSS6: [(f64, f64); 6] = [
    (-0.932_469_514_203_152, 0.171_324_492_379_170),
    (-0.661_209_386_466_265, 0.360_761_573_048_139),
    (-0.238_619_186_083_197, 0.467_913_934_572_691),
    (0.238_619_186_083_197, 0.467_913_934_572_691),
    (0.661_209_386_466_265, 0.360_761_573_048_139),
    (0.932_469_514_203_152, 0.171_324_492_379_170),
];
const AZIMUTHS: usize = 8;

/// How much of a view ray's chord the sky term needs (mfp): beyond 32 mfp the slab's split of
/// the sky between orders moves by less than 1 % of the light per group (the shares of a
/// face-on slab lit on both faces, integrated from the shipped tables: 31+ holds 66.3 % at
/// t = 32, 67.0 % at 45, 66.4 % at 64, 65.8 % at 128), so the march stops there.
pub const CHORD_ENOUGH: f64 = 32.0;

/// S of order 1 (index 0) and of every group of the tables (index g + 1) of the face-on slab,
/// S_g(0, t, 1) from the near face and S_g(t, t, −1) from the far one, at [`N_T`] thicknesses.
pub struct SkyTable {
    ln_t: (f64, f64),
    groups: usize,
    /// [face][group][t], the near face first.
    values: Vec<f32>,
    /// The first order of each entry: 1, then the tables' groups'.
    first: Vec<f64>,
}

impl SkyTable {
    /// Integrates `tables` over the sky (48 directions per face and node, nodes in parallel).
    pub fn build(tables: &TransportTables) -> Self {
        let domain = tables.domain();
        let ln_t = (
            f64::from(domain.thickness.0).ln(),
            f64::from(domain.thickness.1).ln(),
        );
        let groups = tables.groups() + 1;
        let nodes: Vec<Vec<f32>> = (0..2 * N_T)
            .into_par_iter()
            .map(|i| {
                let (far, it) = (i / N_T == 1, i % N_T);
                let t = (ln_t.0 + (ln_t.1 - ln_t.0) * it as f64 / (N_T - 1) as f64).exp();
                if far {
                    integrate(tables, t, t, -1.0, groups)
                } else {
                    integrate(tables, 0.0, t, 1.0, groups)
                }
            })
            .collect();
        let mut values = vec![0f32; 2 * groups * N_T];
        for (i, node) in nodes.iter().enumerate() {
            let (face, it) = (i / N_T, i % N_T);
            for (g, v) in node.iter().enumerate() {
                values[(face * groups + g) * N_T + it] = *v;
            }
        }
        let first = std::iter::once(1.0)
            .chain(
                (0..groups - 1)
                    .map(|g| tables.group_first_order(g).map_or(f64::INFINITY, f64::from)),
            )
            .collect();
        Self {
            ln_t,
            groups,
            values,
            first,
        }
    }

    /// [`sides_escape`] of a pixel's sky radiances `s` (order 1 first, then the groups) under a
    /// loss of `kappa` per lateral order, for a phase function of mean cosine `g`.
    pub fn sides_escape(&self, s: &mut [f64], kappa: f64, g: f64) {
        let n = s.len().min(self.first.len());
        sides_escape(&mut s[..n], &self.first[..n], kappa, |order| {
            lateral_orders(order, g)
        });
    }

    /// The slab of the sky term: the medium a view ray crosses, its optical depth `chord` τ
    /// (mfp) through the whole medium, as a slab across the ray seen face-on from its near
    /// face (d = 0, μ_V = 1), τ held inside the tables' thickness range.
    ///
    /// Why not the sun's slab: under a uniform sky the light has no direction to follow; what
    /// sets it is how much medium lies around the point seen, and the view ray measures that.
    /// A ray through the middle of a cloud crosses a thick slab (the face glows by diffusion); a
    /// ray that grazes the edge crosses a thin one, which the sky lights from behind through
    /// the forward peak (the bright rim). Both faces lit, all orders and the unscattered sky sum
    /// to the sky's radiance, as they must in a conservative body.
    pub fn view_slab(&self, chord: f64) -> SlabPoint<f32> {
        let t = chord.clamp(self.ln_t.0.exp(), self.ln_t.1.exp());
        SlabPoint {
            depth: 0.0,
            thickness: t as f32,
            mu_v: 1.0,
            psi_v: 0.0,
            mu_l: 1.0,
        }
    }

    /// L/L_sky of every group (index 0: order 1, g ≥ 1: the tables' group g − 1) seen along a
    /// view ray of optical depth `chord` through the medium, into `out`, from the ray's `at =`
    /// [`Self::view_slab`]. Where τ lies outside the tables' range, S at the nearest thickness
    /// is scaled by the ray's opacity over that slab's, so that thin matter scatters in
    /// proportion to what it holds.
    pub fn view_radiances(&self, chord: f64, at: &SlabPoint<f32>, out: &mut [f64]) {
        let t = f64::from(at.thickness);
        let opacity = (-chord).exp_m1() / (-t).exp_m1();
        // The node below ln t and the weight of the one above (t held in the range already).
        let x = ((f64::from(at.thickness).ln() - self.ln_t.0) / (self.ln_t.1 - self.ln_t.0)
            * (N_T - 1) as f64)
            .clamp(0.0, (N_T - 1) as f64);
        let k = (x as usize).min(N_T - 2);
        let w = x - k as f64;
        for (g, v) in out.iter_mut().enumerate().take(self.groups) {
            let face = |f: usize| {
                let node = |i: usize| f64::from(self.values[(f * self.groups + g) * N_T + i]);
                (1.0 - w) * node(k) + w * node(k + 1)
            };
            *v = opacity * (face(0) + face(1));
        }
    }
}

/// Moves to the orders at which it leaves the light an adjoint walk from the eye loses through a
/// body's sides, `s` the slab's escape per group (order 1 first; `first[g]` the first order of
/// entry g, increasing): with a loss κ per lateral order, the walk is still inside at its n-th
/// scattering with probability A(n) e^{−κ n⊥(n)}, A(n) = Σ_{m ≥ n} s_m the slab's and n⊥ =
/// `lateral(n)` the orders by which it has spread across its entry line (the sides cannot take
/// the first orders of a forward-peaked walk; [`lateral_orders`]), and leaves with exactly the
/// orders of group g with the difference at its ends,
///
///   s′_g = A(a_g) e^{−κ n⊥(a_g)} − A(a_{g+1}) e^{−κ n⊥(a_{g+1})}.
///
/// Σ s′ = Σ s (the walk leaves either way) and s′ ≥ 0 for n⊥ increasing; κ ≤ 0 leaves `s`.
pub fn sides_escape(s: &mut [f64], first: &[f64], kappa: f64, lateral: impl Fn(f64) -> f64) {
    if !(kappa > 0.0) {
        return; // no sides: the slab's own split, bit for bit
    }
    let n = s.len().min(first.len());
    let mut above = 0.0; // A(a_{g+1}) e^{−κ n⊥(a_{g+1})}
    let mut tail = 0.0; // A(a_{g+1})
    for g in (0..n).rev() {
        tail += s[g];
        let alive = tail * (-kappa * lateral(first[g])).exp();
        s[g] = alive - above;
        above = alive;
    }
}

/// S of order 1 and of every group at one node.
fn integrate(tables: &TransportTables, d: f64, t: f64, mu_v: f64, groups: usize) -> Vec<f32> {
    let mut sum = vec![0f64; groups];
    let mut t_g = vec![0f32; groups - 1];
    for (x, wx) in GAUSS6 {
        let mu_l = 0.5 * (x + 1.0);
        for k in 0..AZIMUTHS {
            let psi = (k as f64 + 0.5) * std::f64::consts::PI / AZIMUTHS as f64;
            // dμ_L = ½ dx; ∫₀^{2π} dφ = 2 ∫₀^π dψ, midpoints of width π/AZIMUTHS.
            let w = 0.5 * wx * 2.0 * std::f64::consts::PI / AZIMUTHS as f64;
            let at = SlabPoint {
                depth: d as f32,
                thickness: t as f32,
                mu_v: mu_v as f32,
                psi_v: psi as f32,
                mu_l: mu_l.max(f64::from(tables.domain().mu_l.0)) as f32,
            };
            tables.transport_all(&at, &mut t_g);
            for (g, v) in t_g.iter().enumerate() {
                sum[g + 1] += w * *v as f64;
            }
        }
    }
    sum[0] = order1(tables, d, t, mu_v);
    sum.into_iter().map(|v| v as f32).collect()
}

/// Order 1 of the slab under a sky of unit radiance on its lit face, S₁ = ∫ T₁ dΩ_L, in
/// polar coordinates (Θ, φ) around the direction s* whose light reaches the view unscattered
/// in angle (Θ = 0 is the forward peak). The sun grid of the other groups would miss that peak
/// (a degree wide for 10 µm droplets, half of all scattering): Θ runs on Gauss–Legendre panels
/// that narrow toward 0, and the lit face's hemisphere (μ_L > 0) is what counts.
fn order1(tables: &TransportTables, d: f64, t: f64, mu_v: f64) -> f64 {
    use std::f64::consts::PI;
    const EDGES_DEG: [f64; 8] = [0.0, 0.25, 1.0, 3.0, 8.0, 20.0, 60.0, 180.0];
    const AZ: usize = 24;
    // The light leaves along ω = (sin θ_V, 0, μ_V); s* = −ω, and e₁, e₂ complete the frame.
    let sin_v = (1.0 - mu_v * mu_v).max(0.0).sqrt();
    let star = [-sin_v, 0.0, -mu_v];
    let e1 = [mu_v, 0.0, -sin_v];
    let e2 = [0.0, 1.0, 0.0];
    let mut sum = 0.0;
    for edge in EDGES_DEG.windows(2) {
        let (a, b) = (edge[0].to_radians(), edge[1].to_radians());
        for (x, wx) in GAUSS6 {
            let theta = 0.5 * (a + b) + 0.5 * (b - a) * x;
            let (st, ct) = theta.sin_cos();
            for k in 0..AZ {
                let phi = (k as f64 + 0.5) * 2.0 * PI / AZ as f64;
                let (sp, cp) = phi.sin_cos();
                let s: [f64; 3] =
                    std::array::from_fn(|i| ct * star[i] + st * (cp * e1[i] + sp * e2[i]));
                if s[2] <= 0.0 {
                    continue;
                }
                // ψ_V: the view's azimuth (0) from the sun's horizontal travel (the sun's + π).
                let at = SlabPoint {
                    depth: d as f32,
                    thickness: t as f32,
                    mu_v: mu_v as f32,
                    psi_v: (-s[1].atan2(s[0]) - PI) as f32,
                    mu_l: s[2] as f32,
                };
                let w = 0.5 * (b - a) * wx * st * 2.0 * PI / AZ as f64;
                sum += w * tables.order1(&at) as f64;
            }
        }
    }
    sum
}

#[cfg(test)]
mod tests {
    use super::sides_escape;

    const FIRST: [f64; 9] = [1.0, 2.0, 3.0, 5.0, 7.0, 9.0, 13.0, 19.0, 31.0];

    #[test]
    fn the_sides_move_light_to_lower_orders_and_keep_the_sum() {
        let slab = [0.02, 0.02, 0.03, 0.03, 0.03, 0.05, 0.07, 0.11, 0.64];
        for kappa in [0.0, 1e-3, 0.02, 0.3, 5.0] {
            let mut s = slab;
            sides_escape(&mut s, &FIRST, kappa, |n| n - 1.0);
            let (a, b): (f64, f64) = (slab.iter().sum(), s.iter().sum());
            assert!((a - b).abs() < 1e-15, "κ {kappa}: sum {a} → {b}");
            assert!(s.iter().all(|&v| v >= 0.0), "κ {kappa}: {s:?}");
            if kappa == 0.0 {
                assert_eq!(s, slab);
            } else {
                // The last group loses, the first gains.
                assert!(s[8] < slab[8] && s[0] > slab[0], "κ {kappa}: {s:?}");
            }
        }
    }

    #[test]
    fn a_single_order_leaves_with_the_hazard_law() {
        // All of the slab's light leaves with group 3 (orders 5–6): with hazard κ per
        // scattering (n⊥ = n − 1), the walk leaves at order n < 5 with probability
        // e^{−κ(n−1)} − e^{−κn}, the rest with the group.
        let mut s = [0.0; 9];
        s[3] = 1.0;
        let kappa = 0.1f64;
        sides_escape(&mut s, &FIRST, kappa, |n| n - 1.0);
        let at = |n: f64| (-kappa * (n - 1.0)).exp();
        assert!((s[0] - (at(1.0) - at(2.0))).abs() < 1e-15);
        assert!((s[1] - (at(2.0) - at(3.0))).abs() < 1e-15);
        assert!((s[2] - (at(3.0) - at(5.0))).abs() < 1e-15);
        assert!((s[3] - at(5.0)).abs() < 1e-15);
        assert!(s[4..].iter().all(|&v| v == 0.0));
    }

    #[test]
    fn a_forward_peaked_walk_keeps_its_first_orders_from_the_sides() {
        // g = 0.86: after 2 flights the walk has spread 0.04 lateral orders, so order 1 gains
        // a few % (counted per scattering it would nearly double); by order 31, 21.
        let slab = [0.02, 0.02, 0.03, 0.03, 0.03, 0.05, 0.07, 0.11, 0.64];
        let g = 0.86;
        let (mut counted, mut per_scattering) = (slab, slab);
        super::sides_escape(&mut counted, &FIRST, 0.02, |n| {
            nephele_runtime::transport::leakage::lateral_orders(n, g)
        });
        sides_escape(&mut per_scattering, &FIRST, 0.02, |n| n - 1.0);
        assert!(counted[0] < 1.05 * slab[0], "{counted:?}");
        assert!(per_scattering[0] > 1.5 * slab[0], "{per_scattering:?}");
        assert!(
            counted[8] < slab[8] && counted[8] > per_scattering[8],
            "{counted:?}"
        );
    }
}
