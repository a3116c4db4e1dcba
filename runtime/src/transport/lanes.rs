//! The vector machinery under [`super::tables`]: a point's features summed against the
//! parameters of many groups at once ([`Sums`], feature-major, one multiply-add per feature),
//! the rows of packed features ([`Row`]), the Legendre terms in lanes, the AVX2 copies and
//! gathers, and the node brackets. The tables' API and the forms' equations stay in
//! `tables.rs`; what is here only adds and multiplies, in a fixed order (the same bits on every
//! CPU).

use super::collector::MAX_COLLECTOR_LEGENDRE;
use super::format::{Strides, MAX_Q};
use super::log_additive::{Lerp, MAX_LEGENDRE};
use crate::container::ArrayView;
use crate::legendre::LegendreLanes;
use core::mem::MaybeUninit;

/// Floats of the sums of T's features: 8 groups × Q ≤ 6 × J ≤ 8 at once (more groups are
/// taken in runs).
pub(super) const T_SUMS: usize = 384;
/// Floats of the sums of one collector statistic: 8 groups × Q ≤ 4 × J ≤ 4 at once.
pub(super) const C_SUMS: usize = 128;
// Every form the loader accepts fits at least one group.
/// Floats of the sums of T's features for one group of the forms the shipped tables use (Q = 5,
/// J = 8; a form beyond takes [`T_SUMS`]).
pub(super) const ONE_T_SUMS: usize = 48;
/// The same for one collector statistic (Q = 4, J = 4 shipped).
pub(super) const ONE_C_SUMS: usize = 16;
const _: () = assert!(T_SUMS >= MAX_LEGENDRE * MAX_Q);
const _: () = assert!(C_SUMS >= MAX_COLLECTOR_LEGENDRE * MAX_Q);

/// A point's features summed against the parameters of a run of groups at once:
/// acc[j][(g − first) Q + k] = Σ over the features of depth degree j of v β[col][g][k].
/// Feature-major β makes each feature one contiguous run of (groups × Q) values, one
/// vectorised multiply-add. The sums
/// are linear in β, so the Legendre terms in ln t, which differ per group, are applied after
/// ([`Sums::depth_sums`], [`Sums::dot`]).
#[derive(Clone, Copy)]
pub(super) struct Sums<const N: usize> {
    acc: [f32; N],
    strides: Strides,
    first: usize,
    groups: usize,
    q: usize,
    depth: usize,
}

impl<const N: usize> Sums<N> {
    pub(super) const EMPTY: Self = Self {
        acc: [0.0; N],
        strides: Strides { param: 0, group: 0 },
        first: 0,
        groups: 0,
        q: 0,
        depth: 0,
    };

    /// Most groups of `q` terms in `depth` depth terms one holds (≥ 1: a form's q and depth
    /// terms are at most 16 each).
    pub(super) fn capacity(q: usize, depth: usize) -> usize {
        (N / (q * depth).max(1)).max(1)
    }

    /// Empty sums of the groups `first .. first + groups` (at most [`Self::capacity`]).
    pub(super) fn new(
        strides: Strides,
        (first, groups): (usize, usize),
        q: usize,
        depth: usize,
    ) -> Self {
        Self {
            acc: [0.0; N],
            strides,
            first,
            groups: groups.min(Self::capacity(q, depth)),
            q,
            depth: depth.min(MAX_LEGENDRE),
        }
    }

    /// [`Self::new`] in place: only the accumulators the run uses are zeroed. (`new` keeps its
    /// own struct literal: built through `reset` and moved out, one group's T read 3 % slower.)
    pub(super) fn reset(
        &mut self,
        strides: Strides,
        (first, groups): (usize, usize),
        q: usize,
        depth: usize,
    ) {
        self.strides = strides;
        self.first = first;
        self.groups = groups.min(Self::capacity(q, depth));
        self.q = q;
        self.depth = depth.min(MAX_LEGENDRE);
        let used = (self.groups * q * self.depth).min(N);
        self.acc[..used].iter_mut().for_each(|a| *a = 0.0);
    }

    /// Adds feature `v` of column `col` and depth degree `j`, its parameters in `beta`.
    #[inline(always)]
    fn add(&mut self, beta: &[u8], col: usize, v: f32, j: usize) {
        let width = self.groups * self.q;
        let Some(acc) = self.acc.get_mut(j * width..(j + 1) * width) else {
            return;
        };
        let start = self.strides.at(self.first, col);
        if let Some(run) = beta.get(4 * start..4 * (start + width)) {
            multiply_add(acc, v, run);
        }
    }

    /// Adds every feature of `row` (packed keys, values). With `std` on x86-64 the loop is also
    /// compiled for AVX2 and that copy runs where the CPU has it: a feature's parameters for
    /// all groups (8 × 5 for T) take half the vector adds. Each accumulator gets the same
    /// products in the same order either way (no FMA), so the answers are bit-identical.
    pub(super) fn add_row(&mut self, beta: &[u8], row: &[(u32, f32)]) {
        crate::simd::avx2_or!(self.add_row_avx2(beta, row), self.add_row_any(beta, row))
    }

    /// [`Self::add_row`] compiled for AVX2.
    #[cfg(all(feature = "std", target_arch = "x86_64"))]
    #[target_feature(enable = "avx2")]
    fn add_row_avx2(&mut self, beta: &[u8], row: &[(u32, f32)]) {
        self.add_row_any(beta, row);
    }

    /// [`Self::add_row`] for the target's baseline.
    #[inline(always)]
    fn add_row_any(&mut self, beta: &[u8], row: &[(u32, f32)]) {
        // The shipped forms' widths: 8 groups × Q = 5 (T) and 8 × 4 (the collector), and one
        // group of each (what a search's later reads take).
        match self.groups * self.q {
            40 => return self.add_runs::<40>(beta, row),
            32 => return self.add_runs::<32>(beta, row),
            5 => return self.add_runs::<5>(beta, row),
            4 => return self.add_runs::<4>(beta, row),
            _ => {}
        }
        self.add_each(beta, row);
    }

    /// Adds the features of `row` one by one ([`Self::add`]: each feature's parameters
    /// checked, and skipped where they would end beyond β).
    fn add_each(&mut self, beta: &[u8], row: &[(u32, f32)]) {
        for &(key, v) in row {
            self.add(
                beta,
                (key & COL) as usize,
                v,
                (key >> DEGREE_SHIFT) as usize,
            );
        }
    }

    /// [`Self::add_row`] for feature-major β of `W` = groups × Q: each run of consecutive
    /// features of one depth degree is summed in registers (a fixed-size copy of its
    /// accumulators, loaded where the degree changes and stored where it changes again),
    /// rather than each feature's sums going through memory and waiting on the previous one's.
    /// The row's columns are checked against β once, not feature by feature. The same
    /// products reach each accumulator in the same order, so the same bits.
    #[inline(always)]
    fn add_runs<const W: usize>(&mut self, beta: &[u8], row: &[(u32, f32)]) {
        let (base, param) = (self.strides.at(self.first, 0), self.strides.param);
        let last_col = row.iter().map(|&(k, _)| k & COL).max().unwrap_or(0) as usize;
        // Every feature's W parameters lie within β: checked once for the row (else feature by
        // feature).
        let fits = (base + last_col * param + W) * 4 <= beta.len();
        if !fits {
            return self.add_each(beta, row);
        }
        // The accumulators of the current degree, in registers; those of a degree beyond the
        // sums start at 0 and are dropped (as `add` drops its features).
        let Some(&(first, _)) = row.first() else {
            return;
        };
        let mut degree = first >> DEGREE_SHIFT;
        let mut sums = self.load_degree::<W>(degree);
        for &(key, v) in row {
            if key >> DEGREE_SHIFT != degree {
                self.store_degree::<W>(degree, &sums);
                degree = key >> DEGREE_SHIFT;
                sums = self.load_degree::<W>(degree);
            }
            let start = 4 * (base + (key & COL) as usize * param);
            // SAFETY: start + 4 W ≤ beta.len() for every key of the row (`fits`: the largest
            // column's parameters end within β).
            let params = unsafe { beta.get_unchecked(start..start + 4 * W) };
            multiply_add(&mut sums, v, params);
        }
        self.store_degree::<W>(degree, &sums);
    }

    /// The accumulators of depth degree `j` (zeros for a degree beyond the sums).
    #[inline(always)]
    fn load_degree<const W: usize>(&self, j: u32) -> [f32; W] {
        let j = j as usize;
        let mut sums = [0.0f32; W];
        if let Some(acc) = self.acc.get(j * W..(j + 1) * W) {
            sums.copy_from_slice(acc);
        }
        sums
    }

    /// Stores the accumulators of depth degree `j` (nothing for a degree beyond the sums).
    #[inline(always)]
    fn store_degree<const W: usize>(&mut self, j: u32, sums: &[f32; W]) {
        let j = j as usize;
        if let Some(acc) = self.acc.get_mut(j * W..(j + 1) * W) {
            acc.copy_from_slice(sums);
        }
    }

    /// The depth sums of the groups `g0 ..` of the run side by side: per depth degree j,
    /// Σ_k acc[j][g, k] L_k(ln t), `lq` [k][lane] — the coefficients of each group's depth
    /// polynomial at this point ([`depth_polynomial`](super::log_additive::depth_polynomial));
    /// into `d` [j][lane] (the first `depth` rows; lanes past the run untouched).
    #[inline(always)]
    pub(super) fn depth_lanes<const L: usize>(
        &self,
        g0: usize,
        lq: &[[f32; L]],
        d: &mut [[f32; L]],
    ) {
        let width = self.groups * self.q;
        let lanes = (self.first + self.groups).saturating_sub(g0).min(L);
        let (base, q) = ((g0 - self.first) * self.q, self.q);
        #[cfg(all(feature = "std", target_arch = "x86_64"))]
        let gather = L == 8 && crate::simd::avx2();
        for (j, d) in d.iter_mut().enumerate().take(self.depth) {
            let at = j * width + base;
            match self.acc.get(at..at + L * q) {
                // A full run: every lane's sum in one register, each lane's products added in
                // the same order as below, from −0.0 as `sum` starts (the same bits).
                Some(block) if L > 1 && lanes == L && q <= MAX_Q => {
                    #[cfg(all(feature = "std", target_arch = "x86_64"))]
                    if gather {
                        // SAFETY: the CPU has AVX2 and L = 8; block holds 8 q values, q ≤ MAX_Q.
                        unsafe { depth_sum_gathered(block, q, lq, d) };
                        continue;
                    }
                    let mut s = [-0.0f32; L];
                    for (k, l) in lq.iter().enumerate().take(q) {
                        // SAFETY: i < L and k < q, so i q + k < L q = block.len().
                        let a: [f32; L] =
                            core::array::from_fn(|i| unsafe { *block.get_unchecked(i * q + k) });
                        for i in 0..L {
                            s[i] += a[i] * l[i];
                        }
                    }
                    *d = s;
                }
                _ => {
                    for (i, slot) in d.iter_mut().enumerate().take(lanes) {
                        let at = at + i * q;
                        if let Some(run) = self.acc.get(at..at + q) {
                            *slot = run.iter().zip(lq).map(|(a, l)| a * l[i]).sum();
                        }
                    }
                }
            }
        }
    }
}

/// One depth degree's sums of [`Sums::depth_lanes`] for a run of 8 lanes, each lane's Q
/// coefficients gathered into one register a k at a time (`block` is [lane, k], 8 q values).
/// The inserts of the portable loop kept the shuffle port busy (a tenth of T, c and σ of all
/// groups); the gather loads them. The same products are added in the same order from −0.0,
/// with no FMA: the same bits.
///
/// # Safety
/// The CPU has AVX2; `L` = 8, `block.len()` ≥ 8 q and q ≤ [`MAX_Q`].
#[cfg(all(feature = "std", target_arch = "x86_64"))]
#[target_feature(enable = "avx2")]
unsafe fn depth_sum_gathered<const L: usize>(
    block: &[f32],
    q: usize,
    lq: &[[f32; L]],
    d: &mut [f32; L],
) {
    use core::arch::x86_64::*;
    debug_assert!(L == 8 && block.len() >= 8 * q && q <= MAX_Q);
    let index = _mm256_mullo_epi32(
        _mm256_setr_epi32(0, 1, 2, 3, 4, 5, 6, 7),
        _mm256_set1_epi32(q as i32),
    );
    let mut s = _mm256_set1_ps(-0.0);
    for (k, l) in lq.iter().enumerate().take(q) {
        // SAFETY: lane i reads block[i q + k] < 8 q; l holds L = 8 values.
        let a = unsafe { _mm256_i32gather_ps::<4>(block.as_ptr().add(k), index) };
        let l = unsafe { _mm256_loadu_ps(l.as_ptr()) };
        s = _mm256_add_ps(s, _mm256_mul_ps(a, l));
    }
    // SAFETY: d holds L = 8 values.
    unsafe { _mm256_storeu_ps(d.as_mut_ptr(), s) };
}

/// A point's features as packed keys and values ([`packed`]), at most `CAP` (more are
/// dropped). Not zeroed first: a collector read's rows are 5 KB, and clearing them took 2–3 %
/// of a read.
pub(super) struct Row<const CAP: usize> {
    keys: [MaybeUninit<(u32, f32)>; CAP],
    n: usize,
}

impl<const CAP: usize> Row<CAP> {
    #[inline(always)]
    pub(super) fn new() -> Self {
        Self {
            keys: [const { MaybeUninit::uninit() }; CAP],
            n: 0,
        }
    }

    /// Adds feature `v` of column `col` and depth degree `j`.
    #[inline(always)]
    pub(super) fn push(&mut self, col: usize, v: f32, j: usize) {
        if let Some(slot) = self.keys.get_mut(self.n) {
            slot.write((packed(col, j), v));
            self.n += 1;
        }
    }

    /// The features pushed, in order.
    #[inline(always)]
    pub(super) fn as_slice(&self) -> &[(u32, f32)] {
        // SAFETY: `push` wrote every one of the first `n` slots.
        unsafe { assume_written(&self.keys[..self.n]) }
    }
}

/// `slots` as the values they hold.
///
/// # Safety
/// Every slot has been written. (`MaybeUninit<T>` has the layout of `T`.)
#[inline(always)]
unsafe fn assume_written<T>(slots: &[MaybeUninit<T>]) -> &[T] {
    // SAFETY: the caller's promise, and the layouts are the same.
    unsafe { &*(slots as *const [MaybeUninit<T>] as *const [T]) }
}

/// Bits of a packed feature key below its depth degree: the column.
pub(super) const DEGREE_SHIFT: u32 = 24;
/// Mask of the column in a packed feature key.
pub(super) const COL: u32 = (1 << DEGREE_SHIFT) - 1;

/// A feature's column and the degree j of its depth polynomial P_j as one key (columns are
/// below 2^24: [`MAX_NODES`] bounds the form's parameters).
#[inline]
pub(super) fn packed(col: usize, j: usize) -> u32 {
    (col as u32 & COL) | ((j as u32) << DEGREE_SHIFT)
}

/// acc += v × the little-endian f32s of `run`.
#[inline(always)]
fn multiply_add(acc: &mut [f32], v: f32, run: &[u8]) {
    for (a, b) in acc.iter_mut().zip(run.chunks_exact(4)) {
        *a += v * f32::from_le_bytes([b[0], b[1], b[2], b[3]]);
    }
}

/// Groups evaluated side by side: 8 f32 lanes, one AVX2 register.
pub(super) const LANES: usize = 8;

/// P_0 … P_{n−1} of each lane of `x` ([k][lane]), by the same steps as [`legendre`], written
/// into the n = `rows.len()` rows and returned as written. The rows are not zeroed first: a
/// 512-byte array cleared and copied out for the 5 or 4 rows used cost ~5 % of T of all groups.
#[inline(always)]
pub(super) fn legendre_lanes<'r, const L: usize>(
    x: &[f32; L],
    rows: &'r mut [MaybeUninit<[f32; L]>],
) -> &'r [[f32; L]] {
    let mut steps = LegendreLanes::new(*x);
    for row in rows.iter_mut() {
        row.write(steps.next_row());
    }
    // SAFETY: every row was written just above.
    unsafe { assume_written(rows) }
}

/// Σ_{j<n} d[j][i] p[j] for every lane i, added in j order from `zero` (0.0 as
/// [`depth_polynomial`](super::log_additive::depth_polynomial) starts, −0.0 as `sum` does): one
/// lane's arithmetic in each, so the lanes share a register.
#[inline(always)]
pub(super) fn lane_sums<const L: usize>(
    d: &[[f32; L]],
    p: &[f32],
    n: usize,
    zero: f32,
) -> [f32; L] {
    let mut s = [zero; L];
    for (d, &p) in d.iter().zip(p).take(n) {
        for i in 0..L {
            s[i] += d[i] * p;
        }
    }
    s
}

/// Where x sits among the values of `a` (held at the ends).
#[inline]
pub(super) fn lerp(a: &ArrayView, x: f32) -> Lerp<f32> {
    let n = a.len();
    if n <= 1 || !(x > a.get(0).unwrap_or(0.0)) {
        return Lerp::at(0);
    }
    if x >= a.get(n - 1).unwrap_or(0.0) {
        return Lerp::at(n - 1);
    }
    let lo = bracket(a, x);
    let (va, vb) = (a.get(lo).unwrap_or(0.0), a.get(lo + 1).unwrap_or(1.0));
    Lerp {
        lo,
        hi: lo + 1,
        w: (x - va) / (vb - va),
    }
}

/// The interval i of the increasing values of `a` (at least two) that holds x: a[i] ≤ x <
/// a[i + 1], held to the first and the last interval outside them.
#[inline]
pub(super) fn bracket(a: &ArrayView, x: f32) -> usize {
    let (mut lo, mut hi) = (0, a.len().max(2) - 1);
    while hi - lo > 1 {
        let mid = (lo + hi) / 2;
        if a.get(mid).unwrap_or(0.0) <= x {
            lo = mid
        } else {
            hi = mid
        }
    }
    lo
}

#[cfg(all(test, feature = "std", target_arch = "x86_64"))]
mod tests {
    use super::*;

    /// The gathered depth sums are each lane's Σ_k a_k l_k added in k order from −0.0, bit for
    /// bit, for every Q the loader accepts; zeros of both signs among the values.
    #[test]
    fn gathered_depth_sums_add_in_order() {
        if !std::is_x86_feature_detected!("avx2") {
            return;
        }
        let mut rng = nephele_stats::XorShift32::new(7);
        let mut next = move || {
            let x = rng.next_u32();
            match x % 13 {
                0 => 0.0,
                1 => -0.0,
                _ => (x as f32 / u32::MAX as f32 - 0.5) * 3.0,
            }
        };
        for q in 1..=MAX_Q {
            for _ in 0..200 {
                let block: Vec<f32> = (0..8 * q).map(|_| next()).collect();
                let lq: Vec<[f32; 8]> = (0..q).map(|_| core::array::from_fn(|_| next())).collect();
                let mut got = [0.0f32; 8];
                // SAFETY: the CPU has AVX2 (checked above), 8 lanes, 8 q values, q ≤ MAX_Q.
                unsafe { depth_sum_gathered(&block, q, &lq, &mut got) };
                for (i, got) in got.iter().enumerate() {
                    let want = (0..q).fold(-0.0f32, |s, k| s + block[i * q + k] * lq[k][i]);
                    assert_eq!(got.to_bits(), want.to_bits(), "q = {q}, lane {i}");
                }
            }
        }
    }
}
