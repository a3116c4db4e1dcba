//! Compression of the 5D slab tables (docs/compress.md): per order group, an analytic form
//! whose parameters are small tables in (t, μ_V), (t, μ_L) and (t, Θ), fitted to the Monte
//! Carlo tables by weighted least squares (weights from their standard errors: noise is never
//! fitted), with the error measured on every cell against the tables' own noise.

pub mod bouthors;
pub mod collector;
pub mod coverage;
pub mod figure;
pub mod fit;
pub mod form;
pub mod joint;
mod manifest;
pub mod near_beam;
mod ntt;
pub mod report;
pub mod run;
pub mod ship;

pub use crate::slab::SlabTables;
pub use fit::{fit_all, GroupFit};
pub use form::LogAdditive;
