//! Where in the canonical slab the transport is evaluated: one named value instead of five
//! floats of the same type (which invite swapped arguments).
//!
//! The slab: thickness t (mean free paths, mfp), lit from above by the sun at μ_L = cos φ_L;
//! depth d from the lit face (0 ≤ d ≤ t). The view direction is the direction the light
//! travels toward the eye: μ_V its cosine with the upward normal (> 0: going up, toward the
//! lit face), ψ_V its azimuth from the sun's horizontal travel (radians). docs/conventions.md
//! draws the frame.

/// A viewpoint and direction in a slab lit by the sun.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct SlabPoint<F> {
    /// Depth d from the lit face (mfp), 0 ≤ d ≤ t.
    pub depth: F,
    /// Optical thickness t of the slab (mfp), > 0.
    pub thickness: F,
    /// Cosine μ_V of the light's travel toward the eye with the upward normal (> 0: up).
    pub mu_v: F,
    /// Azimuth ψ_V of that travel from the sun's horizontal travel (radians).
    pub psi_v: F,
    /// Sun cosine μ_L ∈ (0, 1].
    pub mu_l: F,
}

impl<F: Copy> SlabPoint<F> {
    /// The point in the argument order of the C ABI, Python, WGSL and the command line:
    /// thickness t (mfp), sun cosine μ_L, depth d (mfp), view cosine μ_V, azimuth ψ_V
    /// (radians).
    pub const fn new(thickness: F, mu_l: F, depth: F, mu_v: F, psi_v: F) -> Self {
        Self {
            depth,
            thickness,
            mu_v,
            psi_v,
            mu_l,
        }
    }

    /// The same place and sun, another view direction.
    pub fn with_view(self, mu_v: F, psi_v: F) -> Self {
        Self {
            mu_v,
            psi_v,
            ..self
        }
    }
}

impl SlabPoint<f64> {
    /// The point rounded to f32, as a renderer would ask for it.
    pub fn to_f32(&self) -> SlabPoint<f32> {
        SlabPoint {
            depth: self.depth as f32,
            thickness: self.thickness as f32,
            mu_v: self.mu_v as f32,
            psi_v: self.psi_v as f32,
            mu_l: self.mu_l as f32,
        }
    }
}

impl SlabPoint<f32> {
    /// The slab's optical path beyond the viewpoint, away from the eye (mfp): (t − d)/μ_V
    /// going up, d/|μ_V| going down, +∞ for a horizontal view. The slab's radiance at the
    /// viewpoint gathers its sources over this path, with opacity 1 − e^{−path}; a view ray
    /// of opacity α gathers them over its own, so a renderer weighs T by
    /// [`view_weight`](Self::view_weight) (docs/collector.md, "Thin matter").
    pub fn path_behind(&self) -> f32 {
        if self.mu_v > 0.0 {
            (self.thickness - self.depth) / self.mu_v
        } else if self.mu_v < 0.0 {
            self.depth / -self.mu_v
        } else {
            f32::INFINITY
        }
    }

    /// The weight of T at this point in a pixel whose view ray has opacity `alpha`:
    /// α / (1 − e^{−path}), the path's opacity held ≥ 10⁻³. T is the radiance at p of the
    /// slab's sources over its own path beyond p; the pixel holds them over the whole ray, so
    /// α alone would count a thin ray's thinness twice (a silhouette's orders ≥ 2 came out at
    /// 0.3–0.4 of the truth at opacities 0.05–0.5). α where the slab's path is opaque.
    pub fn view_weight(&self, alpha: f32) -> f32 {
        let opacity = -crate::real::exp_m1(-self.path_behind());
        alpha / opacity.max(1e-3)
    }

    /// The point in f64 (exactly), for an f64 reference evaluation.
    pub fn to_f64(&self) -> SlabPoint<f64> {
        SlabPoint {
            depth: self.depth as f64,
            thickness: self.thickness as f64,
            mu_v: self.mu_v as f64,
            psi_v: self.psi_v as f64,
            mu_l: self.mu_l as f64,
        }
    }

    /// Whether the point is in a slab the tables can be read at: t finite and > 0,
    /// 0 ≤ d ≤ t, μ_L finite and > 0, μ_V and ψ_V finite. Elsewhere every T and order 1 is 0,
    /// so a caller computing d or μ_L from positions clamps them first (d a few ulps below 0
    /// at the lit face, μ_L at +0 for a grazing sun: `local_slab` does). Cosines past 1 by
    /// rounding are taken as they are (finite, within rounding of the value at 1).
    pub fn in_slab(&self) -> bool {
        self.thickness > 0.0
            && self.thickness.is_finite()
            && self.depth >= 0.0
            && self.depth <= self.thickness
            && self.mu_l > 0.0
            && self.mu_l.is_finite()
            && self.mu_v.is_finite()
            && self.psi_v.is_finite()
    }
}

/// Cosines are taken up to 1 + this, the rounding of a cosine computed from unit vectors in
/// f32 (a few ulps); past it a cosine is an error.
pub const COSINE_SLACK: f32 = 1e-6;

/// Why a point is not in the canonical slab: the coordinate and the caller's value.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum PointError {
    /// t is not finite and > 0 (mfp).
    Thickness(f32),
    /// μ_L is not in (0, 1].
    SunCosine(f32),
    /// d is not in [0, t] (mfp).
    Depth { depth: f32, thickness: f32 },
    /// μ_V is not in [−1, 1].
    ViewCosine(f32),
    /// ψ_V is not finite (radians).
    Azimuth(f32),
}

impl core::fmt::Display for PointError {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        match *self {
            PointError::Thickness(t) => {
                write!(f, "t = {t} mfp is not a thickness (finite, > 0)")
            }
            PointError::SunCosine(m) => write!(
                f,
                "mu_L = {m} is not a sun cosine in (0, 1] (a sun below the horizon lights no slab)"
            ),
            PointError::Depth { depth, thickness } => {
                write!(
                    f,
                    "depth = {depth} mfp is outside the slab [0, t = {thickness}]"
                )
            }
            PointError::ViewCosine(m) => write!(f, "mu_V = {m} is not a cosine in [-1, 1]"),
            PointError::Azimuth(p) => write!(f, "psi_V = {p} rad is not a finite angle"),
        }
    }
}

impl SlabPoint<f32> {
    /// The point checked: t finite and > 0, μ_L ∈ (0, 1], 0 ≤ d ≤ t, μ_V ∈ [−1, 1] and ψ_V
    /// finite (the cosines up to [`COSINE_SLACK`] past 1). What every interface refuses
    /// before it evaluates; [`Self::in_slab`] is the renderer's looser test.
    pub fn check(&self) -> Result<(), PointError> {
        let cosine = |m: f32| m.abs() <= 1.0 + COSINE_SLACK;
        if !(self.thickness > 0.0 && self.thickness.is_finite()) {
            return Err(PointError::Thickness(self.thickness));
        }
        if !(self.mu_l > 0.0 && cosine(self.mu_l)) {
            return Err(PointError::SunCosine(self.mu_l));
        }
        if !(self.depth >= 0.0 && self.depth <= self.thickness) {
            return Err(PointError::Depth {
                depth: self.depth,
                thickness: self.thickness,
            });
        }
        if !cosine(self.mu_v) {
            return Err(PointError::ViewCosine(self.mu_v));
        }
        if !self.psi_v.is_finite() {
            return Err(PointError::Azimuth(self.psi_v));
        }
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::{PointError, SlabPoint};

    /// Every coordinate outside the slab, NaN and ±∞ among them, is refused by name; the
    /// edges (d = 0, d = t, μ_L = 1, μ_V = ±1, ±0) and cosines within rounding of 1 are not.
    #[test]
    fn points_outside_the_slab_are_refused_by_coordinate() {
        let ok = at(3.0, -0.6);
        assert_eq!(ok.check(), Ok(()));
        for edge in [at(0.0, 1.0), at(10.0, -1.0), at(5.0, 0.0), at(5.0, -0.0)] {
            assert_eq!(edge.check(), Ok(()), "{edge:?}");
        }
        assert_eq!(at(5.0, 1.000_000_1).check(), Ok(()));
        let bad = |f: fn(&mut SlabPoint<f32>)| {
            let mut p = ok;
            f(&mut p);
            p.check().unwrap_err()
        };
        assert_eq!(bad(|p| p.thickness = 0.0), PointError::Thickness(0.0));
        for v in [-1.0, f32::NAN, f32::INFINITY] {
            let mut p = ok;
            p.thickness = v;
            assert!(matches!(p.check(), Err(PointError::Thickness(_))), "{v}");
        }
        for v in [
            0.0,
            -0.0,
            -0.3,
            1.5,
            f32::NAN,
            f32::INFINITY,
            f32::NEG_INFINITY,
        ] {
            let mut p = ok;
            p.mu_l = v;
            assert!(matches!(p.check(), Err(PointError::SunCosine(_))), "{v}");
        }
        for v in [-1e-3, 10.5, f32::NAN, f32::INFINITY] {
            let mut p = ok;
            p.depth = v;
            assert!(matches!(p.check(), Err(PointError::Depth { .. })), "{v}");
        }
        for v in [2.0, -1.01, f32::NAN, f32::NEG_INFINITY] {
            let mut p = ok;
            p.mu_v = v;
            assert!(matches!(p.check(), Err(PointError::ViewCosine(_))), "{v}");
        }
        for v in [f32::NAN, f32::INFINITY] {
            let mut p = ok;
            p.psi_v = v;
            assert!(matches!(p.check(), Err(PointError::Azimuth(_))), "{v}");
        }
        assert_eq!(
            bad(|p| p.mu_l = 1.5).to_string(),
            "mu_L = 1.5 is not a sun cosine in (0, 1] (a sun below the horizon lights no slab)"
        );
    }

    fn at(depth: f32, mu_v: f32) -> SlabPoint<f32> {
        SlabPoint {
            depth,
            thickness: 10.0,
            mu_v,
            psi_v: 0.0,
            mu_l: 0.8,
        }
    }

    /// The slab's path beyond p: to the far face going up, to the lit face going down,
    /// unbounded along the faces; a thin path raises the weight above α, an opaque one keeps α.
    #[test]
    fn the_path_behind_and_the_view_weight() {
        assert_eq!(at(6.0, 0.5).path_behind(), 8.0);
        assert_eq!(at(6.0, -0.5).path_behind(), 12.0);
        assert_eq!(at(6.0, 0.0).path_behind(), f32::INFINITY);
        let thin = at(9.9, 0.5);
        let want = 0.3 / (1.0 - (-0.2f64).exp());
        assert!((thin.view_weight(0.3) as f64 - want).abs() < 1e-5 * want);
        assert!((at(6.0, 0.0).view_weight(0.3) - 0.3).abs() < 1e-7);
        assert!((at(0.0, 0.5).view_weight(0.3) - 0.3).abs() < 1e-6);
        // At the far face seen going up the path is 0: the weight is held finite.
        assert!((at(10.0, 0.5).view_weight(0.3) - 300.0).abs() < 1e-3);
    }

    #[test]
    fn new_takes_the_interfaces_order() {
        let p = SlabPoint::new(8.0f32, 0.5, 2.0, -0.6, 0.35);
        let named = SlabPoint {
            thickness: 8.0,
            mu_l: 0.5,
            depth: 2.0,
            mu_v: -0.6,
            psi_v: 0.35,
        };
        assert_eq!(p, named);
    }
}
