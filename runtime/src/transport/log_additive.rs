//! The log-additive form (the best of the compression study, docs/compress.md): per order group,
//! the transport T of orders ≥ 2 as
//!
//!   ln T = ln B + Σ_j [a_j(μ_V) + b_j(μ_L)] P_j(2u − 1) + γ(μ_V) max(ln F₁, −10)
//!          + Σ_i h_i(Θ) [P0_i + P1_i (2u − 1)] + Σ_k [p_k(μ_V) + q_k(μ_L)] (s_V s_L)^k cos kψ_V,
//!
//! u the stretched depth in [0, 1] (the plane index over planes − 1 on the slab grid), B the
//! boundary factor (the share of optical path behind the viewpoint: 1 − e^{−(t−d)/μ_V} for light
//! going up, 1 − e^{−d/|μ_V|} going down), F₁ the single-scattering depth factor (T₁ of
//! [`super::single`] without its phase function), held at e⁻¹⁰ (deep in thick slabs it falls
//! like e^{−d/μ_L} while multiple scattering does not), h_i the hat functions of the nodes
//! Θ_i = π (i/(n − 1))² (dense at the forward peak), s = sin of the polar angles. With `pairs`,
//! γ becomes γ(μ_V, μ_L) and an offset and a depth slope per (μ_V, μ_L) pair are added. With
//! `cross` = A > 0, the view × sun interaction that the additive terms lack:
//!
//!   + γ_L(μ_L) max(ln F₁, −10) + Σ_{j<3} Σ_{a,b<A} e_{jab}^± P_j(2u − 1) P_a(2|μ_V| − 1) P_b(2μ_L − 1)
//!
//! (± a set per hemisphere of μ_V), smooth in both cosines so that it interpolates between
//! their nodes — unlike the per-pair terms.
//!
//! Linear in its parameters; parameters indexed by μ_V or μ_L are read between their grid nodes
//! with [`Lerp`] weights. The toolchain fits it (`nephele compress`) with these very features.

use super::geometry::SlabPoint;
use super::single::{beam_scattered_once, scattering_cosine};
use crate::legendre::Legendre;
use crate::phase::{Cosine, HenyeyGreenstein, PhaseFunction};
use crate::real::{exp_m1, Math, Real};

/// Most Legendre terms in depth.
pub const MAX_LEGENDRE: usize = 16;
/// Floor of ln F₁ as a feature.
pub const LN_F1_FLOOR: f64 = -10.0;

/// The form's sizes.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct LogAdditive {
    /// Legendre terms in depth, J (≤ [`MAX_LEGENDRE`]).
    pub legendre: usize,
    /// Azimuth harmonics, K.
    pub harmonics: usize,
    /// Θ nodes (≥ 2).
    pub theta_nodes: usize,
    /// Per-(μ_V, μ_L) γ, offset and depth slope.
    pub pairs: bool,
    /// Smooth (μ_V, μ_L) interaction terms of degree < A (0: none; at most [`MAX_CROSS`]).
    pub cross: usize,
}

/// Most polynomial terms per cosine in the interaction terms.
pub const MAX_CROSS: usize = 6;
/// Most azimuth harmonics (bounds the features of a point).
pub const MAX_HARMONICS: usize = 8;
/// Most Θ nodes.
pub const MAX_THETA_NODES: usize = 512;
/// Depth terms (P_0 … P_2) of the interaction.
const CROSS_DEPTH: usize = 3;

impl Default for LogAdditive {
    fn default() -> Self {
        Self {
            legendre: 7,
            harmonics: 3,
            theta_nodes: 24,
            pairs: false,
            cross: 3,
        }
    }
}

/// A position between two nodes of a parameter grid: weight 1 − w on `lo`, w on `hi`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Lerp<F> {
    /// Lower node.
    pub lo: usize,
    /// Upper node.
    pub hi: usize,
    /// Weight of the upper node, in [0, 1].
    pub w: F,
}

impl<F: Real> Lerp<F> {
    /// Exactly on node `i`.
    pub fn at(i: usize) -> Self {
        Self {
            lo: i,
            hi: i,
            w: F::of(0.0),
        }
    }

    /// `x` between the increasing `nodes` (held at the end nodes outside them; node 0 if empty).
    pub fn between(nodes: &[F], x: F) -> Self {
        let n = nodes.len();
        if n <= 1 || !(x > nodes[0]) {
            return Self::at(0);
        }
        if x >= nodes[n - 1] {
            return Self::at(n - 1);
        }
        let hi = nodes.partition_point(|&v| v <= x).clamp(1, n - 1);
        let lo = hi - 1;
        Self {
            lo,
            hi,
            w: (x - nodes[lo]) / (nodes[hi] - nodes[lo]),
        }
    }

    /// Calls `f(node, weight)` for its one or two nodes.
    #[inline(always)]
    pub fn each(&self, mut f: impl FnMut(usize, F)) {
        if self.hi != self.lo && self.w > F::of(0.0) {
            f(self.lo, F::of(1.0) - self.w);
            f(self.hi, self.w);
        } else {
            f(self.lo, F::of(1.0));
        }
    }
}

/// Where the form is evaluated: a slab point, where its cosines sit among the parameter
/// nodes, and its stretched depth.
#[derive(Clone, Copy, Debug)]
pub struct Cell<F> {
    /// The geometry.
    pub at: SlabPoint<F>,
    /// μ_L among the parameter nodes of the sun cosines.
    pub l: Lerp<F>,
    /// μ_V among the parameter nodes of the view cosines.
    pub v: Lerp<F>,
    /// Stretched depth in [0, 1].
    pub u: F,
    /// The scattering angle Θ (radians) between the sun's direction and the view's, which
    /// the Θ-table features of T and of the collector read: computed once ([`Cell::new`]).
    pub theta: F,
}

impl<F: Real> Cell<F> {
    /// The cell of `at` with its cosines among the nodes (`l`, `v`) and stretched depth `u`.
    pub fn new(at: SlabPoint<F>, l: Lerp<F>, v: Lerp<F>, u: F) -> Self {
        Self {
            at,
            l,
            v,
            u,
            theta: scattering_angle(&at),
        }
    }

    /// A cell at zero everything (for counting features).
    pub(crate) fn zero() -> Self {
        let z = F::of(0.0);
        Self {
            at: SlabPoint {
                depth: z,
                thickness: z,
                mu_v: z,
                psi_v: z,
                mu_l: z,
            },
            l: Lerp::at(0),
            v: Lerp::at(0),
            u: z,
            theta: z,
        }
    }
}

impl LogAdditive {
    /// Whether the runtime can evaluate this form: the name of the first size outside its
    /// limits otherwise (the loader refuses such files, the compressor such options).
    pub fn check(&self) -> Result<(), &'static str> {
        if !(1..=MAX_LEGENDRE).contains(&self.legendre) {
            Err("Legendre terms in depth: 1 to MAX_LEGENDRE = 16")
        } else if self.harmonics > MAX_HARMONICS {
            Err("azimuth harmonics: at most MAX_HARMONICS = 8")
        } else if !(2..=MAX_THETA_NODES).contains(&self.theta_nodes) {
            Err("Θ nodes: 2 to MAX_THETA_NODES = 512")
        } else if self.cross > MAX_CROSS {
            Err("interaction degree A: at most MAX_CROSS = 6")
        } else {
            Ok(())
        }
    }

    /// Parameters for `nm` view-cosine and `nl` sun-cosine nodes.
    pub fn n_params(&self, nm: usize, nl: usize) -> usize {
        let gamma = if self.pairs { nm * nl } else { nm };
        let pairs = if self.pairs { 2 * nm * nl } else { 0 };
        self.legendre * (nm + nl)
            + gamma
            + pairs
            + 2 * self.theta_nodes
            + self.harmonics * (nm + nl)
            + self.n_cross(nl)
    }

    /// Parameters of the interaction terms: γ_L(μ_L) on the sun-cosine nodes and
    /// 3 depth terms × 2 hemispheres × A × A polynomial products.
    fn n_cross(&self, nl: usize) -> usize {
        let a = self.cross.min(MAX_CROSS);
        if a == 0 {
            0
        } else {
            nl + CROSS_DEPTH * 2 * a * a
        }
    }

    /// Calls `f(column, value)` for every feature of `c` that is not zero by construction;
    /// false (and no call) where F₁ is not a number (a point outside the slab).
    pub fn for_each_feature<F: Real>(
        &self,
        c: &Cell<F>,
        nm: usize,
        nl: usize,
        mut f: impl FnMut(usize, F),
    ) -> bool {
        let p = legendre(F::of(2.0) * c.u - F::of(1.0), self.depth_terms());
        self.for_each_feature_in_depth(c, nm, nl, |col, v, j| f(col, v * p[j]))
    }

    /// Legendre terms in x = 2u − 1 the features use: every feature is a depth-free value times
    /// one of P_0(x) … P_{n−1}(x) (the J depth terms, the Θ table's slope, the interaction's 3).
    pub fn depth_terms(&self) -> usize {
        let cross = if self.cross > 0 { CROSS_DEPTH } else { 0 };
        self.legendre.max(2).max(cross).min(MAX_LEGENDRE)
    }

    /// As [`Self::for_each_feature`], the feature split as `f(column, value, j)`: the feature
    /// is value · P_j(2u − 1), value independent of u. The runtime evaluates the depth
    /// polynomials of each group at its own (held) depth with one set of features.
    pub fn for_each_feature_in_depth<F: Real>(
        &self,
        c: &Cell<F>,
        nm: usize,
        nl: usize,
        mut f: impl FnMut(usize, F, usize),
    ) -> bool {
        let four_pi = F::of(4.0 * core::f64::consts::PI);
        // An isotropic phase function's value, as HG with g = 0 gives it at any angle.
        let iso = HenyeyGreenstein::new(F::of(0.0)).pdf_cosine(Cosine::from_mu(F::of(1.0)));
        let f1 = four_pi * beam_scattered_once(iso, &c.at);
        if !(f1 >= F::of(0.0)) {
            return false;
        }
        // Deep in thick slabs F₁ ~ e^{−d/μ_L} underflows f32 (e^{−107} at d = 80, μ_L = 0.75)
        // where multiple scattering is at its strongest: the floor, as f64 gives it.
        let ln_f1 = if f1 > F::of(0.0) && f1.ln() > F::of(LN_F1_FLOOR) {
            f1.ln()
        } else {
            F::of(LN_F1_FLOOR)
        };
        let mut col = 0;
        for j in 0..self.legendre.min(MAX_LEGENDRE) {
            on_nodes(c, nm, col, F::of(1.0), &mut |col, v| f(col, v, j));
            col += nm + nl;
        }
        if self.pairs {
            let each_pair = |g: &mut dyn FnMut(usize, F)| {
                c.v.each(|m, wm| c.l.each(|il, wl| g(m * nl + il, wm * wl)));
            };
            each_pair(&mut |p, w| f(col + p, w * ln_f1, 0));
            col += nm * nl;
            each_pair(&mut |p, w| {
                f(col + 2 * p, w, 0);
                f(col + 2 * p + 1, w, 1);
            });
            col += 2 * nm * nl;
        } else {
            c.v.each(|m, w| f(col + m, w * ln_f1, 0));
            col += nm;
        }
        theta_hats(self.theta_nodes, c, F::of(1.0), col, &mut f);
        col += 2 * self.theta_nodes;
        let one = F::of(1.0);
        let (mu_v, mu_l) = (c.at.mu_v, c.at.mu_l);
        let s = ((one - mu_v * mu_v) * (one - mu_l * mu_l))
            .clamp_to(F::of(0.0), one)
            .sqrt();
        let mut s_k = one;
        // cos kψ by Chebyshev's recurrence cos (k+1)ψ = 2 cos ψ cos kψ − cos (k−1)ψ: one
        // cosine per point, not one per harmonic.
        let (_, cos_1) = c.at.psi_v.sin_cos();
        let (mut cos_prev, mut cos_k) = (cos_1, one);
        for k in 1..=self.harmonics {
            s_k = s_k * s;
            (cos_prev, cos_k) = (
                cos_k,
                if k == 1 {
                    cos_1
                } else {
                    F::of(2.0) * cos_1 * cos_k - cos_prev
                },
            );
            on_nodes(c, nm, col, s_k * cos_k, &mut |col, v| f(col, v, 0));
            col += nm + nl;
        }
        let a = self.cross.min(MAX_CROSS);
        if a > 0 {
            // γ_L(μ_L) ln F₁, and Σ e_jab P_j(x) P_a(2|μ_V| − 1) P_b(2μ_L − 1) per hemisphere:
            // the view × sun interaction the additive terms lack, smooth in both cosines so
            // that it interpolates (per-pair terms do not).
            c.l.each(|il, w| f(col + il, w * ln_f1, 0));
            col += nl;
            let two = F::of(2.0);
            let pv = legendre(two * mu_v.abs() - one, a);
            let pl = legendre(two * mu_l - one, a);
            let hemi = if mu_v > F::of(0.0) { 0 } else { a * a };
            for j in 0..CROSS_DEPTH {
                let base = col + j * 2 * a * a + hemi;
                for (ia, &va) in pv[..a].iter().enumerate() {
                    for (ib, &vb) in pl[..a].iter().enumerate() {
                        f(base + ia * a + ib, va * vb, j);
                    }
                }
            }
        }
        true
    }

    /// ln T at `c` with parameters `coef(column)`, or None where the form says T = 0.
    pub fn ln_t<F: Real>(
        &self,
        c: &Cell<F>,
        nm: usize,
        nl: usize,
        coef: impl Fn(usize) -> F,
    ) -> Option<F> {
        let offset = ln_boundary(&c.at)?;
        let mut sum = offset;
        self.for_each_feature(c, nm, nl, |col, v| sum = sum + v * coef(col))
            .then_some(sum)
    }
}

impl LogAdditive {
    /// ln T at `c` with parameters `coef(column)` as the runtime reads it around the group's
    /// fitted depths `range`: the depth polynomials by [`depth_polynomial`], T scaled by the
    /// range's share; None where the form says T = 0.
    pub fn ln_t_in_range<F: Real>(
        &self,
        c: &Cell<F>,
        (nm, nl): (usize, usize),
        coef: impl Fn(usize) -> F,
        range: &FittedDepths<F>,
    ) -> Option<F> {
        let offset = ln_boundary(&c.at)?;
        let mut d = [F::of(0.0); MAX_LEGENDRE];
        let ok = self.for_each_feature_in_depth(c, nm, nl, |col, v, j| d[j] = d[j] + v * coef(col));
        let depth = depth_polynomial(&d, self.depth_terms(), c.u, c.at.thickness, range);
        ok.then(|| offset + depth + range.share.ln())
    }
}

/// ln B at `c`, or None where the form says T = 0 (no medium behind the viewpoint): the
/// boundary factor depends on the geometry only, not on the form's sizes.
pub fn ln_boundary<F: Real>(at: &SlabPoint<F>) -> Option<F> {
    // The horizon (either sign of zero): the medium behind is unbounded, B = 1, at the faces
    // too (the limit from inside).
    if at.mu_v == F::of(0.0) {
        return Some(F::of(0.0));
    }
    let path = if at.mu_v > F::of(0.0) {
        at.thickness - at.depth
    } else {
        at.depth
    };
    let b = -exp_m1(-path / at.mu_v.abs());
    (b > F::of(0.0)).then(|| b.ln())
}

/// The depths a group's fit had cells at, around a point, and how much of the point's
/// parameter weight lies on nodes that had any.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct FittedDepths<F> {
    /// Shallowest fitted stretched depth.
    pub lo: F,
    /// Deepest.
    pub hi: F,
    /// The share of the weight on nodes with fitted cells, in (0, 1]: T is scaled by it, so
    /// that a group fades continuously toward nodes where the tables resolve none of its light
    /// (a high order in a thin slab) instead of jumping to 0 there.
    pub share: F,
}

impl<F: Real> FittedDepths<F> {
    /// From (weight, lo, hi) of the parameter nodes a point draws on (lo > hi: a node without
    /// fitted cells): the ranges of the nodes with cells averaged by their weights. None where
    /// no node has fitted cells: the tables resolve no light of the group there.
    pub fn of(ranges: impl IntoIterator<Item = (F, F, F)>) -> Option<Self> {
        let zero = F::of(0.0);
        let (mut all, mut w, mut lo, mut hi) = (zero, zero, zero, zero);
        for (wk, a, b) in ranges {
            all = all + wk;
            if a <= b && wk > zero {
                w = w + wk;
                lo = lo + wk * a;
                hi = hi + wk * b;
            }
        }
        (w > zero).then(|| Self {
            lo: lo / w,
            hi: hi / w,
            share: w / all,
        })
    }

    /// `u` held inside the fitted depths.
    pub fn held(&self, u: F) -> F {
        if u < self.lo {
            self.lo
        } else if u > self.hi {
            self.hi
        } else {
            u
        }
    }
}

/// The stretch of nephele slab's default depth planes: d/t = (e^{βu} − 1)/(e^β − 1) at
/// stretched depth u ∈ [0, 1], β = `STRETCH_SCALE` · t^`STRETCH_EXPONENT` (t in mfp), which
/// crowds the planes toward the lit face of thick slabs ([`stretched_u`] is its inverse,
/// [`depth_fraction`] the map itself). x = 2u − 1 is the form's depth variable.
pub const STRETCH_SCALE: f64 = 0.3;
/// See [`STRETCH_SCALE`].
pub const STRETCH_EXPONENT: f64 = 0.65;

/// The stretched depth u ∈ [0, 1] of depth d in a slab of thickness t (both in mfp): the
/// inverse of [`depth_fraction`].
pub fn stretched_u(d: f32, t: f32) -> f32 {
    Stretch::of(t).u_of(d)
}

/// d/t at stretched depth u in a slab of thickness t (mfp): (e^{βu} − 1)/(e^β − 1).
pub fn depth_fraction<F: Real>(u: F, t: F) -> F {
    Stretch::of(t).fraction(false, u)
}

/// 1 − d/t at stretched depth u in a slab of thickness t (mfp), the distance to the far face
/// over t: e^{βu} (e^{β(1−u)} − 1)/(e^β − 1), without the cancellation of 1 − [`depth_fraction`]
/// near the far face (in f32 a depth 1 mfp from the face of a 100 mfp slab would carry 1e-5).
pub fn far_fraction<F: Real>(u: F, t: F) -> F {
    Stretch::of(t).fraction(true, u)
}

/// The stretched-depth map of one slab: its thickness t (mfp) and β = `STRETCH_SCALE` ·
/// t^`STRETCH_EXPONENT`, computed once for every depth a caller maps (a point's own, and the
/// depths at which its groups continue their polynomials toward a face).
#[derive(Clone, Copy, Debug)]
pub struct Stretch<F> {
    t: F,
    beta: F,
}

impl<F: Real> Stretch<F> {
    /// The map of a slab `t` mfp thick.
    pub fn of(t: F) -> Self {
        Self::with_ln_t(t, t.ln())
    }

    /// [`Self::of`] given `ln_t` = ln t, which a caller often has already.
    pub fn with_ln_t(t: F, ln_t: F) -> Self {
        Self {
            t,
            beta: F::of(STRETCH_SCALE) * (F::of(STRETCH_EXPONENT) * ln_t).exp(),
        }
    }

    /// The stretched depth u ∈ [0, 1] of depth `d` (mfp; [`stretched_u`], the same steps).
    pub fn u_of(&self, d: F) -> F {
        if self.beta < F::of(1e-6) {
            return d / self.t;
        }
        let one = F::of(1.0);
        ((one + (self.beta.exp() - one) * d / self.t).ln() / self.beta).clamp_to(F::of(0.0), one)
    }

    /// The distance to the far face over t ([`far_fraction`], with `far`) or d/t
    /// ([`depth_fraction`]) at stretched depth `u`.
    pub fn fraction(&self, far: bool, u: F) -> F {
        self.fraction_with(far, u, self.exp_m1_beta())
    }

    /// e^β − 1 (unused below the β at which the map is linear).
    fn exp_m1_beta(&self) -> F {
        if self.beta < F::of(1e-6) {
            F::of(0.0)
        } else {
            exp_m1(self.beta)
        }
    }

    /// [`Self::fraction`] given `em1` = e^β − 1 (computed once by a caller that maps several
    /// depths).
    #[inline]
    fn fraction_with(&self, far: bool, u: F, em1: F) -> F {
        let one = F::of(1.0);
        if self.beta < F::of(1e-6) {
            if far {
                one - u
            } else {
                u
            }
        } else if far {
            (self.beta * u).exp() * exp_m1(self.beta * (one - u)) / em1
        } else {
            exp_m1(self.beta * u) / em1
        }
    }
}

/// A point's distances (mfp) to the faces of its slab, for the depth continuations of all its
/// groups ([`depth_polynomial_in`]): e^β − 1 and the point's own distance to each face are
/// computed at most once, however many groups continue toward that face; each distance is t
/// × [`Stretch::fraction`].
pub(crate) struct FaceDistances<F> {
    stretch: Stretch<F>,
    /// The point's stretched depth.
    u: F,
    em1: Option<F>,
    /// The point's distance to the lit face and to the far face, once asked for.
    own: [Option<F>; 2],
}

impl<F: Real> FaceDistances<F> {
    /// For the point at stretched depth `u` of the slab `stretch` maps.
    pub(crate) fn new(stretch: Stretch<F>, u: F) -> Self {
        Self {
            stretch,
            u,
            em1: None,
            own: [None; 2],
        }
    }

    /// The distances to the far face (`far`) or to the lit face from stretched depths `a`, `b`
    /// and from the point itself.
    pub(crate) fn distances(&mut self, far: bool, a: F, b: F) -> [F; 3] {
        let s = self.stretch;
        let em1 = *self.em1.get_or_insert_with(|| s.exp_m1_beta());
        let at = |u: F| s.t * s.fraction_with(far, u, em1);
        let own = *self.own[usize::from(far)].get_or_insert_with(|| at(self.u));
        [at(a), at(b), own]
    }
}

/// The stretch of depth (in u) over which [`depth_polynomial`] measures the slope at the end of
/// the fitted depths: one plane spacing of the default grid (16 planes).
pub const EDGE_STEP: f64 = 1.0 / 15.0;

/// Σ_{j<n} d_j P_j(2u − 1), the depth part of ln T (ln T/B less the share) at stretched depth
/// `u` of a slab `thickness` mfp thick, read as the tables' information allows. Inside the
/// fitted depths `range`: the polynomial itself. Beyond them, where ln T falls outward over the
/// last [`EDGE_STEP`] inside, T/B is continued from the range's end toward the face ahead, by
/// [`continued_toward_face`]; where it rises, it is held. So T never exceeds its value at the
/// fitted edge, while B and F₁, which follow the point itself, take T to 0 where the light
/// goes (a face behind the viewpoint) — a polynomial's swing beyond its data never does.
pub fn depth_polynomial<F: Real>(
    d: &[F; MAX_LEGENDRE],
    n: usize,
    u: F,
    thickness: F,
    range: &FittedDepths<F>,
) -> F {
    depth_polynomial_in(d, n, u, &mut FaceDistances::new(Stretch::of(thickness), u), range)
}

/// [`depth_polynomial`] at the point whose distances to its slab's faces `faces` gives (asked
/// for only where the polynomial is continued toward a face).
pub(crate) fn depth_polynomial_in<F: Real>(
    d: &[F; MAX_LEGENDRE],
    n: usize,
    u: F,
    faces: &mut FaceDistances<F>,
    range: &FittedDepths<F>,
) -> F {
    let at = |u: F| {
        let p = Legendre::new(F::of(2.0) * u - F::of(1.0));
        d.iter()
            .take(n)
            .zip(p)
            .fold(F::of(0.0), |s, (a, b)| s + *a * b)
    };
    let edge = range.held(u);
    let value = at(edge);
    if edge == u {
        return value;
    }
    let step = F::of(EDGE_STEP);
    // One step back inside (the range itself if narrower), and the outward rate of change.
    let far = u > range.hi;
    let inside = range.held(if far {
        range.hi - step
    } else {
        range.lo + step
    });
    let inner = at(inside);
    if !((edge - inside).abs() > F::of(0.0)) || !(inner > value) {
        return value;
    }
    // Distances (mfp) to the face ahead: the far face d = t beyond `hi`, the lit face d = 0
    // below `lo`.
    let [h_inside, h_edge, h] = faces.distances(far, inside, edge);
    value + continued_toward_face(inner - value, (h_inside, h_edge, h))
}

/// ln of T/B at distance `h` from a face relative to its value at the fitted edge (distance
/// `h_edge`), given `rise` = ln(T/B) one step further inside (distance `h_inside`) less the
/// edge's, > 0. Two shapes agree at both points:
/// - *exponential* in depth (ln T linear in d; the first shape, and linear in
///   the stretched depth u instead): right where a group's light fades away from its fitted
///   cells (low orders deep in a thick slab);
/// - *linear* in depth: the diffusion regime near a face, where the source function falls
///   linearly to the extrapolated boundary a fraction of a transport length beyond the face,
///   and T/B with it. The exponential overshoots there: 2–9× above DISORT within 1–2 mfp of the
///   far face of a 32–64 mfp slab looking at it (docs/compress.md, "Near the far face").
///
/// The line is taken, floored by s × the exponential with s = the line's zero crossing as a
/// share of the edge's distance, clamped to [0, 1]: a line that stays positive up to the face
/// (s = 0, diffusion) is read as is; one that would reach 0 at the edge (s = 1, fast decay)
/// gives the exponential; in between the two blend continuously, so T never jumps between
/// neighbouring points, stays > 0 away from the face, and never exceeds the exponential. The
/// blend is not monotone in `rise` (a slightly steeper fall at the edge can end a little higher
/// near the face, between the two shapes): two points cannot tell the shapes apart better.
fn continued_toward_face<F: Real>(rise: F, (h_inside, h_edge, h): (F, F, F)) -> F {
    let zero = F::of(0.0);
    let one = F::of(1.0);
    let run = h_inside - h_edge;
    if !(run > zero) || !(h_edge > zero) {
        return zero; // no room: held
    }
    let exponential = -rise * (h_edge - h) / run;
    let up = exp_m1(rise); // T_inside/T_edge − 1 > 0
    let line = one + up * (h - h_edge) / run;
    let crossing = h_edge - run / up;
    let s = clamp01(crossing / h_edge);
    let floor = s * exponential.exp();
    let rel = if line > floor { line } else { floor };
    if rel > zero {
        rel.ln()
    } else {
        exponential
    }
}

/// x clamped to [0, 1] (NaN to 0).
fn clamp01<F: Real>(x: F) -> F {
    if x > F::of(1.0) {
        F::of(1.0)
    } else if x > F::of(0.0) {
        x
    } else {
        F::of(0.0)
    }
}

/// P_0(x) … P_{n−1}(x) (Legendre polynomials; n ≤ [`MAX_LEGENDRE`], the rest 0).
pub fn legendre<F: Real>(x: F, n: usize) -> [F; MAX_LEGENDRE] {
    let mut p = [F::of(0.0); MAX_LEGENDRE];
    for (slot, v) in p.iter_mut().zip(Legendre::new(x)).take(n) {
        *slot = v;
    }
    p
}

/// s ∈ [−1, 1], the place of ln t in a group's span `(a, b)` of ln t (held at ±1 outside it;
/// 0 for an empty span): the argument of the Legendre polynomials in ln t of the parameters.
pub fn ln_t_position<F: Real>((a, b): (F, F), ln_t: F) -> F {
    if b > a {
        (F::of(2.0) * (ln_t - a) / (b - a) - F::of(1.0)).clamp_to(F::of(-1.0), F::of(1.0))
    } else {
        F::of(0.0)
    }
}

/// Θ (radians) at `at`, from 1 − cos Θ as 2 asin √((1 − cos Θ)/2): exact near the forward
/// peak, where the hats are dense.
fn scattering_angle<F: Real>(at: &SlabPoint<F>) -> F {
    let cos = scattering_cosine(at);
    let half = (F::of(0.5) * cos.one_minus_mu).sqrt();
    F::of(2.0) * (if half > F::of(1.0) { F::of(1.0) } else { half }).asin()
}

/// `f(col + node, weight · val)` for the μ_V nodes of `c` (columns col … col + nm − 1) and the
/// μ_L nodes (columns col + nm …): a parameter a(μ_V) + b(μ_L) read between its nodes.
#[inline(always)]
pub(crate) fn on_nodes<F: Real>(
    c: &Cell<F>,
    nm: usize,
    col: usize,
    val: F,
    f: &mut impl FnMut(usize, F),
) {
    c.v.each(|m, w| f(col + m, w * val));
    c.l.each(|il, w| f(col + nm + il, w * val));
}

/// The Θ-table features `val · h_i(Θ) · (P_0, P_1)(2u − 1)` at columns col + 2i, col + 2i + 1,
/// as `f(column, val · h_i, j)` with j the Legendre degree in depth (0, 1): h_i the hat
/// functions of the nodes Θ_i = π (i/(n − 1))², n = `nodes` (dense at the forward peak).
#[inline(always)]
pub fn theta_hats<F: Real>(
    nodes: usize,
    c: &Cell<F>,
    val: F,
    col: usize,
    f: &mut impl FnMut(usize, F, usize),
) {
    let theta = c.theta;
    let n = nodes.max(2);
    let top = (n - 1) as f64;
    let node = |i: usize| {
        let r = i as f64 / top;
        F::of(core::f64::consts::PI * r * r)
    };
    // The first node at or beyond Θ (from 1, at most n − 1): found from Θ's square root, then
    // settled by the nodes themselves, so that rounding cannot move it.
    let guess = Math::sqrt((theta.f64() / core::f64::consts::PI).max(0.0)) * top;
    let mut i = (guess as usize).clamp(1, n - 1);
    while i > 1 && node(i - 1) >= theta {
        i -= 1;
    }
    while i < n - 1 && node(i) < theta {
        i += 1;
    }
    let (a, b) = (node(i - 1), node(i));
    let w = ((theta - a) / (b - a)).clamp_to(F::of(0.0), F::of(1.0));
    // Degree by degree: a sum over the features of one degree takes them as one run.
    for j in 0..2 {
        for (k, h) in [(i - 1, F::of(1.0) - w), (i, w)] {
            f(col + 2 * k + j, val * h, j);
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn cell<F: Real>(mu_l: f64, mu_v: f64, psi: f64, u: f64, t: f64) -> Cell<F> {
        let lnodes = [0.25, 0.5, 0.75, 1.0].map(F::of);
        let vnodes = [-0.75, -0.25, 0.25, 0.75].map(F::of);
        Cell::new(
            SlabPoint {
                depth: F::of(u * t),
                thickness: F::of(t),
                mu_v: F::of(mu_v),
                psi_v: F::of(psi),
                mu_l: F::of(mu_l),
            },
            Lerp::between(&lnodes, F::of(mu_l)),
            Lerp::between(&vnodes, F::of(mu_v)),
            F::of(u),
        )
    }

    #[test]
    fn f32_follows_f64_and_lerp_finds_its_nodes() {
        for pairs in [false, true] {
            let form = LogAdditive {
                pairs,
                ..LogAdditive::default()
            };
            let n = form.n_params(4, 4);
            let coef = |i: usize| 0.2 * ((i * 7919 % 103) as f64 / 103.0 - 0.5);
            let mut worst = 0.0f64;
            for &(mu_l, mu_v, psi, u, t) in &[
                (0.3, 0.6, 0.2, 0.3, 4.0),
                (0.8, -0.4, 2.5, 0.7, 16.0),
                (1.0, -0.9, 0.0, 0.95, 1.0),
                (0.55, 0.1, 1.3, 0.1, 64.0),
            ] {
                let a = form
                    .ln_t(&cell::<f64>(mu_l, mu_v, psi, u, t), 4, 4, coef)
                    .unwrap();
                let b = form
                    .ln_t(&cell::<f32>(mu_l, mu_v, psi, u, t), 4, 4, |i| {
                        coef(i) as f32
                    })
                    .unwrap();
                worst = worst.max((b as f64 - a).abs());
                let mut cols = 0;
                form.for_each_feature(&cell::<f64>(mu_l, mu_v, psi, u, t), 4, 4, |c, _| {
                    assert!(c < n);
                    cols += 1;
                });
                assert!(cols > 0);
            }
            assert!(worst < 2e-5, "pairs {pairs}: |Δ ln T| {worst}");
        }
        let l = Lerp::between(&[0.0, 1.0, 3.0], 2.0);
        assert_eq!((l.lo, l.hi), (1, 2));
        assert!((l.w - 0.5f64).abs() < 1e-15);
        assert_eq!(Lerp::between(&[0.0, 1.0], 5.0), Lerp::at(1));
        assert_eq!(Lerp::between(&[0.0, 1.0], -5.0), Lerp::at(0));
    }

    /// Inside the fitted depths the polynomial itself; beyond them it falls on where it falls
    /// outward and is held where it would rise; nodes without cells do not count and none at
    /// all is None.
    #[test]
    fn depth_polynomial_reads_within_the_fitted_depths() {
        // ln T part = 2 P_1(x) = 2x: rising with depth.
        let mut d = [0.0f64; MAX_LEGENDRE];
        d[1] = 2.0;
        let range = FittedDepths::of([(1.0, 0.25, 0.75)]).unwrap();
        let x = |u: f64| 2.0 * u - 1.0;
        let t = 16.0;
        assert!((depth_polynomial(&d, 2, 0.5, t, &range) - 2.0 * x(0.5)).abs() < 1e-15);
        // Deeper than the range: rising outward, held at the edge.
        assert!((depth_polynomial(&d, 2, 0.9, t, &range) - 2.0 * x(0.75)).abs() < 1e-15);
        // Toward the lit face: falling outward, below the edge, never above the exponential
        // continuation with the edge's slope (4 per unit u there, at most 4 · 0.2 down at
        // u = 0.05), finite at the face itself.
        let edge = 2.0 * x(0.25);
        let v = depth_polynomial(&d, 2, 0.05, t, &range);
        assert!(v < edge && v.is_finite(), "{v}");
        let h = |u: f64| t * depth_fraction(u, t);
        let exponential =
            edge - 4.0 / 15.0 * (h(0.25) - h(0.05)) / (h(0.25 + 1.0 / 15.0) - h(0.25));
        assert!(v <= exponential + 1e-12, "{v} vs {exponential}");
        assert!(depth_polynomial(&d, 2, 0.0, t, &range).is_finite());
        // A narrow range (one depth) holds.
        let one = FittedDepths::of([(1.0, 0.5, 0.5)]).unwrap();
        assert!((depth_polynomial(&d, 2, 0.9, t, &one) - 0.0).abs() < 1e-15);
        assert_eq!(FittedDepths::of([(1.0, 0.6, 0.2)]), None);
        assert_eq!(FittedDepths::<f64>::of([]), None);
        let r = FittedDepths::of([(0.25, 0.0, 1.0), (0.75, 0.4, 0.8), (0.5, 0.9, 0.1)]).unwrap();
        assert!(
            (r.lo - 0.3).abs() < 1e-15 && (r.hi - 0.85).abs() < 1e-15,
            "{r:?}"
        );
        assert!((r.share - 2.0 / 3.0).abs() < 1e-15);
        assert_eq!(r.held(2.0), r.hi);
    }

    /// The continuation toward a face is exact on the diffusion regime's profile, T/B linear in
    /// the distance h to the face with the extrapolated boundary z₀ beyond it, and follows a
    /// fast exponential fall within 5 %; it never exceeds the exponential through the same two
    /// points and T is continuous where the blend changes.
    #[test]
    fn continuation_toward_a_face_follows_diffusion_and_fast_decay() {
        let (h_inside, h_edge) = (29.0, 17.0);
        for z0 in [0.5, 5.0, 20.0] {
            let rise = ((h_inside + z0) / (h_edge + z0)).ln();
            for h in [0.0, 0.5, 1.3, 8.0, 16.0] {
                let got = continued_toward_face(rise, (h_inside, h_edge, h));
                let want = ((h + z0) / (h_edge + z0)).ln();
                assert!(
                    (got - want).abs() < 1e-12,
                    "z0 {z0}, h {h}: {got} vs {want}"
                );
            }
        }
        for k in [0.3, 1.0] {
            // T/B ∝ e^{k h}: falls by e^{k · 12} over one step.
            let rise = k * (h_inside - h_edge);
            for h in [1.0, 5.0, 12.0] {
                let got = continued_toward_face(rise, (h_inside, h_edge, h));
                let want = -k * (h_edge - h);
                assert!(
                    got <= want + 1e-12 && got > want + (0.95f64).ln(),
                    "k {k}, h {h}"
                );
            }
        }
        let mut last = None;
        for i in 0..=4000 {
            let rise = 0.001 * i as f64;
            let v = continued_toward_face(rise, (h_inside, h_edge, 4.0));
            assert!(v <= 0.0 && v >= -rise * (h_edge - 4.0) / (h_inside - h_edge) - 40.0);
            if let Some(prev) = last {
                // Continuous in T (relative to the edge's): steps of 0.001 in the rise.
                let (a, b) = (f64::exp(prev), v.exp());
                assert!((a - b).abs() < 0.01, "jump at rise {rise}: {a} → {b}");
            }
            last = Some(v);
        }
    }

    #[test]
    fn no_medium_behind_the_viewpoint_is_zero() {
        let form = LogAdditive::default();
        // Light going up at the far face, going down at the lit face.
        let mut c = cell::<f64>(0.5, 0.5, 0.0, 1.0, 4.0);
        assert!(form.ln_t(&c, 4, 4, |_| 0.0).is_none());
        c = cell::<f64>(0.5, -0.5, 0.0, 0.0, 4.0);
        assert!(form.ln_t(&c, 4, 4, |_| 0.0).is_none());
    }
}
