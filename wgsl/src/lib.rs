//! nephele in WGSL (the shading language of wgpu, Dawn and browsers; Naga translates it to
//! GLSL, HLSL and MSL) for renderers that evaluate nephele's artefacts on the GPU.
//!
//! [`PHASE`] holds the phase models renderers use — Henyey–Greenstein, Draine, and HG + Draine
//! (Jendersie & d'Eon 2023) by its parameters or by droplet diameter — each with eval and exact
//! sampling, as functions to paste or `#include` into a shader (no entry point, no bindings):
//!
//! ```wgsl
//! let hd = nephele_hg_draine_from_diameter(10.0);
//! let c = nephele_hg_draine_sample(hd, xi);   // c.mu, c.one_minus_mu
//! let p = nephele_hg_draine_eval(hd, c);      // sr⁻¹
//! ```
//!
//! [`tabulated`] adds the tabulated phase function (a Mie table: f = 2π p sin θ linear between
//! nodes in θ, exact inverse-CDF sampling) over a storage buffer that [`tabulated_buffer`] fills
//! from the runtime's table.
//!
//! [`tables`] adds the transport tables — T, c and σ of each order group and order 1 at a slab
//! point — from a `.ntt` in a storage buffer ([`ntt_for_gpu`] checks the file as the runtime
//! does, copies the arrays the shaders read and writes the index uniform):
//!
//! ```wgsl
//! let at = nephele_slab_point(thickness, mu_l, depth, mu_v, psi_v);  // C's order, ψ in radians
//! var t = nephele_order1(at);                // sr⁻¹, albedo 1
//! let groups = nephele_transport_all(at);    // T of every group, the features built once
//! for (var g = 0u; g < nephele_ntt_index.groups; g++) { t += groups[g]; }
//! ```
//!
//! The port follows `nephele_runtime` formula for formula in f32, with its own exp, ln, sin, cos
//! and asin (math.wgsl, Cephes': a driver's built-ins may be thousands of ulps off). It is
//! checked by running it: `cargo test -p nephele-wgsl` evaluates and samples every model and
//! evaluates the shipped tables at 10⁵ points on a Vulkan device (Mesa's lavapipe on the CPU:
//! `apt-get install mesa-vulkan-drivers`) against the Rust runtime and an f64 evaluation, with
//! the runtime's chi-square test on the GPU's samples, and its Naga translations to SPIR-V and
//! GLSL through their validators.
//!
//! [`SEARCH`] adds the collector search and the finite-cloud correction over the renderer's lit
//! surface, which the renderer's shader supplies as four functions (docs/integration.md).
//!
//! Every name the sources declare at module scope starts with `nephele_`, `Nephele` or
//! `NEPHELE_`, so that they share a module with a renderer's own code.

/// The elementary functions (`nephele_exp`, `nephele_ln`, `nephele_exp_m1`, `nephele_sin_cos`,
/// `nephele_asin`) and the phase models in WGSL: `nephele_hg_eval`, `nephele_hg_sample`,
/// `nephele_draine_eval`, `nephele_draine_cdf`, `nephele_draine_sample`, `nephele_hg_draine_eval`,
/// `nephele_hg_draine_sample`, `nephele_hg_draine_from_diameter`, over the `NepheleCosine`
/// (μ, 1 − μ) and `NepheleHgDraine` (g_HG, g_D, α, w_D) structs.
pub const PHASE: &str = concat!(include_str!("math.wgsl"), include_str!("phase.wgsl"));

/// The tabulated phase function in WGSL (`nephele_tabulated_eval`, `nephele_tabulated_sample`), reading its
/// table from `var<storage, read> nephele_tab: array<f32>` at `@group(group) @binding(binding)`;
/// needs [`PHASE`] before it (for `NepheleCosine`).
pub fn tabulated(group: u32, binding: u32) -> String {
    include_str!("tabulated.wgsl")
        .replace("NEPHELE_TAB_GROUP", &group.to_string())
        .replace("NEPHELE_TAB_BINDING", &binding.to_string())
}

/// The buffer [`tabulated`] reads, from the runtime's table: n, θ (radians), f and the CDF at
/// the nodes, then a guide table of n − 1 interval indices (`guide[k]` the interval holding
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

/// The transport tables in WGSL, from a `.ntt` laid out by [`ntt_for_gpu`]: its words (`array<u32>`,
/// [`NttGpu::words`]) at `@group(group) @binding(binding)` and its index ([`NttGpu::index`], a
/// uniform struct `NepheleNttIndex` of [`NTT_INDEX_WORDS`] u32) at `binding + 1`; needs
/// [`PHASE`] before it. It gives, over `NepheleSlabPoint` (thickness, μ_L, depth, μ_V, ψ_V
/// in radians: C's field order; `nephele_slab_point(…)`, `nephele_slab_point_deg(…)` with ψ_V
/// in degrees):
/// - `nephele_transport_all(at) -> array<f32, 8>`: T of every order group (orders ≥ 2, sr⁻¹;
///   at most [`MAX_GROUPS`], the rest 0), the point's features built once, the runtime's
///   `TransportTables::transport_all`; `nephele_transport(g, at)` for one group;
/// - `nephele_evaluate_all(at) -> array<NepheleTransport, 8>`: T, the collector (c_x, c_z) and
///   its spread σ (mfp) of every group, `TransportTables::evaluate_all`;
///   `nephele_evaluate(g, at)` for one group;
/// - `nephele_order1(at) -> f32`: order 1 (sr⁻¹, albedo 1), `TransportTables::order1`.
/// - `nephele_tables_domain() -> NepheleDomain` (the grid's ends and g, `TransportTables::domain`)
///   and `nephele_outside(at) -> u32` (the bits of `Outside::bits`).
pub fn tables(group: u32, binding: u32) -> String {
    [
        include_str!("ntt.wgsl"),
        include_str!("order1.wgsl"),
        include_str!("transport.wgsl"),
        include_str!("collector.wgsl"),
    ]
    .concat()
    .replace("NEPHELE_NTT_GROUP", &group.to_string())
    .replace("NEPHELE_NTT_INDEX_BINDING", &(binding + 1).to_string())
    .replace("NEPHELE_NTT_BINDING", &binding.to_string())
}

/// [`PHASE`] and [`tables`] together: the transport tables as one self-contained module source
/// an engine includes before its own shader code (what `nephele export-gpu` writes).
pub fn tables_module(group: u32, binding: u32) -> String {
    format!("{PHASE}\n{}", tables(group, binding))
}

/// The collector search and the finite-cloud correction in WGSL (`nephele_find_collector(g,
/// viewpoint, sun, options) -> NepheleCollector`, `nephele_finite_cloud(g, collector, finite)
/// -> NepheleKept`), for
/// after [`tables`]. The renderer supplies its lit surface as four functions of its module:
/// `nephele_surface_filtered(at: vec3<f32>, sigma: f32) -> NepheleLitSample`,
/// `nephele_surface_lateral(at: vec3<f32>, sigma: f32) -> NepheleLateralSample`,
/// `nephele_surface_initial_scale() -> f32` and `nephele_surface_sun_depth(at: vec3<f32>) -> f32`
/// (the sun's optical depth, negative where unknown; search.wgsl has the structs).
pub const SEARCH: &str = concat!(include_str!("search.wgsl"), include_str!("finite.wgsl"));

/// Most order groups of a `.ntt` the WGSL port reads (`NEPHELE_MAX_GROUPS`: `transport_all`
/// and `evaluate_all` return arrays of 8).
pub const MAX_GROUPS: usize = 8;

/// Words of the index uniform ([`NttGpu::index`]).
pub const NTT_INDEX_WORDS: usize = 48;

/// A `.ntt` as the WGSL port reads it: the arrays the shaders read as f32 bits, the Θ-hat nodes
/// after them, and the index of where each starts.
#[derive(Clone, Debug)]
pub struct NttGpu {
    /// The arrays' f32 bits, then the Θ-hat nodes (storage buffer).
    pub words: Vec<u32>,
    /// The `NttIndex` uniform of ntt.wgsl: the form's sizes, word offsets and lengths.
    pub index: [u32; NTT_INDEX_WORDS],
}

/// Checks `bytes` as the runtime does ([`TransportTables::from_bytes`]) and lays them out for
/// the GPU ([`NttGpu`]): the arrays the shaders read, each copied to whole words (the format
/// does not align them), then the Θ-hat nodes.
///
/// [`TransportTables::from_bytes`]: nephele_runtime::transport::TransportTables::from_bytes
pub fn ntt_for_gpu(bytes: &[u8]) -> Result<NttGpu, String> {
    use nephele_runtime::container::Container;
    use nephele_runtime::fitting::log_additive::LogAdditive;
    use nephele_runtime::fitting::{names, CollectorForm};
    let err = |e: &dyn std::fmt::Display| format!("transport tables: {e}");
    let tables =
        nephele_runtime::transport::TransportTables::from_bytes(bytes).map_err(|e| err(&e))?;
    let c = Container::from_bytes(bytes).map_err(|e| err(&e))?;
    let mut words = Vec::new();
    let mut word_of = |name: &str| put(&mut words, &c, name);
    // The loader has checked the sizes: whole numbers within its limits.
    let form = c.find(names::FORM).ok_or("no form")?;
    let size = |i: usize| form.get(i).unwrap_or(0.0) as usize;
    let shape = LogAdditive {
        legendre: size(0),
        harmonics: size(1),
        theta_nodes: size(2),
        pairs: size(3) == 1,
        cross: if form.len() == 6 { size(5) } else { 0 },
    };
    let q = size(4);
    let (mu_l, n_l) = word_of(names::MU_L_NODES)?;
    let (mu_v, n_v) = word_of(names::MU_V_NODES)?;
    let (thickness, n_t) = word_of(names::THICKNESS)?;
    let (group_first, groups) = word_of(names::GROUP_FIRST)?;
    // β is feature-major, [P, G, Q].
    let (param_stride, group_stride) = (groups as usize * q, q);
    let ceiling = word_of(names::T_CEILING).ok();
    let (ln_t_range, _) = word_of(names::LN_T_RANGE)?;
    let (beta, _) = word_of(names::BETA)?;
    let (u_range, _) = word_of(names::U_RANGE)?;
    let (phase_theta, n_phase) = word_of(names::PHASE_THETA)?;
    let (phase, _) = word_of(names::PHASE)?;
    let collector_beta = names::COLLECTOR_BETA.map(|name| word_of(name).map(|(at, _)| at));
    // The halo: edges, then h; its shape as two index words.
    let halo = match c.find(names::HALO_SHAPE) {
        Some(shape) => {
            let (edges, n_edges) = word_of(names::HALO_EDGES)?;
            let (values, _) = word_of(names::HALO)?;
            let size = |i: usize| shape.get(i).unwrap_or(0.0) as u32;
            [edges, n_edges, values, size(0), size(1)]
        }
        None => [0; 5],
    };
    // The Θ-hat nodes as the runtime rounds them (π (i/(n − 1))² in f64, then f32).
    let hats = |words: &mut Vec<u32>, nodes: usize| {
        let at = words.len() as u32;
        let top = (nodes.max(2) - 1) as f64;
        words.extend((0..nodes.max(2)).map(|i| {
            let r = i as f64 / top;
            ((std::f64::consts::PI * r * r) as f32).to_bits()
        }));
        at
    };
    let theta_hats = hats(&mut words, shape.theta_nodes);
    let collector = match c.find(names::COLLECTOR_FORM) {
        Some(sizes) => {
            let size = |i: usize| sizes.get(i).unwrap_or(0.0) as usize;
            let form = CollectorForm {
                legendre: size(0),
                harmonics: size(1),
                theta_nodes: size(2),
            };
            let q_c = size(3);
            let (n_v, n_l) = (n_v as usize, n_l as usize);
            let mut beta = [0u32; 3];
            for (k, at) in collector_beta.iter().enumerate() {
                beta[k] = at.clone()?;
            }
            let group_stride = [q_c as u32; 3];
            let param = groups as usize * q_c;
            [
                1,
                form.legendre as u32,
                form.harmonics as u32,
                form.theta_nodes as u32,
                q_c as u32,
                form.depth_terms() as u32,
                beta[0],
                beta[1],
                beta[2],
                param as u32,
                group_stride[0],
                group_stride[1],
                group_stride[2],
                form.cz_reach_start(n_v, n_l) as u32,
                hats(&mut words, form.theta_nodes),
            ]
        }
        None => [0; 15],
    };
    if groups as usize > MAX_GROUPS {
        return Err(format!(
            "transport tables: {groups} order groups; the WGSL port reads at most {MAX_GROUPS}"
        ));
    }
    let u32_of = |n: usize| n as u32;
    let index = [
        groups,
        u32_of(q),
        u32_of(shape.legendre),
        u32_of(shape.harmonics),
        u32_of(shape.theta_nodes),
        u32::from(shape.pairs),
        u32_of(shape.cross),
        u32_of(shape.depth_terms()),
        mu_l,
        n_l,
        mu_v,
        n_v,
        thickness,
        n_t,
        ln_t_range,
        beta,
        u32_of(param_stride),
        u32_of(group_stride),
        u_range,
        ceiling.map_or(0, |(w, _)| w),
        u32::from(ceiling.is_some()),
        phase_theta,
        phase,
        n_phase,
        theta_hats,
    ];
    let mut all = [0u32; NTT_INDEX_WORDS];
    all[..index.len()].copy_from_slice(&index);
    all[index.len()..index.len() + collector.len()].copy_from_slice(&collector);
    let tail = index.len() + collector.len();
    all[tail] = group_first;
    all[tail + 1..tail + 1 + halo.len()].copy_from_slice(&halo);
    // g of the stored phase function, as the runtime computes it at load (the continuation
    // past the thickest slab).
    all[tail + 1 + halo.len()] = tables.mean_cosine().to_bits();
    Ok(NttGpu { words, index: all })
}

/// Appends array `name` of `c` to `words` as f32 bits: (its first word, its length).
fn put(
    words: &mut Vec<u32>,
    c: &nephele_runtime::container::Container,
    name: &str,
) -> Result<(u32, u32), String> {
    let a = c
        .find(name)
        .ok_or(format!("transport tables: no array {name}"))?;
    let at = words.len() as u32;
    words.extend(a.iter().map(f32::to_bits));
    Ok((at, a.len() as u32))
}
