//! Participating media of the path tracer: an extinction coefficient σ_t(p) (1/m) inside
//! bounds, and a majorant σ̄ ≥ σ_t along any ray for delta tracking.

/// A point or direction in world space (m); z is up.
pub type Vec3 = [f64; 3];

/// The medium as the integrator sees it.
pub trait Medium: Sync {
    /// σ_t at `p` (1/m); 0 outside the medium.
    fn sigma_t(&self, p: Vec3) -> f64;

    /// The segment [t0, t1] (t0 ≥ 0) of the ray o + t w where the medium may be non-zero, or
    /// None if the ray misses it.
    fn clip(&self, o: Vec3, w: Vec3) -> Option<(f64, f64)>;

    /// A majorant σ̄ ≥ σ_t on the ray's segment [t0, t1] (1/m).
    fn majorant(&self, o: Vec3, w: Vec3, t0: f64, t1: f64) -> f64;

    /// The optical depth ∫ σ_t dt over [t0, t1] in closed form, where the medium has one
    /// (homogeneous media): shadow rays then cost nothing and add no noise.
    fn optical_depth(&self, _o: Vec3, _w: Vec3, _t0: f64, _t1: f64) -> Option<f64> {
        None
    }
}

/// A homogeneous slab z ∈ [0, h] (m), unbounded in x and y: the canonical slab of spec 40 with
/// its lit face at z = h.
#[derive(Clone, Copy, Debug)]
pub struct Slab {
    /// Thickness (m).
    pub h: f64,
    /// Extinction coefficient (1/m).
    pub sigma_t: f64,
}

impl Medium for Slab {
    fn sigma_t(&self, p: Vec3) -> f64 {
        if (0.0..=self.h).contains(&p[2]) {
            self.sigma_t
        } else {
            0.0
        }
    }

    fn clip(&self, o: Vec3, w: Vec3) -> Option<(f64, f64)> {
        slab_clip(o[2], w[2], 0.0, self.h)
    }

    fn majorant(&self, _: Vec3, _: Vec3, _: f64, _: f64) -> f64 {
        self.sigma_t
    }

    fn optical_depth(&self, _: Vec3, _: Vec3, t0: f64, t1: f64) -> Option<f64> {
        Some(self.sigma_t * (t1 - t0))
    }
}

/// The parameter range where z0 + t wz lies in [lo, hi], t ≥ 0.
pub fn slab_clip(z0: f64, wz: f64, lo: f64, hi: f64) -> Option<(f64, f64)> {
    if wz.abs() < 1e-300 {
        return (lo..=hi).contains(&z0).then_some((0.0, f64::INFINITY));
    }
    let (a, b) = ((lo - z0) / wz, (hi - z0) / wz);
    let (t0, t1) = (a.min(b).max(0.0), a.max(b));
    (t1 > t0).then_some((t0, t1))
}
