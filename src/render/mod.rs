//! Rendering clouds: the ground-truth volumetric path tracer (docs/render.md) — scenes,
//! participating media, the estimator, the camera and the outputs of `nephele render` — and
//! the fast renderers judged against it (docs/collector.md): the collector renderer on the
//! transport tables, and the single-scattering and multi-octave baselines.

pub mod compare;
pub mod fast;
pub mod geometry;
pub mod integrator;
pub mod light_map;
pub mod majorant;
pub mod march;
pub mod medium;
pub mod octaves;
pub mod output;
pub mod run;
pub mod scene;
pub mod sky;
pub mod sun_lobe;
pub mod sun_side;
