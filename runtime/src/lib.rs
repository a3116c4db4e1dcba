//! `nephele-runtime`: what a renderer links to evaluate nephele's artefacts.
//!
//! `no_std` unless the default `std` feature is on; without `std` the math comes from `libm`
//! when its feature is on (as with glam: `default-features = false, features = ["libm"]`), else
//! from a small built-in implementation; no other dependency; f32-first,
//! every evaluator also in f64. It owns every evaluator of the project (phase models, table
//! lookups, collector search) so that the generators in `nephele` and the renderers that ship
//! its tables run the very same code.
//!
//! Conventions: scattering angle θ between incident and scattered propagation directions,
//! μ = cos θ (μ = 1 is forward); phase functions are normalised so that ∮ p dΩ = 1 (sr⁻¹).
#![cfg_attr(not(feature = "std"), no_std)]

pub mod container;
#[cfg(feature = "embed")]
pub mod embedded;
pub mod frame;
#[cfg_attr(not(feature = "fitting"), allow(dead_code))]
mod legendre;
pub mod phase;
pub mod presets;
pub mod real;
#[cfg_attr(not(feature = "fitting"), allow(dead_code))]
mod simd;
#[cfg_attr(not(feature = "fitting"), allow(dead_code))]
mod small_angle;
// The math of a bare no_std build; compiled (and unit-tested) with std too.
#[cfg_attr(any(feature = "std", feature = "libm"), allow(dead_code))]
mod soft_math;
pub mod transport;

pub use phase::PhaseFunction;

/// The insides the toolchain needs to fit and write tables (feature `fitting`; a renderer does
/// not): the features of the compressed T ([`fitting::LogAdditive`]) and of the collector
/// ([`fitting::CollectorForm`]), where a point sits among the parameter nodes
/// ([`fitting::Cell`], [`fitting::Lerp`]), the `.ntt` array names and the runtime's size limits
/// (which writers must respect), the packed depth ranges, and the Legendre recurrence.
#[cfg(feature = "fitting")]
pub mod fitting {
    /// The modules themselves, for their documentation (the equations of each form, the
    /// `.ntt` array table).
    pub use crate::transport::{collector, format, log_additive, single, tables};

    pub use crate::container::layout::{
        crc32, ENTRY_BYTES, HEADER_BYTES, MAGIC, MAX_ARRAYS, NAME_BYTES,
    };
    pub use crate::legendre::Legendre;
    pub use crate::simd::Simd;
    pub use crate::small_angle::sin_cos_small;
    pub use crate::transport::collector::{
        CollectorForm, Statistic, MAX_COLLECTOR_HARMONICS, MAX_COLLECTOR_LEGENDRE,
    };
    pub use crate::transport::format::{
        names, pack_u_range, unpack_u_range, DEFAULT_GROUP_FIRST, MAX_GROUPS, MAX_NODES, MAX_Q,
        U_STEPS,
    };
    pub use crate::transport::log_additive::{
        depth_fraction, depth_polynomial, far_fraction, legendre, ln_boundary, ln_t_position,
        stretched_u, theta_hats, Cell, FittedDepths, Lerp, LogAdditive, LN_F1_FLOOR, MAX_CROSS,
        MAX_HARMONICS, MAX_LEGENDRE, MAX_THETA_NODES, STRETCH_EXPONENT, STRETCH_SCALE,
    };
    pub use crate::transport::single::single_scattering_bin;
    pub use crate::transport::tables::CEILING_FACTOR;
}
pub use real::Real;

/// The crate version, for the JSON sidecars of artefacts built with it.
pub const VERSION: &str = env!("CARGO_PKG_VERSION");

/// 1 / (4π): the isotropic phase function, in sr⁻¹.
pub const INV_FOUR_PI: f64 = 0.079_577_471_545_947_67;
