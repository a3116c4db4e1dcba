//! The compressed transport tables as renderers use them: loaded in place from the bytes of a
//! `.ntt` container ([`crate::container`], docs/format.md), checked once, then evaluated at any
//! (d, t, μ_V, ψ_V, μ_L) without allocation: T per order group of orders ≥ 2 from the
//! log-additive form ([`super::log_additive`]) with its parameters read between the grid's
//! nodes, and order 1 in closed form ([`super::single`]) from the stored phase function.
//!
//! The arrays, their shapes and limits, and their loading and checking: [`super::format`].
//! Files without the collector arrays load too; their [`Transport`] has c = 0, σ = 0.

use super::collector::{Statistic, MAX_COLLECTOR_HARMONICS, MAX_COLLECTOR_LEGENDRE};
use super::format::{unpack_u_range, CollectorPart, Strides, EMPTY_RANGE, MAX_Q};
use super::geometry::SlabPoint;
use super::halo::{Halo, HaloAt};
use super::log_additive::{
    depth_polynomial_in, legendre, FaceDistances, ln_boundary, ln_t_position, Cell, FittedDepths,
    LogAdditive, Stretch, MAX_CROSS, MAX_HARMONICS, MAX_LEGENDRE,
};
use super::single::{single_scattering, PhaseValue};
use super::thick::{continued, Continued};
use crate::container::ArrayView;
use crate::phase::{angle, phase_between, Cosine};
use crate::real::{Math, Real};
use super::domain::Domain;
use super::lanes::{
    bracket, lane_sums, legendre_lanes, lerp, Row, Sums, COL, C_SUMS, LANES, ONE_C_SUMS, ONE_T_SUMS,
    T_SUMS,
};
use core::mem::MaybeUninit;

/// A group's T never exceeds this factor times the largest value its fitted cells hold at the
/// thickness and sun-cosine nodes a point draws on: where a form's polynomials are thin on data
/// (a high order in a thin slab) their swings stay within what the tables saw.
pub const CEILING_FACTOR: f64 = 1.5;
/// Room for the features of one point: J ≤ 16 Legendre terms on two μ_V and two μ_L nodes,
/// γ and the pair terms on four (μ_V, μ_L) pairs, two Θ hats, K ≤ 8 harmonics, γ_L on two
/// μ_L nodes and 3 A² interaction products.
const MAX_FEATURES: usize = 16 * 4 + 4 * 3 + 4 + MAX_HARMONICS * 4 + 2 + 3 * MAX_CROSS * MAX_CROSS;
/// Room for the features of a collector statistic at one point: at most two Θ blocks (4 values
/// each) and K + 2 depth blocks of J values on two μ_V and two μ_L nodes.
const MAX_C_FEATURES: usize = 8 + (MAX_COLLECTOR_HARMONICS + 2) * MAX_COLLECTOR_LEGENDRE * 4;

/// Transport of one order group at a point: T = L/E⊥ (sr⁻¹), the collector c = (c_x, c_z) and
/// its spread σ (mfp; docs/conventions.md).
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct Transport {
    /// T (sr⁻¹).
    pub t: f32,
    /// c_x (mfp), across the sun's horizontal travel.
    pub c_x: f32,
    /// c_z (mfp), along it.
    pub c_z: f32,
    /// σ (mfp).
    pub sigma: f32,
}

impl Transport {
    /// Every field NaN: the answer at a point that is not in the slab.
    pub const NAN: Self = Self {
        t: f32::NAN,
        c_x: f32::NAN,
        c_z: f32::NAN,
        sigma: f32::NAN,
    };
}

/// Validated compressed tables, borrowing the container's bytes.
#[derive(Clone, Copy, Debug)]
pub struct TransportTables<'a> {
    pub(super) collector: Option<CollectorPart<'a>>,
    pub(super) form: LogAdditive,
    pub(super) q: usize,
    pub(super) group_first: ArrayView<'a>,
    pub(super) mu_l: ArrayView<'a>,
    pub(super) mu_v: ArrayView<'a>,
    pub(super) thickness: ArrayView<'a>,
    pub(super) ln_t_range: ArrayView<'a>,
    pub(super) beta: ArrayView<'a>,
    pub(super) strides: Strides,
    pub(super) u_range: ArrayView<'a>,
    pub(super) t_ceiling: Option<ArrayView<'a>>,
    pub(super) phase_theta: ArrayView<'a>,
    pub(super) phase: ArrayView<'a>,
    pub(super) halo: Option<Halo<'a>>,
    /// g of the stored phase function ([`Self::mean_cosine`]), by which the tables continue
    /// past their thickest slab ([`super::thick`]).
    pub(super) mean_cosine: f32,
    /// The grid's ends ([`Self::domain`]), read once at load: every evaluation asks for the
    /// lowest sun.
    pub(super) domain: Domain,
}

impl<'a> TransportTables<'a> {
    /// Number of order groups (of orders ≥ 2).
    pub fn groups(&self) -> usize {
        self.group_first.len()
    }

    /// First scattering order of group `g`.
    pub fn group_first_order(&self, g: usize) -> Option<f32> {
        self.group_first.get(g)
    }

    /// T = L/E⊥ (sr⁻¹) of group `g` at `at`; 0 where the tables resolve nothing or `g` is not
    /// a group; NaN where `at` is not a point of the slab ([`SlabPoint::check`] says why).
    /// For several groups at one point, [`Self::transport_all`] shares the work.
    pub fn transport(&self, g: usize, at: &SlabPoint<f32>) -> f32 {
        let mut out = [0.0];
        if g < self.groups() {
            self.transport_run(at, (g, 1), &mut out);
        }
        out[0]
    }

    /// T of every group at `at` into `out[..groups()]` (the rest untouched; NaN where `at` is
    /// not a point of the slab): the features
    /// (geometry, single-scattering factor, scattering angle) are computed once and summed
    /// against every group's parameters together.
    pub fn transport_all(&self, at: &SlabPoint<f32>, out: &mut [f32]) {
        let groups = self.groups().min(out.len());
        let chunk = Sums::<T_SUMS>::capacity(self.q, self.form.depth_terms());
        for first in (0..groups).step_by(chunk) {
            let count = chunk.min(groups - first);
            self.transport_run(at, (first, count), &mut out[first..first + count]);
        }
    }

    /// T of the groups `first .. first + count` at `at` into `out[..count]` (the run fits one
    /// [`Sums`]).
    fn transport_run(&self, at: &SlabPoint<f32>, run: (usize, usize), out: &mut [f32]) {
        if at.check().is_err() {
            out.iter_mut().for_each(|v| *v = f32::NAN);
            return;
        }
        let (at, sun) = self.lowest_sun(at);
        if let Some(c) = self.continued(&at) {
            self.transport_run_within(&c.at, run, out);
            for (g, v) in (run.0..).zip(out.iter_mut()) {
                *v *= self.diffuse_scale(g, &c) * sun;
            }
            return;
        }
        self.transport_run_within(&at, run, out);
        out.iter_mut().for_each(|v| *v *= sun);
    }

    /// A point under a sun lower than the grid's lowest, μ_L < μ₀, read under μ₀ (every
    /// coordinate else the point's) with the factor μ_L/μ₀ on T: below the grid the tables hold
    /// T/μ_L, the radiance per unit irradiance on the lit face, which varies slowly toward the
    /// horizon while T itself falls like μ_L (docs/compress.md, "Outside the grid"). Within the
    /// grid, the point itself and 1.
    fn lowest_sun(&self, at: &SlabPoint<f32>) -> (SlabPoint<f32>, f32) {
        let lowest = self.domain().mu_l.0;
        if at.mu_l < lowest {
            (SlabPoint { mu_l: lowest, ..*at }, at.mu_l / lowest)
        } else {
            (*at, 1.0)
        }
    }

    /// [`Self::transport_run`] at a point within the grid's thicknesses.
    fn transport_run_within(&self, at: &SlabPoint<f32>, run: (usize, usize), out: &mut [f32]) {
        crate::simd::avx2_or!(self.transport_run_avx2(at, run, out), self.transport_run_any(at, run, out))
    }

    /// [`Self::transport_run`] compiled for AVX2: the groups' lanes ([`LANES`]) in one
    /// register. No FMA: the same answers, bit for bit.
    #[cfg(all(feature = "std", target_arch = "x86_64"))]
    #[target_feature(enable = "avx2")]
    fn transport_run_avx2(&self, at: &SlabPoint<f32>, run: (usize, usize), out: &mut [f32]) {
        self.transport_run_any(at, run, out);
    }

    /// [`Self::transport_run`] for the target's baseline.
    #[inline(always)]
    fn transport_run_any(
        &self,
        at: &SlabPoint<f32>,
        (first, count): (usize, usize),
        out: &mut [f32],
    ) {
        out.iter_mut().for_each(|v| *v = 0.0);
        let Some(pt) = self.point(at) else {
            return;
        };
        // One group (a search's read) in a lane of its own, with sums sized for one group: no
        // work for seven empty lanes, and no kilobytes of empty sums to set up.
        if count == 1 && self.q * self.form.depth_terms() <= ONE_T_SUMS {
            self.t_from::<ONE_T_SUMS, 1>(&pt, (first, count), out);
        } else if count == 1 {
            self.t_from::<T_SUMS, 1>(&pt, (first, count), out);
        } else {
            self.t_from::<T_SUMS, LANES>(&pt, (first, count), out);
        }
    }

    /// T of the groups `first .. first + count` at `pt` into `out`, through sums of `N` floats
    /// (the run fits them), `L` groups side by side.
    #[inline(always)]
    fn t_from<const N: usize, const L: usize>(
        &self,
        pt: &Point,
        (first, count): (usize, usize),
        out: &mut [f32],
    ) {
        let mut sums = Sums::<N>::new(
            self.strides,
            (first, count),
            self.q,
            self.form.depth_terms(),
        );
        if self.add_t_features(pt, &mut sums) {
            self.t_runs::<N, L>(pt, first, &sums, out);
        }
    }

    /// T of the groups `first ..` into `out`, `L` groups side by side at a time.
    #[inline(always)]
    fn t_runs<const N: usize, const L: usize>(
        &self,
        pt: &Point,
        first: usize,
        sums: &Sums<N>,
        out: &mut [f32],
    ) {
        for (g0, out) in (first..).step_by(L).zip(out.chunks_mut(L)) {
            let (t, _) = self.t_lanes::<N, L>(pt, (g0, out.len()), sums);
            out.copy_from_slice(&t[..out.len()]);
        }
    }

    /// T, c and σ of group `g` at `at`; c and σ are 0 where T is, or when the file holds no
    /// collector; all 0 when `g` is not a group; all NaN where `at` is not a point of the slab
    /// ([`SlabPoint::check`] says why).
    pub fn evaluate(&self, g: usize, at: &SlabPoint<f32>) -> Transport {
        let mut out = [Transport::default()];
        if g < self.groups() {
            self.evaluate_run(at, (g, 1), &mut out);
        }
        out[0]
    }

    /// T, c and σ of every group at `at` into `out[..groups()]` (the rest untouched); c and σ
    /// are 0 where T is, or when the file holds no collector; NaN where `at` is not a point of
    /// the slab. The features are computed once
    /// and summed against every group's parameters together.
    pub fn evaluate_all(&self, at: &SlabPoint<f32>, out: &mut [Transport]) {
        let groups = self.groups().min(out.len());
        let mut chunk = Sums::<T_SUMS>::capacity(self.q, self.form.depth_terms());
        if let Some(cp) = &self.collector {
            chunk = chunk.min(Sums::<C_SUMS>::capacity(cp.q, cp.form.depth_terms()));
        }
        for first in (0..groups).step_by(chunk) {
            let count = chunk.min(groups - first);
            self.evaluate_run(at, (first, count), &mut out[first..first + count]);
        }
    }

    /// T, c and σ of the groups `first .. first + count` at `at` into `out[..count]`.
    fn evaluate_run(&self, at: &SlabPoint<f32>, run: (usize, usize), out: &mut [Transport]) {
        if at.check().is_err() {
            out.fill(Transport::NAN);
            return;
        }
        let (at, sun) = self.lowest_sun(at);
        if let Some(c) = self.continued(&at) {
            self.evaluate_run_within(&c.at, run, out);
            for (g, v) in (run.0..).zip(out.iter_mut()) {
                v.t *= self.diffuse_scale(g, &c) * sun;
                v.sigma *= if g + 1 == self.groups() {
                    c.spread_diffuse
                } else {
                    c.spread
                };
            }
            return;
        }
        self.evaluate_run_within(&at, run, out);
        out.iter_mut().for_each(|v| v.t *= sun);
    }

    /// The point past the thickest slab continued into it ([`super::thick`]), or None within
    /// the grid's thicknesses (and outside the slab, where every group is 0 anyway).
    fn continued(&self, at: &SlabPoint<f32>) -> Option<Continued> {
        let t_max = self.thickness.get(self.thickness.len().max(1) - 1)?;
        at.in_slab()
            .then(|| continued(at, t_max, self.mean_cosine))
            .flatten()
    }

    /// How group `g`'s T scales past the thickest slab: the open-ended last group as the
    /// diffuse fluence, the others never above their value at the thickest slab.
    fn diffuse_scale(&self, g: usize, c: &Continued) -> f32 {
        if g + 1 == self.groups() {
            c.diffuse
        } else {
            c.diffuse.min(1.0)
        }
    }

    /// [`Self::evaluate_run`] at a point within the grid's thicknesses.
    fn evaluate_run_within(&self, at: &SlabPoint<f32>, run: (usize, usize), out: &mut [Transport]) {
        crate::simd::avx2_or!(self.evaluate_run_avx2(at, run, out), self.evaluate_run_any(at, run, out))
    }

    /// [`Self::evaluate_run`] compiled for AVX2 (as [`Self::transport_run_avx2`]).
    #[cfg(all(feature = "std", target_arch = "x86_64"))]
    #[target_feature(enable = "avx2")]
    fn evaluate_run_avx2(&self, at: &SlabPoint<f32>, run: (usize, usize), out: &mut [Transport]) {
        self.evaluate_run_any(at, run, out);
    }

    /// [`Self::evaluate_run`] for the target's baseline.
    #[inline(always)]
    fn evaluate_run_any(
        &self,
        at: &SlabPoint<f32>,
        (first, count): (usize, usize),
        out: &mut [Transport],
    ) {
        out.iter_mut().for_each(|v| *v = Transport::default());
        let Some(pt) = self.point(at) else {
            return;
        };
        // One group (a search's read) with sums sized for one group, as in transport_run_any.
        let one_c = self
            .collector
            .as_ref()
            .is_none_or(|cp| cp.q * cp.form.depth_terms() <= ONE_C_SUMS);
        if count == 1 && self.q * self.form.depth_terms() <= ONE_T_SUMS && one_c {
            self.evaluate_from::<ONE_T_SUMS, ONE_C_SUMS, 1>(&pt, (first, count), out);
        } else if count == 1 {
            self.evaluate_from::<T_SUMS, C_SUMS, 1>(&pt, (first, count), out);
        } else {
            self.evaluate_from::<T_SUMS, C_SUMS, LANES>(&pt, (first, count), out);
        }
    }

    /// T, c and σ of the groups `first .. first + count` at `pt` into `out`, through sums of
    /// `N` (T) and `M` (each collector statistic) floats, `L` groups side by side.
    #[inline(always)]
    fn evaluate_from<const N: usize, const M: usize, const L: usize>(
        &self,
        pt: &Point,
        (first, count): (usize, usize),
        out: &mut [Transport],
    ) {
        let mut sums = Sums::<N>::new(
            self.strides,
            (first, count),
            self.q,
            self.form.depth_terms(),
        );
        if !self.add_t_features(pt, &mut sums) {
            return;
        }
        // Filled in place: the sums are kilobytes, and moving them cost 6 % of a read.
        let mut c = [Sums::<M>::EMPTY; 4];
        if let Some(cp) = &self.collector {
            self.add_collector_features(cp, pt, (first, count), &mut c);
        }
        self.evaluate_runs::<N, M, L>(pt, first, (&sums, &c), out);
    }

    /// T, c and σ of the groups `first ..` into `out` from the features' sums, `L` groups side
    /// by side at a time.
    #[inline(always)]
    fn evaluate_runs<const N: usize, const M: usize, const L: usize>(
        &self,
        pt: &Point,
        first: usize,
        (sums, c): (&Sums<N>, &[Sums<M>; 4]),
        out: &mut [Transport],
    ) {
        for (g0, out) in (first..).step_by(L).zip(out.chunks_mut(L)) {
            let (t, ranges) = self.t_lanes::<N, L>(pt, (g0, out.len()), sums);
            match &self.collector {
                Some(cp) => self.collector_lanes::<M, L>(cp, pt, (&t, &ranges), (g0, c), out),
                None => out.iter_mut().zip(t).for_each(|(slot, t)| slot.t = t),
            }
        }
    }

    /// The thicknesses and sun cosines the tables cover ([`Domain`]).
    pub fn domain(&self) -> Domain {
        self.domain
    }

    /// The grid's ends, from the arrays.
    pub(super) fn read_domain(&self) -> Domain {
        let ends = |a: &ArrayView| {
            (
                a.get(0).unwrap_or(0.0),
                a.get(a.len().max(1) - 1).unwrap_or(0.0),
            )
        };
        Domain {
            thickness: ends(&self.thickness),
            mu_l: ends(&self.mu_l),
        }
    }

    /// g = ∮ μ p dΩ of the phase function the tables were made with (computed once, at load).
    pub fn mean_cosine(&self) -> f32 {
        self.mean_cosine
    }

    /// Whether the tables hold the collector (c, σ).
    pub fn has_collector(&self) -> bool {
        self.collector.is_some()
    }

    /// The phase function the tables were made with, p(μ) (sr⁻¹) at μ = cos θ: what a
    /// renderer checks its own against before it uses the tables.
    pub fn phase(&self, mu: f32) -> f32 {
        self.phase_at(Cosine::from_mu(mu.clamp(-1.0, 1.0)))
    }

    /// Order 1 (single scattering of the sun beam, sr⁻¹) at `at`, albedo 1; NaN where `at` is
    /// not a point of the slab ([`SlabPoint::check`] says why), as T is.
    pub fn order1(&self, at: &SlabPoint<f32>) -> f32 {
        if at.check().is_err() {
            return f32::NAN;
        }
        single_scattering(&StoredPhase(self), 1.0, at)
    }

    /// The geometry of T at a point, or None where every group is 0.
    fn point(&self, at: &SlabPoint<f32>) -> Option<Point> {
        let (t, d) = (at.thickness, at.depth);
        if !at.in_slab() {
            return None;
        }
        let ln_t = Math::ln(t);
        let stretch = Stretch::with_ln_t(t, ln_t);
        let (nt, nl, nm) = (self.thickness.len(), self.mu_l.len(), self.mu_v.len());
        let cell = Cell::new(
            *at,
            lerp(&self.mu_l, at.mu_l),
            lerp(&self.mu_v, at.mu_v),
            stretch.u_of(d),
        );
        let offset = ln_boundary(at)?;
        let near_t = lerp(&self.thickness, t);
        // The grid nodes the point draws on, the same for every group: (thickness, μ_L, μ_V)
        // corners for the fitted depths, (thickness, μ_L) for the ceiling.
        let mut corners = [(0usize, 0.0f32); 8];
        let mut ceiling = [0usize; 4];
        let (mut nc, mut nceil) = (0, 0);
        near_t.each(|it, wt| {
            cell.l.each(|il, wl| {
                ceiling[nceil] = it * nl + il;
                nceil += 1;
                cell.v.each(|m, wm| {
                    corners[nc] = (((it * nl) + il) * nm + m, wt * wl * wm);
                    nc += 1;
                })
            })
        });
        let nodes = (nt, nl);
        Some(Point {
            halo: self.halo.as_ref().and_then(|h| h.at(&cell, near_t, nodes)),
            cell,
            offset,
            ln_t,
            corners,
            n_corners: nc,
            ceiling,
            n_ceiling: nceil,
            per_group: (nt * nl * nm, nt * nl),
            p_u: legendre(2.0 * cell.u - 1.0, self.depth_terms()),
            stretch,
        })
    }

    /// The most depth terms T or the collector reads at a point.
    fn depth_terms(&self) -> usize {
        let c = self
            .collector
            .as_ref()
            .map_or(0, |cp| cp.form.depth_terms());
        self.form.depth_terms().max(c)
    }

    /// Adds T's features at `pt` to `sums`; false where the form says every group is 0.
    fn add_t_features<const N: usize>(&self, pt: &Point, sums: &mut Sums<N>) -> bool {
        let (nl, nm) = (self.mu_l.len(), self.mu_v.len());
        // The features are listed first and summed after, in one loop (faster than adding
        // each from inside the generator, measured: 1–3 % on 3 Dec, 10–40 % on 4 Dec against
        // a degree run held in registers as they come).
        let mut row = Row::<MAX_FEATURES>::new();
        let ok = self
            .form
            .for_each_feature_in_depth(&pt.cell, nm, nl, |col, v, j| row.push(col, v, j));
        sums.add_row(self.beta.bytes(), row.as_slice());
        ok
    }

    /// Adds the collector's features at `pt` for the groups `run`: ln σ, c_z's terms, c_z's
    /// ℓ/σ̂ terms (computed with σ̂ = 1, divided by the group's σ̂ after), c_x.
    fn add_collector_features<const M: usize>(
        &self,
        cp: &CollectorPart,
        pt: &Point,
        run: (usize, usize),
        out: &mut [Sums<M>; 4],
    ) {
        let (nl, nm) = (self.mu_l.len(), self.mu_v.len());
        let n = cp.form.depth_terms();
        let reach = cp.form.cz_reach_start(nm, nl);
        for (part, s) in [0, 1, 1, 2].into_iter().enumerate() {
            out[part].reset(cp.strides[s], run, cp.q, n);
        }
        let azimuth = cp.form.azimuth(pt.cell.at.psi_v);
        for (s, stat) in Statistic::ALL.iter().enumerate() {
            let mut row = Row::<MAX_C_FEATURES>::new();
            cp.form
                .for_each_feature_at(*stat, &pt.cell, &azimuth, 1.0, (nm, nl), |col, v, j| {
                    row.push(col, v, j)
                });
            let beta = cp.beta[s].bytes();
            let row = row.as_slice();
            match s {
                0 => out[0].add_row(beta, row),
                1 => {
                    // The ℓ/σ̂ terms are c_z's last blocks: a suffix of its row.
                    let split = row.partition_point(|&(key, _)| ((key & COL) as usize) < reach);
                    out[1].add_row(beta, &row[..split]);
                    out[2].add_row(beta, &row[split..]);
                }
                _ => out[3].add_row(beta, row),
            }
        }
    }

    /// T of the groups `g0 .. g0 + n` (n ≤ `L`: [`LANES`] for a run, 1 for one group) at `pt`
    /// from the features' `sums`, and each group's fitted depths there (None where no node the
    /// point draws on has fitted cells: T is 0). The groups are taken side by side, lane i for
    /// group g0 + i, with the arithmetic of one group (the same operations in the same order),
    /// so that the compiler can put the lanes in one vector register.
    #[inline(always)]
    fn t_lanes<const N: usize, const L: usize>(
        &self,
        pt: &Point,
        (g0, n): (usize, usize),
        sums: &Sums<N>,
    ) -> ([f32; L], [Option<FittedDepths<f32>>; L]) {
        let n = n.min(L);
        let ranges = self.fitted_lanes(pt, (g0, n));
        let mut d = [[0.0; L]; MAX_LEGENDRE];
        let mut rows = [const { MaybeUninit::uninit() }; MAX_Q];
        let lq = self.ln_t_lanes(pt.ln_t, (g0, n), self.q, &mut rows);
        sums.depth_lanes(g0, lq, &mut d);
        let top = self.ceiling_lanes::<L>(pt, (g0, n));
        let depth_terms = self.form.depth_terms();
        let u = pt.cell.u;
        let mut faces = FaceDistances::new(pt.stretch, u);
        // depth_polynomial's own sum at the point's depth, on its P_j computed once (from 0.0,
        // as depth_polynomial starts): for every lane at once in a run, where a lone group
        // reads it.
        let at_u = if L > 1 {
            lane_sums(&d, &pt.p_u, depth_terms, 0.0)
        } else {
            [0.0; L]
        };
        let mut t = [0.0f32; L];
        for i in 0..n {
            let Some(range) = &ranges[i] else {
                continue;
            };
            let depth = if range.held(u) == u {
                if L > 1 {
                    at_u[i]
                } else {
                    lane_sums(&d, &pt.p_u, depth_terms, 0.0)[i]
                }
            } else {
                let d_i: [f32; MAX_LEGENDRE] = core::array::from_fn(|j| d[j][i]);
                depth_polynomial_in(&d_i, depth_terms, u, &mut faces, range)
            };
            let v = range.share * Math::exp(pt.offset + depth);
            t[i] = match top[i] {
                Some(top) if v > top => top,
                _ => v,
            };
            if let (Some(halo), Some(at)) = (&self.halo, &pt.halo) {
                t[i] *= at.factor(halo, g0 + i);
            }
        }
        (t, ranges)
    }

    /// L_k(s_g), s_g the place of ln t in group g's span, for k < `q` and the groups `g0 .. g0
    /// + n`: [k][lane], written into the first q of `rows` and returned as written.
    #[inline(always)]
    fn ln_t_lanes<'r, const L: usize>(
        &self,
        ln_t: f32,
        (g0, n): (usize, usize),
        q: usize,
        rows: &'r mut [MaybeUninit<[f32; L]>; MAX_Q],
    ) -> &'r [[f32; L]] {
        let span = |i: usize, e: usize| self.ln_t_range.get(2 * (g0 + i) + e).unwrap_or(0.0);
        let s: [f32; L] = core::array::from_fn(|i| {
            if i < n {
                ln_t_position((span(i, 0), span(i, 1)), ln_t)
            } else {
                0.0
            }
        });
        legendre_lanes(&s, &mut rows[..q.min(MAX_Q)])
    }

    /// The fitted depths of the groups `g0 .. g0 + n` around `pt` ([`FittedDepths::of`] of
    /// the grid corners the point draws on), lane by lane.
    #[inline(always)]
    fn fitted_lanes<const L: usize>(
        &self,
        pt: &Point,
        (g0, n): (usize, usize),
    ) -> [Option<FittedDepths<f32>>; L] {
        let (mut all, mut w, mut lo, mut hi) = ([0.0f32; L], [0.0f32; L], [0.0f32; L], [0.0f32; L]);
        for &(at, wk) in &pt.corners[..pt.n_corners] {
            // Gathered first, then the same arithmetic on every lane of the run: with a full
            // run (n = L) a loop of constant length, which the compiler puts in one register.
            let mut packed = [EMPTY_RANGE; L];
            for (i, p) in packed.iter_mut().enumerate().take(n) {
                *p = self
                    .u_range
                    .get((g0 + i) * pt.per_group.0 + at)
                    .unwrap_or(EMPTY_RANGE);
            }
            let lanes = if n == L { L } else { n };
            for i in 0..lanes {
                let (a, b) = unpack_u_range(packed[i]);
                all[i] += wk;
                // 1 where the node has fitted cells, else 0: adding 0 leaves each sum as it
                // was, with no branch to mispredict (empty nodes are common and irregular).
                let has = f32::from(u8::from(a <= b && wk > 0.0));
                w[i] += wk * has;
                lo[i] += wk * a * has;
                hi[i] += wk * b * has;
            }
        }
        core::array::from_fn(|i| {
            (w[i] > 0.0).then(|| FittedDepths {
                lo: lo[i] / w[i],
                hi: hi[i] / w[i],
                share: w[i] / all[i],
            })
        })
    }

    /// [`CEILING_FACTOR`] × the largest T each of the groups `g0 .. g0 + n` holds in its
    /// fitted cells at the thickness and sun-cosine nodes `pt` draws on; None for files
    /// without the ceiling.
    #[inline(always)]
    fn ceiling_lanes<const L: usize>(
        &self,
        pt: &Point,
        (g0, n): (usize, usize),
    ) -> [Option<f32>; L] {
        let Some(top) = self.t_ceiling.as_ref() else {
            return [None; L];
        };
        core::array::from_fn(|i| {
            let base = (g0 + i) * pt.per_group.1;
            let most = || {
                pt.ceiling[..pt.n_ceiling]
                    .iter()
                    .map(|&k| top.get(base + k).unwrap_or(0.0))
                    .fold(0.0f32, f32::max)
            };
            (i < n).then(|| CEILING_FACTOR as f32 * most())
        })
    }

    /// T, c and σ of the groups `g0 .. g0 + out.len()` (at most `L`) at `pt` into
    /// `out`, given their T and fitted depths there, from the collector's `sums`; c and σ are 0
    /// where T is. Lanes as in [`Self::t_lanes`].
    #[inline(always)]
    fn collector_lanes<const M: usize, const L: usize>(
        &self,
        cp: &CollectorPart,
        pt: &Point,
        (t, ranges): (&[f32; L], &[Option<FittedDepths<f32>>; L]),
        (g0, sums): (usize, &[Sums<M>; 4]),
        out: &mut [Transport],
    ) {
        let mut rows = [const { MaybeUninit::uninit() }; MAX_Q];
        let lq = self.ln_t_lanes(pt.ln_t, (g0, out.len()), cp.q, &mut rows);
        let mut parts = [[[0.0; L]; MAX_COLLECTOR_LEGENDRE]; 4];
        for (d, sums) in parts.iter_mut().zip(sums) {
            sums.depth_lanes(g0, lq, d);
        }
        let depth = cp.form.depth_terms().min(MAX_COLLECTOR_LEGENDRE);
        // In a run, each part's sum at the point's own depth for every lane at once (`dot`'s
        // arithmetic below, from −0.0 as `sum` starts).
        let mut at_u = [[-0.0f32; L]; 4];
        if L > 1 {
            for (s, d) in at_u.iter_mut().zip(&parts) {
                *s = lane_sums(d, &pt.p_u, depth, -0.0);
            }
        }
        for (i, slot) in out.iter_mut().enumerate() {
            *slot = Transport {
                t: t[i],
                ..Transport::default()
            };
            let Some(range) = ranges[i].filter(|_| t[i] > 0.0) else {
                continue;
            };
            // c and σ are held within the fitted depths.
            let u = range.held(pt.cell.u);
            let p_x = if u == pt.cell.u {
                pt.p_u
            } else {
                legendre(2.0 * u - 1.0, depth)
            };
            let dot = |part: usize| -> f32 {
                if L > 1 && u == pt.cell.u {
                    return at_u[part][i];
                }
                let d = &parts[part];
                d.iter().zip(&p_x).take(depth).map(|(d, p)| d[i] * p).sum()
            };
            let sigma = Math::exp(dot(0));
            let cz = dot(1) + dot(2) / sigma;
            slot.c_x = sigma * dot(3);
            slot.c_z = sigma * cz;
            slot.sigma = sigma;
        }
    }

    /// p(θ) of the stored table between its nodes as the tabulated model samples it: the
    /// density per unit angle f = 2π p sin θ linear between nodes ([`phase_between`]).
    fn phase_at(&self, c: Cosine<f32>) -> f32 {
        let (theta, sin) = angle(c);
        let to_rad = core::f32::consts::PI / 180.0;
        let i = bracket(&self.phase_theta, theta / to_rad);
        let node = |k: usize| {
            let t = self.phase_theta.get(k).unwrap_or(0.0) * to_rad;
            let p = self.phase.get(k).unwrap_or(0.0);
            (t, 2.0 * core::f32::consts::PI * p * Math::sin_cos(t).0)
        };
        phase_between(node(i), node(i + 1), theta, sin)
    }
}

/// The geometry of T at one point, the same for every group.
struct Point {
    cell: Cell<f32>,
    /// Where the point reads the halo (None outside it).
    halo: Option<HaloAt>,
    offset: f32,
    ln_t: f32,
    /// (index within a group's depth ranges, weight) of the grid corners the point draws on.
    corners: [(usize, f32); 8],
    n_corners: usize,
    /// Indices within a group's ceilings of the (thickness, μ_L) nodes it draws on.
    ceiling: [usize; 4],
    n_ceiling: usize,
    /// Depth ranges and ceilings per group.
    per_group: (usize, usize),
    /// P_j(2u − 1) at the point's own depth: every group's depth polynomial where the point
    /// lies within the group's fitted depths (most points), computed once.
    p_u: [f32; MAX_LEGENDRE],
    /// The slab's stretched-depth map (for the depths continued toward a face).
    stretch: Stretch<f32>,
}

/// The orders group `g` holds: its first and its last (None: no end).
pub(super) fn group_orders(tables: &TransportTables, g: usize) -> (f32, Option<f32>) {
    let first = tables.group_first_order(g).unwrap_or(2.0);
    (
        first,
        tables.group_first_order(g + 1).map(|next| next - 1.0),
    )
}

/// The stored phase function, for order 1.
struct StoredPhase<'t, 'a>(&'t TransportTables<'a>);

impl PhaseValue<f32> for StoredPhase<'_, '_> {
    fn value(&self, c: Cosine<f32>) -> f32 {
        self.0.phase_at(c)
    }
}


/// g = ∮ μ p dΩ of the tables' phase function (midpoint rule on 4096 angles).
pub(super) fn integrate_mean_cosine(tables: &TransportTables) -> f32 {
    let n = 4096;
    let h = f64::PI / n as f64;
    let mut sum = 0.0f64;
    for k in 0..n {
        let (sin, cos) = Math::sin_cos((k as f64 + 0.5) * h);
        sum += 2.0 * f64::PI * cos * tables.phase(cos as f32) as f64 * sin * h;
    }
    sum as f32
}
