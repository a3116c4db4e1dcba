//! Views on an orbit from one set of light maps and one sky table (`nephele render --orbit N`):
//! the camera turned about the vertical through its look-at point. Each view is bit for bit its
//! camera rendered alone (`tests/render_views.rs`); only the pixels are paid per view.

use super::Prepared;
use crate::render::image::Rendered;
use crate::render::scene::{Camera, Scene};
use anyhow::Result;

/// View `k` of `n` on the orbit of `cam`: its position turned by 360° k/n about the vertical
/// through its look-at point.
pub fn orbit_camera(cam: &Camera, k: usize, n: usize) -> Camera {
    let phi = std::f64::consts::TAU * k as f64 / n as f64;
    let (s, c) = phi.sin_cos();
    let d = [0, 1].map(|i| cam.position[i] - cam.look_at[i]);
    let mut out = *cam;
    out.position[0] = cam.look_at[0] + c * d[0] - s * d[1];
    out.position[1] = cam.look_at[1] + s * d[0] + c * d[1];
    out
}

/// Renders the `n` views of `scene`'s orbit with `prepared`, handing each to `each(k, view,
/// rendered)` as it finishes (to write it: one frame is held at a time); `progress` gets the
/// fraction of all views done.
pub fn render_orbit(
    prepared: &Prepared,
    scene: &Scene,
    n: usize,
    progress: &(dyn Fn(f64) + Sync),
    each: &mut dyn FnMut(usize, &Scene, &Rendered) -> Result<()>,
) -> Result<()> {
    for k in 0..n {
        let mut view = scene.clone();
        view.camera = orbit_camera(&scene.camera, k, n);
        let r = prepared.render(&view.camera, &|done| progress((k as f64 + done) / n as f64));
        each(k, &view, &r)?;
    }
    Ok(())
}
