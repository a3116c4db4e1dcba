// The finite-cloud correction of a collector (nephele-runtime's `finite_cloud`; the equations
// in runtime/src/transport/leakage.rs and docs/collector.md, "Finite clouds"): the share of the
// infinite slab's T_g a real cloud keeps. Lateral leakage: the cross-section around the
// collector has a mean distance δ̄ to its edge, R = 3 δ̄ (mfp), κ⊥ = D j₀² / (R + z_e)²;
// absorption κ_a = −ln ϖ; the group keeps Σ_{n∈g} w_n e^{−κ_a n − κ⊥ n⊥(n)} / Σ w_n with w_n
// the orders' distribution from diffusion (closed groups order by order, the open last group
// by the first-passage integral with erfcx) and n⊥ the lateral orders (the walk's spread
// across the light; n itself with `spread` = 0). Needs search.wgsl before it.

// Which corrections apply (1 on) and the medium's constants.
struct NepheleFiniteCloud {
    leakage: u32,
    coverage: u32,
    rate_scale: f32,
    delay_scale: f32,
    spread: u32,
    absorption: f32,
    mean_cosine: f32,
}

// What a group's collector keeps: the factor on T_g, the lateral radius (mfp; the largest f32
// where the surface knows no edge: the runtime's +inf) and the footprint's coverage.
struct NepheleKept {
    factor: f32,
    radius: f32,
    coverage: f32,
}

// What a path loses per scattering: absorption, the sides' rate, the orders before they count,
// and whether the sides count the lateral orders (1) or the orders (0), for mean cosine g.
struct NepheleLoss {
    absorption: f32,
    lateral: f32,
    delay: f32,
    spread: u32,
    g: f32,
}

const NEPHELE_NF_J0_SQUARED: f32 = 5.783185962946784;

fn nephele_nf_diffusion(g: f32) -> f32 {
    return 1.0 / (3.0 * (1.0 - g));
}

fn nephele_nf_extrapolation(g: f32) -> f32 {
    return 2.0 / (3.0 * (1.0 - g));
}

fn nephele_nf_lateral_rate(radius: f32, g: f32) -> f32 {
    if !(radius >= 0.0) || radius >= NEPHELE_F32_MAX {
        return 0.0;
    }
    let re = radius + nephele_nf_extrapolation(g);
    return nephele_nf_diffusion(g) * NEPHELE_NF_J0_SQUARED / (re * re);
}

// n⊥(n): the order at which diffusion would have spread as far across the light as a
// persistent walk of mean cosine g (⟨P₂⟩ = g²) entering along it after n flights (the walk's
// exact moments; runtime's leakage::lateral_orders).
fn nephele_nf_lateral_orders(n: f32, g0: f32) -> f32 {
    let g = nephele_ns_clamp(g0, 1e-3, 0.999);
    let h = g * g;
    let gn = nephele_exp(n * nephele_ln(g));
    let hn = nephele_exp(n * nephele_ln(h));
    let s = g * (n * (1.0 - g) - (1.0 - gn)) / ((1.0 - g) * (1.0 - g));
    let t = g / (1.0 - g) * ((1.0 - hn) / (1.0 - h) - (gn - hn) / (g - h));
    let third = 1.0 / 3.0;
    let r2 = 2.0 * (n + s);
    let rz2 = 2.0 * third * (n + 2.0 * (1.0 - hn) / (1.0 - h)) + 2.0 * third * s
        + 4.0 * third * t;
    let across = (r2 - rz2) * 0.75 * (1.0 - g);
    return select(0.0, across, across > 0.0);
}

// n − n⊥(n) for large n: g/(1 − g) + 1/(1 − g²).
fn nephele_nf_lateral_offset(g0: f32) -> f32 {
    let g = nephele_ns_clamp(g0, 1e-3, 0.999);
    return g / (1.0 - g) + 1.0 / (1.0 - g * g);
}

fn nephele_nf_loss_exponent(l: NepheleLoss, n: f32) -> f32 {
    var across = n;
    if l.spread != 0u {
        across = nephele_nf_lateral_orders(n, l.g);
    }
    let late = select(0.0, across - l.delay, across - l.delay > 0.0);
    return -l.absorption * n - l.lateral * late;
}

// erfcx(x) = e^{x²} erfc(x), x ≥ 0 (Numerical Recipes' erfcc fit, < 1.2e-7 relative).
fn nephele_nf_erfcx(x: f32) -> f32 {
    let t = 1.0 / (1.0 + 0.5 * x);
    var p = 0.17087277;
    p = -0.82215223 + t * p;
    p = 1.48851587 + t * p;
    p = -1.13520398 + t * p;
    p = 0.27886807 + t * p;
    p = -0.18628806 + t * p;
    p = 0.09678418 + t * p;
    p = 0.37409196 + t * p;
    p = 1.00002368 + t * p;
    p = -1.26551223 + t * p;
    return t * nephele_exp(p);
}

// The first-passage integral's arguments at n₀: (u, v, e^{−u² − v²}).
fn nephele_nf_passage(n0: f32, s: f32, z: f32, d: f32) -> vec3<f32> {
    let u = z / (2.0 * sqrt(d * n0));
    let v = sqrt(s * n0);
    return vec3<f32>(u, v, nephele_exp(-(u * u) - v * v));
}

// e^{−2uv} erfc(x) for x = ±(u − v), without overflow.
fn nephele_nf_tilted_erfc(p: vec3<f32>, x: f32) -> f32 {
    if x >= 0.0 {
        return p.z * nephele_nf_erfcx(x);
    }
    return 2.0 * nephele_exp(-(2.0 * p.x * p.y)) - p.z * nephele_nf_erfcx(-x);
}

// W(n₀, s) = ∫₀^{n₀} f(n) e^{−s n} dn.
fn nephele_nf_below(n0: f32, s: f32, z: f32, d: f32) -> f32 {
    if !(n0 > 0.0) {
        return 0.0;
    }
    let p = nephele_nf_passage(n0, s, z, d);
    return 0.5 * (nephele_nf_tilted_erfc(p, p.x - p.y) + p.z * nephele_nf_erfcx(p.x + p.y));
}

// W(∞, s) − W(n₀, s).
fn nephele_nf_above(n0: f32, s: f32, z: f32, d: f32) -> f32 {
    if !(n0 > 0.0) {
        return nephele_exp(-z * sqrt(s / d));
    }
    let p = nephele_nf_passage(n0, s, z, d);
    let tail = 0.5 * (nephele_nf_tilted_erfc(p, p.y - p.x) - p.z * nephele_nf_erfcx(p.x + p.y));
    return select(0.0, tail, tail > 0.0);
}

// The share of [start, to) (`open`: no end) of f e^{−s n}.
fn nephele_nf_share(start: f32, to: f32, open: bool, s: f32, z: f32, d: f32) -> f32 {
    if open {
        return nephele_nf_above(start, s, z, d);
    }
    if to > start {
        return nephele_nf_below(to, s, z, d) - nephele_nf_below(start, s, z, d);
    }
    return 0.0;
}

fn nephele_nf_order_exponent(n: f32, s: f32, z: f32, d: f32) -> f32 {
    return -(z * z) / (4.0 * d * n) - s * n - 1.5 * nephele_ln(n);
}

// The share of a group's light (orders first ..= last, `open` without end) the loss leaves,
// seen at `depth` of a slab `thickness` mfp thick, mean cosine g.
fn nephele_group_survival(first: f32, last: f32, open: bool, depth: f32, thickness: f32, g: f32,
    l: NepheleLoss) -> f32 {
    if !(l.absorption > 0.0) && !(l.lateral > 0.0) {
        return 1.0;
    }
    let d = nephele_nf_diffusion(g);
    let ze = nephele_nf_extrapolation(g);
    let z = abs(depth - 1.0 / (1.0 - g)) + ze;
    let te = thickness + 2.0 * ze;
    let slab_rate = d * NEPHELE_PI * NEPHELE_PI / (te * te);
    var with_loss = 0.0;
    var without = 0.0;
    if !open && last - first < 64.0 {
        let count = u32(last - first) + 1u;
        var shift = nephele_nf_order_exponent(first, slab_rate, z, d);
        for (var k = 1u; k < count; k++) {
            shift = max(shift, nephele_nf_order_exponent(first + f32(k), slab_rate, z, d));
        }
        for (var k = 0u; k < count; k++) {
            let n = first + f32(k);
            let e = nephele_nf_order_exponent(n, slab_rate, z, d);
            with_loss += nephele_exp(e + nephele_nf_loss_exponent(l, n) - shift);
            without += nephele_exp(e + 0.0 - shift);
        }
    } else {
        let lo = first - 0.5;
        let hi = last + 0.5;
        let rate = select(1e-30, l.lateral, l.lateral > 1e-30);
        // Beyond order 30 the lateral orders are n − their offset to within 0.1.
        let offset = select(0.0, nephele_nf_lateral_offset(g), l.spread != 0u);
        var delay = nephele_ns_clamp(l.delay + offset, 0.0, 60.0 / rate);
        if !open {
            delay = nephele_ns_clamp(delay, 0.0, hi);
        }
        let split = select(lo, delay, delay > lo);
        let early = nephele_nf_share(lo, split, false, slab_rate + l.absorption, z, d);
        let late = nephele_exp(l.lateral * delay)
            * nephele_nf_share(split, hi, open, slab_rate + l.absorption + l.lateral, z, d);
        with_loss = early + late;
        without = nephele_nf_share(lo, hi, open, slab_rate, z, d);
    }
    if !(without > 1e-30) || !(with_loss >= 0.0) {
        return nephele_exp(nephele_nf_loss_exponent(l, first));
    }
    return nephele_ns_clamp(with_loss / without, 0.0, 1.0);
}

// The share of group g's T the cloud keeps at the collector `c` (found = 1).
fn nephele_finite_cloud(g: u32, c: NepheleCollector, opts: NepheleFiniteCloud) -> NepheleKept {
    let x = nephele_ntt_index;
    var kept = NepheleKept(1.0, NEPHELE_F32_MAX, 1.0);
    if opts.leakage == 0u && opts.coverage == 0u && !(opts.absorption > 0.0) {
        return kept;
    }
    let g_mean = opts.mean_cosine;
    var l = NepheleLoss(max(opts.absorption, 0.0), 0.0, 0.0, 0u, g_mean);
    let side = nephele_surface_lateral(c.centre, c.sigma);
    if side.hit != 0u {
        kept.coverage = nephele_ns_clamp(side.coverage, 0.0, 1.0);
        if opts.leakage != 0u && abs(side.edge_distance) < NEPHELE_F32_MAX {
            let edge = side.edge_distance * c.extinction;
            kept.radius = 3.0 * edge;
            l.lateral = opts.rate_scale * nephele_nf_lateral_rate(kept.radius, g_mean);
            let reach = edge + nephele_nf_extrapolation(g_mean);
            l.delay = opts.delay_scale * reach * reach / nephele_nf_diffusion(g_mean);
            l.spread = opts.spread;
        }
    }
    var first = 2.0;
    if g < x.groups {
        first = nephele_ntt_f32(x.group_first + g);
    }
    let open = g + 1u >= x.groups;
    var last = 0.0;
    if !open {
        last = nephele_ntt_f32(x.group_first + g + 1u) - 1.0;
    }
    kept.factor = nephele_group_survival(first, last, open, c.at.depth, c.at.thickness, g_mean, l);
    if opts.coverage != 0u {
        kept.factor *= kept.coverage;
    }
    return kept;
}
