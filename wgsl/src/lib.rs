//! nephele in WGSL (the shading language of wgpu, Dawn and browsers; Naga translates it to
//! GLSL, HLSL and MSL) for renderers that evaluate nephele's artefacts on the GPU.
//!
//! [`PHASE`] holds the phase models renderers use — Henyey–Greenstein, Draine, and HG + Draine
//! (Jendersie & d'Eon 2023) by its parameters or by droplet diameter — each with eval and exact
//! sampling, as functions to paste or `#include` into a shader (no entry point, no bindings):
//!
//! ```wgsl
//! let c = hg_draine_sample(hg_draine_from_diameter(10.0), xi);   // c.mu, c.one_minus_mu
//! let p = hg_draine_eval(hg_draine_from_diameter(10.0), c);      // sr⁻¹
//! ```
//!
//! The port follows `nephele_runtime::phase` formula for formula in f32. It is checked by
//! running it: `cargo test -p nephele-wgsl` evaluates and samples every model on a Vulkan
//! device (Mesa's lavapipe on the CPU: `apt-get install mesa-vulkan-drivers`) against the Rust
//! runtime, with the runtime's chi-square test on the GPU's samples, and its Naga translations
//! to SPIR-V and GLSL through their validators. The transport tables and
//! the collector search are not ported yet (docs/integration.md).

/// The phase models in WGSL: `hg_eval`, `hg_sample`, `draine_eval`, `draine_cdf`,
/// `draine_sample`, `hg_draine_eval`, `hg_draine_sample`, `hg_draine_from_diameter`, over the
/// `Cosine` (μ, 1 − μ) and `HgDraine` (g_HG, g_D, α, w_D) structs.
pub const PHASE: &str = include_str!("phase.wgsl");
