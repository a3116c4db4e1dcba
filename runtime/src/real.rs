//! The floating-point types the runtime works in: `f32` (what renderers use) and `f64` (what
//! the generators use), with the few math functions the evaluators need — from `std`, or from
//! `libm` in `no_std` builds (as glam does).

use core::ops::{Add, Div, Mul, Neg, Sub};

/// `f32` or `f64`.
pub trait Real:
    Copy
    + PartialOrd
    + core::fmt::Debug
    + Add<Output = Self>
    + Sub<Output = Self>
    + Mul<Output = Self>
    + Div<Output = Self>
    + Neg<Output = Self>
{
    /// π.
    const PI: Self;
    /// Converts from f64 (rounding for f32).
    fn of(v: f64) -> Self;
    /// Converts to f64 (exact).
    fn f64(self) -> f64;
    /// √x.
    fn sqrt(self) -> Self;
    /// eˣ.
    fn exp(self) -> Self;
    /// ln x.
    fn ln(self) -> Self;
    /// |x|.
    fn abs(self) -> Self;
    /// (sin x, cos x).
    fn sin_cos(self) -> (Self, Self);
    /// ∛x.
    fn cbrt(self) -> Self;
    /// asin x.
    fn asin(self) -> Self;
    /// Clamps to [lo, hi].
    fn clamp_to(self, lo: Self, hi: Self) -> Self {
        if self < lo {
            lo
        } else if self > hi {
            hi
        } else {
            self
        }
    }
}

macro_rules! impl_real {
    ($t:ident, $sqrt:ident, $exp:ident, $ln:ident, $sin:ident, $cos:ident, $cbrt:ident, $asin:ident) => {
        impl Real for $t {
            const PI: Self = core::$t::consts::PI;
            #[inline]
            fn of(v: f64) -> Self {
                v as $t
            }
            #[inline]
            fn f64(self) -> f64 {
                self as f64
            }
            #[cfg(feature = "std")]
            #[inline]
            fn sqrt(self) -> Self {
                $t::sqrt(self)
            }
            #[cfg(feature = "std")]
            #[inline]
            fn exp(self) -> Self {
                $t::exp(self)
            }
            #[cfg(feature = "std")]
            #[inline]
            fn ln(self) -> Self {
                $t::ln(self)
            }
            #[cfg(feature = "std")]
            #[inline]
            fn sin_cos(self) -> (Self, Self) {
                $t::sin_cos(self)
            }
            #[cfg(feature = "std")]
            #[inline]
            fn cbrt(self) -> Self {
                $t::cbrt(self)
            }
            #[cfg(feature = "std")]
            #[inline]
            fn asin(self) -> Self {
                $t::asin(self)
            }
            #[cfg(not(feature = "std"))]
            #[inline]
            fn asin(self) -> Self {
                libm::$asin(self)
            }
            #[cfg(not(feature = "std"))]
            #[inline]
            fn cbrt(self) -> Self {
                libm::$cbrt(self)
            }
            #[cfg(not(feature = "std"))]
            #[inline]
            fn sqrt(self) -> Self {
                libm::$sqrt(self)
            }
            #[cfg(not(feature = "std"))]
            #[inline]
            fn exp(self) -> Self {
                libm::$exp(self)
            }
            #[cfg(not(feature = "std"))]
            #[inline]
            fn ln(self) -> Self {
                libm::$ln(self)
            }
            #[cfg(not(feature = "std"))]
            #[inline]
            fn sin_cos(self) -> (Self, Self) {
                (libm::$sin(self), libm::$cos(self))
            }
            #[inline]
            fn abs(self) -> Self {
                if self < 0.0 {
                    -self
                } else {
                    self
                }
            }
        }
    };
}

impl_real!(f32, sqrtf, expf, logf, sinf, cosf, cbrtf, asinf);
impl_real!(f64, sqrt, exp, log, sin, cos, cbrt, asin);
