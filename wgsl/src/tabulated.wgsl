// The tabulated phase function (nephele-runtime's `Tabulated`) in WGSL: the density per unit
// angle f(θ) = 2π p(θ) sin θ piecewise linear between nodes θ_0 = 0 < … < θ_{n−1} = π, the CDF
// exact at the nodes, p(θ) = f(θ)/(2π sin θ), and sampling by the exact inverse of that CDF:
// the interval from a guide table, then Δ = 2r / (f_i + √(f_i² + 2 s r)), s = (f_{i+1} − f_i)/h,
// r = ξ − C_i. Needs `NepheleCosine` from phase.wgsl.
//
// The table lives in one storage buffer of f32 words (`nephele_wgsl::tabulated_buffer`):
//   [0] n, [1, 1 + n) θ (radians), [1 + n, 1 + 2n) f, [1 + 2n, 1 + 3n) CDF,
//   [1 + 3n, 4n) the guide table (interval indices; guide[k] holds ξ = k/(n − 1)).
// `nephele_wgsl::tabulated(group, binding)` gives this source with the binding chosen.

@group(NEPHELE_TAB_GROUP) @binding(NEPHELE_TAB_BINDING)
var<storage, read> nephele_tab: array<f32>;

fn nephele_tab_n() -> u32 {
    return u32(nephele_tab[0]);
}

fn nephele_tab_theta(k: u32) -> f32 {
    return nephele_tab[1u + k];
}

fn nephele_tab_f(k: u32) -> f32 {
    return nephele_tab[1u + nephele_tab_n() + k];
}

fn nephele_tab_cdf(k: u32) -> f32 {
    return nephele_tab[1u + 2u * nephele_tab_n() + k];
}

// The interval i with θ_i ≤ θ < θ_{i+1} (the first or the last outside them), by bisection.
fn nephele_tab_interval(theta: f32) -> u32 {
    var lo = 0u;
    var hi = nephele_tab_n() - 1u;
    while hi - lo > 1u {
        let mid = (lo + hi) / 2u;
        if nephele_tab_theta(mid) <= theta {
            lo = mid;
        } else {
            hi = mid;
        }
    }
    return lo;
}

fn nephele_tabulated_eval(c: NepheleCosine) -> f32 {
    let a = nephele_cosine_angle(c);
    let i = nephele_tab_interval(a.x);
    return nephele_phase_between(vec2<f32>(nephele_tab_theta(i), nephele_tab_f(i)),
        vec2<f32>(nephele_tab_theta(i + 1u), nephele_tab_f(i + 1u)), a);
}

fn nephele_tabulated_sample(xi_in: f32) -> NepheleCosine {
    // The CDF runs in θ, forward first; ξ counts from the back (μ = −1) as in every model.
    let xi = 1.0 - xi_in;
    let n = nephele_tab_n();
    let guides = n - 1u;
    let k = min(u32(xi * f32(guides)), guides - 1u);
    var i = u32(nephele_tab[1u + 3u * n + k]);
    // ξ·(n − 1) in f32 may round up across a guide boundary: step back first.
    while i > 0u && nephele_tab_cdf(i) > xi {
        i -= 1u;
    }
    while i + 2u < n && nephele_tab_cdf(i + 1u) <= xi {
        i += 1u;
    }
    let h = nephele_tab_theta(i + 1u) - nephele_tab_theta(i);
    let a = nephele_tab_f(i);
    let s = (nephele_tab_f(i + 1u) - a) / h;
    let r = clamp(xi - nephele_tab_cdf(i), 0.0, 1.0);
    let disc = max(a * a + 2.0 * s * r, 0.0);
    let denom = a + sqrt(disc);
    var delta = 0.0;
    if denom > 0.0 {
        delta = 2.0 * r / denom;
    }
    let theta = nephele_tab_theta(i) + clamp(delta, 0.0, h);
    // The built-in sin and cos: Vulkan allows them 2⁻¹¹ absolute; lavapipe's agree with the
    // runtime's samples within 4 ulps of μ (tests/lavapipe.rs).
    let sh = sin(0.5 * theta);
    if theta < 0.5 * NEPHELE_PI {
        return nephele_cosine_from_one_minus_mu(2.0 * sh * sh);
    }
    return nephele_cosine_from_mu(cos(theta));
}
