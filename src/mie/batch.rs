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
}

impl BlockCoefficients {
    fn new(block_idx: &[usize], particles: &[Particle], basis: &AngleBasis) -> Self {
        let b = block_idx.len();
        let k = block_idx
            .iter()
            .map(|&i| n_terms(particles[i].x))
            .max()
            .unwrap_or(1);
        assert!(
            k <= basis.n_max,
            "angle basis has {} orders, sphere needs {k}",
            basis.n_max
        );
        let mut plus = vec![0.0; 2 * b * k];
        let mut minus = vec![0.0; 2 * b * k];
        let mut efficiencies = Vec::with_capacity(b);
        for (p, &i) in block_idx.iter().enumerate() {
            let coef = MieCoefficients::new(particles[i].m, particles[i].x);
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
        }
    }

    /// The two products' flops over `n_ang` angles, the zero padding of short series included.
    fn flops(&self, n_ang: usize) -> f64 {
        2.0 * 2.0 * (2 * self.spheres * self.terms * n_ang) as f64
    }
}

/// W · I of one chunk on the angles of the basis's panel `q`: the blocks' intensities there,
/// then their weighted sums, in scratch memory of the thread (reused: fresh multi-megabyte
/// buffers cost more in page faults than the products themselves for small droplets); with the
/// panel's first angle.
fn chunk_panel(
    blocks: &[BlockCoefficients],
    basis: &AngleBasis,
    weights: &ChunkWeights,
    q: usize,
) -> (usize, Vec<f64>) {
    let (columns, u, v) = basis.panel(q);
    let width = columns.len();
    let spheres: usize = blocks.iter().map(|b| b.spheres).sum();
    SCRATCH.with_borrow_mut(|(sp, sm, intensity)| {
        intensity.resize(spheres * width, 0.0);
        let mut rows = &mut intensity[..spheres * width];
        for block in blocks {
            let (b, k) = (block.spheres, block.terms);
            let (mine, rest) = rows.split_at_mut(b * width);
            rows = rest;
            sp.resize(2 * b * width, 0.0);
            sm.resize(2 * b * width, 0.0);
            gemm_strided(2 * b, k, width, &block.plus, &u[..k * width], width, sp);
            gemm_strided(2 * b, k, width, &block.minus, &v[..k * width], width, sm);
            squared_sum(b, width, sp, sm, mine);
        }
        (
            columns.start,
            weights.apply(&intensity[..spheres * width], width),
        )
    })
}

thread_local! {
    static SCRATCH: std::cell::RefCell<(Vec<f64>, Vec<f64>, Vec<f64>)> =
        const { std::cell::RefCell::new((Vec::new(), Vec::new(), Vec::new())) };
}

/// rows[p] = (|S1 + S2|² + |S1 − S2|²)/4 from the [Re; Im] rows of both products (`width`
/// angles each).
fn squared_sum(b: usize, width: usize, sp: &[f64], sm: &[f64], rows: &mut [f64]) {
    for p in 0..b {
        let row = &mut rows[p * width..(p + 1) * width];
        let (pr, pi) = (&sp[2 * p * width..], &sp[(2 * p + 1) * width..]);
        let (mr, mi) = (&sm[2 * p * width..], &sm[(2 * p + 1) * width..]);
        for j in 0..width {
            row[j] = 0.25 * (pr[j] * pr[j] + pi[j] * pi[j] + mr[j] * mr[j] + mi[j] * mi[j]);
        }
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
        Self {
            active,
            w,
            kc,
            nnz,
            sparse,
        }
    }

    /// W · I on one panel: `intensity` is kc × `width` (the chunk's spheres in order); the
    /// result active × `width`.
    fn apply(&self, intensity: &[f64], width: usize) -> Vec<f64> {
        let (na, kc) = (self.active.len(), self.kc);
        let mut c = vec![0.0; na * width];
        if self.sparse {
            for (a, c_row) in c.chunks_mut(width).enumerate() {
                for (p, &wp) in self.w[a * kc..(a + 1) * kc]
                    .iter()
                    .enumerate()
                    .filter(|(_, v)| **v != 0.0)
                {
                    let src = &intensity[p * width..(p + 1) * width];
                    c_row.iter_mut().zip(src).for_each(|(d, s)| *d += wp * s);
                }
            }
        } else {
            gemm_strided(na, kc, width, &self.w, intensity, width, &mut c);
        }
        c
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

/// C (m × n, contiguous) = A (m × k, contiguous) · B (k × n with row stride `ldb`), through
/// matrixmultiply's dgemm (its kernels are picked at run time: AVX-512, AVX2/FMA, SSE2). Public
/// for the GEMM benchmark (benches/mie.rs), which times this very call against the `gemm` crate.
pub fn gemm_strided(m: usize, k: usize, n: usize, a: &[f64], b: &[f64], ldb: usize, c: &mut [f64]) {
    if m == 0 || n == 0 {
        return;
    }
    assert!(a.len() >= m * k && c.len() >= m * n && b.len() >= (k - 1) * ldb + n);
    // SAFETY: bounds checked just above.
    unsafe {
        matrixmultiply::dgemm(
            m,
            k,
            n,
            1.0,
            a.as_ptr(),
            k as isize,
            1,
            b.as_ptr(),
            ldb as isize,
            1,
            0.0,
            c.as_mut_ptr(),
            n as isize,
            1,
        );
    }
}
