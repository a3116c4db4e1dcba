//! Stage 6 — the ground-truth volumetric path tracer (spec 60): participating media, the
//! estimator, and (to come) scenes, the camera and the `nephele render` command.

pub mod integrator;
pub mod medium;
