//! Light transport in the canonical slab of spec 40 (thickness t in mean free paths, sun at
//! μ_L = cos φ_L, viewpoint at depth d, view direction (μ_V, ψ_V) of the light leaving toward
//! the eye, μ_V > 0 going up, ψ_V from the sun's horizontal travel).

pub mod collector;
pub mod log_additive;
pub mod single;
pub mod tables;

pub use single::{scattering_cosine, single_scattering, single_scattering_bin};
