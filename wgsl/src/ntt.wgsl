// A `.ntt` (nephele's compressed transport tables) in a storage buffer, as the WGSL port of
// nephele-runtime's `transport` reads it: the file's bytes whole as `array<u32>`
// (`nephele_wgsl::NttGpu::words`, with the Θ-hat nodes appended), and a uniform index of where
// each array starts and the form's sizes (`NttGpu::index`, written by `nephele_wgsl::ntt_for_gpu`
// after the runtime's own checks of the file). Needs math.wgsl and phase.wgsl before it.

struct NepheleNttIndex {
    groups: u32,
    q: u32,            // Legendre terms in ln t
    legendre: u32,     // J, Legendre terms in depth
    harmonics: u32,    // K
    theta_nodes: u32,
    pairs: u32,        // 1: per-(μ_V, μ_L) γ, offset and slope
    cross: u32,        // A, the interaction's degree (0: none)
    depth_terms: u32,  // max(J, 2, 3 if A > 0)
    mu_l: u32,         // word offset of the sun-cosine nodes
    n_l: u32,
    mu_v: u32,
    n_v: u32,
    thickness: u32,
    n_t: u32,
    ln_t_range: u32,   // [G, 2]
    beta: u32,         // T's coefficients, β[p][g][k] at beta + g group_stride + p param_stride + k
    param_stride: u32,
    group_stride: u32,
    u_range: u32,      // [G, N, L·M], packed fitted depths
    t_ceiling: u32,    // [G, N, L], if has_ceiling
    has_ceiling: u32,
    phase_theta: u32,  // degrees
    phase: u32,
    n_phase: u32,
    theta_hats: u32,   // the Θ-hat nodes π (i/(n − 1))² as the runtime rounds them (appended)
    has_collector: u32,
    c_legendre: u32,   // the collector form's J, K, Θ nodes, Q, depth terms
    c_harmonics: u32,
    c_theta_nodes: u32,
    c_q: u32,
    c_depth_terms: u32,
    sigma_beta: u32,   // ln σ's, c_z's and c_x's coefficients
    cz_beta: u32,
    cx_beta: u32,
    c_param_stride: u32,
    sigma_group_stride: u32,
    cz_group_stride: u32,
    cx_group_stride: u32,
    cz_reach: u32,     // the first column of c_z's ℓ/σ̂ terms
    c_theta_hats: u32, // the collector's Θ-hat nodes (appended)
    group_first: u32,  // the first order of each group
    halo_edges: u32,   // the halo's annulus edges (degrees), if halo_groups > 0
    n_halo_edges: u32,
    halo: u32,         // h over [group, thickness, μ_L, plane, annulus]
    halo_groups: u32,  // the groups the halo covers (0: none)
    halo_planes: u32,
    mean_cosine: u32,  // g of the stored phase function (f32 bits), for the continuation past t_max
    pad1: u32,
}

@group(NEPHELE_NTT_GROUP) @binding(NEPHELE_NTT_BINDING)
var<storage, read> nephele_ntt: array<u32>;
@group(NEPHELE_NTT_GROUP) @binding(NEPHELE_NTT_INDEX_BINDING)
var<uniform> nephele_ntt_index: NepheleNttIndex;

fn nephele_ntt_f32(word: u32) -> f32 {
    return bitcast<f32>(nephele_ntt[word]);
}

// A point of the slab, in the field order and units of C's `NepheleSlabPoint` and Python's
// rows: thickness t and depth d below the lit face (mean free paths), sun cosine μ_L ∈ (0, 1],
// view cosine μ_V (> 0: the light goes up), view azimuth ψ_V (radians, from the sun's
// horizontal travel).
struct NepheleSlabPoint {
    thickness: f32,
    mu_l: f32,
    depth: f32,
    mu_v: f32,
    psi_v: f32,
}

// The point at thickness t, sun cosine μ_L, depth d, view cosine μ_V and azimuth ψ_V (radians).
fn nephele_slab_point(thickness: f32, mu_l: f32, depth: f32, mu_v: f32, psi_v: f32)
    -> NepheleSlabPoint {
    return NepheleSlabPoint(thickness, mu_l, depth, mu_v, psi_v);
}

// The point at azimuth ψ_V given in degrees (the CLI's `--psi-deg`).
fn nephele_slab_point_deg(thickness: f32, mu_l: f32, depth: f32, mu_v: f32, psi_v_deg: f32)
    -> NepheleSlabPoint {
    return NepheleSlabPoint(thickness, mu_l, depth, mu_v, psi_v_deg * (NEPHELE_PI / 180.0));
}

// The tables' domain (the runtime's `Domain`, C's `nephele_tables_domain`): the grid's
// thinnest and thickest slab (mfp), its lowest and highest sun cosine, and g of the stored
// phase function (the continuation past the thickest slab uses it).
struct NepheleDomain {
    thickness: vec2<f32>,
    mu_l: vec2<f32>,
    mean_cosine: f32,
}

fn nephele_tables_domain() -> NepheleDomain {
    let x = nephele_ntt_index;
    return NepheleDomain(
        vec2<f32>(nephele_ntt_f32(x.thickness), nephele_ntt_f32(x.thickness + x.n_t - 1u)),
        vec2<f32>(nephele_ntt_f32(x.mu_l), nephele_ntt_f32(x.mu_l + x.n_l - 1u)),
        bitcast<f32>(x.mean_cosine));
}

// Where a point lies outside the grid, as C's `nephele_outside`: t past the thickest slab
// (continued by diffusion theory), t below the thinnest (held), the sun below the lowest (read
// there, T scaled by μ_L/μ₀).
// A point that is not in the slab at all (t not finite and > 0, μ_L ∉ (0, 1], d ∉ [0, t],
// |μ_V| > 1, ψ_V not finite) has NEPHELE_NOT_IN_SLAB alone: where C, Python and the CLI refuse
// the point, a shader has no error path, and the evaluators' values there mean nothing.
const NEPHELE_OUTSIDE_THICKER: u32 = 1u;
const NEPHELE_OUTSIDE_THINNER: u32 = 2u;
const NEPHELE_OUTSIDE_LOWER_SUN: u32 = 4u;
const NEPHELE_NOT_IN_SLAB: u32 = 8u;

// The runtime's `SlabPoint::check`: cosines up to 1 + 10⁻⁶ (f32 rounding of unit vectors).
fn nephele_is_slab_point(at: NepheleSlabPoint) -> bool {
    let top = NEPHELE_F32_MAX;
    let one = 1.0 + 1e-6;
    return at.thickness > 0.0 && at.thickness <= top && at.mu_l > 0.0 && at.mu_l <= one
        && at.depth >= 0.0 && at.depth <= at.thickness && abs(at.mu_v) <= one
        && abs(at.psi_v) <= top;
}

fn nephele_outside(at: NepheleSlabPoint) -> u32 {
    if !nephele_is_slab_point(at) {
        return NEPHELE_NOT_IN_SLAB;
    }
    let d = nephele_tables_domain();
    var bits = 0u;
    if !(at.thickness >= d.thickness.x && at.thickness <= d.thickness.y) {
        bits |= select(NEPHELE_OUTSIDE_THINNER, NEPHELE_OUTSIDE_THICKER,
            at.thickness > d.thickness.y);
    }
    if !(at.mu_l >= d.mu_l.x) {
        bits |= NEPHELE_OUTSIDE_LOWER_SUN;
    }
    return bits;
}

// The weight of T at `at` in a pixel whose view ray has opacity `alpha`: α / (1 − e^{−τ_b}),
// τ_b the slab's own path beyond the viewpoint — (t − d)/μ_V going up, d/|μ_V| going down,
// unbounded along the faces — its opacity held ≥ 10⁻³ (the runtime's `SlabPoint::view_weight`:
// T holds the slab's sources over that path, the pixel over its own ray).
fn nephele_view_weight(at: NepheleSlabPoint, alpha: f32) -> f32 {
    var opacity = 1.0;
    if at.mu_v > 0.0 {
        opacity = -nephele_exp_m1(-(at.thickness - at.depth) / at.mu_v);
    } else if at.mu_v < 0.0 {
        opacity = -nephele_exp_m1(at.depth / at.mu_v);
    }
    return alpha / max(opacity, 1e-3);
}

// Whether the tables can be read at `at` (the runtime's `SlabPoint::in_slab`): t finite and
// > 0, 0 ≤ d ≤ t, μ_L finite and > 0, μ_V and ψ_V finite. Elsewhere T and order 1 are 0. (A
// driver may assume no NaN or infinity: pass finite values.)
fn nephele_in_slab(at: NepheleSlabPoint) -> bool {
    let top = NEPHELE_F32_MAX;
    return at.thickness > 0.0 && at.thickness <= top && at.depth >= 0.0
        && at.depth <= at.thickness && at.mu_l > 0.0 && at.mu_l <= top
        && abs(at.mu_v) <= top && abs(at.psi_v) <= top;
}

// x between two nodes of a grid: weight 1 − w on `lo`, w on `hi` (one node where lo = hi or
// w = 0: `nephele_lerp_nodes`).
struct NepheleLerp {
    lo: u32,
    hi: u32,
    w: f32,
}

// 1 or 2: the nodes a NepheleLerp draws on.
fn nephele_lerp_nodes(l: NepheleLerp) -> u32 {
    return select(1u, 2u, l.hi != l.lo && l.w > 0.0);
}

// The k-th node of `l` (k < nephele_lerp_nodes(l)).
fn nephele_lerp_node(l: NepheleLerp, k: u32) -> u32 {
    return select(l.lo, l.hi, k == 1u);
}

// Its weight.
fn nephele_lerp_weight(l: NepheleLerp, k: u32) -> f32 {
    if nephele_lerp_nodes(l) == 1u {
        return 1.0;
    }
    return select(1.0 - l.w, l.w, k == 1u);
}

// The interval i of the n ≥ 2 increasing values at `offset` with a[i] ≤ x < a[i + 1], held
// to the first and the last outside them.
fn nephele_ntt_bracket(offset: u32, n: u32, x: f32) -> u32 {
    var lo = 0u;
    var hi = max(n, 2u) - 1u;
    while hi - lo > 1u {
        let mid = (lo + hi) / 2u;
        if nephele_ntt_f32(offset + mid) <= x {
            lo = mid;
        } else {
            hi = mid;
        }
    }
    return lo;
}

// Where x sits among the n increasing values at `offset` (held at the ends).
fn nephele_ntt_lerp(offset: u32, n: u32, x: f32) -> NepheleLerp {
    if n <= 1u || !(x > nephele_ntt_f32(offset)) {
        return NepheleLerp(0u, 0u, 0.0);
    }
    if x >= nephele_ntt_f32(offset + n - 1u) {
        return NepheleLerp(n - 1u, n - 1u, 0.0);
    }
    let lo = nephele_ntt_bracket(offset, n, x);
    let va = nephele_ntt_f32(offset + lo);
    let vb = nephele_ntt_f32(offset + lo + 1u);
    return NepheleLerp(lo, lo + 1u, (x - va) / (vb - va));
}

// cos Θ between the sun's propagation direction and the view, 1 − cos Θ = |ω_L − ω_V|²/2, the
// sines from (1 − |μ|)(1 + |μ|) (exact near |μ| = 1).
fn nephele_scattering_cosine(at: NepheleSlabPoint) -> NepheleCosine {
    let sin_l = sqrt(clamp((1.0 - abs(at.mu_l)) * (1.0 + abs(at.mu_l)), 0.0, 1.0));
    let sin_v = sqrt(clamp((1.0 - abs(at.mu_v)) * (1.0 + abs(at.mu_v)), 0.0, 1.0));
    let sc = nephele_sin_cos(at.psi_v);
    let dx = sin_v * sc.x;
    let dz = sin_l - sin_v * sc.y;
    let dd = at.mu_l + at.mu_v;
    return nephele_cosine_from_one_minus_mu(clamp(0.5 * (dx * dx + dz * dz + dd * dd), 0.0, 2.0));
}
