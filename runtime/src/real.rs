//! The floating-point types the runtime works in: `f32` (what renderers use) and `f64` (what
//! the generators use), with the few math functions the evaluators need. They come from `std`
//! (default), else from the `libm` crate (feature `libm`, as glam does), else from the small
//! built-in `soft_math` so that a bare `--no-default-features` build still works.

use core::ops::{Add, Div, Mul, Neg, Sub};

/// `f32` or `f64`: what the evaluators are generic over. Sealed: no other type implements it,
/// and its math (the runtime's own, from `std`, `libm` or the built-in fallback) is not part of
/// the crate's interface.
pub trait Real:
    Copy
    + PartialOrd
    + core::fmt::Debug
    + Add<Output = Self>
    + Sub<Output = Self>
    + Mul<Output = Self>
    + Div<Output = Self>
    + Neg<Output = Self>
    + sealed::Math
{
    /// π.
    const PI: Self;
    /// Significand bits, the implicit one included (24 for f32, 53 for f64).
    const DIGITS: u32;
    /// Converts from f64 (rounding for f32).
    fn of(v: f64) -> Self;
    /// Converts to f64 (exact).
    fn f64(self) -> f64;
}

pub(crate) use sealed::Math;

mod sealed {
    /// The few math functions the evaluators need, on f32 and f64 alike.
    pub trait Math: Sized + PartialOrd {
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
}

macro_rules! impl_real {
    ($t:ident, $sqrt:path, $exp:path, $ln:path, $sin_cos:path, $cbrt:path, $asin:path) => {
        impl Real for $t {
            const PI: Self = core::$t::consts::PI;
            const DIGITS: u32 = $t::MANTISSA_DIGITS;
            #[inline]
            fn of(v: f64) -> Self {
                v as $t
            }
            #[inline]
            fn f64(self) -> f64 {
                self as f64
            }
        }

        impl sealed::Math for $t {
            #[inline]
            fn sqrt(self) -> Self {
                $sqrt(self)
            }
            #[inline]
            fn exp(self) -> Self {
                $exp(self)
            }
            #[inline]
            fn ln(self) -> Self {
                $ln(self)
            }
            #[inline]
            fn sin_cos(self) -> (Self, Self) {
                $sin_cos(self)
            }
            #[inline]
            fn cbrt(self) -> Self {
                $cbrt(self)
            }
            #[inline]
            fn asin(self) -> Self {
                $asin(self)
            }
            #[inline]
            fn abs(self) -> Self {
                // 0 − x: exactly −x for x ≠ 0, and +0 for −0 (whose reciprocal must be +∞).
                if self <= 0.0 {
                    0.0 - self
                } else {
                    self
                }
            }
        }
    };
}

#[cfg(feature = "std")]
impl_real!(
    f32,
    f32::sqrt,
    f32::exp,
    f32::ln,
    f32::sin_cos,
    f32::cbrt,
    f32::asin
);
#[cfg(feature = "std")]
impl_real!(
    f64,
    f64::sqrt,
    f64::exp,
    f64::ln,
    f64::sin_cos,
    f64::cbrt,
    f64::asin
);

#[cfg(all(not(feature = "std"), feature = "libm"))]
impl_real!(
    f32,
    libm::sqrtf,
    libm::expf,
    libm::logf,
    libm::sincosf,
    libm::cbrtf,
    libm::asinf
);
#[cfg(all(not(feature = "std"), feature = "libm"))]
impl_real!(
    f64,
    libm::sqrt,
    libm::exp,
    libm::log,
    libm::sincos,
    libm::cbrt,
    libm::asin
);

/// eˣ − 1 without the cancellation of small x: a series below |x| = 0.01 (truncation
/// < 3e-17); up to |x| = 1/2 Kahan's (u − 1) x / ln u with u = eˣ as rounded, whose rounding
/// errors cancel (eˣ − 1 itself loses up to ulp(1)/|x|: 1.2e-5 relative in f32 at 0.01);
/// beyond, eˣ − 1 is within a few ulps.
pub(crate) fn exp_m1<F: Real>(x: F) -> F {
    let one = F::of(1.0);
    if x.abs() >= F::of(0.01) && x.abs() < F::of(0.5) {
        let u = x.exp();
        return (u - one) * x / u.ln();
    }
    if x.abs() < F::of(0.01) {
        x * (one
            + x / F::of(2.0)
                * (one
                    + x / F::of(3.0)
                        * (one + x / F::of(4.0) * (one + x / F::of(5.0) * (one + x / F::of(6.0))))))
    } else {
        x.exp() - F::of(1.0)
    }
}

#[cfg(not(any(feature = "std", feature = "libm")))]
use crate::soft_math as soft;
#[cfg(not(any(feature = "std", feature = "libm")))]
impl_real!(
    f32,
    soft::sqrtf,
    soft::expf,
    soft::lnf,
    soft::sin_cosf,
    soft::cbrtf,
    soft::asinf
);
#[cfg(not(any(feature = "std", feature = "libm")))]
impl_real!(
    f64,
    soft::sqrt,
    soft::exp,
    soft::ln,
    soft::sin_cos,
    soft::cbrt,
    soft::asin
);
