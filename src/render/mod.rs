//! Stage 6 — the ground-truth volumetric path tracer (spec 60): scenes, participating media, the
//! estimator, the camera and the outputs of `nephele render`.

pub mod integrator;
pub mod majorant;
pub mod medium;
pub mod output;
pub mod run;
pub mod scene;
