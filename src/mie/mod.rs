//! Lorenz–Mie scattering by water droplets (docs/mie.md).
//!
//! - [`sphere`]: one sphere — a_n, b_n, efficiencies, S1/S2;
//! - [`angular`]: π_n, τ_n and the tabulated angle basis;
//! - [`batch`]: intensities of many spheres as matrix products;
//! - [`distribution`], [`index`], [`colour`], [`grid`]: the ingredients of a polydisperse job;
//! - [`polydisperse`]: the job itself, producing [`polydisperse::PhaseTable`]s;
//! - [`limits`]: the ranges a job must lie in, and its memory, checked before it runs;
//! - [`cache`]: the phase functions scenes ask for by diameter, kept on disk between runs.

pub mod angular;
pub mod batch;
pub mod cache;
pub mod colour;
pub mod distribution;
pub mod grid;
pub mod index;
pub mod limits;
pub mod output;
pub mod polydisperse;
pub mod sphere;
pub mod water;

pub use polydisperse::{MieJob, PhaseTable, SizeRule};
pub use sphere::{Efficiencies, MieCoefficients};
