//! nephele: light scattering by water droplets, from Mie theory to renderer-ready artefacts.
//!
//! Data flows one way, each stage a module with one job (docs/architecture.md draws it):
//!
//! - [`mie`]: polydisperse, spectral Mie phase functions of water droplets (`nephele mie`,
//!   `nephele sphere`);
//! - [`phase`]: phase functions as configs, scenes and the command line name them, built into
//!   the runtime's evaluators (`nephele phase`);
//! - [`fit`]: analytic models fitted to the Mie tables by E_AS, and their diameter curves
//!   (`nephele fit`);
//! - [`slab`]: the slab Monte Carlo and its transport tables ⟨T, c, σ⟩ per order group
//!   (`nephele slab`, `nephele merge`);
//! - [`compress`]: those tables compressed into the `.ntt` file renderers load (`nephele
//!   compress`; `nephele transport` evaluates one);
//! - [`render`]: the ground-truth volumetric path tracer (`nephele render`);
//! - [`io`]: atomic NumPy/JSON/PNG/`.ntt` outputs; [`stats`]: quadratures, statistical tests and
//!   random seeds shared by the stages.
//!
//! Every evaluator a renderer needs (phase models, transport tables) lives in `nephele-runtime`;
//! this crate depends on it (with its `fitting` feature) and never duplicates it.

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
