//! Phase functions for the toolchain: the one place where a phase function named in a config,
//! a scene or on the command line becomes a runtime evaluator. [`Model`] and [`ModelParams`]
//! name the analytic models of nephele-runtime ([`build`] checks and builds one), [`PhaseSpec`]
//! is what configs and scenes write (`"phase": {"kind": …}`), and [`Phase`] is the built,
//! owned phase function (per sRGB channel where asked). The evaluators themselves live in
//! `nephele_runtime::phase`; slab, compress, render, fit and the CLI depend on this module, not
//! on each other.

mod function;
pub mod lut;
pub mod mitsuba;
mod model;
mod spec;

pub use function::{Phase, Source};
pub use model::{build, Boxed, Model, ModelParams, Preset};
pub use spec::PhaseSpec;
