//! Fitting analytic phase functions to Mie (docs/fit.md).
//!
//! - [`loss`]: E_AS (Jendersie & d'Eon eq. 1) as a grid-independent integral, with its gradient.
//! - [`model`]: what fitting needs of the fitted models (HG, two-term HG, Cornette–Shanks,
//!   Draine, HG+Draine — `crate::phase::Model`): ln p and ∂ ln p/∂θ in closed form, bounds as
//!   smooth maps.
//! - [`optimize`]: coarse-grid start + L-BFGS (argmin) in unconstrained variables.
//! - [`curves`]: HG+Draine parameters as functions of the diameter.
//! - [`run`]: a whole config — per-diameter fits, warm-start sweeps, curves, the paper beside.
//! - [`output`]: fits.json and fits.npz; [`figures`], [`config`].

pub mod config;
pub mod curves;
pub mod figures;
pub mod loss;
pub mod model;
pub mod optimize;
pub mod output;
pub mod run;

pub use config::FitConfig;
pub use loss::{Loss, Target};
pub use model::{Model, FITTED};
pub use run::{run, FitReport};
