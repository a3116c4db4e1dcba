//! nephele: light scattering by water droplets, from Mie theory to renderer-ready artefacts.
//!
//! Stages are modules with one job each: [`mie`] (phase-function tables), [`fit`] (analytic models
//! fitted to them, diameter curves), [`io`] (atomic
//! NumPy/JSON/CSV/PNG outputs). The evaluators renderers need live in `nephele-runtime`.

pub mod compress;
pub mod fit;
pub mod io;
pub mod mie;
pub mod phase;
pub mod render;
pub mod slab;
pub mod stats;

/// Tool version written into every JSON sidecar.
pub const VERSION: &str = env!("CARGO_PKG_VERSION");
