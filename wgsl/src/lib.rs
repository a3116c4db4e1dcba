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
//! [`tabulated`] adds the tabulated phase function (a Mie table: f = 2π p sin θ linear between
//! nodes in θ, exact inverse-CDF sampling) over a storage buffer that [`tabulated_buffer`] fills
//! from the runtime's table.
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

/// The tabulated phase function in WGSL (`tabulated_eval`, `tabulated_sample`), reading its
/// table from `var<storage, read> nephele_tab: array<f32>` at `@group(group) @binding(binding)`;
/// needs [`PHASE`] before it (for `Cosine`).
pub fn tabulated(group: u32, binding: u32) -> String {
    include_str!("tabulated.wgsl")
        .replace("NEPHELE_TAB_GROUP", &group.to_string())
        .replace("NEPHELE_TAB_BINDING", &binding.to_string())
}

/// The buffer [`tabulated`] reads, from the runtime's table: n, θ (radians), f and the CDF at
/// the nodes, then a guide table of n − 1 interval indices (guide[k] the interval holding
/// ξ = k/(n − 1)), all as f32 words (indices exact below 2²⁴ nodes).
pub fn tabulated_buffer(table: &nephele_runtime::phase::Tabulated<f32>) -> Vec<f32> {
    let (theta, f, cdf, _) = table.parts();
    let n = theta.len();
    let mut out = Vec::with_capacity(4 * n);
    out.push(n as f32);
    out.extend_from_slice(theta);
    out.extend_from_slice(f);
    out.extend_from_slice(cdf);
    out.extend((0..n.saturating_sub(1)).map(|k| {
        let xi = k as f32 / (n - 1) as f32;
        (cdf.partition_point(|c| *c <= xi).clamp(1, n - 1) - 1) as f32
    }));
    out
}

/// Order 1 in WGSL (`order1(at: SlabPoint) -> f32`, sr⁻¹, albedo 1) from the phase function
/// of a `.ntt` uploaded whole: its words (`array<u32>`, [`NttGpu::words`]) at
/// `@group(group) @binding(binding)` and its index ([`NttGpu::index`], a uniform of 4 u32) at
/// `binding + 1`; needs [`PHASE`] before it.
pub fn order1(group: u32, binding: u32) -> String {
    include_str!("order1.wgsl")
        .replace("NEPHELE_NTT_GROUP", &group.to_string())
        .replace("NEPHELE_NTT_INDEX_BINDING", &(binding + 1).to_string())
        .replace("NEPHELE_NTT_BINDING", &binding.to_string())
}

/// A `.ntt` as the WGSL port reads it: the whole file as little-endian u32 words, and the
/// index of what the shaders read in it (word offsets of `phase_theta` and `phase`, the phase
/// table's length, 0).
#[derive(Clone, Debug)]
pub struct NttGpu {
    /// The file's bytes as words (storage buffer).
    pub words: Vec<u32>,
    /// [phase_theta offset, phase offset, phase nodes, 0] (uniform).
    pub index: [u32; 4],
}

/// Checks `bytes` as the runtime does ([`TransportTables::from_bytes`]) and lays them out for
/// the GPU ([`NttGpu`]).
///
/// [`TransportTables::from_bytes`]: nephele_runtime::transport::TransportTables::from_bytes
pub fn ntt_for_gpu(bytes: &[u8]) -> Result<NttGpu, String> {
    use nephele_runtime::container::Container;
    use nephele_runtime::fitting::names;
    nephele_runtime::transport::TransportTables::from_bytes(bytes)
        .map_err(|e| format!("transport tables: {e}"))?;
    let c = Container::from_bytes(bytes).map_err(|e| format!("transport tables: {e}"))?;
    let word_of = |name: &str| -> Result<(u32, u32), String> {
        let a = c.find(name).ok_or(format!("no array {name}"))?;
        let offset = a.bytes().as_ptr() as usize - bytes.as_ptr() as usize;
        if offset % 4 != 0 {
            return Err(format!("array {name} at byte {offset}, not on a word"));
        }
        Ok(((offset / 4) as u32, a.len() as u32))
    };
    let (theta, n) = word_of(names::PHASE_THETA)?;
    let (phase, _) = word_of(names::PHASE)?;
    let words = bytes
        .chunks(4)
        .map(|b| {
            let mut w = [0u8; 4];
            w[..b.len()].copy_from_slice(b);
            u32::from_le_bytes(w)
        })
        .collect();
    Ok(NttGpu {
        words,
        index: [theta, phase, n, 0],
    })
}
