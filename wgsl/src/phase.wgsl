// nephele's phase models in WGSL (f32): the port of nephele-runtime's `phase` module that
// renderers use on the GPU. Conventions as the runtime's: θ between the incident and the
// scattered propagation directions, μ = cos θ (μ = 1 forward), ∮ p dΩ = 1 (sr⁻¹). Each model has
// eval (p at a cosine), pdf (the same: the samplers are exact), and sample (μ from ξ ∈ [0, 1)).
// A cosine travels with 1 − μ (`NepheleCosine`), exact near the forward peak where μ is not.
//
// Checked by running it: wgsl/tests/lavapipe.rs evaluates and samples every model on a Vulkan
// driver (Mesa's lavapipe on the CPU in CI) against the Rust runtime. Needs math.wgsl first.

struct NepheleCosine {
    mu: f32,
    one_minus_mu: f32,
}

fn nephele_cosine_from_mu(mu: f32) -> NepheleCosine {
    return NepheleCosine(mu, 1.0 - mu);
}

fn nephele_cosine_from_one_minus_mu(omm: f32) -> NepheleCosine {
    return NepheleCosine(1.0 - omm, omm);
}

// θ and sin θ of a cosine, accurate near both poles.
fn nephele_cosine_angle(c: NepheleCosine) -> vec2<f32> {
    let omm = clamp(c.one_minus_mu, 0.0, 2.0);
    var theta: f32;
    if c.mu >= 0.0 {
        theta = 2.0 * nephele_asin(sqrt(omm / 2.0));
    } else {
        theta = NEPHELE_PI - 2.0 * nephele_asin(sqrt(clamp(1.0 + c.mu, 0.0, 1.0) / 2.0));
    }
    return vec2<f32>(theta, sqrt(omm * (2.0 - omm)));
}

// A tabulated phase function between two nodes (θ_a, f_a), (θ_b, f_b) of f = 2π p sin θ, linear
// in θ, at the angle `at` = (θ, sin θ): p (sr⁻¹); at the poles (sin θ = 0) the limit
// |f_b − f_a| / (h 2π).
fn nephele_phase_between(a: vec2<f32>, b: vec2<f32>, at: vec2<f32>) -> f32 {
    let h = b.x - a.x;
    if at.y <= 0.0 {
        return abs(b.y - a.y) / h / (2.0 * NEPHELE_PI);
    }
    return (a.y + (b.y - a.y) * (at.x - a.x) / h) / (2.0 * NEPHELE_PI * at.y);
}

// ---- Henyey–Greenstein: p = (1 − g²) / (4π (1 + g² − 2gμ)^{3/2}) ----------------------------

// p from d = 1 + g² − 2gμ, written as (1 − g)² + 2g(1 − μ) for g ≥ 0 and (1 + g)² − 2g(1 + μ)
// for g < 0, so that the peak's small d keeps its digits.
fn nephele_hg_from_d(g: f32, d: f32) -> f32 {
    return NEPHELE_INV_FOUR_PI * (1.0 - g) * (1.0 + g) / (d * sqrt(d));
}

fn nephele_hg_eval(g: f32, c: NepheleCosine) -> f32 {
    if g >= 0.0 {
        return nephele_hg_from_d(g, (1.0 - g) * (1.0 - g) + 2.0 * g * c.one_minus_mu);
    }
    return nephele_hg_from_d(g, (1.0 + g) * (1.0 + g) - 2.0 * g * (1.0 + c.mu));
}

// The inverse of the CDF F(μ) = (1 − g)(1 + μ) / (v (1 + g + v)), v = √(1 + g² − 2gμ): the
// textbook root for |g| > 1/2 (1 − μ from it where μ > 0), the root with 1/g divided out below.
fn nephele_hg_sample(g: f32, xi: f32) -> NepheleCosine {
    let m0 = 2.0 * xi - 1.0;
    let s = 1.0 + g * m0;
    if abs(g) > 0.5 {
        let inv_s = 1.0 / s;
        let t = (1.0 - g) * (1.0 + g) * inv_s;
        if g > 0.0 && t * t < 1.0 + g * g {
            let omm = (1.0 - g) * (1.0 - xi) * (t + 1.0 - g) * inv_s;
            return nephele_cosine_from_one_minus_mu(clamp(omm, 0.0, 1.0));
        }
        return nephele_cosine_from_mu(clamp((1.0 + g * g - t * t) / (2.0 * g), -1.0, 1.0));
    }
    let num = m0 + 0.5 * g * (3.0 + m0 * m0) + g * g * m0 + 0.5 * g * g * g * (m0 * m0 - 1.0);
    return nephele_cosine_from_mu(clamp(num / (s * s), -1.0, 1.0));
}

// ---- Draine (2003): p = HG(μ; g) (1 + α μ²) / (1 + α (1 + 2g²)/3) -----------------------------

fn nephele_draine_norm(g: f32, alpha: f32) -> f32 {
    return 1.0 + alpha * (1.0 + 2.0 * g * g) / 3.0;
}

fn nephele_draine_eval(g: f32, alpha: f32, c: NepheleCosine) -> f32 {
    return nephele_hg_eval(g, c) * (1.0 + alpha * c.mu * c.mu) / nephele_draine_norm(g, alpha);
}

// F(μ) of Draine without the 1/g³ cancellation of the textbook form (the runtime's
// `cdf_and_density`): M₂ = (1 − g²)(1 + μ) T / (12 P (v + v₀)), P = v v₀,
// T = 3(1 − μ) Q + s (P − 3a), Q = (g − 2μ)(1 + g)/(v + 1) + 1 − g,
// s = [g − 2μ − v + μ(g − 2μ)/(v + 1)]/(v + 1), F = (F_HG + α M₂)/N.
fn nephele_draine_cdf(g: f32, alpha: f32, mu: f32) -> f32 {
    let a = 1.0 + g * g;
    var d: f32;
    if g >= 0.0 {
        d = (1.0 - g) * (1.0 - g) + 2.0 * g * (1.0 - mu);
    } else {
        d = (1.0 + g) * (1.0 + g) - 2.0 * g * (1.0 + mu);
    }
    let v = sqrt(max(d, 0.0));
    let v0 = 1.0 + g;
    let f_hg = (1.0 - g) * (1.0 + mu) / (v * (v0 + v));
    let p = v * v0;
    let q = (g - 2.0 * mu) * (1.0 + g) / (v + 1.0) + 1.0 - g;
    let s = (g - 2.0 * mu - v + mu * (g - 2.0 * mu) / (v + 1.0)) / (v + 1.0);
    let t = 3.0 * (1.0 - mu) * q + s * (p - 3.0 * a);
    let m2 = (1.0 - g * g) * (1.0 + mu) * t / (12.0 * p * (v + v0));
    return (f_hg + alpha * m2) / nephele_draine_norm(g, alpha);
}

// μ with F(μ) = ξ: Newton's method (F′ = 2π p) from the HG root of the same g, kept inside a
// bracket that every step shrinks (bisection where a step would leave it), until F is within
// 2 f32 units of ξ or the bracket closes. In f32 the CDF is good to a few units of 1e-7, which
// bounds how well any f32 root can do.
fn nephele_draine_sample(g: f32, alpha: f32, xi_in: f32) -> NepheleCosine {
    let xi = clamp(xi_in, 0.0, 1.0);
    var lo = -1.0;
    var hi = 1.0;
    var mu = nephele_hg_sample(g, xi).mu;
    for (var i = 0; i < 60; i++) {
        let f = nephele_draine_cdf(g, alpha, mu) - xi;
        if abs(f) <= 2.4e-7 {
            break;
        }
        if f > 0.0 {
            hi = mu;
        } else {
            lo = mu;
        }
        let density = 2.0 * NEPHELE_PI * nephele_draine_eval(g, alpha, nephele_cosine_from_mu(mu));
        let next = mu - f / density;
        if next > lo && next < hi {
            mu = next;
        } else {
            mu = 0.5 * (lo + hi);
        }
        if hi - lo <= 1.2e-7 {
            break;
        }
    }
    return nephele_cosine_from_mu(mu);
}

// ---- HG + Draine (Jendersie & d'Eon 2023): (1 − w_D) HG(g_HG) + w_D Draine(g_D, α) ----------

struct NepheleHgDraine {
    g_hg: f32,
    g_d: f32,
    alpha: f32,
    w_d: f32,
}

fn nephele_hg_draine_eval(m: NepheleHgDraine, c: NepheleCosine) -> f32 {
    return (1.0 - m.w_d) * nephele_hg_eval(m.g_hg, c)
        + m.w_d * nephele_draine_eval(m.g_d, m.alpha, c);
}

// The HG lobe when ξ < 1 − w_D (ξ rescaled to it), else the Draine lobe: the pdf of a sample
// is the mixture's.
fn nephele_hg_draine_sample(m: NepheleHgDraine, xi: f32) -> NepheleCosine {
    let w = 1.0 - m.w_d;
    if xi < w {
        return nephele_hg_sample(m.g_hg, xi / w);
    }
    return nephele_draine_sample(m.g_d, m.alpha, clamp((xi - w) / (1.0 - w), 0.0, 1.0));
}

// Jendersie & d'Eon's fits of the four parameters to Mie theory for water droplets of
// diameter d (µm), 0 < d ≤ 50 (the runtime's `presets::jendersie_deon`).
fn nephele_hg_draine_from_diameter(d: f32) -> NepheleHgDraine {
    if d >= 5.0 {
        return NepheleHgDraine(
            exp(-0.0990567 / (d - 1.67154)),
            exp(-2.20679 / (d + 3.91029) - 0.428934),
            exp(3.62489 - 8.29288 / (d + 5.52825)),
            exp(-0.599085 / (d - 0.641583) - 0.665888),
        );
    }
    let l = log(d);
    if d >= 1.5 {
        let ln_l = log(l);
        return NepheleHgDraine(
            0.0604931 * ln_l + 0.940256,
            0.500411 - 0.081287 / (-2.0 * l + tan(l) + 1.27551),
            7.30354 * l + 6.31675,
            0.026914 * (l - cos(5.68947 * (ln_l - 0.0292149))) + 0.376475,
        );
    }
    if d > 0.1 {
        let a = (l - 0.238604) * (l + 1.00667);
        let b = 0.507522 - 0.15677 * l;
        let c = 1.19692 * cos(a / b) + 1.37932 * l + 0.0625835;
        return NepheleHgDraine(
            0.862 - 0.143 * l * l,
            0.379685 * cos(c) + 0.344213,
            250.0,
            0.146209 * cos(3.38707 * l + 2.11193) + 0.316072 + 0.0778917 * l,
        );
    }
    return NepheleHgDraine(
        13.8 * d * d,
        1.1456 * d * sin(9.29044 * d),
        250.0,
        0.252977 - 312.983 * exp(4.3 * l),
    );
}
