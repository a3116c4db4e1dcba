//! Ray marching through a medium for the fast renderers: sub-steps of at most a given length
//! with the extinction on each, read from the majorant grid where a cell is homogeneous (no
//! lookup) and at the sub-step's midpoint elsewhere; empty cells are skipped.

use crate::render::geometry::Vec3;
use crate::render::medium::Medium;
use std::ops::ControlFlow;

/// Calls `f(a, b, σ)` on consecutive sub-steps [a, b] (b − a ≤ `step`) of the ray o + t w
/// within `range`, σ the extinction there (1/m), until `f` breaks; returns the break value.
///
/// A lookup's reach ([`Medium::sigma_t_reach`]: the distance within which σ is the same) is
/// kept along the ray, across cells: the sub-steps whose midpoints lie within it take that σ
/// without a lookup of their own (the same bits as looking up; most of a noisy boundary's
/// clear sub-steps on the default cloud).
pub fn substeps<B>(
    medium: &dyn Medium,
    o: Vec3,
    w: Vec3,
    range: (f64, f64),
    step: f64,
    mut f: impl FnMut(f64, f64, f64) -> ControlFlow<B>,
) -> Option<B> {
    let speed = w.iter().map(|x| x * x).sum::<f64>().sqrt();
    // σ holds up to the ray parameter `until` (none yet).
    let (mut until, mut held) = (f64::NEG_INFINITY, 0.0);
    medium.majorants().walk(o, w, range, |a, b, bounds| {
        if bounds.max <= 0.0 || b <= a {
            return ControlFlow::Continue(());
        }
        let n = ((b - a) / step).ceil().max(1.0);
        let h = (b - a) / n;
        for k in 0..n as usize {
            let (s0, s1) = (a + k as f64 * h, a + (k + 1) as f64 * h);
            let sigma = if bounds.homogeneous() {
                bounds.max
            } else {
                let m = 0.5 * (s0 + s1);
                if m > until {
                    let (sigma, reach) =
                        medium.sigma_t_reach(std::array::from_fn(|i| o[i] + m * w[i]));
                    (until, held) = (m + reach / speed, sigma);
                }
                held
            };
            f(s0, s1, sigma)?;
        }
        ControlFlow::Continue(())
    })
}
