// The collector search of Bouthors et al. 2008, §6.1, on the GPU: nephele-runtime's
// `find_collector`, step for step. Where, on the cloud's lit surface, the light of one order
// group seen at p entered: the fixed point of (c, σ) with the surface filtered at σ
// (docs/collector.md):
//
//   c₀ = p, σ₀ = the surface's initial scale;
//   step i: S = the surface filtered at σ_{i−1} on the light line through c_{i−1}; the local
//           slab of p under S; (c, σ) from the tables there mapped to the world (c_i, σ_i);
//           the move across the light clamped to σ_i from step 2 on;
//   stop when the move across the light and the change of σ are both ≤ ε σ_i, or after N reads.
//
// The renderer supplies its lit surface (its light-space maps) as four functions of this
// module, which the port calls:
//
//   fn nephele_surface_filtered(at: vec3<f32>, sigma: f32) -> NepheleLitSample
//   fn nephele_surface_lateral(at: vec3<f32>, sigma: f32) -> NepheleLateralSample
//   fn nephele_surface_initial_scale() -> f32
//   fn nephele_surface_sun_depth(at: vec3<f32>) -> f32
//
// (positions in metres, world; `hit` 0 where no cloud covers the light line through `at`;
// the sun's optical depth to `at` in mfp, negative where unknown).
// They are called in non-uniform control flow: sample textures with `textureSampleLevel`
// (the level of σ), not `textureSample`.
// Needs ntt.wgsl, order1.wgsl, transport.wgsl and collector.wgsl before it.

// The lit surface filtered at one place and scale: the lit face's point on the light line,
// its outward unit normal, the chord's geometric (m) and optical (mfp) lengths.
struct NepheleLitSample {
    entry: vec3<f32>,
    normal: vec3<f32>,
    length: f32,
    optical_length: f32,
    hit: u32,
}

// The cloud's cross-section across the light, filtered: the share of the footprint covered,
// the mean distance to its edge over the covered part (m).
struct NepheleLateralSample {
    coverage: f32,
    edge_distance: f32,
    hit: u32,
}

// p (m, world), the direction the light travels toward the eye (unit), the optical depth
// the view ray holds beyond p: at least `behind_min`, at most `behind_max`, and p's optical
// depth to the sun through the cloud as it is, `sun_depth` (mfp; unknown: NEPHELE_F32_MAX, as
// WGSL has no infinity constant).
struct NepheleViewpoint {
    position: vec3<f32>,
    view: vec3<f32>,
    behind_min: f32,
    behind_max: f32,
    sun_depth: f32,
}

// Most reads N, tolerance ε, the step clamp and the filtering at σ (1 on), and each group's
// sun depth averaged across the light over its walks' spread (1 on, for a phase function of
// mean cosine `mean_cosine`).
struct NepheleSearchOptions {
    max_reads: u32,
    tolerance: f32,
    step_clamp: u32,
    filtering: u32,
    sun_spread: u32,
    mean_cosine: f32,
}

// One group's search (the runtime's `Collector`): `found` 0 where none; T, c, σ (mfp) of the
// last read, the slab it was read at, the centre on the filtered lit face (m, world) and σ (m),
// the reads, convergence, the clamps (bits: 1 thickness, 2 μ_L, 4 depth, 8 view, 16 the slab
// cut or grown to p's depth to the sun) and κ̄ (1/m).
struct NepheleCollector {
    found: u32,
    transport: NepheleTransport,
    at: NepheleSlabPoint,
    centre: vec3<f32>,
    sigma: f32,
    reads: u32,
    converged: u32,
    clamps: u32,
    extinction: f32,
}

// The local slab of a viewpoint under a filtered surface and its horizontal frame.
struct NepheleLocalSlab {
    at: NepheleSlabPoint,
    clamps: u32,
    foot: vec3<f32>,
    z_axis: vec3<f32>,
    x_axis: vec3<f32>,
    extinction: f32,
    mu_l_unheld: f32,  // n̄·ω_L before it was held (≤ 0 on a face turned from the sun)
}

// The point the tables are read at (the runtime's `LocalSlab::read_at`): the slab's, under the
// sun's own μ_L where it lies below the tables' lowest (they scale T for it); a face turned
// from the sun under 10⁻⁶ (`GRAZING_FLOOR`), next to no light.
fn nephele_ns_read_at(slab: NepheleLocalSlab) -> NepheleSlabPoint {
    var at = slab.at;
    at.mu_l = nephele_ns_clamp(slab.mu_l_unheld, 1e-6, slab.at.mu_l);
    return at;
}

// Vector steps in the runtime's order of operations.
fn nephele_ns_dot(a: vec3<f32>, b: vec3<f32>) -> f32 {
    return a.x * b.x + a.y * b.y + a.z * b.z;
}

fn nephele_ns_add(a: vec3<f32>, b: vec3<f32>, s: f32) -> vec3<f32> {
    return vec3<f32>(a.x + s * b.x, a.y + s * b.y, a.z + s * b.z);
}

fn nephele_ns_length(a: vec3<f32>) -> f32 {
    return sqrt(nephele_ns_dot(a, a));
}

fn nephele_ns_clamp(x: f32, lo: f32, hi: f32) -> f32 {
    if x < lo {
        return lo;
    }
    if x > hi {
        return hi;
    }
    return x;
}

fn nephele_ns_cross(a: vec3<f32>, b: vec3<f32>) -> vec3<f32> {
    return vec3<f32>(a.y * b.z - a.z * b.y, a.z * b.x - a.x * b.z, a.x * b.y - a.y * b.x);
}

// A unit vector ⊥ n (Duff et al. 2017's first basis vector).
fn nephele_ns_perpendicular(n: vec3<f32>) -> vec3<f32> {
    let sign = select(1.0, -1.0, n.z < 0.0);
    let a = -1.0 / (sign + n.z);
    let b = n.x * n.y * a;
    return vec3<f32>(1.0 + sign * n.x * n.x * a, sign * b, -sign * n.x);
}

// The second basis vector of Duff et al. 2017, with `nephele_ns_perpendicular` ⊥ n.
fn nephele_ns_perpendicular2(n: vec3<f32>) -> vec3<f32> {
    let sign = select(1.0, -1.0, n.z < 0.0);
    let a = -1.0 / (sign + n.z);
    let b = n.x * n.y * a;
    return vec3<f32>(b, sign + n.y * n.y * a, -n.y);
}

// The lateral spread (mfp) of group g's light for mean cosine `mean_cosine`: √(4 D n⊥(n̄)), n̄
// the group's middle order, twice the first for the open last group (the runtime's
// `sun_depth::group_spread`).
fn nephele_ns_group_spread(g: u32, mean_cosine: f32) -> f32 {
    let x = nephele_ntt_index;
    var first = 2.0;
    if g < x.groups {
        first = nephele_ntt_f32(x.group_first + g);
    }
    var middle = 2.0 * first;
    if g + 1u < x.groups {
        middle = 0.5 * (first + (nephele_ntt_f32(x.group_first + g + 1u) - 1.0));
    }
    let across = nephele_nf_lateral_orders(middle, mean_cosine);
    return sqrt(max(4.0 * nephele_nf_diffusion(mean_cosine) * across, 0.0));
}

// The viewpoint group g's search reads: p's depth to the sun averaged over p and four points
// at the group's spread across the light (the cloud's extinction `extinction`, 1/m), where
// the options ask for it and every depth is known; `v` as it is otherwise (the runtime's
// `sun_depth::group_viewpoint`).
fn nephele_ns_group_viewpoint(g: u32, v: NepheleViewpoint, sun: vec3<f32>, extinction: f32,
        opts: NepheleSearchOptions) -> NepheleViewpoint {
    if opts.sun_spread == 0u || !(extinction > 0.0) {
        return v;
    }
    let radius = nephele_ns_group_spread(g, opts.mean_cosine) / extinction;
    if !(v.sun_depth < NEPHELE_F32_MAX) || !(radius > 0.0) {
        return v;
    }
    let e1 = nephele_ns_perpendicular(sun);
    let e2 = nephele_ns_perpendicular2(sun);
    var sum = v.sun_depth;
    for (var k = 0u; k < 4u; k++) {
        let e = select(e1, e2, k >= 2u);
        let s = select(1.0, -1.0, k % 2u == 1u);
        let p = v.position;
        let q = vec3<f32>(p.x + s * radius * e.x, p.y + s * radius * e.y, p.z + s * radius * e.z);
        let tau = nephele_surface_sun_depth(q);
        if !(tau >= 0.0) {
            return v;
        }
        sum += tau;
    }
    let mean = sum / 5.0;
    if !(mean < NEPHELE_F32_MAX) {
        return v;
    }
    var out = v;
    out.sun_depth = mean;
    return out;
}

// The angle in [0, π] from its cosine and sine (≥ 0) up to a common positive factor.
fn nephele_ns_angle(c: f32, s: f32) -> f32 {
    let r = sqrt(c * c + s * s);
    if r <= 0.0 {
        return 0.0;
    }
    if s < abs(c) {
        let a = nephele_asin(s / r);
        return select(NEPHELE_PI - a, a, c >= 0.0);
    }
    return 0.5 * NEPHELE_PI - nephele_asin(c / r);
}

// t held within the tables' thicknesses.
fn nephele_ns_hold_thickness(t: f32) -> f32 {
    let x = nephele_ntt_index;
    return nephele_ns_clamp(t, nephele_ntt_f32(x.thickness),
        nephele_ntt_f32(x.thickness + x.n_t - 1u));
}

// The slab tangent to `s` that holds the viewpoint, the sun toward `sun`: μ_L = n̄·ω_L,
// t = max(τ_chord μ_L, d + μ_V⁺ behind_min), d = κ̄ (entry − p)·n̄ held within the view ray's own
// medium, μ_V = ω_V·n̄, ψ_V between the horizontal parts of the beam's travel and of ω_V; t and
// μ_L held within the tables' grid; seen going up, where p lies deeper than μ_L τ_☉, the slab
// above p cut to it; where μ_L τ_☉ exceeds the slab's thickness, the slab grown at its lit face
// by the excess, p with it (the runtime's `local_slab`).
fn nephele_local_slab(s: NepheleLitSample, v: NepheleViewpoint,
    sun: vec3<f32>) -> NepheleLocalSlab {
    let x = nephele_ntt_index;
    let p = v.position;
    let n = s.normal;
    var clamps = 0u;
    let mu_l_raw = nephele_ns_dot(n, sun);
    let mu_l = nephele_ns_clamp(mu_l_raw, nephele_ntt_f32(x.mu_l),
        nephele_ntt_f32(x.mu_l + x.n_l - 1u));
    clamps |= select(0u, 2u, mu_l != mu_l_raw);
    var extinction = 0.0;
    if s.length > 0.0 {
        extinction = s.optical_length / s.length;
    }
    let below = nephele_ns_dot(vec3<f32>(s.entry.x - p.x, s.entry.y - p.y, s.entry.z - p.z), n);
    let d_raw = extinction * below;
    let mu_v = nephele_ns_clamp(nephele_ns_dot(v.view, n), -1.0, 1.0);
    // The slab holds the viewpoint, and seen going up the view ray's medium below p.
    var held = d_raw;
    if mu_v > 0.0 {
        held = d_raw + mu_v * v.behind_min;
    }
    let t_raw = max(s.optical_length * mu_l, held);
    let thickness = nephele_ns_hold_thickness(t_raw);
    clamps |= select(0u, 1u, thickness != t_raw);
    let depth = nephele_ns_clamp(d_raw, 0.0, thickness);
    clamps |= select(0u, 4u, depth != d_raw);
    var lo = 0.0;
    var hi = thickness;
    if mu_v > 0.0 {
        lo = thickness - mu_v * v.behind_max;
        hi = thickness - mu_v * v.behind_min;
    } else if mu_v < 0.0 {
        lo = -mu_v * v.behind_min;
        hi = -mu_v * v.behind_max;
    }
    lo = nephele_ns_clamp(lo, 0.0, thickness);
    hi = nephele_ns_clamp(hi, 0.0, thickness);
    var depth_v = nephele_ns_clamp(depth, lo, max(hi, lo));
    clamps |= select(0u, 8u, depth_v != depth);
    var thickness_v = thickness;
    // Seen going up, p lies no deeper than its own depth to the sun.
    let d_sun = mu_l * v.sun_depth;
    if mu_v > 0.0 && depth_v > d_sun {
        clamps |= 16u;
        let t_cut = d_sun + (thickness - depth_v);
        thickness_v = nephele_ns_hold_thickness(t_cut);
        clamps |= select(0u, 1u, thickness_v != t_cut);
        depth_v = min(d_sun, thickness_v);
    } else if v.sun_depth < NEPHELE_F32_MAX && d_sun > thickness {
        clamps |= 16u;
        let excess = d_sun - thickness;
        let t_grown = thickness + excess;
        thickness_v = nephele_ns_hold_thickness(t_grown);
        clamps |= select(0u, 1u, thickness_v != t_grown);
        depth_v = min(depth_v + excess, thickness_v);
    }
    let beam_h = nephele_ns_add(-sun, n, mu_l_raw);
    let view_h = nephele_ns_add(v.view, n, -mu_v);
    let bl = nephele_ns_length(beam_h);
    let vl = nephele_ns_length(view_h);
    var z_axis: vec3<f32>;
    if bl > 1e-6 {
        z_axis = beam_h / bl;
    } else if vl > 1e-6 {
        z_axis = view_h / vl;
    } else {
        z_axis = nephele_ns_perpendicular(n);
    }
    let cos_psi = nephele_ns_dot(view_h, z_axis);
    let across = nephele_ns_add(view_h, z_axis, -cos_psi);
    let al = nephele_ns_length(across);
    var x_axis: vec3<f32>;
    if al > 1e-6 * max(vl, 1e-30) && al > 0.0 {
        x_axis = across / al;
    } else {
        x_axis = nephele_ns_cross(n, z_axis);
    }
    return NepheleLocalSlab(NepheleSlabPoint(thickness_v, mu_l, depth_v, mu_v,
        nephele_ns_angle(cos_psi, al)), clamps,
        nephele_ns_add(p, n, below), z_axis, x_axis, extinction, mu_l_raw);
}

// The surface at c; where no cloud covers it, halfway back toward the last collector, at
// most four times.
fn nephele_ns_query(c_in: vec3<f32>, scale: f32, last: NepheleCollector) -> NepheleLitSample {
    var c = c_in;
    for (var i = 0; i < 4; i++) {
        let s = nephele_surface_filtered(c, scale);
        if s.hit != 0u {
            return s;
        }
        if last.found == 0u {
            return s;
        }
        let prev = last.centre;
        c = vec3<f32>(0.5 * (c.x + prev.x), 0.5 * (c.y + prev.y), 0.5 * (c.z + prev.z));
    }
    return nephele_surface_filtered(c, scale);
}

// The collector of group g seen from `v`, the sun toward `sun` (unit).
fn nephele_find_collector(g: u32, v_in: NepheleViewpoint, sun: vec3<f32>,
    opts: NepheleSearchOptions) -> NepheleCollector {
    var c = v_in.position;
    var sigma = nephele_surface_initial_scale();
    var last: NepheleCollector;
    var reads = 0u;
    // The cloud's extinction along the light at the first scale: the group's spread in metres.
    let s0 = nephele_ns_query(c, select(0.0, sigma, opts.filtering != 0u), last);
    var extinction0 = 0.0;
    if s0.hit != 0u && s0.length > 0.0 {
        extinction0 = s0.optical_length / s0.length;
    }
    let v = nephele_ns_group_viewpoint(g, v_in, sun, extinction0, opts);
    loop {
        // The first step's surface is s0, already queried.
        var s = s0;
        if reads > 0u {
            s = nephele_ns_query(c, select(0.0, sigma, opts.filtering != 0u), last);
        }
        if s.hit == 0u {
            return last;
        }
        let slab = nephele_local_slab(s, v, sun);
        let tr = nephele_evaluate(g, nephele_ns_read_at(slab));
        reads += 1u;
        if !(tr.t > 0.0 && tr.sigma > 0.0 && slab.extinction > 0.0) {
            return last;
        }
        let k = 1.0 / slab.extinction;
        let aim = nephele_ns_add(nephele_ns_add(slab.foot, slab.z_axis, tr.c_z * k), slab.x_axis,
            tr.c_x * k);
        let new_sigma = tr.sigma * k;
        let delta = vec3<f32>(aim.x - c.x, aim.y - c.y, aim.z - c.z);
        let along = nephele_ns_dot(delta, sun);
        var across = nephele_ns_add(delta, sun, -along);
        var moved = nephele_ns_length(across);
        if opts.step_clamp != 0u && reads > 1u && moved > new_sigma {
            across = across * new_sigma / moved;
            moved = new_sigma;
        }
        let converged = reads > 1u && moved <= opts.tolerance * new_sigma
            && abs(new_sigma - sigma) <= opts.tolerance * new_sigma;
        c = nephele_ns_add(nephele_ns_add(c, across, 1.0), sun, along);
        sigma = new_sigma;
        let found = NepheleCollector(1u, tr, slab.at, c, sigma, reads, select(0u, 1u, converged),
            slab.clamps, slab.extinction);
        if converged || reads >= max(opts.max_reads, 1u) {
            return found;
        }
        last = found;
    }
    return last; // not reached: every step returns or reads once more, up to N reads
}
