//! Core-only math for `no_std` builds without the `libm` feature: √, eˣ, ln, sin/cos, ∛, asin
//! in f64 (the f32 versions round the f64 result).
//!
//! Stable Rust has no float math in `core`, so without `std` the runtime needs either the `libm`
//! crate (feature `libm`, the recommended choice, as glam does) or these few functions. They are
//! short series after an exact range reduction, accurate to a few ulp (tested against `std` over
//! dense sweeps below); `sin_cos` reduces by a three-part π/2, exact for |x| ≲ 10⁵, which covers
//! every argument the evaluators pass (azimuths in [0, 2π)).

const LN2_HI: f64 = 6.931_471_803_691_238e-1; // ln 2 to 32 bits: k·LN2_HI is exact
const LN2_LO: f64 = 1.908_214_929_270_587_7e-10;
const INV_LN2: f64 = core::f64::consts::LOG2_E;
// π/2 in three 33-bit pieces (fdlibm's pio2_1, pio2_2, pio2_3): n·piece is exact for n < 2²⁰.
const PIO2_1: f64 = 1.570_796_326_734_125_6;
const PIO2_2: f64 = 6.077_100_506_303_966e-11;
const PIO2_3: f64 = 2.022_266_248_711_166_5e-21;
const PIO2_3T: f64 = 8.478_427_660_368_9e-32;

/// 2^k as an f64, for −1022 ≤ k ≤ 1023.
pub(crate) fn pow2(k: i64) -> f64 {
    f64::from_bits(((k + 1023) as u64) << 52)
}

/// x·2^k for any k, without overflow in the intermediate steps.
fn scale_pow2(mut x: f64, mut k: i64) -> f64 {
    while k > 1023 {
        x *= pow2(1023);
        k -= 1023;
    }
    while k < -1022 {
        x *= pow2(-1022);
        k += 1022;
    }
    x * pow2(k)
}

/// The nearest integer (ties away from zero), for |x| < 2⁶².
fn round_i64(x: f64) -> i64 {
    if x < 0.0 {
        (x - 0.5) as i64
    } else {
        (x + 0.5) as i64
    }
}

/// √x: Newton from an exponent-halving guess (≤ 6 % off), five steps.
pub fn sqrt(x: f64) -> f64 {
    if x.is_nan() || x < 0.0 {
        return f64::NAN;
    }
    if x == 0.0 || x.is_infinite() {
        return x;
    }
    // Subnormals: scale by 2¹⁰⁸ so that the bit trick sees a normal number.
    let (x, undo) = if x < f64::MIN_POSITIVE {
        (x * pow2(108), pow2(-54))
    } else {
        (x, 1.0)
    };
    let mut y = f64::from_bits((x.to_bits() >> 1) + (1023 << 51));
    for _ in 0..5 {
        y = 0.5 * (y + x / y);
    }
    y * undo
}

/// eˣ = 2ᵏ·eʳ with k = round(x/ln 2), |r| ≤ ln 2 / 2, eʳ by its Taylor series to r¹⁴
/// (remainder < 10⁻¹⁷).
pub fn exp(x: f64) -> f64 {
    if x.is_nan() {
        return x;
    }
    if x > 709.782_712_893_384 {
        return f64::INFINITY;
    }
    if x < -745.133_219_101_941_2 {
        return 0.0;
    }
    let k = round_i64(x * INV_LN2);
    let kf = k as f64;
    let r = (x - kf * LN2_HI) - kf * LN2_LO;
    // Horner form of Σ rⁿ/n!: 1 + r(1 + r/2(1 + r/3(…))).
    let mut p = 1.0;
    for n in (1..=14).rev() {
        p = 1.0 + p * r / n as f64;
    }
    scale_pow2(p, k)
}

/// ln x = e·ln 2 + ln m with m ∈ [√½, √2), ln m = 2 atanh s = 2 Σ s²ᵏ⁺¹/(2k+1), s = (m−1)/(m+1),
/// |s| ≤ 0.172 (terms to s²³, remainder < 10⁻¹⁸).
pub fn ln(x: f64) -> f64 {
    if x.is_nan() || x < 0.0 {
        return f64::NAN;
    }
    if x == 0.0 {
        return f64::NEG_INFINITY;
    }
    if x.is_infinite() {
        return x;
    }
    let (x, mut e) = if x < f64::MIN_POSITIVE {
        (x * pow2(54), -54)
    } else {
        (x, 0)
    };
    let bits = x.to_bits();
    e += ((bits >> 52) & 0x7ff) as i64 - 1023;
    let mut m = f64::from_bits((bits & 0x000f_ffff_ffff_ffff) | 0x3ff0_0000_0000_0000);
    if m > core::f64::consts::SQRT_2 {
        m *= 0.5;
        e += 1;
    }
    // With f = m − 1 (exact), 2s = f − s·f, so ln m = f − s·(f − R), R = 2 Σₖ≥₁ s²ᵏ/(2k+1):
    // the rounding of s then only touches the small correction, not the leading f.
    let f = m - 1.0;
    let s = f / (2.0 + f);
    let s2 = s * s;
    let mut p = 0.0;
    for k in (1..=11).rev() {
        p = p * s2 + 2.0 / (2 * k + 1) as f64;
    }
    let ln_m = f - s * (f - s2 * p);
    let ef = e as f64;
    ef * LN2_HI + (ln_m + ef * LN2_LO)
}

/// (sin x, cos x): x = n·π/2 + r with |r| ≤ π/4, Taylor series of both to r²¹ (remainder
/// < 10⁻²¹), then the quadrant n mod 4 picks signs and order.
pub fn sin_cos(x: f64) -> (f64, f64) {
    if !x.is_finite() {
        return (f64::NAN, f64::NAN);
    }
    let n = round_i64(x * core::f64::consts::FRAC_2_PI);
    let nf = n as f64;
    let r = (((x - nf * PIO2_1) - nf * PIO2_2) - nf * PIO2_3) - nf * PIO2_3T;
    let r2 = r * r;
    // sin r = r(1 − r²/(2·3)(1 − r²/(4·5)(…))), cos r = 1 − r²/(1·2)(1 − r²/(3·4)(…)).
    let (mut ps, mut pc) = (1.0, 1.0);
    for k in (1..=10).rev() {
        let k2 = (2 * k) as f64;
        ps = 1.0 - r2 * ps / (k2 * (k2 + 1.0));
        pc = 1.0 - r2 * pc / ((k2 - 1.0) * k2);
    }
    let (s, c) = (r * ps, pc);
    match n & 3 {
        0 => (s, c),
        1 => (c, -s),
        2 => (-s, -c),
        _ => (-c, s),
    }
}

/// ∛x: Newton from fdlibm's exponent-dividing guess, six steps.
pub fn cbrt(x: f64) -> f64 {
    if x.is_nan() || x == 0.0 || x.is_infinite() {
        return x;
    }
    let a = if x < 0.0 { -x } else { x };
    let (a, undo) = if a < f64::MIN_POSITIVE {
        (a * pow2(162), pow2(-54))
    } else {
        (a, 1.0)
    };
    let mut y = f64::from_bits(a.to_bits() / 3 + (715_094_163u64 << 32));
    for _ in 0..6 {
        y = (2.0 * y + a / (y * y)) / 3.0;
    }
    let y = y * undo;
    if x < 0.0 {
        -y
    } else {
        y
    }
}

/// asin x: the Maclaurin series Σ (2n)!/(4ⁿ(n!)²(2n+1)) z²ⁿ⁺¹ for |x| ≤ ½, and
/// asin x = π/2 − 2 asin √((1−x)/2) above (the argument is then ≤ ½ again).
pub fn asin(x: f64) -> f64 {
    if x.is_nan() || !(-1.0..=1.0).contains(&x) {
        return f64::NAN;
    }
    let a = if x < 0.0 { -x } else { x };
    let y = if a <= 0.5 {
        asin_series(a)
    } else {
        core::f64::consts::FRAC_PI_2 - 2.0 * asin_series(sqrt((1.0 - a) * 0.5))
    };
    if x < 0.0 {
        -y
    } else {
        y
    }
}

/// The asin series for 0 ≤ z ≤ ½: 28 terms (z⁵⁷ < 10⁻¹⁷), summed smallest first.
fn asin_series(z: f64) -> f64 {
    const N: usize = 28;
    let z2 = z * z;
    let mut terms = [0.0; N];
    let (mut a, mut zp) = (1.0, z);
    for (n, t) in terms.iter_mut().enumerate() {
        *t = a * zp / (2 * n + 1) as f64;
        a *= (2 * n + 1) as f64 / (2 * n + 2) as f64;
        zp *= z2;
    }
    terms.iter().rev().sum()
}

/// √x in f32 (through f64).
pub fn sqrtf(x: f32) -> f32 {
    sqrt(x as f64) as f32
}
/// eˣ in f32 (through f64).
pub fn expf(x: f32) -> f32 {
    exp(x as f64) as f32
}
/// ln x in f32 (through f64).
pub fn lnf(x: f32) -> f32 {
    ln(x as f64) as f32
}
/// (sin x, cos x) in f32 (through f64).
pub fn sin_cosf(x: f32) -> (f32, f32) {
    let (s, c) = sin_cos(x as f64);
    (s as f32, c as f32)
}
/// ∛x in f32 (through f64).
pub fn cbrtf(x: f32) -> f32 {
    cbrt(x as f64) as f32
}
/// asin x in f32 (through f64).
pub fn asinf(x: f32) -> f32 {
    asin(x as f64) as f32
}

#[cfg(all(test, feature = "std"))]
mod tests {
    /// Distance in units in the last place (of the reference).
    fn ulps(got: f64, want: f64) -> f64 {
        if got == want {
            return 0.0;
        }
        let ulp = f64::from_bits(want.abs().to_bits() + 1) - want.abs();
        (got - want).abs() / ulp
    }

    /// Largest ulp error of `f` against `g` over `xs`.
    fn worst(xs: impl Iterator<Item = f64>, f: fn(f64) -> f64, g: fn(f64) -> f64) -> (f64, f64) {
        xs.map(|x| (ulps(f(x), g(x)), x))
            .fold((0.0, 0.0), |a, b| if b.0 > a.0 { b } else { a })
    }

    /// Log-spaced positive sample, 10^lo … 10^hi, plus random-looking mantissas.
    fn logspace(lo: f64, hi: f64, n: usize) -> impl Iterator<Item = f64> {
        (0..n).map(move |i| 10f64.powf(lo + (hi - lo) * (i as f64 + 0.37) / n as f64))
    }

    fn linspace(lo: f64, hi: f64, n: usize) -> impl Iterator<Item = f64> {
        (0..=n).map(move |i| lo + (hi - lo) * i as f64 / n as f64)
    }

    #[test]
    fn sqrt_cbrt_within_one_ulp() {
        let (e, x) = worst(logspace(-310.0, 308.0, 200_000), super::sqrt, f64::sqrt);
        assert!(e <= 1.0, "sqrt {e} ulp at {x}");
        let (e, x) = worst(logspace(-310.0, 308.0, 200_000), super::cbrt, f64::cbrt);
        assert!(e <= 1.0, "cbrt {e} ulp at {x}");
        assert_eq!(super::cbrt(-8.0), -2.0);
        assert!(super::sqrt(-1.0).is_nan());
    }

    #[test]
    fn exp_ln_within_two_ulp() {
        let (e, x) = worst(linspace(-745.0, 709.0, 400_000), super::exp, f64::exp);
        assert!(e <= 2.0, "exp {e} ulp at {x}");
        let (e, x) = worst(linspace(-1.0, 1.0, 100_000), super::exp, f64::exp);
        assert!(e <= 2.0, "exp {e} ulp at {x}");
        let (e, x) = worst(logspace(-320.0, 308.0, 400_000), super::ln, f64::ln);
        assert!(e <= 2.0, "ln {e} ulp at {x}");
        let (e, x) = worst(linspace(0.5, 2.0, 100_000), super::ln, f64::ln);
        assert!(e <= 2.0, "ln near 1: {e} ulp at {x}");
        assert_eq!(super::ln(1.0), 0.0);
        assert_eq!(super::exp(0.0), 1.0);
    }

    #[test]
    fn sin_cos_within_two_ulp_or_1e_minus_16_absolute() {
        for x in linspace(-1.0e4, 1.0e4, 400_000).chain(linspace(-7.0, 7.0, 100_000)) {
            let (s, c) = super::sin_cos(x);
            let (s0, c0) = x.sin_cos();
            // Near zeros of sin/cos the ulp of the result is tiny; absolute error is what counts.
            assert!(
                ulps(s, s0) <= 2.0 || (s - s0).abs() <= 1e-16,
                "sin({x}) = {s} vs {s0}"
            );
            assert!(
                ulps(c, c0) <= 2.0 || (c - c0).abs() <= 1e-16,
                "cos({x}) = {c} vs {c0}"
            );
        }
    }

    #[test]
    fn asin_within_two_ulp() {
        let (e, x) = worst(linspace(-1.0, 1.0, 400_000), super::asin, f64::asin);
        assert!(e <= 2.0, "asin {e} ulp at {x}");
        let (e, x) = worst(logspace(-300.0, 0.0, 10_000), super::asin, f64::asin);
        assert!(e <= 2.0, "asin {e} ulp at {x}");
        assert!(super::asin(1.5).is_nan());
    }

    #[test]
    fn f32_versions_round_the_f64_result() {
        for x in linspace(0.01, 50.0, 10_000) {
            let x = x as f32;
            assert!((super::expf(-x) - (-x).exp()).abs() <= f32::EPSILON * (-x).exp());
            assert!((super::lnf(x) - x.ln()).abs() <= 2.0 * f32::EPSILON * x.ln().abs().max(1.0));
            assert!((super::sqrtf(x) - x.sqrt()).abs() <= f32::EPSILON * x.sqrt());
        }
    }
}
