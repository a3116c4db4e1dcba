//! Vectors, ray–box clipping and affine maps in world space (m, z up): what the media, the
//! majorant grids and the camera share.

pub use nephele_runtime::frame::{cross, dot};

/// A point or direction in world space (m); z is up (the runtime's vector, in f64).
pub type Vec3 = nephele_runtime::frame::Vec3<f64>;

/// The distance below which a ray leaving a surface point meets that same surface again (m):
/// 10⁻⁹ of the point's distance from the world's origin, at least 10⁻⁹ m — a rounding error
/// of the point, not a new hit.
pub fn self_hit_distance(o: Vec3) -> f64 {
    1e-9 * dot(o, o).sqrt().max(1.0)
}

/// a / |a|.
pub fn normalize(a: Vec3) -> Vec3 {
    let n = dot(a, a).sqrt();
    a.map(|x| x / n)
}

/// Whether p lies outside the closed box [lo, hi] (a NaN coordinate counts as inside, as
/// the comparisons have it).
#[inline]
pub fn outside_box(p: Vec3, lo: Vec3, hi: Vec3) -> bool {
    (0..3).any(|k| p[k] < lo[k] || p[k] > hi[k])
}

/// The parameter range where o + t w lies in the box [lo, hi], t ≥ 0.
pub fn box_clip(o: Vec3, w: Vec3, lo: Vec3, hi: Vec3) -> Option<(f64, f64)> {
    let (mut t0, mut t1) = (0.0f64, f64::INFINITY);
    for k in 0..3 {
        let (a, b) = slab_clip(o[k], w[k], lo[k], hi[k])?;
        t0 = t0.max(a);
        t1 = t1.min(b);
    }
    (t1 > t0).then_some((t0, t1))
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

/// An affine map p ↦ M p + b, and its inverse: a voxel grid's unit cube to the world. Ray
/// parameters are kept by the inverse map (o + t w ↦ M⁻¹(o − b) + t M⁻¹ w, the direction not
/// renormalised), so clipping and tracking in the grid's own coordinates give world distances.
#[derive(Clone, Copy, Debug)]
pub struct Affine {
    m: [[f64; 3]; 3],
    t: Vec3,
    inv: [[f64; 3]; 3],
    /// M is diagonal: the inverse divides by its entries (exact at voxel centres).
    diagonal: bool,
}

impl Affine {
    /// The map p ↦ M p + b (b = `t`), or None if M is singular.
    pub fn new(m: [[f64; 3]; 3], t: Vec3) -> Option<Self> {
        let c = |r: usize, k: usize| {
            m[(r + 1) % 3][(k + 1) % 3] * m[(r + 2) % 3][(k + 2) % 3]
                - m[(r + 1) % 3][(k + 2) % 3] * m[(r + 2) % 3][(k + 1) % 3]
        };
        let det = m[0][0] * c(0, 0) + m[0][1] * c(0, 1) + m[0][2] * c(0, 2);
        if !(det.abs() > 1e-300 && det.is_finite()) {
            return None;
        }
        // The inverse is the transposed cofactor matrix over the determinant.
        let inv = std::array::from_fn(|r| std::array::from_fn(|k| c(k, r) / det));
        let diagonal = (0..3).all(|r| (0..3).all(|k| r == k || m[r][k] == 0.0));
        Some(Self {
            m,
            t,
            inv,
            diagonal,
        })
    }

    /// The box [origin, origin + size] as the image of the unit cube.
    pub fn from_box(origin: Vec3, size: Vec3) -> Self {
        let m =
            std::array::from_fn(|r| std::array::from_fn(|k| if r == k { size[r] } else { 0.0 }));
        Self::new(m, origin).expect("a box of positive size")
    }

    /// The length of the image of the unit vector along local axis `k` (a column of M).
    pub fn axis_length(&self, k: usize) -> f64 {
        (0..3).map(|r| self.m[r][k].powi(2)).sum::<f64>().sqrt()
    }

    /// M p + b.
    pub fn apply(&self, p: Vec3) -> Vec3 {
        std::array::from_fn(|r| dot(self.m[r], p) + self.t[r])
    }

    /// M⁻¹ (p − b).
    pub fn local_point(&self, p: Vec3) -> Vec3 {
        self.local_dir(std::array::from_fn(|k| p[k] - self.t[k]))
    }

    /// M⁻¹ w.
    pub fn local_dir(&self, w: Vec3) -> Vec3 {
        if self.diagonal {
            return std::array::from_fn(|k| w[k] / self.m[k][k]);
        }
        std::array::from_fn(|r| dot(self.inv[r], w))
    }
}
