//! p's depth to the sun as the scattered light of one order group sees it (docs/collector.md,
//! "The sun's depth, spread across the light").
//!
//! The local slab holds p no deeper than its own optical depth to the sun, d_☉ = μ_L τ_☉
//! ([`super::local_slab`]). τ_☉ is the depth along one straight line; light of order n reaches
//! p along walks that have spread across the light by ⟨r⊥²⟩ = 4 D n⊥(n) (mfp²; D = 1/(3(1 − g)),
//! n⊥ the walk's lateral orders, [`lateral_orders`]). So group g reads τ_☉ averaged over a disk
//! of that radius around p across the light:
//!
//! ```text
//!     τ_g = ⅕ [τ_☉(p) + Σ_{k=1..4} τ_☉(p + r_g e_k)],   r_g = √(4 D n⊥(n̄_g)) / κ̄  (m),
//! ```
//!
//! e_k = ±e₁, ±e₂ unit vectors across the light, n̄_g the group's middle order (the open last
//! group: twice its first), κ̄ the cloud's extinction along the light at the cloud's own scale
//! (the search's first read; 1/m). No fitted constant: for g = 0.854 order 2 spreads by
//! 0.6 mfp and keeps nearly p's own depth, orders 19–30 by 11.8 mfp, the open group 31+ (read
//! at order 62) by 21.9 mfp. A tap outside the cloud counts τ = 0: light does not reach p from
//! where there is no cloud.

use super::leakage::{diffusion_coefficient, lateral_orders};
use super::surface::{LitSurface, SearchOptions, Viewpoint};
use super::tables::{group_orders, TransportTables};
use crate::frame::{orthonormal_basis, Vec3};
use crate::real::Math;

/// The lateral spread (mfp) of the light of the orders `first ..= last` (None: no end) for a
/// phase function of mean cosine `g`: √(4 D n⊥(n̄)), n̄ = (first + last)/2 or 2 first.
pub fn group_spread(first: f32, last: Option<f32>, g: f32) -> f32 {
    let middle = last.map_or(2.0 * first, |b| 0.5 * (first + b));
    let across = lateral_orders(middle, g);
    Math::sqrt((4.0 * diffusion_coefficient(g) * across).max(0.0))
}

/// The viewpoint group `g`'s search reads: `v` with p's depth to the sun averaged over the
/// group's spread ([`spread_sun_depth`], the spread in metres at the cloud's extinction
/// `extinction`, 1/m) when `opts.sun_spread` is set and the surface knows the sun's depth;
/// `v` as it is otherwise.
pub(crate) fn group_viewpoint<S: LitSurface + ?Sized>(
    tables: &TransportTables,
    g: usize,
    surface: &S,
    v: &Viewpoint,
    sun: Vec3<f32>,
    extinction: f32,
    opts: &SearchOptions,
) -> Viewpoint {
    let Some(mean_cosine) = opts.sun_spread else {
        return *v;
    };
    if !(extinction > 0.0) {
        return *v;
    }
    let (first, last) = group_orders(tables, g);
    let radius = group_spread(first, last, mean_cosine) / extinction;
    match spread_sun_depth(surface, v.position, sun, v.sun_depth, radius) {
        Some(sun_depth) => Viewpoint { sun_depth, ..*v },
        None => *v,
    }
}

/// τ_☉ (mfp) averaged over p and four points `radius` metres from it across the light toward
/// `sun` (unit), `own` = τ_☉(p) (the renderer's): None where the surface does not know the
/// sun's depth (or gives a negative one), or `own` is not finite (no cloud toward the sun).
pub fn spread_sun_depth<S: LitSurface + ?Sized>(
    surface: &S,
    p: Vec3<f32>,
    sun: Vec3<f32>,
    own: f32,
    radius: f32,
) -> Option<f32> {
    if !own.is_finite() || !(radius > 0.0) {
        return None;
    }
    let (e1, e2) = orthonormal_basis(sun);
    let mut sum = own;
    for (e, s) in [(e1, 1.0f32), (e1, -1.0), (e2, 1.0), (e2, -1.0)] {
        let q = core::array::from_fn(|k| p[k] + s * radius * e[k]);
        let tau = surface.sun_depth(q)?;
        if !(tau >= 0.0) {
            return None;
        }
        sum += tau;
    }
    let mean = sum / 5.0;
    mean.is_finite().then_some(mean)
}

#[cfg(all(test, feature = "std"))]
mod tests {
    use super::*;
    use crate::transport::FilteredSurface;

    /// A sun's depth that grows linearly below z = 0: τ_☉ = max(0, −z).
    struct Ground;

    impl LitSurface for Ground {
        fn filtered(&self, _at: Vec3<f32>, _sigma: f32) -> Option<FilteredSurface> {
            None
        }
        fn initial_scale(&self) -> f32 {
            1.0
        }
        fn sun_depth(&self, at: Vec3<f32>) -> Option<f32> {
            Some((-at[2]).max(0.0))
        }
    }

    #[test]
    fn the_spread_grows_with_the_order() {
        let g = 0.86;
        let two = group_spread(2.0, Some(2.0), g);
        assert!((two - 0.59).abs() < 0.02, "{two}");
        let mut prev = two;
        for (a, b) in [
            (3.0, Some(4.0)),
            (9.0, Some(12.0)),
            (19.0, Some(30.0)),
            (31.0, None),
        ] {
            let r = group_spread(a, b, g);
            assert!(r > prev, "{a}: {r}");
            prev = r;
        }
        // Isotropic scattering: n⊥ = ⅔ n, D = ⅓.
        let iso = group_spread(6.0, Some(6.0), 0.0);
        assert!((iso - (4.0f32 / 3.0 * lateral_orders(6.0, 0.0)).sqrt()).abs() < 1e-5);
    }

    #[test]
    fn a_plane_keeps_its_depth_and_unknown_depths_give_none() {
        let sun = [0.0, 0.0, 1.0];
        let p = [0.3, -0.2, -2.0];
        let got = spread_sun_depth(&Ground, p, sun, 2.0, 5.0).unwrap();
        assert!((got - 2.0).abs() < 1e-5, "{got}");
        assert_eq!(spread_sun_depth(&Ground, p, sun, f32::INFINITY, 5.0), None);
        assert_eq!(spread_sun_depth(&Ground, p, sun, 2.0, 0.0), None);
        // An oblique sun: the taps across the light go up and down by the same amounts, so a
        // depth linear in z averages to p's own; where the disk reaches above z = 0 the taps
        // there count 0 where a line would go negative, and the mean rises.
        let sun = [0.6, 0.0, 0.8];
        let got = spread_sun_depth(&Ground, p, sun, 2.0, 1.0).unwrap();
        assert!((got - 2.0).abs() < 1e-5, "{got}");
        let wide = spread_sun_depth(&Ground, p, sun, 2.0, 5.0).unwrap();
        assert!(wide > 2.0, "{wide}");
    }
}
