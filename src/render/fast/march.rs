//! Ray marching through a medium for the fast renderers: sub-steps of at most a given length
//! with the extinction on each, read from the majorant grid where a cell is homogeneous (no
//! lookup) and at the sub-step's midpoint elsewhere; empty cells are skipped.

use crate::render::geometry::Vec3;
use crate::render::medium::Medium;
use std::ops::ControlFlow;

/// Calls `f(a, b, σ)` on consecutive sub-steps [a, b] (b − a ≤ `step`) of the ray o + t w
/// within `range`, σ the extinction there (1/m), until `f` breaks; returns the break value.
pub fn substeps<B>(
    medium: &dyn Medium,
    o: Vec3,
    w: Vec3,
    range: (f64, f64),
    step: f64,
    mut f: impl FnMut(f64, f64, f64) -> ControlFlow<B>,
) -> Option<B> {
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
                medium.sigma_t(std::array::from_fn(|i| o[i] + m * w[i]))
            };
            f(s0, s1, sigma)?;
        }
        ControlFlow::Continue(())
    })
}
