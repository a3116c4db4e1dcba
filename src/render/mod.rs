//! Rendering clouds: the ground-truth volumetric path tracer (docs/render.md) and the fast
//! renderers judged against it (docs/collector.md), in three wings over a shared floor.
//!
//! - The floor, what every renderer and the judge share: [`geometry`], the [`scene`] and its
//!   [`medium`] with the [`majorant`] grid, the pinhole [`camera`], the rendered [`image`] with
//!   its AOVs and order groups, its [`regions`], and the [`output`] files with their tone
//!   mapping.
//! - [`path`]: the path tracer — the driver, its estimator and the sun-lobe next-event
//!   estimation.
//! - [`fast`]: the collector renderer on the transport tables, and the single-scattering and
//!   multi-octave baselines — the view-ray march, the collector branch, the table checks, the
//!   sun side from light-space maps, the sky term.
//! - [`compare`] on top: a candidate render against a path-traced reference, from the files
//!   they wrote (it reads only the floor).

pub mod camera;
pub mod compare;
pub mod fast;
mod fbm;
pub mod geometry;
mod grid_file;
pub mod image;
pub mod light;
pub mod majorant;
pub mod medium;
pub mod mesh;
pub mod output;
pub mod path;
pub mod regions;
pub mod scene;
pub mod surface;
