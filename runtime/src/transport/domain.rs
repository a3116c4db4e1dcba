//! Where the transport tables hold information ([`Domain`]: the thicknesses and sun cosines of
//! their grid) and where a point lies outside it ([`Outside`], tallied over many points by
//! [`OutsideTally`]).

use super::geometry::SlabPoint;
use crate::real::{Math, Real};

/// Where the tables hold information: the thicknesses and sun cosines of their grid. Every
/// other coordinate is covered whole (d ∈ [0, t], μ_V ∈ [−1, 1] with the horizon, any ψ_V).
/// Past the thickest slab the tables continue by diffusion theory ([`super::thick`]); below
/// the thinnest slab the form's parameters are held at the grid's end while the geometry (the
/// boundary factor, the single-scattering factor, the scattering angle) follows the point;
/// below the lowest sun μ₀ the point is read under μ₀ and T scaled by μ_L/μ₀ (T/μ_L, the
/// radiance per unit irradiance on the lit face, is held). Finite and bounded, an
/// extrapolation a caller detects with [`Domain::outside`].
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Domain {
    /// Smallest and largest thickness (mfp).
    pub thickness: (f32, f32),
    /// Smallest and largest sun cosine.
    pub mu_l: (f32, f32),
}

/// Where a point in the slab lies outside the tables' grid, and by how much: each coordinate
/// past its end, None where it is within. Past the thickest slab the tables continue by
/// diffusion theory (docs/compress.md, "Past the thickest slab"); below the thinnest the
/// form's parameters are held at the grid's end; below the lowest sun T/μ_L is held.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct Outside {
    /// The point's t when it is outside the grid's thicknesses (mfp).
    pub thickness: Option<f32>,
    /// The point's μ_L when it is below the grid's lowest sun cosine.
    pub mu_l: Option<f32>,
}

impl Outside {
    /// t above the thickest slab (continued by diffusion).
    pub const THICKER: u32 = 1;
    /// t below the thinnest slab (held).
    pub const THINNER: u32 = 2;
    /// μ_L below the lowest sun cosine (read under it, T scaled by μ_L/μ₀).
    pub const LOWER_SUN: u32 = 4;

    /// Whether the point is within the grid.
    pub fn is_within(&self) -> bool {
        self.thickness.is_none() && self.mu_l.is_none()
    }

    /// The flags as bits ([`Self::THICKER`], [`Self::THINNER`], [`Self::LOWER_SUN`]) given
    /// the domain the point was placed in.
    pub fn bits(&self, domain: &Domain) -> u32 {
        let mut b = 0;
        if let Some(t) = self.thickness {
            b |= if t > domain.thickness.1 {
                Self::THICKER
            } else {
                Self::THINNER
            };
        }
        if self.mu_l.is_some() {
            b |= Self::LOWER_SUN;
        }
        b
    }
}

/// What a caller says of a point outside the grid: each coordinate, its value against the
/// grid's end, and what the tables do there ([`Outside::describe`]).
pub struct OutsideText<'a>(&'a Outside, &'a Domain);

impl core::fmt::Display for OutsideText<'_> {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        let (o, d) = (self.0, self.1);
        let mut sep = "";
        if let Some(t) = o.thickness {
            if t > d.thickness.1 {
                write!(f, "t = {t} mfp is past the tables' thickest slab ({} mfp): continued by diffusion theory", d.thickness.1)?;
            } else {
                write!(
                    f,
                    "t = {t} mfp is below the tables' thinnest slab ({} mfp): held there",
                    d.thickness.0
                )?;
            }
            sep = "; ";
        }
        if let Some(m) = o.mu_l {
            let deg = |mu: f32| Math::asin(mu as f64) * 180.0 / f64::PI;
            write!(
                f,
                "{sep}mu_L = {m} (sun {:.1} deg up) is below the tables' lowest sun ({} = {:.1} deg up): read there, T scaled by mu_L",
                deg(m),
                d.mu_l.0,
                deg(d.mu_l.0)
            )?;
        }
        Ok(())
    }
}

impl Outside {
    /// A one-line description ("t = 500 mfp is past the tables' thickest slab (128 mfp):
    /// continued by diffusion theory"); empty within the grid.
    pub fn describe<'a>(&'a self, domain: &'a Domain) -> OutsideText<'a> {
        OutsideText(self, domain)
    }
}

/// Points outside the grid counted: how many, and the farthest of each kind. What a renderer
/// that evaluates many points says once at the end.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct OutsideTally {
    /// Points counted.
    pub points: u64,
    /// Points past the thickest slab, and the largest t among them (mfp).
    pub thicker: (u64, f32),
    /// Points below the thinnest slab, and the smallest t.
    pub thinner: (u64, f32),
    /// Points below the lowest sun, and the smallest μ_L.
    pub lower_sun: (u64, f32),
}

impl OutsideTally {
    /// Counts one point.
    pub fn add(&mut self, o: &Outside, domain: &Domain) {
        self.points += 1;
        if let Some(t) = o.thickness {
            if t > domain.thickness.1 {
                self.thicker = (self.thicker.0 + 1, self.thicker.1.max(t));
            } else {
                let lo = if self.thinner.0 == 0 {
                    t
                } else {
                    self.thinner.1.min(t)
                };
                self.thinner = (self.thinner.0 + 1, lo);
            }
        }
        if let Some(m) = o.mu_l {
            let lo = if self.lower_sun.0 == 0 {
                m
            } else {
                self.lower_sun.1.min(m)
            };
            self.lower_sun = (self.lower_sun.0 + 1, lo);
        }
    }

    /// Adds another tally (of another thread's points).
    pub fn merge(&mut self, o: &OutsideTally) {
        let pick = |a: (u64, f32), b: (u64, f32), f: fn(f32, f32) -> f32| match (a.0, b.0) {
            (0, _) => b,
            (_, 0) => a,
            _ => (a.0 + b.0, f(a.1, b.1)),
        };
        self.points += o.points;
        self.thicker = pick(self.thicker, o.thicker, f32::max);
        self.thinner = pick(self.thinner, o.thinner, f32::min);
        self.lower_sun = pick(self.lower_sun, o.lower_sun, f32::min);
    }
}

impl Domain {
    /// Which of `at`'s coordinates lie outside the grid (t, μ_L), with their values.
    pub fn outside(&self, at: &SlabPoint<f32>) -> Outside {
        let past = |x: f32, (a, b): (f32, f32)| (!(x >= a && x <= b)).then_some(x);
        Outside {
            thickness: past(at.thickness, self.thickness),
            mu_l: past(at.mu_l, (self.mu_l.0, f32::INFINITY)),
        }
    }

    /// Whether `at` is inside: t and μ_L within the grid (ends included), 0 ≤ d ≤ t and
    /// −1 ≤ μ_V ≤ 1.
    pub fn contains(&self, at: &SlabPoint<f32>) -> bool {
        let within = |x: f32, (a, b): (f32, f32)| x >= a && x <= b;
        within(at.thickness, self.thickness)
            && within(at.mu_l, self.mu_l)
            && within(at.depth, (0.0, at.thickness))
            && within(at.mu_v, (-1.0, 1.0))
    }
}
