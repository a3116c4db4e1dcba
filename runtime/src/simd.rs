//! The vector units the CPU has, as the runtime's and the toolchain's run-time dispatch picks
//! them: every loop compiled for several levels (the phase models' many samples, the slab
//! walk) takes the best one this returns.

/// `$avx2` (an unsafe call of a copy compiled with `#[target_feature(enable = "avx2")]`) where
/// the CPU has AVX2, else `$any`: the runtime's one hand-off to such copies. Without `std` or
/// off x86-64, `$any` alone (the AVX2 copies are not compiled there).
macro_rules! avx2_or {
    ($avx2:expr, $any:expr) => {{
        #[cfg(all(feature = "std", target_arch = "x86_64"))]
        {
            if $crate::simd::avx2() {
                // SAFETY: the CPU has AVX2, checked just above.
                unsafe { $avx2 }
            } else {
                $any
            }
        }
        #[cfg(not(all(feature = "std", target_arch = "x86_64")))]
        {
            $any
        }
    }};
}
pub(crate) use avx2_or;

/// Whether the CPU has AVX2 (one cached feature test: the hand-offs run per point).
#[cfg(all(feature = "std", target_arch = "x86_64"))]
#[inline]
pub(crate) fn avx2() -> bool {
    std::is_x86_feature_detected!("avx2")
}

/// A level of x86-64 vector units, the best first.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
// Without std (no feature detection) or off x86-64 only the baseline is ever picked.
#[cfg_attr(not(all(feature = "std", target_arch = "x86_64")), allow(dead_code))]
pub enum Simd {
    /// AVX-512 F, DQ and VL (and so AVX2).
    Avx512,
    /// AVX2.
    Avx2,
    /// What the crate was built for.
    Baseline,
}

impl Simd {
    /// The best level the CPU has (the baseline without `std` or off x86-64).
    #[inline]
    pub fn detected() -> Self {
        #[cfg(all(feature = "std", target_arch = "x86_64"))]
        {
            if std::is_x86_feature_detected!("avx512f")
                && std::is_x86_feature_detected!("avx512dq")
                && std::is_x86_feature_detected!("avx512vl")
            {
                return Self::Avx512;
            }
            if std::is_x86_feature_detected!("avx2") {
                return Self::Avx2;
            }
        }
        Self::Baseline
    }

    /// Every level the CPU can run, the best first (tests run each).
    #[cfg(test)]
    pub(crate) fn available() -> impl Iterator<Item = Self> {
        let best = Self::detected();
        [Self::Avx512, Self::Avx2, Self::Baseline]
            .into_iter()
            .skip_while(move |s| *s != best)
    }

    /// Whether this level has AVX2 (what the single-copy dispatches, the cloud's density and
    /// the light maps' lookup, compile for).
    pub fn has_avx2(self) -> bool {
        matches!(self, Self::Avx512 | Self::Avx2)
    }

    /// The level's name, for reports.
    pub fn name(self) -> &'static str {
        match self {
            Self::Avx512 => "AVX-512 (F, DQ, VL)",
            Self::Avx2 => "AVX2",
            Self::Baseline => "the target's baseline",
        }
    }
}
