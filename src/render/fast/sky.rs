//! The sky term of the fast renderers: light of a constant sky scattered in the cloud, from the
//! slab tables (docs/collector.md). A slab under a sky of radiance L_sky on its lit face is the
//! tables integrated over sun directions (E⊥ = L_sky dΩ per direction):
//!
//!   S_g(d, t, μ_V) = ∫₀¹ dμ_L ∫₀^{2π} dφ T_g(d, t, μ_V, φ, μ_L)      (dimensionless),
//!
//! and the sky all around the cloud (as the path tracer has it) lights both faces: the radiance
//! of group g is L_sky [S_g(d, t, μ_V) + S_g(t − d, t, −μ_V)]. The approximation: the slab is
//! the one the sun's collector search found for that group (the sky's own collector is not
//! searched), and sun cosines under the tables' smallest (0.125) read the tables there.
//! Order 1 is S₀ with the closed-form single scattering of the tables' phase function.
//!
//! S is tabulated once per frame on a small grid (ln t, d/t, μ_V), trilinear between nodes:
//! 6 Gauss–Legendre sun cosines × 8 azimuths (midpoints on [0, π], mirror symmetry) per node.

use nephele_runtime::transport::{SlabPoint, TransportTables};
use rayon::prelude::*;

const N_T: usize = 8;
const N_U: usize = 6;
const N_MU: usize = 13;
/// Gauss–Legendre nodes and weights on [−1, 1], 6 points.
const GAUSS6: [(f64, f64); 6] = [
    (-0.932_469_514_203_152, 0.171_324_492_379_170),
    (-0.661_209_386_466_265, 0.360_761_573_048_139),
    (-0.238_619_186_083_197, 0.467_913_934_572_691),
    (0.238_619_186_083_197, 0.467_913_934_572_691),
    (0.661_209_386_466_265, 0.360_761_573_048_139),
    (0.932_469_514_203_152, 0.171_324_492_379_170),
];
const AZIMUTHS: usize = 8;

/// S of order 1 (index 0) and of every group of the tables (index g + 1) on the grid.
pub struct SkyTable {
    ln_t: (f64, f64),
    groups: usize,
    /// [group][t][u][μ_V].
    values: Vec<f32>,
}

impl SkyTable {
    /// Integrates `tables` over the sky (48 directions per node, nodes in parallel).
    pub fn build(tables: &TransportTables) -> Self {
        let domain = tables.domain();
        let ln_t = (
            f64::from(domain.thickness.0).ln(),
            f64::from(domain.thickness.1).ln(),
        );
        let groups = tables.groups() + 1;
        let nodes: Vec<Vec<f32>> = (0..N_T * N_U * N_MU)
            .into_par_iter()
            .map(|i| {
                let (it, iu, im) = (i / (N_U * N_MU), (i / N_MU) % N_U, i % N_MU);
                let t = (ln_t.0 + (ln_t.1 - ln_t.0) * it as f64 / (N_T - 1) as f64).exp();
                let d = t * iu as f64 / (N_U - 1) as f64;
                let mu_v = -1.0 + 2.0 * im as f64 / (N_MU - 1) as f64;
                integrate(tables, d, t, mu_v, groups)
            })
            .collect();
        let mut values = vec![0f32; groups * nodes.len()];
        for (i, node) in nodes.iter().enumerate() {
            for (g, v) in node.iter().enumerate() {
                values[g * nodes.len() + i] = *v;
            }
        }
        Self {
            ln_t,
            groups,
            values,
        }
    }

    /// L/L_sky of group `g` (0: order 1, g ≥ 1: the tables' group g − 1) in the slab `at`, lit
    /// by the sky on both faces.
    pub fn radiance(&self, g: usize, at: &SlabPoint<f32>) -> f64 {
        let (d, t, mu) = (at.depth as f64, at.thickness as f64, at.mu_v as f64);
        self.lookup(g, d, t, mu) + self.lookup(g, t - d, t, -mu)
    }

    fn lookup(&self, g: usize, d: f64, t: f64, mu_v: f64) -> f64 {
        if g >= self.groups || t <= 0.0 {
            return 0.0;
        }
        let x = |v: f64, n: usize| {
            let v = v.clamp(0.0, (n - 1) as f64);
            let k = (v as usize).min(n - 2);
            (k, v - k as f64)
        };
        let (kt, wt) = x(
            (t.ln() - self.ln_t.0) / (self.ln_t.1 - self.ln_t.0) * (N_T - 1) as f64,
            N_T,
        );
        let (ku, wu) = x(d / t * (N_U - 1) as f64, N_U);
        let (km, wm) = x((mu_v + 1.0) / 2.0 * (N_MU - 1) as f64, N_MU);
        let base = g * N_T * N_U * N_MU;
        let mut v = 0.0;
        for (a, wa) in [(kt, 1.0 - wt), (kt + 1, wt)] {
            for (b, wb) in [(ku, 1.0 - wu), (ku + 1, wu)] {
                for (c, wc) in [(km, 1.0 - wm), (km + 1, wm)] {
                    v += wa * wb * wc * self.values[base + (a * N_U + b) * N_MU + c] as f64;
                }
            }
        }
        v
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
            sum[0] += w * tables.order1(&at) as f64;
            tables.transport_all(&at, &mut t_g);
            for (g, v) in t_g.iter().enumerate() {
                sum[g + 1] += w * *v as f64;
            }
        }
    }
    sum.into_iter().map(|v| v as f32).collect()
}
