//! Scattered intensity of many spheres at many angles as dense matrix products.
//!
//! For a block of spheres sorted by size parameter, with K the largest number of terms,
//!   [Re, Im] (S1 + S2) = C⁺ (2b × K) · U (K × n_θ),   C⁺_pn = c_n (a_n + b_n),
//!   [Re, Im] (S1 − S2) = C⁻ (2b × K) · V (K × n_θ),   C⁻_pn = c_n (a_n − b_n),
//! (U, V from [`AngleBasis`]; coefficients past a sphere's own N are zero), and
//!   i(θ) = (|S1|² + |S2|²)/2 = (|S1 + S2|² + |S1 − S2|²)/4.
//! The requested outputs are weighted sums over spheres, `out = W · I` (W sparse: each row
//! weighs a contiguous run of spheres), accumulated chunk by chunk with one more matrix
//! product. Within a chunk the work runs in panels of the basis's angles, one per task: no sum
//! runs across angles, so a panel's values are those of the whole width. The chunking does not
//! depend on the thread count and every sum runs in a fixed order, so results are
//! bit-identical for any number of threads.

use super::angular::AngleBasis;
use super::sphere::{n_terms, Efficiencies, MieCoefficients};
use num_complex::Complex64;
use rayon::prelude::*;

/// Spheres per block of the first product (2 rows each per matrix, so M = 256). The GEMM packs
/// the coefficients and the angle basis anew for every product: with 32 spheres that packing
/// took 29 % of the time, with 128 it takes 11 % (docs/mie.md, "Where the time goes").
pub const BLOCK: usize = 128;
/// Spheres per chunk of the accumulating product (eight blocks).
const CHUNK: usize = 1024;

/// One sphere: size parameter and relative refractive index (Im ≥ 0 absorbs).
#[derive(Clone, Copy, Debug)]
pub struct Particle {
    /// Size parameter x = π d / λ.
    pub x: f64,
    /// Relative refractive index m.
    pub m: Complex64,
}

/// Floating-point operations and sphere count of a [`weighted_intensity`] call.
#[derive(Clone, Copy, Debug, Default)]
pub struct Work {
    /// Multiply–adds × 2 spent in the matrix products, zero padding of short series included.
    pub flops: f64,
    /// The same without the padding and the zero weights: 8 N n_θ per sphere plus 2 n_θ per
    /// non-zero weight.
    pub useful_flops: f64,
    /// Spheres evaluated.
    pub spheres: usize,
}

/// One output row: weights on the contiguous particles `start..start + weights.len()`.
#[derive(Clone, Debug)]
pub struct WeightRow {
    /// First particle the row weighs.
    pub start: usize,
    /// Weights of particles start, start + 1, ….
    pub weights: Vec<f64>,
}

impl AsRef<WeightRow> for WeightRow {
    fn as_ref(&self) -> &WeightRow {
        self
    }
}

impl WeightRow {
    fn end(&self) -> usize {
        self.start + self.weights.len()
    }

    /// The particles this row weighs.
    pub fn particles(&self) -> std::ops::Range<usize> {
        self.start..self.end()
    }
}

/// `out (n_rows × n_θ) = W · I` with I the intensities (|S1|² + |S2|²)/2 of `particles` at
/// the angles of `basis` and W the sparse `rows`. Spheres are evaluated in order of size
/// parameter, in blocks of [`BLOCK`] (each block pays for its largest term count, so sorting
/// keeps the padding small). Also returns every sphere's efficiencies, from the same
/// coefficients. `progress` is called with the work finished so far: the Mie terms N summed
/// over the finished spheres.
pub fn weighted_intensity<R: AsRef<WeightRow> + Sync>(
    particles: &[Particle],
    rows: &[R],
    basis: &AngleBasis,
    progress: &(dyn Fn(usize) + Sync),
) -> (Vec<f64>, Vec<Efficiencies>, Work) {
    let n_p = particles.len();
    let n_ang = basis.n_angles();
    assert!(
        rows.iter().all(|r| r.as_ref().end() <= n_p),
        "weight rows must lie within the particles"
    );
    let mut order: Vec<usize> = (0..n_p).collect();
    order.sort_by(|&i, &j| particles[i].x.total_cmp(&particles[j].x));
    let mut out = vec![0.0; rows.len() * n_ang];
    let mut work = Work {
        spheres: n_p,
        ..Default::default()
    };
    let mut eff = vec![Efficiencies::default(); n_p];
    let mut terms_done = 0;
    for idx in order.chunks(CHUNK) {
        let blocks: Vec<BlockCoefficients> = idx
            .par_chunks(BLOCK)
            .map(|block_idx| BlockCoefficients::new(block_idx, particles, basis))
            .collect();
        for (block, block_idx) in blocks.iter().zip(idx.chunks(BLOCK)) {
            work.flops += block.flops(n_ang);
            for (&i, e) in block_idx.iter().zip(&block.efficiencies) {
                eff[i] = *e;
            }
        }
        let terms: usize = idx.iter().map(|&i| n_terms(particles[i].x)).sum();
        work.useful_flops += 8.0 * (terms * n_ang) as f64;
        let weights = ChunkWeights::new(rows, idx);
        // Each panel is computed in the same order whatever the thread that takes it: the
        // products' sums run over the terms k, never across angles, so a panel's values are
        // bit for bit those of the whole width.
        let panels: Vec<(usize, Vec<f64>)> = (0..basis.panels())
            .into_par_iter()
            .map(|q| chunk_panel(&blocks, basis, &weights, q))
            .collect();
        for (j0, c) in panels {
            weights.add_into(&mut out, n_ang, j0, &c);
        }
        let (done, useful) = weights.flops(n_ang);
        work.flops += done;
        work.useful_flops += useful;
        terms_done += terms;
        progress(terms_done);
    }
    (out, eff, work)
}

/// The coefficient matrices C⁺ and C⁻ ([Re; Im] rows, 2b × K each) of a block of spheres
/// (sorted by x), with their efficiencies.
struct BlockCoefficients {
    /// Spheres in the block.
    spheres: usize,
    /// K: the largest number of terms among them.
    terms: usize,
    plus: Vec<f64>,
    minus: Vec<f64>,
    efficiencies: Vec<Efficiencies>,
    /// The products' steps ([`term_steps`]): (first sphere, last order + 1), orders growing.
    steps: Vec<(usize, usize)>,
}

/// Spheres whose Mie coefficients are computed side by side ([`MieCoefficients::many`]).
const LANES: usize = 4;
/// Spheres per part of a block that [`term_steps`] may give its own term count.
const PART: usize = 8;
/// The fewest orders a step adds: a product over fewer terms spends more on loading and
/// storing its rows than it saves on the padding.
const MIN_STEP: usize = 8;

/// The steps of a block's products, from its spheres' term counts `terms` (non-decreasing, as
/// the block is sorted by x): step j multiplies orders `steps[j−1].1 .. steps[j].1` for the
/// spheres from `steps[j].0` on, the only ones with terms there. One product over all K
/// orders would multiply the short series' zero padding too (12 % of the flops at 20 µm).
fn term_steps(terms: &[usize]) -> Vec<(usize, usize)> {
    let mut steps: Vec<(usize, usize)> = Vec::new();
    // The order count the current step opened with: a step grows in small increments until
    // its parts need MIN_STEP orders more than that.
    let mut opened = 0;
    for first in (0..terms.len()).step_by(PART) {
        let k = terms[(first + PART).min(terms.len()) - 1];
        match steps.last_mut() {
            Some(last) if k < opened + MIN_STEP => last.1 = k,
            _ => {
                steps.push((first, k));
                opened = k;
            }
        }
    }
    steps
}

impl BlockCoefficients {
    fn new(block_idx: &[usize], particles: &[Particle], basis: &AngleBasis) -> Self {
        let b = block_idx.len();
        let terms: Vec<usize> = block_idx.iter().map(|&i| n_terms(particles[i].x)).collect();
        let steps = term_steps(&terms);
        let k = steps.last().map_or(1, |s| s.1);
        assert!(
            k <= basis.n_max,
            "angle basis has {} orders, sphere needs {k}",
            basis.n_max
        );
        let mut plus = vec![0.0; 2 * b * k];
        let mut minus = vec![0.0; 2 * b * k];
        let mut efficiencies = Vec::with_capacity(b);
        let sphere = |i: usize| (particles[i].m, particles[i].x);
        let lanes = block_idx.chunks_exact(LANES);
        let rest = lanes.remainder().iter();
        let coefficients = lanes
            .flat_map(|l| MieCoefficients::many::<LANES>(std::array::from_fn(|j| sphere(l[j]))))
            .chain(rest.map(|&i| MieCoefficients::new(particles[i].m, particles[i].x)));
        for (p, coef) in coefficients.enumerate() {
            efficiencies.push(coef.efficiencies());
            for (n0, (a, bn)) in coef.a.iter().zip(&coef.b).enumerate() {
                let n = (n0 + 1) as f64;
                let c = (2.0 * n + 1.0) / (n * (n + 1.0));
                let (sp, sm): (Complex64, Complex64) = (c * (a + bn), c * (a - bn));
                plus[2 * p * k + n0] = sp.re;
                plus[(2 * p + 1) * k + n0] = sp.im;
                minus[2 * p * k + n0] = sm.re;
                minus[(2 * p + 1) * k + n0] = sm.im;
            }
        }
        Self {
            spheres: b,
            terms: k,
            plus,
            minus,
            efficiencies,
            steps,
        }
    }

    /// The two products' flops over `n_ang` angles, the zero padding within steps included.
    fn flops(&self, n_ang: usize) -> f64 {
        let mut from = 0;
        let mut multiplied = 0;
        for &(first, to) in &self.steps {
            multiplied += (self.spheres - first) * (to - from);
            from = to;
        }
        2.0 * 2.0 * (2 * multiplied * n_ang) as f64
    }

    /// [Re; Im] rows (2b × `width`) of `coefficients` (C⁺ or C⁻) times the panel's `basis`
    /// (U or V, its orders' rows `width` wide), step by step: each step's orders are added to
    /// the rows of the spheres that have them.
    fn product(&self, coefficients: &[f64], basis: &[f64], width: usize, rows: &mut [f64]) {
        let (b, k) = (self.spheres, self.terms);
        let mut from = 0;
        for &(first, to) in &self.steps {
            let a = Strided::new(&coefficients[2 * first * k + from..], k);
            let u = Strided::new(&basis[from * width..], width);
            let beta = if from == 0 { 0.0 } else { 1.0 };
            gemm(
                2 * (b - first),
                to - from,
                width,
                a,
                u,
                beta,
                &mut rows[2 * first * width..],
            );
            from = to;
        }
    }
}

/// W · I of one chunk on the angles of the basis's panel `q`: the blocks' intensities there,
/// then their weighted sums, in scratch memory of the thread (reused: fresh multi-megabyte
/// buffers cost more in page faults than the products themselves for small droplets); with the
/// panel's first angle. Sparse weights take each sphere's intensities as its block yields
/// them, while they are in cache; dense ones a product over the chunk's intensities.
fn chunk_panel(
    blocks: &[BlockCoefficients],
    basis: &AngleBasis,
    weights: &ChunkWeights,
    q: usize,
) -> (usize, Vec<f64>) {
    let (columns, u, v) = basis.panel(q);
    let width = columns.len();
    let spheres: usize = blocks.iter().map(|b| b.spheres).sum();
    let mut c = vec![0.0; weights.active.len() * width];
    SCRATCH.with_borrow_mut(|(sp, sm, intensity)| {
        let dense = !weights.sparse;
        intensity.resize(if dense { spheres } else { 1 } * width, 0.0);
        let mut first = 0;
        for block in blocks {
            let (b, k) = (block.spheres, block.terms);
            sp.resize(2 * b * width, 0.0);
            sm.resize(2 * b * width, 0.0);
            block.product(&block.plus, &u[..k * width], width, sp);
            block.product(&block.minus, &v[..k * width], width, sm);
            for p in 0..b {
                let row = if dense { first + p } else { 0 };
                let row = &mut intensity[row * width..(row + 1) * width];
                intensity_row(p, width, sp, sm, row);
                if !dense {
                    weights.add_sphere(first + p, row, &mut c);
                }
            }
            first += b;
        }
        if dense {
            weights.apply_dense(&intensity[..spheres * width], width, &mut c);
        }
    });
    (columns.start, c)
}

thread_local! {
    static SCRATCH: std::cell::RefCell<(Vec<f64>, Vec<f64>, Vec<f64>)> =
        const { std::cell::RefCell::new((Vec::new(), Vec::new(), Vec::new())) };
}

/// row = (|S1 + S2|² + |S1 − S2|²)/4 of sphere `p` from the [Re; Im] rows of both products
/// (`width` angles each).
fn intensity_row(p: usize, width: usize, sp: &[f64], sm: &[f64], row: &mut [f64]) {
    let (pr, pi) = (&sp[2 * p * width..], &sp[(2 * p + 1) * width..]);
    let (mr, mi) = (&sm[2 * p * width..], &sm[(2 * p + 1) * width..]);
    for j in 0..width {
        row[j] = 0.25 * (pr[j] * pr[j] + pi[j] * pi[j] + mr[j] * mr[j] + mi[j] * mi[j]);
    }
}

/// The rows of W that weigh spheres of one chunk, restricted to the chunk's spheres (in its
/// order): `out[r] += Σ_p W[r, idx[p]] · I[p]`.
struct ChunkWeights {
    /// The output rows with a non-zero weight in the chunk.
    active: Vec<usize>,
    /// Their weights, active.len() × kc, row-major.
    w: Vec<f64>,
    /// Spheres in the chunk.
    kc: usize,
    /// Non-zero weights.
    nnz: usize,
    /// Whether the weights are added one by one rather than by a matrix product.
    sparse: bool,
    /// The non-zero weights sphere by sphere, (active row, weight), in row order: sphere p's
    /// are `by_sphere[starts[p]..starts[p + 1]]`.
    by_sphere: Vec<(usize, f64)>,
    starts: Vec<usize>,
}

impl ChunkWeights {
    fn new<R: AsRef<WeightRow>>(rows: &[R], idx: &[usize]) -> Self {
        let kc = idx.len();
        let (lo, hi) = idx
            .iter()
            .fold((usize::MAX, 0), |(a, b), &i| (a.min(i), b.max(i + 1)));
        let candidates =
            (0..rows.len()).filter(|&r| rows[r].as_ref().start < hi && rows[r].as_ref().end() > lo);
        let mut active = Vec::new();
        let mut w = Vec::new();
        for r in candidates {
            let row = rows[r].as_ref();
            let weights = idx.iter().map(|&i| {
                if (row.start..row.end()).contains(&i) {
                    row.weights[i - row.start]
                } else {
                    0.0
                }
            });
            let len = w.len();
            w.extend(weights);
            if w[len..].iter().all(|&v| v == 0.0) {
                w.truncate(len);
            } else {
                active.push(r);
            }
        }
        let nnz = w.iter().filter(|&&v| v != 0.0).count();
        // A matrix product does ~4× more flops per second than row updates: below a quarter
        // filled (the product rule puts each sphere in one wavelength row), add the non-zeros
        // one by one. The choice depends on the data only, never on the thread count.
        let sparse = 4 * nnz < active.len() * kc;
        let mut by_sphere = Vec::with_capacity(nnz);
        let mut starts = Vec::with_capacity(kc + 1);
        for p in 0..kc {
            starts.push(by_sphere.len());
            let column = (0..active.len()).map(|a| (a, w[a * kc + p]));
            by_sphere.extend(column.filter(|&(_, v)| v != 0.0));
        }
        starts.push(by_sphere.len());
        Self {
            active,
            w,
            kc,
            nnz,
            sparse,
            by_sphere,
            starts,
        }
    }

    /// c[a] += W[a, p] · I_p for the chunk's sphere `p` and every active row a it weighs
    /// (`c` is active × width). Taken sphere after sphere, each row gets its terms in the
    /// order of a row-by-row sum.
    fn add_sphere(&self, p: usize, intensity: &[f64], c: &mut [f64]) {
        let width = intensity.len();
        for &(a, wp) in &self.by_sphere[self.starts[p]..self.starts[p + 1]] {
            let c_row = &mut c[a * width..(a + 1) * width];
            c_row
                .iter_mut()
                .zip(intensity)
                .for_each(|(d, s)| *d += wp * s);
        }
    }

    /// c = W · I on one panel by a matrix product: `intensity` is kc × `width` (the chunk's
    /// spheres in order), `c` active × `width`.
    fn apply_dense(&self, intensity: &[f64], width: usize, c: &mut [f64]) {
        let w = Strided::new(&self.w, self.kc);
        gemm(
            self.active.len(),
            self.kc,
            width,
            w,
            Strided::new(intensity, width),
            0.0,
            c,
        );
    }

    /// Adds a panel's W · I (from [`Self::apply`], its first column `j0`) into `out`.
    fn add_into(&self, out: &mut [f64], n_ang: usize, j0: usize, c: &[f64]) {
        let width = c.len() / self.active.len().max(1);
        for (a, &r) in self.active.iter().enumerate() {
            let dst = &mut out[r * n_ang + j0..r * n_ang + j0 + width];
            for (d, s) in dst.iter_mut().zip(&c[a * width..(a + 1) * width]) {
                *d += s;
            }
        }
    }

    /// The flops the weighted sums take over `n_ang` angles, and those on non-zero weights.
    fn flops(&self, n_ang: usize) -> (f64, f64) {
        let useful = 2.0 * (self.nnz * n_ang) as f64;
        let done = if self.sparse {
            useful
        } else {
            2.0 * (self.active.len() * self.kc * n_ang) as f64
        };
        (done, useful)
    }
}

/// A matrix operand: its elements and its row stride (columns contiguous).
#[derive(Clone, Copy)]
struct Strided<'a> {
    data: &'a [f64],
    stride: usize,
}

impl<'a> Strided<'a> {
    fn new(data: &'a [f64], stride: usize) -> Self {
        Self { data, stride }
    }
}

/// Which GEMM runs the products: the `gemm` crate (faer's kernels, AVX-512 included through its
/// `x86-v4` feature), or matrixmultiply when `NEPHELE_GEMM=matrixmultiply` (nephele's GEMM
/// before the `gemm` crate, kept so that both can be timed in one run on any CPU: on an Intel
/// Xeon with two 512-bit FMA units the `gemm` crate's kernels are 1.3–1.5× faster,
/// docs/mie.md).
/// Both pick their kernels at run time (AVX-512, AVX2/FMA, SSE2) from one baseline build.
#[derive(Clone, Copy, PartialEq, Eq, Debug)]
pub enum Gemm {
    /// The `gemm` crate (the default).
    Faer,
    /// matrixmultiply 0.3.
    MatrixMultiply,
}

impl Gemm {
    /// The GEMM of this process: `NEPHELE_GEMM` read once (`matrixmultiply`, else the default).
    pub fn current() -> Self {
        static CHOICE: std::sync::LazyLock<Gemm> =
            std::sync::LazyLock::new(|| match std::env::var("NEPHELE_GEMM").as_deref() {
                Ok("matrixmultiply") => Gemm::MatrixMultiply,
                _ => Gemm::Faer,
            });
        *CHOICE
    }
}

/// C (m × n, contiguous) = A (m × k) · B (k × n) + β C (β is 0 or 1), through [`Gemm::current`].
fn gemm(m: usize, k: usize, n: usize, a: Strided, b: Strided, beta: f64, c: &mut [f64]) {
    gemm_with(Gemm::current(), m, k, n, a, b, beta, c)
}

/// [`gemm`] through the given GEMM.
#[allow(clippy::too_many_arguments)]
fn gemm_with(
    which: Gemm,
    m: usize,
    k: usize,
    n: usize,
    a: Strided,
    b: Strided,
    beta: f64,
    c: &mut [f64],
) {
    if m == 0 || n == 0 || k == 0 {
        return;
    }
    assert!(a.data.len() >= (m - 1) * a.stride + k && c.len() >= m * n);
    assert!(b.data.len() >= (k - 1) * b.stride + n);
    assert!(beta == 0.0 || beta == 1.0);
    let start = std::time::Instant::now();
    match which {
        // SAFETY: bounds checked just above; gemm's strides are (column, row), and it reads C
        // only when asked to (β = 1), so β = 0 overwrites whatever C held.
        Gemm::Faer => unsafe {
            gemm::gemm(
                m,
                n,
                k,
                c.as_mut_ptr(),
                1,
                n as isize,
                beta != 0.0,
                a.data.as_ptr(),
                1,
                a.stride as isize,
                b.data.as_ptr(),
                1,
                b.stride as isize,
                beta,
                1.0,
                false,
                false,
                false,
                gemm::Parallelism::None,
            )
        },
        // SAFETY: bounds checked just above.
        Gemm::MatrixMultiply => unsafe {
            matrixmultiply::dgemm(
                m,
                k,
                n,
                1.0,
                a.data.as_ptr(),
                a.stride as isize,
                1,
                b.data.as_ptr(),
                b.stride as isize,
                1,
                beta,
                c.as_mut_ptr(),
                n as isize,
                1,
            );
        },
    }
    GEMM_CLOCK.add(2.0 * (m * k * n) as f64, start.elapsed());
}

/// The flops and the seconds spent inside the GEMM calls of this process, summed over threads:
/// the GEMM part's own rate (the "GEMM part", against numpy's DGEMM), beside the whole
/// job's. Two clock reads per call, against the 10⁵–10⁸ flops of a call.
pub struct GemmClock {
    flops: std::sync::atomic::AtomicU64,
    nanos: std::sync::atomic::AtomicU64,
}

/// The process's [`GemmClock`].
pub static GEMM_CLOCK: GemmClock = GemmClock {
    flops: std::sync::atomic::AtomicU64::new(0),
    nanos: std::sync::atomic::AtomicU64::new(0),
};

impl GemmClock {
    fn add(&self, flops: f64, time: std::time::Duration) {
        use std::sync::atomic::Ordering::Relaxed;
        self.flops.fetch_add(flops as u64, Relaxed);
        self.nanos.fetch_add(time.as_nanos() as u64, Relaxed);
    }

    /// (flops, seconds) so far; the difference of two readings times the calls between them.
    pub fn read(&self) -> (f64, f64) {
        use std::sync::atomic::Ordering::Relaxed;
        let (f, n) = (self.flops.load(Relaxed), self.nanos.load(Relaxed));
        (f as f64, n as f64 * 1e-9)
    }
}

/// C (m × n, contiguous) = A (m × k, contiguous) · B (k × n with row stride `ldb`) through
/// `which`, as the products call it. Public for the GEMM benchmark (benches/mie.rs), which
/// times the two GEMMs at the products' shapes.
#[allow(clippy::too_many_arguments)]
pub fn gemm_strided(
    which: Gemm,
    m: usize,
    k: usize,
    n: usize,
    a: &[f64],
    b: &[f64],
    ldb: usize,
    c: &mut [f64],
) {
    gemm_with(
        which,
        m,
        k,
        n,
        Strided::new(a, k),
        Strided::new(b, ldb),
        0.0,
        c,
    );
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The GEMM clock counts a call's 2 m k n flops (at least: tests running beside this one
    /// may add theirs) and some time, through either GEMM.
    #[test]
    fn the_gemm_clock_counts_every_call() {
        let (m, k, n) = (4, 3, 5);
        let (a, b) = (vec![1.0; m * k], vec![2.0; k * n]);
        for which in [Gemm::Faer, Gemm::MatrixMultiply] {
            let mut c = vec![0.0; m * n];
            let before = GEMM_CLOCK.read();
            gemm_strided(which, m, k, n, &a, &b, n, &mut c);
            let after = GEMM_CLOCK.read();
            assert!(after.0 - before.0 >= (2 * m * k * n) as f64, "{which:?}");
            assert!(after.1 > before.1, "{which:?}");
            assert!(c.iter().all(|&v| v == 6.0));
        }
    }

    /// Every sphere's own terms lie within the orders its steps give it, the steps' orders
    /// grow, and the last step reaches the block's largest term count.
    #[test]
    fn term_steps_cover_every_sphere() {
        let cases: [&[usize]; 4] = [
            &[5],
            &[3, 3, 3, 3, 3, 3, 3, 3, 3, 3],
            &[
                10, 11, 12, 20, 21, 22, 23, 40, 41, 60, 61, 62, 63, 64, 65, 66, 90,
            ],
            &[1, 1, 1, 1, 1, 1, 1, 1, 200],
        ];
        for terms in cases {
            let steps = term_steps(terms);
            assert_eq!(steps[0].0, 0);
            assert_eq!(steps.last().unwrap().1, *terms.last().unwrap());
            assert!(steps.windows(2).all(|s| s[0].0 < s[1].0 && s[0].1 < s[1].1));
            for (p, &n) in terms.iter().enumerate() {
                let reach = steps
                    .iter()
                    .filter(|s| s.0 <= p)
                    .map(|s| s.1)
                    .max()
                    .unwrap();
                assert!(
                    reach >= n,
                    "sphere {p} needs {n} terms, gets {reach}: {steps:?}"
                );
            }
        }
    }
}
