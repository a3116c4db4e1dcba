//! Slabs thicker than the tables' thickest, t > t_max: the tables continued by diffusion theory.
//!
//! Far from both faces light is diffuse, and diffusion theory says how it changes with t. A
//! collimated beam lit from above acts as a source at depth z_s = μ_L ℓ (ℓ = 1/(1 − g) the
//! transport mean free path, in mfp); the fluence vanishes at the extrapolated boundaries
//! z_e = 2ℓ/3 outside each face ([`super::leakage::extrapolation_length`]). Between them the fluence is the slab's Green's function,
//!
//!   φ_t(z) = (min(z, z_s) + z_e) (t + z_e − max(z, z_s)) / (t + 2 z_e),
//!
//! linear on either side of the source. A point at depth d of a slab t > t_max reads the
//! tables at a depth d' of the thickest slab, then scales by φ_t(d) / φ_tmax(d'):
//!
//! - **near the lit face** (d ≤ t_max/2): d' = d. Light of few orders there never reaches a
//!   face t_max/2 away, so it is unchanged; the diffuse light grows by the light the thicker
//!   slab no longer lets through (at most (t_max + 2z_e)/(t_max + z_e − z_s), about 10 %);
//! - **near the far face** (t − d ≤ t_max/2): d' = t_max − (t − d), the same distance from
//!   the far face. Transmission falls as 1/(t + 2z_e), the diffusion asymptote;
//! - **between** (both faces farther than t_max/2): d' = t_max/2, scaled by the linear fluence.
//!
//! Every group but the open-ended last (orders ≥ 31 by default) scales by min(1, φ ratio): it
//! keeps its value near the lit face and falls with the diffuse light toward the far face,
//! where the tables already hold it below 10⁻¹⁵ of the diffuse group at t_max.
//!
//! The lateral spread σ of diffuse light grows with the length of its walks: ⟨r²⟩ ∝ ⟨L⟩.
//! Light reflected near the lit face has explored depths up to ~t, and light at depth d has
//! walked ⟨L⟩ ∝ t d (∝ t² through the far face, the classic transmission time), so the
//! open-ended group's σ scales by √(t d / (t_max d')): √(t/t_max) near the lit face, t/t_max
//! at the far face. The few orders keep their σ near the lit face and scale by d/d'
//! elsewhere (where the tables hold them near 0). c is held. Checked against the slab walk at
//! t = 256, 384 and 512 (docs/compress.md, "Past the thickest slab").

use super::geometry::SlabPoint;
use super::leakage::extrapolation_length;
use crate::real::Math;

/// Where a point past the grid reads the tables, and how its values scale.
#[derive(Clone, Copy, Debug, PartialEq)]
pub(super) struct Continued {
    /// The point in the thickest slab the tables hold.
    pub at: SlabPoint<f32>,
    /// φ_t(d) / φ_tmax(d'): the open-ended group's T scales by it, every other group's by
    /// min(1, it).
    pub diffuse: f32,
    /// σ's scale, d/d' (1 near the lit face).
    pub spread: f32,
    /// The open-ended group's σ scale, √(t d / (t_max d')) (√(t/t_max) at d = 0).
    pub spread_diffuse: f32,
}

/// The point `at` of a slab thicker than `t_max` continued into the slab `t_max` thick, the
/// tables' phase function of mean cosine `g`; None when `at` is within the grid's thicknesses
/// (or its t is not finite).
pub(super) fn continued(at: &SlabPoint<f32>, t_max: f32, g: f32) -> Option<Continued> {
    let t = at.thickness;
    if !(t > t_max) || !t.is_finite() {
        return None;
    }
    let half = 0.5 * t_max;
    let (d, h) = (at.depth, at.thickness - at.depth);
    let depth = if d <= half {
        d
    } else if h <= half {
        t_max - h
    } else {
        half
    };
    // g < 1 for any phase function that scatters at all; held so that ℓ stays finite.
    let g = g.min(0.999);
    // The source lies inside the thickest slab, where its fluence is positive.
    let z_s = (at.mu_l / (1.0 - g)).min(half);
    let z_e = extrapolation_length(g);
    let (here, there) = (fluence(d, t, z_s, z_e), fluence(depth, t_max, z_s, z_e));
    // Factor by factor: no product of two thicknesses, which overflows past t ~ 10¹⁹.
    let diffuse = (here.0 / there.0) * (here.1 / there.1);
    let spread = if depth > 0.0 && d > half {
        d / depth
    } else {
        1.0
    };
    Some(Continued {
        at: SlabPoint {
            thickness: t_max,
            depth,
            ..*at
        },
        diffuse,
        spread,
        spread_diffuse: Math::sqrt(t / t_max)
            * if depth > 0.0 {
                Math::sqrt(d / depth)
            } else {
                1.0
            },
    })
}

/// The diffusion fluence φ_t(z) at depth `z` of a slab `t` thick lit at depth `z_s`, zero at
/// `z_e` outside each face (unnormalised: only ratios are used), as its two factors:
/// min(z, z_s) + z_e and (t + z_e − max(z, z_s)) / (t + 2 z_e).
fn fluence(z: f32, t: f32, z_s: f32, z_e: f32) -> (f32, f32) {
    (z.min(z_s) + z_e, (t + z_e - z.max(z_s)) / (t + 2.0 * z_e))
}

#[cfg(test)]
mod tests {
    use super::*;

    fn point(t: f32, d: f32) -> SlabPoint<f32> {
        SlabPoint {
            thickness: t,
            mu_l: 0.5,
            depth: d,
            mu_v: -0.6,
            psi_v: 0.3,
        }
    }

    /// Up to the largest f32 thickness, and for a phase function of g near 1 (the source
    /// deeper than the thickest slab's middle), the scales stay finite and ≥ 0: positive up
    /// to t = 10⁶, while at the far face of a slab 10²⁰ mfp thick the transmitted light
    /// rounds to 0 in f32.
    #[test]
    fn every_thickness_and_phase_gives_finite_positive_scales() {
        for g in [0.0f32, 0.85, 0.99, 0.9999, 1.0] {
            for t in [129.0f32, 1e6, 1e20, 3e38, f32::MAX] {
                for d in [0.0, 1.0, 0.5 * t, t - 1.0, t] {
                    let c = continued(&point(t, d.min(t)), 128.0, g).unwrap();
                    assert!(
                        c.diffuse.is_finite() && c.diffuse >= 0.0,
                        "g {g} t {t} d {d}: {c:?}"
                    );
                    assert!(c.diffuse > 0.0 || t > 1e6, "g {g} t {t} d {d}: {c:?}");
                    for v in [c.spread, c.spread_diffuse] {
                        assert!(v.is_finite() && v > 0.0, "g {g} t {t} d {d}: {c:?}");
                    }
                }
            }
        }
    }

    #[test]
    fn within_the_grid_nothing_changes() {
        assert_eq!(continued(&point(128.0, 3.0), 128.0, 0.85), None);
        assert_eq!(continued(&point(f32::INFINITY, 3.0), 128.0, 0.85), None);
    }

    #[test]
    fn the_three_regions_meet_continuously() {
        let (t_max, l) = (128.0, 0.85);
        for t in [160.0f32, 500.0, 1e4] {
            // Across d = t_max/2 and across t − d = t_max/2: the diffuse factor and d' join.
            for edge in [64.0f32, t - 64.0] {
                let a = continued(&point(t, edge * (1.0 - 1e-6)), t_max, l).unwrap();
                let b = continued(&point(t, edge * (1.0 + 1e-6)), t_max, l).unwrap();
                assert!(
                    (a.diffuse - b.diffuse).abs() < 1e-3 * a.diffuse,
                    "{t} {edge}"
                );
                assert!((a.at.depth - b.at.depth).abs() < 1e-2, "{t} {edge}");
                assert!((a.spread - b.spread).abs() < 1e-3 * a.spread, "{t} {edge}");
                let diffuse = (a.spread_diffuse, b.spread_diffuse);
                assert!(
                    (diffuse.0 - diffuse.1).abs() < 1e-3 * diffuse.0,
                    "{t} {edge}"
                );
            }
        }
    }

    #[test]
    fn near_the_lit_face_the_diffuse_light_grows_a_little_and_transmission_falls() {
        let (t_max, g) = (128.0, 0.85);
        let l = 1.0 / (1.0 - g);
        let top = continued(&point(1000.0, 2.0), t_max, g).unwrap();
        assert_eq!(top.at.depth, 2.0);
        assert!(top.diffuse > 1.0 && top.diffuse < 1.15, "{}", top.diffuse);
        let bottom = continued(&point(1000.0, 1000.0), t_max, g).unwrap();
        assert_eq!(bottom.at.depth, 128.0);
        // Transmission ∝ 1/(t + 2 z_e).
        let z_e = 2.0 / 3.0 * l;
        let want = (128.0 + 2.0 * z_e) / (1000.0 + 2.0 * z_e);
        assert!(
            (bottom.diffuse - want).abs() < 1e-6,
            "{} {want}",
            bottom.diffuse
        );
        assert!((bottom.spread - 1000.0 / 128.0).abs() < 1e-4);
        assert!((bottom.spread_diffuse - bottom.spread).abs() < 1e-4 * bottom.spread);
        assert_eq!(top.spread, 1.0);
        assert!((top.spread_diffuse - (1000.0f32 / 128.0).sqrt()).abs() < 1e-5);
    }
}
