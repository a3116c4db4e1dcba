//! Light a finite cloud loses through its sides, and light an absorbing medium loses to its
//! droplets, per order group: what the tables of an infinite, conservative slab must be
//! multiplied by (docs/collector.md, "Finite clouds").
//!
//! **Loss as absorption per scattering.** An order-n path under albedo ϖ weighs exactly ϖⁿ =
//! e^{−κ n}. In diffusion theory the light a body loses through its sides decays the same way
//! once the paths have spread across it, at the rate of its lateral buckling: for a cylinder of
//! radius R (mfp) around the light,
//!
//! ```text
//!     κ⊥ = D j₀² / R_e²,   D = 1 / (3 (1 − g)) (mfp² per scattering),   R_e = R + z_e,
//! ```
//!
//! j₀ = 2.405 the first zero of J₀, z_e = 2 / (3 (1 − g)) the extrapolation length (mfp). The
//! slab's own faces already lose what they lose; the sides are what the slab lacks. So one
//! correction, T_g(κ) with κ = κ⊥ + κ_a (κ_a = −ln ϖ), serves clouds and absorbing media.
//!
//! **Per group.** A group [a, b] holds paths of many orders n; it keeps
//! Σ_{n∈g} w_n e^{−κ n} / Σ_{n∈g} w_n, w_n the slab's distribution of orders, which diffusion
//! gives: the light seen at depth d has diffused from the source at one transport mean free
//! path ℓ* = 1/(1 − g) below the lit face to p across z = |d − ℓ*| + z_e (extrapolated), with
//! the first-passage density of a random walk of diffusion coefficient D,
//!
//! ```text
//!     f(n) = z / √(4π D n³) · e^{−z² / (4 D n)},
//! ```
//!
//! and the slab loses its own high orders through its faces at λ_t = D π² / (t + 2 z_e)². With
//! s = λ_t + κ, the share of f e^{−s n} below n₀ is the first-passage distribution of a drifted
//! Brownian motion,
//!
//! ```text
//!     W(n₀, s) = ∫₀^{n₀} f(n) e^{−s n} dn = ½ [e^{−z q} erfc(u − v) + e^{z q} erfc(u + v)],
//!     q = √(s / D),  u = z / (2 √(D n₀)),  v = √(s n₀),   W(∞, s) = e^{−z q},
//! ```
//!
//! and the group keeps [W(b + ½, s) − W(a − ½, s)] / [W(b + ½, λ_t) − W(a − ½, λ_t)]. For a
//! narrow group this is e^{−κ n̄} whatever w_n; for the open last group (31+ by default) the
//! spread of n matters, and the slab's λ_t bounds it.

use crate::real::Real;

/// j₀²: the square of the first zero of the Bessel function J₀ (a cylinder's lateral mode).
const J0_SQUARED: f64 = 5.783_185_962_946_784;

/// D = 1 / (3 (1 − g)): the diffusion coefficient per scattering (mfp² per scattering) of a
/// medium of mean cosine `g`.
pub fn diffusion_coefficient<R: Real>(g: R) -> R {
    R::of(1.0) / (R::of(3.0) * (R::of(1.0) - g))
}

/// z_e = 2 / (3 (1 − g)) (mfp): how far beyond a boundary the diffuse light extrapolates to 0.
pub fn extrapolation_length<R: Real>(g: R) -> R {
    R::of(2.0) / (R::of(3.0) * (R::of(1.0) - g))
}

/// κ⊥ (per scattering): the rate at which light leaves through the sides of a body of lateral
/// radius `radius` (mfp) around the light; 0 for an unbounded one (radius infinite or NaN).
pub fn lateral_rate<R: Real>(radius: R, g: R) -> R {
    if !(radius >= R::of(0.0)) || radius.f64() == f64::INFINITY {
        return R::of(0.0);
    }
    let re = radius + extrapolation_length(g);
    diffusion_coefficient(g) * R::of(J0_SQUARED) / (re * re)
}

/// What a path loses per scattering: absorption from the first scattering on, and the sides'
/// leakage once the paths have spread to the sides (after `delay` orders).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Loss<R> {
    /// κ_a = −ln ϖ.
    pub absorption: R,
    /// κ⊥ ([`lateral_rate`]).
    pub lateral: R,
    /// n_c: the orders before the sides take their toll (0: from the start).
    pub delay: R,
    /// Some(g): the sides count the orders by how far a walk of mean cosine g entering along
    /// the light has spread across it ([`lateral_orders`]); None: order by order.
    pub spread: Option<R>,
}

impl<R: Real> Loss<R> {
    /// The log-weight of order n: −κ_a n − κ⊥ (n⊥ − n_c)⁺, n⊥ = n or [`lateral_orders`].
    fn exponent(&self, n: R) -> R {
        let across = self.spread.map_or(n, |g| lateral_orders(n, g));
        let late = across - self.delay;
        let late = if late > R::of(0.0) { late } else { R::of(0.0) };
        -self.absorption * n - self.lateral * late
    }

    fn none(&self) -> bool {
        !(self.absorption > R::of(0.0)) && !(self.lateral > R::of(0.0))
    }
}

/// The lateral orders n⊥(n) (docs/collector.md, "The sides counted by the lateral spread"):
/// after n flights, a walk that entered along the light, with unit mean free paths and a phase
/// function of mean cosine g (and ⟨P₂⟩ = h = g², as Henyey–Greenstein), has spread across the
/// light by ⟨r⊥²⟩ = ⟨r²⟩ − ⟨r_z²⟩, the persistent walk's exact moments:
///
///   ⟨r²⟩ = 2n + 2S,  ⟨r_z²⟩ = ⅔ (n + 2(1 − hⁿ)/(1 − h)) + ⅔ S + 4⁄3 T,
///   S = g (n(1 − g) − (1 − gⁿ))/(1 − g)²,  T = g/(1 − g) [(1 − hⁿ)/(1 − h) − (gⁿ − hⁿ)/(g − h)],
///
/// and n⊥ = ⟨r⊥²⟩/(4D) is the order at which diffusion would have spread as far: ≈ 0.04 at
/// n = 2 for g = 0.86, → n − g/(1 − g) − 1/(1 − h) for large n. A forward-peaked walk keeps to
/// its entry line for its first orders, so the sides cannot take their light yet.
pub fn lateral_orders<R: Real>(n: R, g: R) -> R {
    let one = R::of(1.0);
    let g = g.clamp_to(R::of(1e-3), R::of(0.999));
    let h = g * g;
    let (gn, hn) = ((n * g.ln()).exp(), (n * h.ln()).exp());
    let s = g * (n * (one - g) - (one - gn)) / ((one - g) * (one - g));
    let t = g / (one - g) * ((one - hn) / (one - h) - (gn - hn) / (g - h));
    let third = R::of(1.0 / 3.0);
    let r2 = R::of(2.0) * (n + s);
    let rz2 = R::of(2.0) * third * (n + R::of(2.0) * (one - hn) / (one - h))
        + R::of(2.0) * third * s
        + R::of(4.0) * third * t;
    let across = (r2 - rz2) * R::of(0.75) * (one - g);
    if across > R::of(0.0) {
        across
    } else {
        R::of(0.0)
    }
}

/// n − n⊥(n) for large n: g/(1 − g) + 1/(1 − g²).
fn lateral_offset<R: Real>(g: R) -> R {
    let one = R::of(1.0);
    let g = g.clamp_to(R::of(1e-3), R::of(0.999));
    g / (one - g) + one / (one - g * g)
}

/// The share of one order group's light that the `loss` leaves: the group holds orders
/// `first` ..= `last` (None: no end), seen at depth `depth` of a slab of thickness `thickness`
/// (mfp), mean cosine `g` (module docs). 1 without loss, falling as the loss grows.
pub fn group_survival<R: Real>(
    first: R,
    last: Option<R>,
    depth: R,
    thickness: R,
    g: R,
    loss: &Loss<R>,
) -> R {
    let (zero, one) = (R::of(0.0), R::of(1.0));
    if loss.none() {
        return one;
    }
    let diffusion = diffusion_coefficient(g);
    let ze = extrapolation_length(g);
    let z = (depth - one / (one - g)).abs() + ze;
    let te = thickness + R::of(2.0) * ze;
    let slab_rate = diffusion * R::PI * R::PI / (te * te);
    let (with, without) = match last {
        Some(b) if b - first < R::of(MAX_TERMS as f64) => {
            let orders = Orders {
                first,
                count: (b - first).f64() as usize + 1,
                z,
                diffusion,
            };
            let shift = orders.largest_exponent(slab_rate);
            (
                orders.sum(slab_rate, shift, Some(loss)),
                orders.sum(slab_rate, shift, None),
            )
        }
        _ => {
            // The continuum between the group's ends, split where the sides begin to count;
            // e^{κ⊥ n_c} stays finite because n_c is held below 60/κ⊥.
            let lo = first - R::of(0.5);
            let hi = last.map(|b| b + R::of(0.5));
            let share = |from: R, to: Option<R>, s: R| match to {
                Some(to) if to > from => below(to, s, z, diffusion) - below(from, s, z, diffusion),
                Some(_) => zero,
                None => above(from, s, z, diffusion),
            };
            let rate = if loss.lateral > R::of(1e-30) {
                loss.lateral
            } else {
                R::of(1e-30)
            };
            // Beyond order 30 the lateral orders are n − their offset to within 0.1.
            let offset = loss.spread.map_or(zero, lateral_offset);
            let mut delay = (loss.delay + offset).clamp_to(zero, R::of(60.0) / rate);
            if let Some(hi) = hi {
                delay = delay.clamp_to(zero, hi);
            }
            let split = if delay > lo { delay } else { lo };
            let early = share(lo, Some(split), slab_rate + loss.absorption);
            let late = (loss.lateral * delay).exp()
                * share(split, hi, slab_rate + loss.absorption + loss.lateral);
            (early + late, share(lo, hi, slab_rate))
        }
    };
    // Deep in a thick slab the open group's shares may both underflow: it then keeps its
    // first order's weight.
    if !(without > R::of(1e-30)) || !(with >= zero) {
        return loss.exponent(first).exp();
    }
    (with / without).clamp_to(zero, one)
}

/// Most orders a closed group sums one by one (wider ones take the continuum).
const MAX_TERMS: usize = 64;

/// A closed group's orders, summed one by one: f(n) e^{−s n} ∝ e^{−z²/(4Dn) − s n − 1.5 ln n}.
struct Orders<R> {
    first: R,
    count: usize,
    z: R,
    diffusion: R,
}

impl<R: Real> Orders<R> {
    fn exponent(&self, k: usize, s: R) -> R {
        let n = self.first + R::of(k as f64);
        -(self.z * self.z) / (R::of(4.0) * self.diffusion * n) - s * n - R::of(1.5) * n.ln()
    }

    fn largest_exponent(&self, s: R) -> R {
        let mut most = self.exponent(0, s);
        for k in 1..self.count {
            let e = self.exponent(k, s);
            if e > most {
                most = e;
            }
        }
        most
    }

    /// Σ e^{exponent − shift}, each order weighed by the loss if given: relative to the
    /// largest term, so that deep points do not underflow.
    fn sum(&self, s: R, shift: R, loss: Option<&Loss<R>>) -> R {
        let mut total = R::of(0.0);
        for k in 0..self.count {
            let extra = loss.map_or(R::of(0.0), |l| l.exponent(self.first + R::of(k as f64)));
            total = total + (self.exponent(k, s) + extra - shift).exp();
        }
        total
    }
}

/// W(n₀, s) = ∫₀^{n₀} f(n) e^{−s n} dn for the first-passage density f across `z` with
/// diffusion coefficient `diffusion` (module docs): ½ [e^{−zq} erfc(u − v) + e^{zq} erfc(u + v)].
fn below<R: Real>(n0: R, s: R, z: R, diffusion: R) -> R {
    if !(n0 > R::of(0.0)) {
        return R::of(0.0);
    }
    let p = Passage::new(n0, s, z, diffusion);
    R::of(0.5) * (p.tilted_erfc(p.u - p.v) + p.damp * erfcx(p.u + p.v))
}

/// W(∞, s) − W(n₀, s), without the cancellation of the difference:
/// ½ [e^{−zq} erfc(v − u) − e^{zq} erfc(u + v)].
fn above<R: Real>(n0: R, s: R, z: R, diffusion: R) -> R {
    let zero = R::of(0.0);
    if !(n0 > zero) {
        return (-z * (s / diffusion).sqrt()).exp();
    }
    let p = Passage::new(n0, s, z, diffusion);
    let tail = R::of(0.5) * (p.tilted_erfc(p.v - p.u) - p.damp * erfcx(p.u + p.v));
    if tail > zero {
        tail
    } else {
        zero
    }
}

/// The arguments of W at n₀: u = z/(2√(D n₀)), v = √(s n₀) (zq = 2uv), and e^{−u² − v²}.
struct Passage<R> {
    u: R,
    v: R,
    damp: R,
}

impl<R: Real> Passage<R> {
    fn new(n0: R, s: R, z: R, diffusion: R) -> Self {
        let u = z / (R::of(2.0) * (diffusion * n0).sqrt());
        let v = (s * n0).sqrt();
        Self {
            u,
            v,
            damp: (-(u * u) - v * v).exp(),
        }
    }

    /// e^{−2uv} erfc(x) for x = ±(u − v), in the scaled erfcx so that nothing overflows:
    /// e^{−u² − v²} erfcx(x) for x ≥ 0, else 2 e^{−2uv} − e^{−u² − v²} erfcx(−x).
    fn tilted_erfc(&self, x: R) -> R {
        if x >= R::of(0.0) {
            self.damp * erfcx(x)
        } else {
            R::of(2.0) * (-(R::of(2.0) * self.u * self.v)).exp() - self.damp * erfcx(-x)
        }
    }
}

/// erfcx(x) = e^{x²} erfc(x) for x ≥ 0, relative error < 1.2·10⁻⁷: the Chebyshev fit of
/// erfc(x) = τ exp(−x² + P(τ)), τ = 1/(1 + x/2) (Numerical Recipes, "erfcc").
fn erfcx<R: Real>(x: R) -> R {
    const C: [f64; 10] = [
        -1.265_512_23,
        1.000_023_68,
        0.374_091_96,
        0.096_784_18,
        -0.186_288_06,
        0.278_868_07,
        -1.135_203_98,
        1.488_515_87,
        -0.822_152_23,
        0.170_872_77,
    ];
    let t = R::of(1.0) / (R::of(1.0) + R::of(0.5) * x);
    let mut p = R::of(C[9]);
    for &c in C[..9].iter().rev() {
        p = R::of(c) + t * p;
    }
    t * p.exp()
}

#[cfg(all(test, feature = "std"))]
mod tests {
    use super::*;

    fn absorbing<R: Real>(kappa: R) -> Loss<R> {
        Loss {
            absorption: kappa,
            lateral: R::of(0.0),
            delay: R::of(0.0),
            spread: None,
        }
    }

    /// A delayed loss keeps every order before the delay and loses at the rate after it, in
    /// the continuum (the open group) as order by order (a closed one).
    #[test]
    fn a_delayed_loss_spares_the_early_orders() {
        let late = Loss {
            absorption: 0.0,
            lateral: 0.05,
            delay: 40.0,
            spread: None,
        };
        assert_eq!(
            group_survival(13.0, Some(18.0), 0.0, 30.0, 0.86, &late),
            1.0
        );
        let open: f64 = group_survival(31.0, None, 0.0, 30.0, 0.86, &late);
        let at_once: f64 =
            group_survival(31.0, None, 0.0, 30.0, 0.86, &Loss { delay: 0.0, ..late });
        assert!(open > at_once && open < 1.0, "{open} {at_once}");
        // A wide closed group in the continuum against the same orders one by one.
        let wide: f64 = group_survival(31.0, Some(200.0), 0.0, 30.0, 0.86, &late);
        let narrow: f64 = group_survival(31.0, Some(94.0), 0.0, 30.0, 0.86, &late);
        assert!(wide < narrow && narrow < 1.0, "{wide} {narrow}");
    }

    /// The first-passage density, summed order by order.
    fn direct(first: u32, last: u32, z: f64, d: f64, s: f64) -> f64 {
        (first..=last)
            .map(|n| {
                let n = n as f64;
                z / (4.0 * std::f64::consts::PI * d * n * n * n).sqrt()
                    * (-(z * z) / (4.0 * d * n) - s * n).exp()
            })
            .sum()
    }

    #[test]
    fn erfcx_matches_erfc() {
        // erfc at a few points (Abramowitz & Stegun, Table 7.1).
        for (x, erfc) in [
            (0.0f64, 1.0),
            (0.5, 0.479_500_122),
            (1.0, 0.157_299_207),
            (2.0, 0.004_677_735),
        ] {
            let got = erfcx(x) * (-(x * x)).exp();
            assert!((got / erfc - 1.0f64).abs() < 2e-7, "{x}: {got} vs {erfc}");
        }
    }

    /// W's closed form against the integral of the density, by the midpoint rule; the open
    /// tail against the whole transform minus W.
    #[test]
    fn the_closed_form_integrates_the_density() {
        let (z, d) = (12.0, 2.4);
        let f = |n: f64, s: f64| {
            z / (4.0 * std::f64::consts::PI * d * n * n * n).sqrt()
                * (-(z * z) / (4.0 * d * n) - s * n).exp()
        };
        for s in [0.0, 0.003, 0.03, 0.2] {
            for n0 in [1.5, 2.5, 8.5, 30.5, 400.0] {
                let m = 200_000;
                let h = n0 / m as f64;
                let quad: f64 = (0..m).map(|k| f(h * (k as f64 + 0.5), s) * h).sum();
                let closed = below(n0, s, z, d);
                assert!(
                    (closed - quad).abs() < 1e-6 + 1e-5 * quad,
                    "s {s}, {n0}: {closed} vs {quad}"
                );
                let whole = (-z * (s / d).sqrt()).exp();
                let tail = above(n0, s, z, d);
                assert!(
                    (tail - (whole - closed)).abs() < 1e-6,
                    "s {s}, {n0}: {tail}"
                );
            }
        }
    }

    /// The survival of a group against the ratio of the density summed order by order (the
    /// continuum's ±½ at the group's ends is the only difference).
    #[test]
    fn survival_follows_the_discrete_orders() {
        let g = 0.86f64;
        let dd = 1.0 / (3.0 * (1.0 - g));
        let ze = 2.0 * dd;
        for (depth, t) in [(0.0, 20.0), (20.0, 20.0), (2.0, 80.0)] {
            let z = (depth - 1.0 / (1.0 - g)).abs() + ze;
            let lambda = dd * std::f64::consts::PI.powi(2) / (t + 2.0 * ze).powi(2);
            for kappa in [0.003, 0.02, 0.08] {
                for (a, b) in [(2u32, 2u32), (5, 6), (13, 18), (31, 100_000)] {
                    let want = direct(a, b, z, dd, lambda + kappa) / direct(a, b, z, dd, lambda);
                    let last = (b < 100_000).then_some(b as f64);
                    let got = group_survival(a as f64, last, depth, t, g, &absorbing(kappa));
                    assert!(
                        (got / want - 1.0).abs() < 0.02,
                        "d {depth} t {t} κ {kappa} [{a}, {b}]: {got} vs {want}"
                    );
                }
            }
        }
    }

    /// No loss keeps everything; a narrow group keeps e^{−κ n}; more loss keeps less; the
    /// open group keeps less than its first order alone would.
    #[test]
    fn survival_is_a_tilted_share() {
        let g = 0.86;
        assert_eq!(
            group_survival(2.0, Some(2.0), 0.0, 20.0, g, &absorbing(0.0)),
            1.0
        );
        for kappa in [0.001, 0.02, 0.1] {
            let two: f64 = group_survival(2.0, Some(2.0), 0.0, 20.0, g, &absorbing(kappa));
            assert!(
                (two / (-2.0 * kappa).exp() - 1.0).abs() < 0.01,
                "{kappa}: {two}"
            );
            let open: f64 = group_survival(31.0, None, 0.0, 40.0, g, &absorbing(kappa));
            assert!(open < (-31.0 * kappa).exp(), "{kappa}: {open}");
        }
        let mut prev = 1.0;
        for k in 1..20 {
            let kept: f64 = group_survival(31.0, None, 5.0, 40.0, g, &absorbing(0.005 * k as f64));
            assert!(kept < prev && kept > 0.0);
            prev = kept;
        }
    }

    /// The renderer's f32 agrees with f64.
    #[test]
    fn f32_follows_f64() {
        for (a, b) in [(2.0, Some(2.0)), (9.0, Some(12.0)), (31.0, None)] {
            for (d, t) in [(0.0, 10.0), (10.0, 10.0), (3.0, 100.0), (120.0, 128.0)] {
                for kappa in [0.001, 0.01, 0.05, 0.3] {
                    let x = group_survival(a, b, d, t, 0.86, &absorbing(kappa));
                    let y = group_survival(
                        a as f32,
                        b.map(|b| b as f32),
                        d as f32,
                        t as f32,
                        0.86f32,
                        &absorbing(kappa as f32),
                    );
                    assert!(
                        (y as f64 - x).abs() < 1e-6 + 1e-3 * x,
                        "{a} {d} {t} {kappa}: {x} {y}"
                    );
                }
            }
        }
    }

    /// The closed form of n⊥ equals the moments summed flight by flight, from the direction
    /// correlations E[ω_i·ω_j] = g^{j−i} and E[ω_iz ω_jz] = g^{j−i} (1 + 2hⁱ)/3 (the ones
    /// tests/pencil.rs checks against the slab walk), and tends to n − g/(1 − g) − 1/(1 − h).
    #[test]
    fn lateral_orders_follow_the_walk_moments() {
        for g in [0.3f64, 0.7, 0.86, 0.95] {
            let h = g * g;
            let d = 1.0 / (3.0 * (1.0 - g));
            for n in 1..=60usize {
                let (mut r2, mut rz2) = (0.0, 0.0);
                for i in 0..n {
                    let ci = (1.0 + 2.0 * h.powi(i as i32)) / 3.0;
                    // E[ℓ²] = 2 for unit exponential flights, E[ℓ_i ℓ_j] = 1 apart.
                    r2 += 2.0;
                    rz2 += 2.0 * ci;
                    for j in i + 1..n {
                        let c = g.powi((j - i) as i32);
                        r2 += 2.0 * c;
                        rz2 += 2.0 * c * ci;
                    }
                }
                let direct = (r2 - rz2) / (4.0 * d);
                let closed: f64 = lateral_orders(n as f64, g);
                assert!(
                    (closed - direct).abs() < 1e-9 * (1.0 + direct),
                    "g {g} n {n}"
                );
                let single = lateral_orders(n as f32, g as f32) as f64;
                assert!(
                    (single - closed).abs() < 1e-4 * (1.0 + closed),
                    "f32 g {g} n {n}"
                );
            }
            let far = 400.0;
            let asymptote = far - lateral_offset(g);
            assert!((lateral_orders(far, g) - asymptote).abs() < 1e-6, "g {g}");
        }
        // A forward-peaked walk keeps to its entry line: g = 0.86, n⊥(2) ≈ 0.04, n⊥(20) ≈ 10.7.
        assert!((lateral_orders(2.0f64, 0.86) - 0.036).abs() < 0.002);
        assert!((lateral_orders(20.0f64, 0.86) - 10.66).abs() < 0.01);
    }

    /// Counting the sides by the walk's spread keeps more of every group than counting them
    /// order by order, and the open group's asymptote agrees with the closed groups' sums.
    #[test]
    fn the_spread_spares_the_early_orders() {
        let by_order = Loss {
            absorption: 0.0,
            lateral: 0.05,
            delay: 0.0,
            spread: None,
        };
        let by_spread = Loss {
            spread: Some(0.86),
            ..by_order
        };
        for (first, last) in [
            (2.0, Some(2.0)),
            (3.0, Some(4.0)),
            (13.0, Some(18.0)),
            (31.0, None),
        ] {
            let a: f64 = group_survival(first, last, 3.0, 30.0, 0.86, &by_order);
            let b: f64 = group_survival(first, last, 3.0, 30.0, 0.86, &by_spread);
            assert!(b > a && b <= 1.0, "{first}: {a} {b}");
        }
        // The open group (the asymptote n⊥ = n − offset in the continuum) against the exact
        // n⊥ summed order by order over the first-passage density, to order 2·10⁵.
        let g = 0.86f64;
        let (d, ze) = (diffusion_coefficient(g), extrapolation_length(g));
        for (depth, thickness) in [(0.0, 200.0), (5.0, 40.0), (20.0, 64.0)] {
            let z = (depth - 1.0 / (1.0 - g)).abs() + ze;
            let te: f64 = thickness + 2.0 * ze;
            let s = d * core::f64::consts::PI.powi(2) / (te * te);
            let (mut with, mut without) = (0.0, 0.0);
            for n in 31..200_000 {
                let n = n as f64;
                let w = (-z * z / (4.0 * d * n) - s * n).exp() * n.powf(-1.5);
                with += w * (-0.05 * lateral_orders(n, g)).exp();
                without += w;
            }
            let open: f64 = group_survival(31.0, None, depth, thickness, g, &by_spread);
            let exact = with / without;
            assert!(
                (open - exact).abs() < 0.02 * exact,
                "{depth} {thickness}: {open} {exact}"
            );
        }
    }

    #[test]
    fn lateral_rate_of_a_body() {
        assert_eq!(lateral_rate(f64::INFINITY, 0.86), 0.0);
        // R = 20 mfp, g = 0.86: D = 2.381, z_e = 4.762, κ⊥ = 2.381 · 5.783 / 24.76².
        let k: f64 = lateral_rate(20.0, 0.86);
        assert!((k - 0.022_46).abs() < 1e-4, "{k}");
    }
}
