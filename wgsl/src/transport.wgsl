// T = L/E⊥ (sr⁻¹) of one order group of orders ≥ 2 at a slab point, from the `.ntt` in the
// storage buffer: nephele-runtime's `TransportTables::transport`, the log-additive form
// (docs/compress.md), step for step and sum for sum in f32:
//
//   ln T = ln B + Σ_j d_j P_j(2u − 1),  d_j = Σ_features v β_g[col] · L(s_g),
//
// the features v (the depth terms a_j(μ_V) + b_j(μ_L), γ ln F₁, the Θ hats, the azimuth
// harmonics, the view × sun interaction) each times the Legendre series in s_g (the place of
// ln t in the group's span) of its coefficients; inside the group's fitted depths the
// polynomial itself, beyond them continued toward the face ahead; T scaled by the share of the
// grid weight on nodes with fitted cells and capped at 1.5 × the largest fitted T around,
// then times the halo around the transmitted beam (if the file has one: `nt_halo`).
// Needs ntt.wgsl and order1.wgsl (for `beam_scattered_once`) before it.

const NT_MAX_LEGENDRE: u32 = 16u;
const NT_LN_F1_FLOOR: f32 = -10.0;
const NT_EDGE_STEP: f32 = 0.0666666666666666667;  // 1/15, one plane of the default grid
const NT_CEILING_FACTOR: f32 = 1.5;

// The running sums of one group: acc[j Q + k] = Σ over the features of depth degree j of
// v β[col][k], summed in the order the features come (as the runtime's `Sums`), for the
// parameters being summed (T's, or one collector statistic's: `nt_pass`), columns in
// [col_lo, col_hi) only (c_z's ℓ/σ̂ terms are summed apart).
struct NtPass {
    beta: u32,
    param_stride: u32,
    group_stride: u32,
    q: u32,
    col_lo: u32,
    col_hi: u32,
}

var<private> nt_acc: array<f32, 256>;
var<private> nt_group: u32;
var<private> nt_pass: NtPass;

// Starts a pass of group g: zero sums.
fn nt_begin(g: u32, sums: NtPass) {
    for (var i = 0u; i < 256u; i++) {
        nt_acc[i] = 0.0;
    }
    nt_group = g;
    nt_pass = sums;
}

fn nt_add(col: u32, v: f32, j: u32) {
    let p = nt_pass;
    if col < p.col_lo || col >= p.col_hi {
        return;
    }
    let start = p.beta + nt_group * p.group_stride + col * p.param_stride;
    for (var k = 0u; k < p.q; k++) {
        nt_acc[j * p.q + k] += v * ntt_f32(start + k);
    }
}

// d_j = Σ_k acc[j Q + k] L_k(s) for j < n: the coefficients of the depth polynomial at the
// group's place s in its ln t span.
fn nt_depth_sums(s: f32, n: u32) -> array<f32, 16> {
    let q = nt_pass.q;
    let lq = nt_legendre(s, q);
    var d: array<f32, 16>;
    for (var j = 0u; j < min(n, NT_MAX_LEGENDRE); j++) {
        var sum = 0.0;
        for (var k = 0u; k < q; k++) {
            sum += nt_acc[j * q + k] * lq[k];
        }
        d[j] = sum;
    }
    return d;
}

// P_0(x) … P_{n−1}(x) by Bonnet's recurrence (n ≤ 16, the rest 0).
fn nt_legendre(x: f32, n: u32) -> array<f32, 16> {
    var p: array<f32, 16>;
    var prev = 0.0;
    var cur = 1.0;
    for (var k = 0u; k < min(n, NT_MAX_LEGENDRE); k++) {
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
struct NtCell {
    at: SlabPoint,
    l: Lerp,
    v: Lerp,
    u: f32,
    theta: f32,
}

// The stretched depth u ∈ [0, 1] of depth d in a slab of thickness t: the inverse of
// d/t = (e^{βu} − 1)/(e^β − 1), β = 0.3 t^0.65.
fn nt_stretched_u(d: f32, t: f32, ln_t: f32) -> f32 {
    let beta = 0.3 * nephele_exp(0.65 * ln_t);
    if beta < 1e-6 {
        return d / t;
    }
    return clamp(nephele_ln(1.0 + (nephele_exp(beta) - 1.0) * d / t) / beta, 0.0, 1.0);
}

// d/t at stretched depth u.
fn nt_depth_fraction(u: f32, t: f32) -> f32 {
    let beta = 0.3 * nephele_exp(0.65 * nephele_ln(t));
    if beta < 1e-6 {
        return u;
    }
    return nephele_exp_m1(beta * u) / nephele_exp_m1(beta);
}

// ln B, the boundary factor (the share of optical path behind the viewpoint); false in .y
// where there is none (T = 0).
fn nt_ln_boundary(at: SlabPoint) -> vec2<f32> {
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
fn nt_on_nodes(c: NtCell, col: u32, val: f32, j: u32) {
    let nm = nephele_ntt_index.n_v;
    for (var k = 0u; k < lerp_nodes(c.v); k++) {
        nt_add(col + lerp_node(c.v, k), lerp_weight(c.v, k) * val, j);
    }
    for (var k = 0u; k < lerp_nodes(c.l); k++) {
        nt_add(col + nm + lerp_node(c.l, k), lerp_weight(c.l, k) * val, j);
    }
}

// The Θ hats val h_i(Θ) (P_0, P_1)(2u − 1) at columns col + 2i + j, nodes Θ_i = π (i/(n − 1))²
// (n = `nodes`, as the runtime rounds them at word `table`).
fn nt_theta_hats(c: NtCell, col: u32, val: f32, nodes: u32, table: u32) {
    let n = max(nodes, 2u);
    let top = f32(n - 1u);
    let theta = c.theta;
    var i = clamp(u32(sqrt(max(theta / PI, 0.0)) * top), 1u, n - 1u);
    while i > 1u && ntt_f32(table + i - 1u) >= theta {
        i -= 1u;
    }
    while i < n - 1u && ntt_f32(table + i) < theta {
        i += 1u;
    }
    let a = ntt_f32(table + i - 1u);
    let b = ntt_f32(table + i);
    let w = clamp((theta - a) / (b - a), 0.0, 1.0);
    for (var j = 0u; j < 2u; j++) {
        nt_add(col + 2u * (i - 1u) + j, val * (1.0 - w), j);
        nt_add(col + 2u * i + j, val * w, j);
    }
}

// Adds every feature of the form at `c` to the running sums; false where F₁ is not a number.
fn nt_features(c: NtCell) -> bool {
    let x = nephele_ntt_index;
    let nm = x.n_v;
    let nl = x.n_l;
    let iso = hg_eval(0.0, cosine_from_mu(1.0));
    let f1 = 4.0 * PI * beam_scattered_once(iso, c.at);
    if !(f1 >= 0.0) {
        return false;
    }
    var ln_f1 = NT_LN_F1_FLOOR;
    if f1 > 0.0 && nephele_ln(f1) > NT_LN_F1_FLOOR {
        ln_f1 = nephele_ln(f1);
    }
    var col = 0u;
    for (var j = 0u; j < min(x.legendre, NT_MAX_LEGENDRE); j++) {
        nt_on_nodes(c, col, 1.0, j);
        col += nm + nl;
    }
    if x.pairs == 1u {
        for (var a = 0u; a < lerp_nodes(c.v); a++) {
            for (var b = 0u; b < lerp_nodes(c.l); b++) {
                let p = lerp_node(c.v, a) * nl + lerp_node(c.l, b);
                nt_add(col + p, lerp_weight(c.v, a) * lerp_weight(c.l, b) * ln_f1, 0u);
            }
        }
        col += nm * nl;
        for (var a = 0u; a < lerp_nodes(c.v); a++) {
            for (var b = 0u; b < lerp_nodes(c.l); b++) {
                let p = lerp_node(c.v, a) * nl + lerp_node(c.l, b);
                let w = lerp_weight(c.v, a) * lerp_weight(c.l, b);
                nt_add(col + 2u * p, w, 0u);
                nt_add(col + 2u * p + 1u, w, 1u);
            }
        }
        col += 2u * nm * nl;
    } else {
        for (var k = 0u; k < lerp_nodes(c.v); k++) {
            nt_add(col + lerp_node(c.v, k), lerp_weight(c.v, k) * ln_f1, 0u);
        }
        col += nm;
    }
    nt_theta_hats(c, col, 1.0, x.theta_nodes, x.theta_hats);
    col += 2u * x.theta_nodes;
    let mu_v = c.at.mu_v;
    let mu_l = c.at.mu_l;
    let s = sqrt(clamp((1.0 - mu_v * mu_v) * (1.0 - mu_l * mu_l), 0.0, 1.0));
    // cos kψ by Chebyshev's recurrence: one cosine per point.
    let cos_1 = nephele_sin_cos(c.at.psi_v).y;
    var s_k = 1.0;
    var cos_prev = cos_1;
    var cos_k = 1.0;
    for (var k = 1u; k <= x.harmonics; k++) {
        s_k = s_k * s;
        let next = select(2.0 * cos_1 * cos_k - cos_prev, cos_1, k == 1u);
        cos_prev = cos_k;
        cos_k = next;
        nt_on_nodes(c, col, s_k * cos_k, 0u);
        col += nm + nl;
    }
    let a = min(x.cross, 6u);
    if a > 0u {
        for (var k = 0u; k < lerp_nodes(c.l); k++) {
            nt_add(col + lerp_node(c.l, k), lerp_weight(c.l, k) * ln_f1, 0u);
        }
        col += nl;
        let pv = nt_legendre(2.0 * abs(mu_v) - 1.0, a);
        let pl = nt_legendre(2.0 * mu_l - 1.0, a);
        let hemi = select(a * a, 0u, mu_v > 0.0);
        for (var j = 0u; j < 3u; j++) {
            let base = col + j * 2u * a * a + hemi;
            for (var ia = 0u; ia < a; ia++) {
                for (var ib = 0u; ib < a; ib++) {
                    nt_add(base + ia * a + ib, pv[ia] * pl[ib], j);
                }
            }
        }
    }
    return true;
}

// The depths the group's fit had cells at around the point and the share of the weight on
// nodes with any: (lo, hi, share); share 0 where no node has cells (T = 0).
fn nt_fitted_depths(g: u32, near_t: Lerp, c: NtCell) -> vec3<f32> {
    let x = nephele_ntt_index;
    let per_group = x.n_t * x.n_l * x.n_v;
    var total = 0.0;
    var w = 0.0;
    var lo = 0.0;
    var hi = 0.0;
    let step = 1.0 / 4095.0;
    for (var a = 0u; a < lerp_nodes(near_t); a++) {
        for (var b = 0u; b < lerp_nodes(c.l); b++) {
            for (var m = 0u; m < lerp_nodes(c.v); m++) {
                let corner = ((lerp_node(near_t, a) * x.n_l) + lerp_node(c.l, b)) * x.n_v
                    + lerp_node(c.v, m);
                let wk = lerp_weight(near_t, a) * lerp_weight(c.l, b) * lerp_weight(c.v, m);
                let packed = u32(ntt_f32(x.u_range + g * per_group + corner));
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
fn nt_ceiling(g: u32, near_t: Lerp, c: NtCell) -> f32 {
    let x = nephele_ntt_index;
    if x.has_ceiling == 0u {
        return -1.0;
    }
    let base = g * x.n_t * x.n_l;
    var most = 0.0;
    for (var a = 0u; a < lerp_nodes(near_t); a++) {
        for (var b = 0u; b < lerp_nodes(c.l); b++) {
            let k = lerp_node(near_t, a) * x.n_l + lerp_node(c.l, b);
            most = max(most, ntt_f32(x.t_ceiling + base + k));
        }
    }
    return NT_CEILING_FACTOR * most;
}

// Σ_{j<n} d_j P_j(2u − 1).
fn nt_polynomial(d: array<f32, 16>, n: u32, u: f32) -> f32 {
    let p = nt_legendre(2.0 * u - 1.0, n);
    var s = 0.0;
    for (var j = 0u; j < n; j++) {
        s += d[j] * p[j];
    }
    return s;
}

fn nt_held(r: vec3<f32>, u: f32) -> f32 {
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
fn nt_continued_toward_face(rise: f32, h_inside: f32, h_edge: f32, h: f32) -> f32 {
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

// 1 − d/t at stretched depth u, without the cancellation of 1 − nt_depth_fraction near the
// far face: e^{βu} (e^{β(1−u)} − 1)/(e^β − 1).
fn nt_far_fraction(u: f32, t: f32) -> f32 {
    let beta = 0.3 * nephele_exp(0.65 * nephele_ln(t));
    if beta < 1e-6 {
        return 1.0 - u;
    }
    return nephele_exp(beta * u) * nephele_exp_m1(beta * (1.0 - u)) / nephele_exp_m1(beta);
}

// The depth part of ln T at u, read as the tables' information allows (the runtime's
// `depth_polynomial`).
fn nt_depth_polynomial(d: array<f32, 16>, n: u32, u: f32, thickness: f32, r: vec3<f32>) -> f32 {
    let edge = nt_held(r, u);
    let value = nt_polynomial(d, n, edge);
    if edge == u {
        return value;
    }
    let far = u > r.y;
    let inside = nt_held(r, select(r.x + NT_EDGE_STEP, r.y - NT_EDGE_STEP, far));
    let inner = nt_polynomial(d, n, inside);
    if !(abs(edge - inside) > 0.0) || !(inner > value) {
        return value;
    }
    var h_inside: f32;
    var h_edge: f32;
    var h: f32;
    if far {
        h_inside = thickness * nt_far_fraction(inside, thickness);
        h_edge = thickness * nt_far_fraction(edge, thickness);
        h = thickness * nt_far_fraction(u, thickness);
    } else {
        h_inside = thickness * nt_depth_fraction(inside, thickness);
        h_edge = thickness * nt_depth_fraction(edge, thickness);
        h = thickness * nt_depth_fraction(u, thickness);
    }
    return value + nt_continued_toward_face(inner - value, h_inside, h_edge, h);
}

// The median angle (degrees) of the halo's annulus b.
fn nt_halo_centre(b: u32) -> f32 {
    let a = ntt_f32(nephele_ntt_index.halo_edges + b);
    let c = ntt_f32(nephele_ntt_index.halo_edges + b + 1u);
    return sqrt(0.5 * (a * a + c * c));
}

// e^h, the halo around the transmitted beam of group g at the cell (the runtime's
// `transport::halo`): for views going down within the last edge, h read linearly between the
// thickness and sun-cosine nodes, the planes and the annuli's median angles, held below the
// first and falling to 0 at the last edge; 1 elsewhere and for the groups it does not cover.
fn nt_halo(g: u32, near_t: Lerp, c: NtCell) -> f32 {
    let x = nephele_ntt_index;
    if g >= x.halo_groups || x.n_halo_edges < 2u {
        return 1.0;
    }
    let nb = x.n_halo_edges - 1u;
    let last = ntt_f32(x.halo_edges + nb);
    let deg = c.theta * (180.0 / PI);
    if !(c.at.mu_v < 0.0) || !(deg < last) {
        return 1.0;
    }
    var ab = vec2<u32>(0u, 0u);
    var aw = vec2<f32>(1.0, 0.0);
    let top = nt_halo_centre(nb - 1u);
    if deg >= top {
        ab.x = nb - 1u;
        aw.x = (last - deg) / (last - top);
    } else if deg > nt_halo_centre(0u) {
        var b = 0u;
        while b + 2u < nb && nt_halo_centre(b + 1u) <= deg {
            b += 1u;
        }
        let w = (deg - nt_halo_centre(b)) / (nt_halo_centre(b + 1u) - nt_halo_centre(b));
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
    for (var a = 0u; a < lerp_nodes(near_t); a++) {
        for (var b = 0u; b < lerp_nodes(c.l); b++) {
            let wtl = lerp_weight(near_t, a) * lerp_weight(c.l, b);
            for (var k = 0u; k < 2u; k++) {
                let j = select(j0, j1, k == 1u);
                let wjk = select(1.0 - wj, wj, k == 1u);
                let row = ((lerp_node(near_t, a) * x.n_l + lerp_node(c.l, b)) * planes + j) * nb;
                for (var e = 0u; e < 2u; e++) {
                    h += wtl * wjk * aw[e] * ntt_f32(base + row + ab[e]);
                }
            }
        }
    }
    return nephele_exp(h);
}

// T of group g at a point, with what the collector needs of it.
struct NtT {
    t: f32,
    cell: NtCell,
    range: vec3<f32>,  // the fitted depths (lo, hi, share)
    s: f32,            // the place of ln t in the group's span
}

// The place of ln t in group g's span of ln t, in [−1, 1] (0 for an empty span).
fn nt_span_position(g: u32, ln_t: f32) -> f32 {
    let x = nephele_ntt_index;
    let a = ntt_f32(x.ln_t_range + 2u * g);
    let b = ntt_f32(x.ln_t_range + 2u * g + 1u);
    if b > a {
        return clamp(2.0 * (ln_t - a) / (b - a) - 1.0, -1.0, 1.0);
    }
    return 0.0;
}

fn nt_transport(g: u32, at: SlabPoint) -> NtT {
    let x = nephele_ntt_index;
    var r: NtT;
    r.t = 0.0;
    let t = at.thickness;
    if g >= x.groups || !in_slab(at) {
        return r;
    }
    let ln_t = nephele_ln(t);
    let omm = scattering_cosine(at).one_minus_mu;
    r.cell = NtCell(at, ntt_lerp(x.mu_l, x.n_l, at.mu_l), ntt_lerp(x.mu_v, x.n_v, at.mu_v),
        nt_stretched_u(at.depth, t, ln_t), 2.0 * nephele_asin(min(sqrt(0.5 * omm), 1.0)));
    let boundary = nt_ln_boundary(at);
    if boundary.y == 0.0 {
        return r;
    }
    let near_t = ntt_lerp(x.thickness, x.n_t, t);
    nt_begin(g, NtPass(x.beta, x.param_stride, x.group_stride, x.q, 0u, 0xffffffffu));
    if !nt_features(r.cell) {
        return r;
    }
    r.range = nt_fitted_depths(g, near_t, r.cell);
    if !(r.range.z > 0.0) {
        return r;
    }
    r.s = nt_span_position(g, ln_t);
    let dj = nt_depth_sums(r.s, x.depth_terms);
    let depth = nt_depth_polynomial(dj, x.depth_terms, r.cell.u, t, r.range);
    let v = r.range.z * nephele_exp(boundary.x + depth);
    let top = nt_ceiling(g, near_t, r.cell);
    r.t = select(v, top, top >= 0.0 && v > top) * nt_halo(g, near_t, r.cell);
    return r;
}

// A point of a slab thicker than the tables' thickest, continued into it by diffusion theory
// (the runtime's transport/thick.rs, step for step): where it reads the tables, and how T and
// σ scale. Within the grid: the point itself, every scale 1.
struct NtContinued {
    at: SlabPoint,
    diffuse: f32,         // φ_t(d)/φ_tmax(d'): the open-ended group's T; the others' min(1, it)
    spread: f32,          // σ's scale for the groups of few orders, d/d' past t_max/2
    spread_diffuse: f32,  // the open-ended group's, √(t d / (t_max d'))
}

// The diffusion fluence at depth z of a slab t thick lit at depth z_s, zero at z_e outside
// each face (unnormalised), as its two factors.
fn nt_fluence(z: f32, t: f32, z_s: f32, z_e: f32) -> vec2<f32> {
    return vec2<f32>(min(z, z_s) + z_e, (t + z_e - max(z, z_s)) / (t + 2.0 * z_e));
}

fn nt_continued(at: SlabPoint) -> NtContinued {
    let x = nephele_ntt_index;
    var c = NtContinued(at, 1.0, 1.0, 1.0);
    let t_max = ntt_f32(x.thickness + x.n_t - 1u);
    let t = at.thickness;
    if !(t > t_max) || !in_slab(at) {
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
    let here = nt_fluence(d, t, z_s, z_e);
    let there = nt_fluence(depth, t_max, z_s, z_e);
    c.diffuse = (here.x / there.x) * (here.y / there.y);
    if depth > 0.0 && d > half {
        c.spread = d / depth;
    }
    c.spread_diffuse = sqrt(t / t_max) * select(1.0, sqrt(d / depth), depth > 0.0);
    c.at = SlabPoint(depth, t_max, at.mu_v, at.psi_v, at.mu_l);
    return c;
}

// How group g's T scales past the thickest slab.
fn nt_diffuse_scale(g: u32, c: NtContinued) -> f32 {
    if g + 1u == nephele_ntt_index.groups {
        return c.diffuse;
    }
    return min(c.diffuse, 1.0);
}

// T (sr⁻¹) of group g at `at`; 0 where the tables resolve nothing or g is not a group. Past
// the thickest slab, continued by diffusion theory (nt_continued).
fn transport(g: u32, at: SlabPoint) -> f32 {
    let c = nt_continued(at);
    return nt_transport(g, c.at).t * nt_diffuse_scale(g, c);
}
