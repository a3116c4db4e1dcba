//! The camera's primary rays: a pinhole at the scene camera's position, looking at its target,
//! with a vertical field of view; pixel (i, j) with row 0 at the top. Shared by the path tracer
//! and the fast renderers, so that both see the very same rays.

use super::geometry::{cross, normalize, Vec3};
use super::scene::Camera;

/// The camera's primary rays: a pinhole at `position`, looking along `fwd`.
pub struct Pinhole {
    /// The eye (m).
    pub position: Vec3,
    fwd: Vec3,
    right: Vec3,
    up: Vec3,
    /// tan(fov_y / 2).
    tan: f64,
    /// Image width and height (pixels).
    pub width: usize,
    /// See `width`.
    pub height: usize,
}

impl Pinhole {
    /// The camera's rays.
    pub fn new(cam: &Camera) -> Self {
        let fwd = normalize(std::array::from_fn(|k| cam.look_at[k] - cam.position[k]));
        let right = normalize(cross(fwd, cam.up));
        Self {
            position: cam.position,
            fwd,
            right,
            up: cross(right, fwd),
            tan: (0.5 * cam.fov_deg.to_radians()).tan(),
            width: cam.width as usize,
            height: cam.height as usize,
        }
    }

    /// The unit direction through (i + u, j + v) in pixel coordinates (row 0 at the top).
    pub fn direction(&self, i: usize, j: usize, u: f64, v: f64) -> Vec3 {
        let (w, h) = (self.width as f64, self.height as f64);
        let x = (2.0 * (i as f64 + u) / w - 1.0) * self.tan * w / h;
        let y = (1.0 - 2.0 * (j as f64 + v) / h) * self.tan;
        normalize(std::array::from_fn(|k| {
            self.fwd[k] + x * self.right[k] + y * self.up[k]
        }))
    }
}
