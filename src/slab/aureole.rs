//! The aureole: transmitted light within a few degrees of the sun's direction, tallied in cones
//! around the beam.
//!
//! A water droplet sends half of what it scatters into a diffraction peak about λ/d wide (1° at
//! d = 10 µm), so the low orders of the light going down are a bright halo around the beam:
//! in a 10 mfp slab under μ_L = 0.71, order 2 is 6× brighter within 2° of the beam than at 10°.
//! The view bins (Δμ_V = 1/8, Δψ_V = 15°) hold that halo's energy spread over a bin 20° wide,
//! and the bins put the beam on their corners (μ_L on the μ_V edges, ψ_V = 0 an edge), so no
//! bin centre sees it. The compressed form read at the bin centres around the beam then came
//! out 2.5–8× too bright at 6–13° and near 0 within 4° (docs/collector.md, `cloud_behind`).
//!
//! Annulus b holds the crossings of the tally planes going down whose angle Θ from the beam
//! lies in [Θ_b, Θ_{b+1}): T = μ_L Σ w/|μ| / (N ΔΩ_b), ΔΩ_b = 2π (cos Θ_b − cos Θ_{b+1}), the
//! view bins' estimator over a cone instead of a bin (no mirror fold: the cone is whole).

use super::lanes::{count_edges, Lane};
use anyhow::{bail, Result};
use nephele_runtime::phase::Cosine;
use nephele_runtime::transport::{scattering_cosine, SlabPoint};
use std::f64::consts::PI;

/// Default annulus edges around the beam (degrees): as narrow as the diffraction peak of
/// order 2 at the centre, out past the widest view bin of the default grid that holds the beam
/// (the μ_V bin [−1, −7/8] under an overhead sun reaches 29° from it).
pub const DEFAULT_AUREOLE_DEG: [f64; 10] = [0.0, 0.7, 2.0, 4.0, 6.5, 10.0, 14.0, 19.0, 25.0, 32.0];

/// Annuli around the transmitted beam (empty: no aureole tally).
#[derive(Clone, Debug, Default)]
pub struct Aureole {
    /// Edges Θ (degrees), increasing from 0.
    pub edges_deg: Vec<f64>,
    /// cos of the edges, decreasing from 1.
    cos_edges: Vec<f64>,
}

impl Aureole {
    /// Annuli with edges `edges_deg` (increasing from 0, at most 90°), or none if empty.
    pub fn new(edges_deg: Vec<f64>) -> Result<Self> {
        if !edges_deg.is_empty()
            && (edges_deg.len() < 2
                || edges_deg[0] != 0.0
                || edges_deg.windows(2).any(|w| !(w[0] < w[1]))
                || !(edges_deg[edges_deg.len() - 1] <= 90.0))
        {
            bail!("aureole_deg must be empty or increase from 0 to at most 90 (degrees)");
        }
        let cos_edges = edges_deg.iter().map(|e| e.to_radians().cos()).collect();
        Ok(Self {
            edges_deg,
            cos_edges,
        })
    }

    /// Number of annuli.
    pub fn n_bins(&self) -> usize {
        self.edges_deg.len().saturating_sub(1)
    }

    /// The annulus of a direction at cos Θ = `cos_theta` from the beam, if any.
    #[inline]
    pub fn bin(&self, cos_theta: f64) -> Option<usize> {
        let last = *self.cos_edges.last()?;
        if cos_theta <= last {
            return None;
        }
        Some(self.cos_edges[1..].partition_point(|c| *c >= cos_theta))
    }

    /// [`Self::bin`] of every lane side by side, [`Self::n_bins`] standing for none (a cosine
    /// at or below the last edge's is at or below every edge's, so the count says it).
    #[inline(always)]
    pub fn bins(&self, cos_theta: &Lane<f64>) -> Lane<usize> {
        count_edges(self.cos_edges.get(1..).unwrap_or(&[]), |c, l| {
            c >= cos_theta[l]
        })
    }

    /// Solid angle (sr) of annulus `b`.
    pub fn solid_angle(&self, b: usize) -> f64 {
        2.0 * PI * (self.cos_edges[b] - self.cos_edges[b + 1])
    }

    /// The angle (radians) that stands for annulus `b`: the median of Θ over its solid angle
    /// for small angles, √((Θ_b² + Θ_{b+1}²)/2).
    pub fn centre(&self, b: usize) -> f64 {
        let (a, c) = (self.edges_deg[b], self.edges_deg[b + 1]);
        (0.5 * (a * a + c * c)).sqrt().to_radians()
    }

    /// Whether annulus `b` lies wholly below the horizon under sun cosine `mu_l`: only the
    /// crossings going down are tallied, so an annulus reaching past the horizon (the beam is
    /// asin μ_L below it: 7.2° at μ_L = 1/8) holds part of its light, and is not used.
    pub fn whole(&self, mu_l: f64, b: usize) -> bool {
        self.edges_deg[b + 1].to_radians() < mu_l.clamp(-1.0, 1.0).asin()
    }

    /// The widest angle (radians) out to which the annuli are whole under sun cosine `mu_l`
    /// (0: none is).
    pub fn cover(&self, mu_l: f64) -> f64 {
        (0..self.n_bins())
            .filter(|&b| self.whole(mu_l, b))
            .map(|b| self.edges_deg[b + 1].to_radians())
            .fold(0.0, f64::max)
    }
}

/// The view (μ_V, ψ_V) at angle `theta` (radians) from the transmitted beam of sun cosine
/// `mu_l`, turned about the beam by `turn` (radians; 0 toward the horizontal direction across
/// the sun's travel, x), with μ_V > 0 going up and ψ_V ∈ [0, π] (the slab frame of
/// docs/conventions.md).
pub fn view_near_beam(mu_l: f64, theta: f64, turn: f64) -> (f64, f64) {
    let sin_l = (1.0 - mu_l * mu_l).max(0.0).sqrt();
    let beam = [0.0, sin_l, mu_l];
    // Two unit vectors across the beam: x, and the one in the sun's vertical plane.
    let across = [1.0, 0.0, 0.0];
    let up = [0.0, mu_l, -sin_l];
    let (st, ct) = theta.sin_cos();
    let (sp, cp) = turn.sin_cos();
    let w: [f64; 3] = std::array::from_fn(|i| ct * beam[i] + st * (cp * across[i] + sp * up[i]));
    (-w[2], w[0].abs().atan2(w[1]))
}

/// The cosine of the angle between the transmitted beam of sun cosine `mu_l` and the view
/// (μ_V, ψ_V): the runtime's scattering angle.
pub fn from_beam(mu_l: f64, mu_v: f64, psi_v: f64) -> Cosine<f64> {
    let at = SlabPoint {
        depth: 0.0,
        thickness: 1.0,
        mu_v,
        psi_v,
        mu_l,
    };
    scattering_cosine(&at)
}

/// The smallest and the largest angle (radians) between the beam of sun cosine `mu_l` and the
/// view bin [μ₀, μ₁] × ±[ψ₀, ψ₁], by a fine grid over the bin (its edges included).
pub fn bin_extent(mu_l: f64, mu: (f64, f64), psi: (f64, f64)) -> (f64, f64) {
    const N: usize = 48;
    let (mut near, mut far) = (2.0f64, 0.0f64);
    for i in 0..=N {
        let mu_v = mu.0 + (mu.1 - mu.0) * i as f64 / N as f64;
        for k in 0..=N {
            let psi_v = psi.0 + (psi.1 - psi.0) * k as f64 / N as f64;
            let omm = from_beam(mu_l, mu_v, psi_v).one_minus_mu;
            (near, far) = (near.min(omm), far.max(omm));
        }
    }
    let angle = |omm: f64| (1.0 - omm).clamp(-1.0, 1.0).acos();
    (angle(near), angle(far))
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::slab::lanes::LANES;

    /// The annuli of lanes side by side are each cosine's own, none where `bin` says none: at
    /// every edge ±1 ulp, both ends, beyond them, NaN and a sweep, with and without annuli.
    #[test]
    fn lane_annuli_are_each_cosines_own() {
        for edges in [DEFAULT_AUREOLE_DEG.to_vec(), vec![0.0, 90.0], vec![]] {
            let a = Aureole::new(edges).unwrap();
            let mut cos = vec![1.0, 1.0f64.next_down(), 0.0, -0.0, -1.0, 2.0, f64::NAN];
            for &c in &a.cos_edges {
                cos.extend([c, c.next_up(), c.next_down()]);
            }
            cos.extend((0..1000).map(|i| 1.0 - 0.2 * i as f64 / 999.0));
            for chunk in cos.chunks(LANES) {
                let mut lanes = [0.5; LANES];
                lanes[..chunk.len()].copy_from_slice(chunk);
                let got = a.bins(&lanes);
                for l in 0..LANES {
                    assert_eq!(
                        got[l],
                        a.bin(lanes[l]).unwrap_or(a.n_bins()),
                        "{}",
                        lanes[l]
                    );
                }
            }
        }
    }

    #[test]
    fn annuli_and_views_near_the_beam() {
        let a = Aureole::new(DEFAULT_AUREOLE_DEG.to_vec()).unwrap();
        assert_eq!(a.n_bins(), 9);
        let deg = |d: f64| d.to_radians().cos();
        assert_eq!(a.bin(1.0), Some(0));
        assert_eq!(a.bin(deg(0.5)), Some(0));
        assert_eq!(a.bin(deg(1.0)), Some(1));
        assert_eq!(a.bin(deg(18.9)), Some(6));
        assert_eq!(a.bin(deg(19.1)), Some(7));
        assert_eq!(a.bin(deg(32.1)), None);
        let total: f64 = (0..9).map(|b| a.solid_angle(b)).sum();
        assert!((total - 2.0 * PI * (1.0 - deg(32.0))).abs() < 1e-14);
        assert!(Aureole::new(vec![]).unwrap().bin(1.0).is_none());
        assert!(Aureole::new(vec![1.0, 2.0]).is_err());
        assert!(Aureole::new(vec![0.0, 2.0, 2.0]).is_err());
        // The views turned about the beam are at Θ from it (the runtime's angle).
        for mu_l in [0.125, 0.5, std::f64::consts::FRAC_1_SQRT_2, 1.0] {
            for turn in [0.0, 1.0, 2.5, 4.0] {
                let (mu_v, psi_v) = view_near_beam(mu_l, 0.1, turn);
                let theta = from_beam(mu_l, mu_v, psi_v).mu.acos();
                assert!(
                    (theta - 0.1).abs() < 1e-9,
                    "μ_L {mu_l}, turn {turn}: {theta}"
                );
                assert!(mu_v < 0.0 && (0.0..=PI).contains(&psi_v));
            }
        }
        // A bin holding the beam is at 0, one across the sky from it far.
        // A bin holding the beam is at 0 from it, one across the sky far; the bin under an
        // overhead sun reaches acos(7/8).
        assert!(bin_extent(0.5, (-0.625, -0.5), (0.0, PI / 12.0)).0 < 1e-9);
        let (near, _) = bin_extent(0.5, (0.5, 0.625), (0.0, PI / 12.0));
        assert!((near - 60f64.to_radians()).abs() < 1e-6, "{near}");
        let (near, far) = bin_extent(1.0, (-1.0, -0.875), (0.0, PI / 12.0));
        assert!(near < 1e-9 && (far - 0.875f64.acos()).abs() < 1e-9, "{far}");
    }
}
