//! `nephele-runtime`: what a renderer links to evaluate nephele's artefacts.
//!
//! `no_std` unless the default `std` feature is on; without `std` the math comes from `libm`
//! when its feature is on (as with glam: `default-features = false, features = ["libm"]`), else
//! from the small built-in [`soft_math`]; no other dependency; f32-first,
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
pub mod phase;
pub mod presets;
pub mod real;
pub mod soft_math;
pub mod transport;

pub use phase::PhaseFunction;
pub use real::Real;

/// The crate version, for the JSON sidecars of artefacts built with it.
pub const VERSION: &str = env!("CARGO_PKG_VERSION");

/// 1 / (4π): the isotropic phase function, in sr⁻¹.
pub const INV_FOUR_PI: f64 = 0.079_577_471_545_947_67;
