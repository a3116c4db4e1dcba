// The elementary functions nephele's WGSL needs, to a few f32 ulps: Vulkan lets a driver's
// built-in exp, log, sin and cos be off by 3 + 2|x| ulps, 3 ulps or 2⁻¹¹ absolute (lavapipe's
// exp was 8e-5 relative), asin by 4096 ulps, while the tables' forward peaks and exponents
// need the runtime's precision. Cephes' single-precision algorithms (S. L. Moshier), written
// out; they use only +, −, ×, floor, frexp and ldexp, which are exact or correctly rounded.

const NEPHELE_PI: f32 = 3.14159265358979;
// The largest f32. WGSL forbids infinities and NaNs as constants (a shader with one fails to
// compile on Tint and WebKit) and lets a driver assume none at run time, so the port
// saturates where the runtime would overflow, and its callers pass finite values.
const NEPHELE_F32_MAX: f32 = 3.40282347e38;
const NEPHELE_INV_FOUR_PI: f32 = 0.0795774715459477;

// asin(x), |x| ≤ 1, to a few f32 ulps (Cephes' asinf): a polynomial in x² up to |x| = 1/2,
// π/2 − 2 asin(√((1 − |x|)/2)) beyond. Vulkan lets the built-in asin be off by 4096 ulps (it
// is atan2's), far too coarse for the angle of a forward peak.
fn nephele_asin(x: f32) -> f32 {
    var a = abs(x);
    var flip = false;
    if a > 0.5 {
        a = sqrt(0.5 * (1.0 - a));
        flip = true;
    }
    let z = a * a;
    let p = ((((4.2163199048e-2 * z + 2.4181311049e-2) * z + 4.5470025998e-2) * z
        + 7.4953002686e-2) * z + 1.6666752422e-1) * z * a + a;
    var r = p;
    if flip {
        r = 0.5 * NEPHELE_PI - 2.0 * p;
    }
    return select(r, -r, x < 0.0);
}

// eˣ to a few f32 ulps (Cephes' expf: x = n ln 2 + r, |r| ≤ ln 2 / 2, a polynomial in r, then
// 2ⁿ): Vulkan lets the built-in exp be 3 + 2|x| ulps off (lavapipe's was 8e-5 relative).
// Below f32's normal range it is 0 (GPUs may flush subnormals); above its range, the largest
// f32.
fn nephele_exp(x: f32) -> f32 {
    if x < -87.336544 {
        return 0.0;
    }
    if x > 88.72283 {
        return NEPHELE_F32_MAX;
    }
    let n = floor(x * 1.44269504088896341 + 0.5);
    let r = (x - n * 0.693359375) + n * 2.12194440e-4;
    let z = r * r;
    let p = ((((( 1.9875691500e-4 * r + 1.3981999507e-3) * r + 8.3334519073e-3) * r
        + 4.1665795894e-2) * r + 1.6666665459e-1) * r + 5.0000001201e-1) * z + r + 1.0;
    // 2ⁿ in two steps at the top (n = 128 with p < 1): ldexp's exponent stays within f32's.
    if n > 127.0 {
        return ldexp(p, i32(n) - 1) * 2.0;
    }
    return ldexp(p, i32(n));
}

// ln x (x > 0; at 0 and below, minus the largest f32), Cephes' logf: x = f 2ᵉ with f ∈ [√½, √2), a
// polynomial in f − 1, e ln 2 added in two parts.
fn nephele_ln(x_in: f32) -> f32 {
    if x_in <= 0.0 {
        return -NEPHELE_F32_MAX;
    }
    let parts = frexp(x_in);
    var x = parts.fract;
    var e = f32(parts.exp);
    if x < 0.707106781186547524 {
        e = e - 1.0;
        x = x + x - 1.0;
    } else {
        x = x - 1.0;
    }
    let z = x * x;
    var y = ((((((((7.0376836292e-2 * x - 1.1514610310e-1) * x + 1.1676998740e-1) * x
        - 1.2420140846e-1) * x + 1.4249322787e-1) * x - 1.6668057665e-1) * x
        + 2.0000714765e-1) * x - 2.4999993993e-1) * x + 3.3333331174e-1) * x * z;
    y = y + -2.12194440e-4 * e;
    y = y + -0.5 * z;
    return x + y + 0.693359375 * e;
}

// eˣ − 1 as the runtime's `exp_m1`: a series below |x| = 0.01, Kahan's (u − 1) x / ln u with
// u = eˣ up to |x| = 1/2, eˣ − 1 beyond.
fn nephele_exp_m1(x: f32) -> f32 {
    let a = abs(x);
    if a < 0.01 {
        return x * (1.0 + x / 2.0 * (1.0 + x / 3.0 * (1.0 + x / 4.0 * (1.0 + x / 5.0
            * (1.0 + x / 6.0)))));
    }
    if a < 0.5 {
        let u = nephele_exp(x);
        return (u - 1.0) * x / nephele_ln(u);
    }
    return nephele_exp(x) - 1.0;
}

// (sin x, cos x), Cephes' sinf and cosf: x reduced by multiples of π/4 (π/4 in three parts),
// a polynomial for each octant. For |x| up to a few thousand radians.
fn nephele_sin_cos(x_in: f32) -> vec2<f32> {
    let x = abs(x_in);
    var j = u32(1.27323954473516 * x);
    var y = f32(j);
    if (j & 1u) == 1u {
        j = j + 1u;
        y = y + 1.0;
    }
    j = j & 7u;
    let r = ((x - y * 0.78515625) - y * 2.4187564849853515625e-4) - y * 3.77489497744594108e-8;
    let z = r * r;
    let c = ((2.443315711809948e-5 * z - 1.388731625493765e-3) * z + 4.166664568298827e-2)
        * z * z - 0.5 * z + 1.0;
    let s = ((-1.9515295891e-4 * z + 8.3321608736e-3) * z - 1.6666654611e-1) * z * r + r;
    // x = j π/4 + r with j even: a quarter turn per 2 of j.
    var sin_v: f32;
    var cos_v: f32;
    switch j {
        case 0u: { sin_v = s; cos_v = c; }
        case 2u: { sin_v = c; cos_v = -s; }
        case 4u: { sin_v = -s; cos_v = -c; }
        default: { sin_v = -c; cos_v = s; }
    }
    return vec2<f32>(select(sin_v, -sin_v, x_in < 0.0), cos_v);
}
