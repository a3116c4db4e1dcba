//! The ground-truth volumetric path tracer (docs/render.md): scenes, participating media, the
//! estimator, the camera and the outputs of `nephele render`.

pub mod geometry;
pub mod integrator;
pub mod majorant;
pub mod medium;
pub mod output;
pub mod run;
pub mod scene;
pub mod sun_lobe;
