//! The halo of the low orders around the transmitted beam, as a correction of the form.
//!
//! Droplets scatter half their light into a diffraction peak about a degree wide, so the low
//! orders of the light going down are a halo of a few degrees around the beam. The slab tables'
//! view bins (Δμ = 1/8, Δψ = 15°) smear it, and the form fitted to them has no halo where the
//! halo is and a ring of it 4–8° out. The slab walk tallies the halo in annuli around the beam
//! (the toolchain's `slab::aureole`), and the compressor stores, per (group, thickness node,
//! sun-cosine node, depth plane, annulus), h = ln(T_annulus / T̄_form), T̄_form the form's
//! mean over the annulus. For a view going down within the last edge of the beam,
//!
//! ```text
//! T = T_form · e^{h},
//! ```
//!
//! h read linearly between the thickness and sun-cosine nodes, the planes (equal steps in the
//! stretched depth u) and the annuli's median angles √((Θ_b² + Θ_{b+1}²)/2), held below the
//! first, and falling linearly to 0 from the last median angle to the last edge. Elsewhere T is
//! the form's.

use super::log_additive::{Cell, Lerp};
use crate::container::ArrayView;
use crate::real::Math;

/// The halo correction of a `.ntt` (arrays `halo_edges`, `halo_shape`, `halo`).
#[derive(Clone, Copy, Debug)]
pub struct Halo<'a> {
    /// Annulus edges Θ (degrees), increasing from 0.
    pub(super) edges: ArrayView<'a>,
    /// h over [group, thickness node, sun-cosine node, plane, annulus].
    pub(super) values: ArrayView<'a>,
    /// Groups covered (the first ones).
    pub(super) groups: usize,
    /// Depth planes, at u = j / (planes − 1).
    pub(super) planes: usize,
}

/// Where a point reads the halo, the same for every group: up to 2 (thickness) × 2 (μ_L) ×
/// 2 (planes) × 2 (annuli) entries of a group's block, with their weights.
#[derive(Clone, Copy, Debug)]
pub(super) struct HaloAt {
    taps: [(usize, f32); 16],
    n: usize,
    /// Entries per group.
    stride: usize,
}

impl Halo<'_> {
    /// The median angle (degrees) of annulus `b`.
    fn centre(&self, b: usize) -> f32 {
        let (a, c) = (
            self.edges.get(b).unwrap_or(0.0),
            self.edges.get(b + 1).unwrap_or(0.0),
        );
        Math::sqrt(0.5 * (a * a + c * c))
    }

    /// The annuli a view `deg` degrees from the beam reads, with weights (short of 1 in all
    /// past the last median angle, where the halo fades out).
    fn annuli(&self, deg: f32, nb: usize, last: f32) -> [(usize, f32); 2] {
        let top = self.centre(nb - 1);
        if deg >= top {
            return [(nb - 1, (last - deg) / (last - top)), (0, 0.0)];
        }
        if deg <= self.centre(0) {
            return [(0, 1.0), (0, 0.0)];
        }
        let mut b = 0;
        while b + 2 < nb && self.centre(b + 1) <= deg {
            b += 1;
        }
        let w = (deg - self.centre(b)) / (self.centre(b + 1) - self.centre(b));
        [(b, 1.0 - w), (b + 1, w)]
    }

    /// Where `cell` reads the halo (None outside it: views going up or past the last edge),
    /// its thickness at `near_t` among the `nt` thickness and `nl` sun-cosine nodes.
    pub(super) fn at(
        &self,
        cell: &Cell<f32>,
        near_t: Lerp<f32>,
        (nt, nl): (usize, usize),
    ) -> Option<HaloAt> {
        let nb = self.edges.len().saturating_sub(1);
        let last = self.edges.get(nb).unwrap_or(0.0);
        let deg = cell.theta * (180.0 / core::f32::consts::PI);
        if self.groups == 0 || nb == 0 || !(cell.at.mu_v < 0.0) || !(deg < last) {
            return None;
        }
        let theta = self.annuli(deg, nb, last);
        let x = cell.u.clamp_to(0.0, 1.0) * (self.planes - 1) as f32;
        let j0 = (x as usize).min(self.planes - 1);
        let j1 = (j0 + 1).min(self.planes - 1);
        let wj = x - j0 as f32;
        let mut at = HaloAt {
            taps: [(0, 0.0); 16],
            n: 0,
            stride: nt * nl * self.planes * nb,
        };
        near_t.each(|it, wt| {
            cell.l.each(|il, wl| {
                for (j, w) in [(j0, 1.0 - wj), (j1, wj)] {
                    let row = ((it * nl + il) * self.planes + j) * nb;
                    for &(b, wb) in &theta {
                        if at.n < at.taps.len() {
                            at.taps[at.n] = (row + b, wt * wl * w * wb);
                            at.n += 1;
                        }
                    }
                }
            })
        });
        Some(at)
    }
}

impl HaloAt {
    /// e^h of group `g` (1 for the groups the halo does not cover).
    pub(super) fn factor(&self, halo: &Halo, g: usize) -> f32 {
        if g >= halo.groups {
            return 1.0;
        }
        let base = g * self.stride;
        let h = self.taps[..self.n].iter().fold(0.0f32, |s, &(k, w)| {
            s + w * halo.values.get(base + k).unwrap_or(0.0)
        });
        Math::exp(h)
    }
}
