// T = L/E⊥ (sr⁻¹) of one order group of orders ≥ 2 at a slab point, from the `.ntt` in the
// storage buffer: nephele-runtime's `TransportTables::transport`, the log-additive form
// (docs/compress.md), step for step in f32:
//
//   ln T = ln B + Σ_j d_j P_j(2u − 1),  d_j = Σ_features v β_g[col] · L(s_g),
//
// the features v (the depth terms a_j(μ_V) + b_j(μ_L), γ ln F₁, the Θ hats, the azimuth
// harmonics, the view × sun interaction) each times the Legendre series in s_g (the place of
// ln t in the group's span) of its coefficients; inside the group's fitted depths the
// polynomial itself, beyond them continued toward the face ahead; T scaled by the share of the
// grid weight on nodes with fitted cells and capped at 1.5 × the largest fitted T around,
// then times the halo around the transmitted beam (if the file has one: `nephele_nt_halo`).
// The runtime sums each accumulator over the features first and then against L(s_g); here
// each feature's coefficients meet L(s_g) first (one running sum per depth term rather than
// Q, the GPU's private memory being dear): the same terms in another order, as close to f64.
// What costs more than a multiplication (F₁, the angles, the Θ brackets, the harmonics) is
// built once per point (`nephele_nt_prepare`) for every group's passes.
// Needs ntt.wgsl and order1.wgsl (for `nephele_beam_scattered_once`) before it.

const NEPHELE_NT_MAX_LEGENDRE: u32 = 16u;
const NEPHELE_NT_LN_F1_FLOOR: f32 = -10.0;
const NEPHELE_NT_EDGE_STEP: f32 = 0.0666666666666666667;  // 1/15, one plane of the default grid
const NEPHELE_NT_CEILING_FACTOR: f32 = 1.5;

// One pass over the features: the parameters being summed (T's, or one collector
// statistic's), their strides, Q, and the columns summed, [col_lo, col_hi) (c_z's ℓ/σ̂ terms
// are summed apart).
struct NepheleNtPass {
    beta: u32,
    param_stride: u32,
    group_stride: u32,
    q: u32,
    col_lo: u32,
    col_hi: u32,
}

// The running sums d_j of one pass, each feature's coefficients already summed against the
// Legendre terms L_k(s) of the group's place s in its ln t span (nephele_nt_lq).
var<private> nephele_nt_acc: array<f32, 16>;
var<private> nephele_nt_lq: array<f32, 16>;
var<private> nephele_nt_group: u32;
var<private> nephele_nt_pass: NepheleNtPass;

// Starts a pass of group g at its place s in its ln t span: zero sums.
fn nephele_nt_begin(g: u32, sums: NepheleNtPass, s: f32) {
    nephele_nt_acc = array<f32, 16>();
    nephele_nt_lq = nephele_nt_legendre(s, sums.q);
    nephele_nt_group = g;
    nephele_nt_pass = sums;
}

fn nephele_nt_add(col: u32, v: f32, j: u32) {
    let p = nephele_nt_pass;
    if col < p.col_lo || col >= p.col_hi {
        return;
    }
    let start = p.beta + nephele_nt_group * p.group_stride + col * p.param_stride;
    var sum = 0.0;
    for (var k = 0u; k < p.q; k++) {
        sum += nephele_ntt_f32(start + k) * nephele_nt_lq[k];
    }
    nephele_nt_acc[j] += v * sum;
}

// P_0(x) … P_{n−1}(x) by Bonnet's recurrence (n ≤ 16, the rest 0).
fn nephele_nt_legendre(x: f32, n: u32) -> array<f32, 16> {
    var p: array<f32, 16>;
    var prev = 0.0;
    var cur = 1.0;
    for (var k = 0u; k < min(n, NEPHELE_NT_MAX_LEGENDRE); k++) {
        p[k] = cur;
        var next = x;
        if k > 0u {
            let a = f32(2u * k + 1u) / f32(k + 1u);
            let b = f32(k) / f32(k + 1u);
            next = a * x * cur - b * prev;
        }
        prev = cur;
        cur = next;
    }
    return p;
}

// A point's cell: its cosines among the parameter nodes, stretched depth and Θ.
struct NepheleNtCell {
    at: NepheleSlabPoint,
    l: NepheleLerp,
    v: NepheleLerp,
    u: f32,
    theta: f32,
}

// The stretched depth u ∈ [0, 1] of depth d in a slab of thickness t: the inverse of
// d/t = (e^{βu} − 1)/(e^β − 1), β = 0.3 t^0.65.
fn nephele_nt_stretched_u(d: f32, t: f32, ln_t: f32) -> f32 {
    let beta = 0.3 * nephele_exp(0.65 * ln_t);
    if beta < 1e-6 {
        return d / t;
    }
    return clamp(nephele_ln(1.0 + (nephele_exp(beta) - 1.0) * d / t) / beta, 0.0, 1.0);
}

// d/t at stretched depth u.
fn nephele_nt_depth_fraction(u: f32, t: f32) -> f32 {
    let beta = 0.3 * nephele_exp(0.65 * nephele_ln(t));
    if beta < 1e-6 {
        return u;
    }
    return nephele_exp_m1(beta * u) / nephele_exp_m1(beta);
}

// ln B, the boundary factor (the share of optical path behind the viewpoint); false in .y
// where there is none (T = 0).
fn nephele_nt_ln_boundary(at: NepheleSlabPoint) -> vec2<f32> {
    if at.mu_v == 0.0 {
        return vec2<f32>(0.0, 1.0);
    }
    let path = select(at.depth, at.thickness - at.depth, at.mu_v > 0.0);
    let b = -nephele_exp_m1(-path / abs(at.mu_v));
    if !(b > 0.0) {
        return vec2<f32>(0.0, 0.0);
    }
    return vec2<f32>(nephele_ln(b), 1.0);
}

// a(μ_V) + b(μ_L) of value `val` at the columns col … (μ_V nodes) and col + M … (μ_L nodes).
fn nephele_nt_on_nodes(c: NepheleNtCell, col: u32, val: f32, j: u32) {
    let nm = nephele_ntt_index.n_v;
    for (var k = 0u; k < nephele_lerp_nodes(c.v); k++) {
        nephele_nt_add(col + nephele_lerp_node(c.v, k), nephele_lerp_weight(c.v, k) * val, j);
    }
    for (var k = 0u; k < nephele_lerp_nodes(c.l); k++) {
        nephele_nt_add(col + nm + nephele_lerp_node(c.l, k), nephele_lerp_weight(c.l, k) * val, j);
    }
}

// Where Θ sits among the hat nodes Θ_i = π (i/(n − 1))² (n = `nodes`, as the runtime rounds
// them at word `table`): the interval's upper node i and the weight w on it.
struct NepheleNtHat {
    i: u32,
    w: f32,
}

fn nephele_nt_hat(theta: f32, nodes: u32, table: u32) -> NepheleNtHat {
    let n = max(nodes, 2u);
    let top = f32(n - 1u);
    var i = clamp(u32(sqrt(max(theta / NEPHELE_PI, 0.0)) * top), 1u, n - 1u);
    while i > 1u && nephele_ntt_f32(table + i - 1u) >= theta {
        i -= 1u;
    }
    while i < n - 1u && nephele_ntt_f32(table + i) < theta {
        i += 1u;
    }
    let a = nephele_ntt_f32(table + i - 1u);
    let b = nephele_ntt_f32(table + i);
    return NepheleNtHat(i, clamp((theta - a) / (b - a), 0.0, 1.0));
}

// The Θ hats val h_i(Θ) (P_0, P_1)(2u − 1) at columns col + 2i + j.
fn nephele_nt_theta_hats(h: NepheleNtHat, col: u32, val: f32) {
    for (var j = 0u; j < 2u; j++) {
        nephele_nt_add(col + 2u * (h.i - 1u) + j, val * (1.0 - h.w), j);
        nephele_nt_add(col + 2u * h.i + j, val * h.w, j);
    }
}

// What a point's features need beyond multiplications, built once per point for all groups
// (`nephele_nt_prepare`) and read by every group's passes.
struct NepheleNtPoint {
    cell: NepheleNtCell,
    near_t: NepheleLerp,
    ln_t: f32,
    ln_b: f32,                 // ln B
    live: bool,                // B > 0 and F₁ a number: the form can be read (else T = 0)
    ln_f1: f32,                // max(ln F₁, −10)
    hat: NepheleNtHat,                // T's Θ hats
    c_hat: NepheleNtHat,              // the collector's
    harmonic: array<f32, 9>,   // (s_V s_L)^k cos kψ, k = 1 … K
    pv: array<f32, 8>,         // P_a(2|μ_V| − 1), a < A
    pl: array<f32, 8>,         // P_b(2μ_L − 1), b < A
    cos_k: array<f32, 5>,      // cos kψ, k = 0 … 4
    sin_k: array<f32, 5>,      // sin kψ
    sv_sl_k: array<f32, 5>,    // (s_V s_L)^k
    s_l: f32,
    reach: f32,                // ℓ = s_L λ (1 − e^{−d/(μ_L λ)})
}

var<private> nephele_nt_pt: NepheleNtPoint;

// Builds the point's features (nephele_nt_pt) at `at`, a point within the grid's thicknesses.
fn nephele_nt_prepare(at: NepheleSlabPoint) {
    let x = nephele_ntt_index;
    let t = at.thickness;
    nephele_nt_pt.live = false;
    if !nephele_in_slab(at) {
        return;
    }
    let ln_t = nephele_ln(t);
    nephele_nt_pt.ln_t = ln_t;
    let omm = nephele_scattering_cosine(at).one_minus_mu;
    let cell = NepheleNtCell(at, nephele_ntt_lerp(x.mu_l, x.n_l, at.mu_l),
        nephele_ntt_lerp(x.mu_v, x.n_v, at.mu_v),
        nephele_nt_stretched_u(at.depth, t, ln_t), 2.0 * nephele_asin(min(sqrt(0.5 * omm), 1.0)));
    nephele_nt_pt.cell = cell;
    nephele_nt_pt.near_t = nephele_ntt_lerp(x.thickness, x.n_t, t);
    let boundary = nephele_nt_ln_boundary(at);
    nephele_nt_pt.ln_b = boundary.x;
    let iso = nephele_hg_eval(0.0, nephele_cosine_from_mu(1.0));
    let f1 = 4.0 * NEPHELE_PI * nephele_beam_scattered_once(iso, at);
    if boundary.y == 0.0 || !(f1 >= 0.0) {
        return;
    }
    nephele_nt_pt.live = true;
    var ln_f1 = NEPHELE_NT_LN_F1_FLOOR;
    if f1 > 0.0 && nephele_ln(f1) > NEPHELE_NT_LN_F1_FLOOR {
        ln_f1 = nephele_ln(f1);
    }
    nephele_nt_pt.ln_f1 = ln_f1;
    nephele_nt_pt.hat = nephele_nt_hat(cell.theta, x.theta_nodes, x.theta_hats);
    let mu_v = at.mu_v;
    let mu_l = at.mu_l;
    let s = sqrt(clamp((1.0 - mu_v * mu_v) * (1.0 - mu_l * mu_l), 0.0, 1.0));
    // cos kψ by Chebyshev's recurrence: one cosine per point.
    let cos_1 = nephele_sin_cos(at.psi_v).y;
    var s_k = 1.0;
    var cos_prev = cos_1;
    var cos_k = 1.0;
    for (var k = 1u; k <= min(x.harmonics, 8u); k++) {
        s_k = s_k * s;
        let next = select(2.0 * cos_1 * cos_k - cos_prev, cos_1, k == 1u);
        cos_prev = cos_k;
        cos_k = next;
        nephele_nt_pt.harmonic[k] = s_k * cos_k;
    }
    let a = min(x.cross, 6u);
    let pv = nephele_nt_legendre(2.0 * abs(mu_v) - 1.0, a);
    let pl = nephele_nt_legendre(2.0 * mu_l - 1.0, a);
    for (var i = 0u; i < a; i++) {
        nephele_nt_pt.pv[i] = pv[i];
        nephele_nt_pt.pl[i] = pl[i];
    }
    if x.has_collector == 0u {
        return;
    }
    nephele_nt_pt.c_hat = nephele_nt_hat(cell.theta, x.c_theta_nodes, x.c_theta_hats);
    let s_l = sqrt(clamp(1.0 - mu_l * mu_l, 0.0, 1.0));
    let s_v = sqrt(clamp(1.0 - mu_v * mu_v, 0.0, 1.0));
    nephele_nt_pt.s_l = s_l;
    var sk = 1.0;
    for (var k = 0u; k <= 4u; k++) {
        let sc = nephele_sin_cos(f32(k) * at.psi_v);
        nephele_nt_pt.cos_k[k] = sc.y;
        nephele_nt_pt.sin_k[k] = sc.x;
        nephele_nt_pt.sv_sl_k[k] = sk;
        sk = sk * s_v * s_l;
    }
    let mu_l_r = select(0.05, mu_l, mu_l > 0.05);
    nephele_nt_pt.reach = s_l * 8.0 * -nephele_exp_m1(-at.depth / (mu_l_r * 8.0));
}

// Adds every feature of the form at the prepared point to the running sums.
fn nephele_nt_features() {
    let x = nephele_ntt_index;
    let c = nephele_nt_pt.cell;
    let nm = x.n_v;
    let nl = x.n_l;
    let ln_f1 = nephele_nt_pt.ln_f1;
    var col = 0u;
    for (var j = 0u; j < min(x.legendre, NEPHELE_NT_MAX_LEGENDRE); j++) {
        nephele_nt_on_nodes(c, col, 1.0, j);
        col += nm + nl;
    }
    if x.pairs == 1u {
        for (var a = 0u; a < nephele_lerp_nodes(c.v); a++) {
            for (var b = 0u; b < nephele_lerp_nodes(c.l); b++) {
                let p = nephele_lerp_node(c.v, a) * nl + nephele_lerp_node(c.l, b);
                let w = nephele_lerp_weight(c.v, a) * nephele_lerp_weight(c.l, b);
                nephele_nt_add(col + p, w * ln_f1, 0u);
            }
        }
        col += nm * nl;
        for (var a = 0u; a < nephele_lerp_nodes(c.v); a++) {
            for (var b = 0u; b < nephele_lerp_nodes(c.l); b++) {
                let p = nephele_lerp_node(c.v, a) * nl + nephele_lerp_node(c.l, b);
                let w = nephele_lerp_weight(c.v, a) * nephele_lerp_weight(c.l, b);
                nephele_nt_add(col + 2u * p, w, 0u);
                nephele_nt_add(col + 2u * p + 1u, w, 1u);
            }
        }
        col += 2u * nm * nl;
    } else {
        for (var k = 0u; k < nephele_lerp_nodes(c.v); k++) {
            nephele_nt_add(col + nephele_lerp_node(c.v, k), nephele_lerp_weight(c.v, k) * ln_f1,
                0u);
        }
        col += nm;
    }
    nephele_nt_theta_hats(nephele_nt_pt.hat, col, 1.0);
    col += 2u * x.theta_nodes;
    for (var k = 1u; k <= min(x.harmonics, 8u); k++) {
        nephele_nt_on_nodes(c, col, nephele_nt_pt.harmonic[k], 0u);
        col += nm + nl;
    }
    let a = min(x.cross, 6u);
    if a > 0u {
        for (var k = 0u; k < nephele_lerp_nodes(c.l); k++) {
            nephele_nt_add(col + nephele_lerp_node(c.l, k), nephele_lerp_weight(c.l, k) * ln_f1,
                0u);
        }
        col += nl;
        let hemi = select(a * a, 0u, c.at.mu_v > 0.0);
        for (var j = 0u; j < 3u; j++) {
            let base = col + j * 2u * a * a + hemi;
            for (var ia = 0u; ia < a; ia++) {
                for (var ib = 0u; ib < a; ib++) {
                    nephele_nt_add(base + ia * a + ib,
                        nephele_nt_pt.pv[ia] * nephele_nt_pt.pl[ib], j);
                }
            }
        }
    }
}

// The depths the group's fit had cells at around the point and the share of the weight on
// nodes with any: (lo, hi, share); share 0 where no node has cells (T = 0).
fn nephele_nt_fitted_depths(g: u32, near_t: NepheleLerp, c: NepheleNtCell) -> vec3<f32> {
    let x = nephele_ntt_index;
    let per_group = x.n_t * x.n_l * x.n_v;
    var total = 0.0;
    var w = 0.0;
    var lo = 0.0;
    var hi = 0.0;
    let step = 1.0 / 4095.0;
    for (var a = 0u; a < nephele_lerp_nodes(near_t); a++) {
        for (var b = 0u; b < nephele_lerp_nodes(c.l); b++) {
            for (var m = 0u; m < nephele_lerp_nodes(c.v); m++) {
                let corner = ((nephele_lerp_node(near_t, a) * x.n_l)
                    + nephele_lerp_node(c.l, b)) * x.n_v
                    + nephele_lerp_node(c.v, m);
                let wk = nephele_lerp_weight(near_t, a) * nephele_lerp_weight(c.l, b)
                    * nephele_lerp_weight(c.v, m);
                let packed = u32(nephele_ntt_f32(x.u_range + g * per_group + corner));
                let ra = f32(packed / 4096u) * step;
                let rb = f32(packed % 4096u) * step;
                total += wk;
                let has = select(0.0, 1.0, ra <= rb && wk > 0.0);
                w += wk * has;
                lo += wk * ra * has;
                hi += wk * rb * has;
            }
        }
    }
    if !(w > 0.0) {
        return vec3<f32>(0.0, 0.0, 0.0);
    }
    return vec3<f32>(lo / w, hi / w, w / total);
}

// 1.5 × the largest fitted T of group g at the (thickness, μ_L) nodes the point draws on; a
// negative number where the file has no ceiling.
fn nephele_nt_ceiling(g: u32, near_t: NepheleLerp, c: NepheleNtCell) -> f32 {
    let x = nephele_ntt_index;
    if x.has_ceiling == 0u {
        return -1.0;
    }
    let base = g * x.n_t * x.n_l;
    var most = 0.0;
    for (var a = 0u; a < nephele_lerp_nodes(near_t); a++) {
        for (var b = 0u; b < nephele_lerp_nodes(c.l); b++) {
            let k = nephele_lerp_node(near_t, a) * x.n_l + nephele_lerp_node(c.l, b);
            most = max(most, nephele_ntt_f32(x.t_ceiling + base + k));
        }
    }
    return NEPHELE_NT_CEILING_FACTOR * most;
}

// Σ_{j<n} d_j P_j(2u − 1).
fn nephele_nt_polynomial(d: array<f32, 16>, n: u32, u: f32) -> f32 {
    let p = nephele_nt_legendre(2.0 * u - 1.0, n);
    var s = 0.0;
    for (var j = 0u; j < n; j++) {
        s += d[j] * p[j];
    }
    return s;
}

fn nephele_nt_held(r: vec3<f32>, u: f32) -> f32 {
    if u < r.x {
        return r.x;
    }
    if u > r.y {
        return r.y;
    }
    return u;
}

// ln of T/B at distance h from the face ahead relative to the fitted edge's (distance
// h_edge), given the rise one step further inside (distance h_inside): the line, floored by
// the exponential scaled by the line's zero crossing (the runtime's `continued_toward_face`).
fn nephele_nt_continued_toward_face(rise: f32, h_inside: f32, h_edge: f32, h: f32) -> f32 {
    let run = h_inside - h_edge;
    if !(run > 0.0) || !(h_edge > 0.0) {
        return 0.0;
    }
    let exponential = -rise * (h_edge - h) / run;
    let up = nephele_exp_m1(rise);
    let line = 1.0 + up * (h - h_edge) / run;
    let crossing = h_edge - run / up;
    var s = crossing / h_edge;
    if s > 1.0 {
        s = 1.0;
    } else if !(s > 0.0) {
        s = 0.0;
    }
    let floor_v = s * nephele_exp(exponential);
    let rel = select(floor_v, line, line > floor_v);
    if rel > 0.0 {
        return nephele_ln(rel);
    }
    return exponential;
}

// 1 − d/t at stretched depth u, without the cancellation of 1 − nephele_nt_depth_fraction near the
// far face: e^{βu} (e^{β(1−u)} − 1)/(e^β − 1).
fn nephele_nt_far_fraction(u: f32, t: f32) -> f32 {
    let beta = 0.3 * nephele_exp(0.65 * nephele_ln(t));
    if beta < 1e-6 {
        return 1.0 - u;
    }
    return nephele_exp(beta * u) * nephele_exp_m1(beta * (1.0 - u)) / nephele_exp_m1(beta);
}

// The depth part of ln T at u, read as the tables' information allows (the runtime's
// `depth_polynomial`).
fn nephele_nt_depth_polynomial(d: array<f32, 16>, n: u32, u: f32, thickness: f32,
    r: vec3<f32>) -> f32 {
    let edge = nephele_nt_held(r, u);
    let value = nephele_nt_polynomial(d, n, edge);
    if edge == u {
        return value;
    }
    let far = u > r.y;
    let inside = nephele_nt_held(r, select(r.x + NEPHELE_NT_EDGE_STEP, r.y - NEPHELE_NT_EDGE_STEP,
        far));
    let inner = nephele_nt_polynomial(d, n, inside);
    if !(abs(edge - inside) > 0.0) || !(inner > value) {
        return value;
    }
    var h_inside: f32;
    var h_edge: f32;
    var h: f32;
    if far {
        h_inside = thickness * nephele_nt_far_fraction(inside, thickness);
        h_edge = thickness * nephele_nt_far_fraction(edge, thickness);
        h = thickness * nephele_nt_far_fraction(u, thickness);
    } else {
        h_inside = thickness * nephele_nt_depth_fraction(inside, thickness);
        h_edge = thickness * nephele_nt_depth_fraction(edge, thickness);
        h = thickness * nephele_nt_depth_fraction(u, thickness);
    }
    return value + nephele_nt_continued_toward_face(inner - value, h_inside, h_edge, h);
}

// The median angle (degrees) of the halo's annulus b.
fn nephele_nt_halo_centre(b: u32) -> f32 {
    let a = nephele_ntt_f32(nephele_ntt_index.halo_edges + b);
    let c = nephele_ntt_f32(nephele_ntt_index.halo_edges + b + 1u);
    return sqrt(0.5 * (a * a + c * c));
}

// e^h, the halo around the transmitted beam of group g at the cell (the runtime's
// `transport::halo`): for views going down within the last edge, h read linearly between the
// thickness and sun-cosine nodes, the planes and the annuli's median angles, held below the
// first and falling to 0 at the last edge; 1 elsewhere and for the groups it does not cover.
fn nephele_nt_halo(g: u32, near_t: NepheleLerp, c: NepheleNtCell) -> f32 {
    let x = nephele_ntt_index;
    if g >= x.halo_groups || x.n_halo_edges < 2u {
        return 1.0;
    }
    let nb = x.n_halo_edges - 1u;
    let last = nephele_ntt_f32(x.halo_edges + nb);
    let deg = c.theta * (180.0 / NEPHELE_PI);
    if !(c.at.mu_v < 0.0) || !(deg < last) {
        return 1.0;
    }
    var ab = vec2<u32>(0u, 0u);
    var aw = vec2<f32>(1.0, 0.0);
    let top = nephele_nt_halo_centre(nb - 1u);
    if deg >= top {
        ab.x = nb - 1u;
        aw.x = (last - deg) / (last - top);
    } else if deg > nephele_nt_halo_centre(0u) {
        var b = 0u;
        while b + 2u < nb && nephele_nt_halo_centre(b + 1u) <= deg {
            b += 1u;
        }
        let lo = nephele_nt_halo_centre(b);
        let w = (deg - lo) / (nephele_nt_halo_centre(b + 1u) - lo);
        ab = vec2<u32>(b, b + 1u);
        aw = vec2<f32>(1.0 - w, w);
    }
    let planes = x.halo_planes;
    let xj = clamp(c.u, 0.0, 1.0) * f32(planes - 1u);
    let j0 = min(u32(xj), planes - 1u);
    let j1 = min(j0 + 1u, planes - 1u);
    let wj = xj - f32(j0);
    let base = x.halo + g * x.n_t * x.n_l * planes * nb;
    var h = 0.0;
    for (var a = 0u; a < nephele_lerp_nodes(near_t); a++) {
        for (var b = 0u; b < nephele_lerp_nodes(c.l); b++) {
            let wtl = nephele_lerp_weight(near_t, a) * nephele_lerp_weight(c.l, b);
            for (var k = 0u; k < 2u; k++) {
                let j = select(j0, j1, k == 1u);
                let wjk = select(1.0 - wj, wj, k == 1u);
                let node = nephele_lerp_node(near_t, a) * x.n_l + nephele_lerp_node(c.l, b);
                let row = (node * planes + j) * nb;
                for (var e = 0u; e < 2u; e++) {
                    h += wtl * wjk * aw[e] * nephele_ntt_f32(base + row + ab[e]);
                }
            }
        }
    }
    return nephele_exp(h);
}

// T of group g at the prepared point, with what the collector needs of it (the point's cell
// is nephele_nt_pt.cell).
struct NepheleNtT {
    t: f32,
    range: vec3<f32>,  // the fitted depths (lo, hi, share)
    s: f32,            // the place of ln t in the group's span
}

// The place of ln t in group g's span of ln t, in [−1, 1] (0 for an empty span).
fn nephele_nt_span_position(g: u32, ln_t: f32) -> f32 {
    let x = nephele_ntt_index;
    let a = nephele_ntt_f32(x.ln_t_range + 2u * g);
    let b = nephele_ntt_f32(x.ln_t_range + 2u * g + 1u);
    if b > a {
        return clamp(2.0 * (ln_t - a) / (b - a) - 1.0, -1.0, 1.0);
    }
    return 0.0;
}

// T of group g at the prepared point (nephele_nt_prepare).
fn nephele_nt_transport(g: u32) -> NepheleNtT {
    let x = nephele_ntt_index;
    var r: NepheleNtT;
    r.t = 0.0;
    let cell = nephele_nt_pt.cell;
    if g >= x.groups || !nephele_nt_pt.live {
        return r;
    }
    let near_t = nephele_nt_pt.near_t;
    r.range = nephele_nt_fitted_depths(g, near_t, cell);
    if !(r.range.z > 0.0) {
        return r;
    }
    r.s = nephele_nt_span_position(g, nephele_nt_pt.ln_t);
    nephele_nt_begin(g, NepheleNtPass(x.beta, x.param_stride, x.group_stride, x.q, 0u,
        0xffffffffu), r.s);
    nephele_nt_features();
    let depth = nephele_nt_depth_polynomial(nephele_nt_acc, x.depth_terms, cell.u,
        cell.at.thickness, r.range);
    let v = r.range.z * nephele_exp(nephele_nt_pt.ln_b + depth);
    let top = nephele_nt_ceiling(g, near_t, cell);
    r.t = select(v, top, top >= 0.0 && v > top) * nephele_nt_halo(g, near_t, cell);
    return r;
}

// A point of a slab thicker than the tables' thickest, continued into it by diffusion theory
// (the runtime's transport/thick.rs, step for step), and a point under a sun below the
// grid's lowest, read under it with T scaled by μ_L/μ₀ (the runtime's `lowest_sun`: T/μ_L
// held): where it reads the tables, and how T and σ scale. Within the grid: the point
// itself, every scale 1.
struct NepheleNtContinued {
    at: NepheleSlabPoint,
    diffuse: f32,         // φ_t(d)/φ_tmax(d'): the open-ended group's T; the others' min(1, it)
    spread: f32,          // σ's scale for the groups of few orders, d/d' past t_max/2
    spread_diffuse: f32,  // the open-ended group's, √(t d / (t_max d'))
    sun: f32,             // μ_L/μ₀ below the lowest sun μ₀, else 1
}

// The diffusion fluence at depth z of a slab t thick lit at depth z_s, zero at z_e outside
// each face (unnormalised), as its two factors.
fn nephele_nt_fluence(z: f32, t: f32, z_s: f32, z_e: f32) -> vec2<f32> {
    return vec2<f32>(min(z, z_s) + z_e, (t + z_e - max(z, z_s)) / (t + 2.0 * z_e));
}

fn nephele_nt_continued(point: NepheleSlabPoint) -> NepheleNtContinued {
    let x = nephele_ntt_index;
    var at = point;
    var sun = 1.0;
    let lowest = nephele_ntt_f32(x.mu_l);
    if at.mu_l < lowest {
        sun = at.mu_l / lowest;
        at.mu_l = lowest;
    }
    var c = NepheleNtContinued(at, 1.0, 1.0, 1.0, sun);
    let t_max = nephele_ntt_f32(x.thickness + x.n_t - 1u);
    let t = at.thickness;
    if !(t > t_max) || !nephele_in_slab(at) {
        return c;
    }
    let half = 0.5 * t_max;
    let d = at.depth;
    let h = at.thickness - at.depth;
    var depth = half;
    if d <= half {
        depth = d;
    } else if h <= half {
        depth = t_max - h;
    }
    let g_mean = min(bitcast<f32>(x.mean_cosine), 0.999);
    let z_s = min(at.mu_l / (1.0 - g_mean), half);
    let z_e = 2.0 / (3.0 * (1.0 - g_mean));
    let here = nephele_nt_fluence(d, t, z_s, z_e);
    let there = nephele_nt_fluence(depth, t_max, z_s, z_e);
    c.diffuse = (here.x / there.x) * (here.y / there.y);
    if depth > 0.0 && d > half {
        c.spread = d / depth;
    }
    c.spread_diffuse = sqrt(t / t_max) * select(1.0, sqrt(d / depth), depth > 0.0);
    c.at = NepheleSlabPoint(t_max, at.mu_l, depth, at.mu_v, at.psi_v);
    return c;
}

// How group g's T scales past the thickest slab and below the lowest sun.
fn nephele_nt_diffuse_scale(g: u32, c: NepheleNtContinued) -> f32 {
    if g + 1u == nephele_ntt_index.groups {
        return c.diffuse * c.sun;
    }
    return min(c.diffuse, 1.0) * c.sun;
}

// T (sr⁻¹) of group g at `at`; 0 where the tables resolve nothing or g is not a group. Past
// the thickest slab, continued by diffusion theory (nephele_nt_continued).
fn nephele_transport(g: u32, at: NepheleSlabPoint) -> f32 {
    let c = nephele_nt_continued(at);
    nephele_nt_prepare(c.at);
    return nephele_nt_transport(g).t * nephele_nt_diffuse_scale(g, c);
}

// The most order groups the WGSL port evaluates in one call (`ntt_for_gpu` refuses more).
const NEPHELE_MAX_GROUPS: u32 = 8u;

// T (sr⁻¹) of every order group at `at` (groups beyond the file's 0), the point's features
// built once: `nephele_transport` for each group at the cost of little more than one.
fn nephele_transport_all(at: NepheleSlabPoint) -> array<f32, 8> {
    let c = nephele_nt_continued(at);
    nephele_nt_prepare(c.at);
    var out: array<f32, 8>;
    for (var g = 0u; g < min(nephele_ntt_index.groups, NEPHELE_MAX_GROUPS); g++) {
        out[g] = nephele_nt_transport(g).t * nephele_nt_diffuse_scale(g, c);
    }
    return out;
}
