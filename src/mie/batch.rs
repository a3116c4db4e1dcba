//! Scattered intensity of many spheres at many angles as dense matrix products.
//!
//! For a block of spheres sorted by size parameter, with K the largest number of terms,
//!   [Re, Im] (S1 + S2) = C⁺ (2b × K) · U (K × n_θ),   C⁺_pn = c_n (a_n + b_n),
//!   [Re, Im] (S1 − S2) = C⁻ (2b × K) · V (K × n_θ),   C⁻_pn = c_n (a_n − b_n),
//! (U, V from [`AngleBasis`]; coefficients past a sphere's own N are zero), and
//!   i(θ) = (|S1|² + |S2|²)/2 = (|S1 + S2|² + |S1 − S2|²)/4.
//! The requested outputs are weighted sums over spheres, `out = W · I` (W sparse: each row
//! weighs a contiguous run of spheres), accumulated chunk by chunk with one more matrix
//! product. The chunking does not depend on the thread count and
//! every sum runs in a fixed order, so results are bit-identical for any number of threads.

use super::angular::AngleBasis;
use super::sphere::{n_terms, Efficiencies, MieCoefficients};
use num_complex::Complex64;
use rayon::prelude::*;

/// Spheres per block of the first product (2 rows each per matrix, so M = 256). The GEMM packs
/// the angle basis (k × n_θ) anew for every product: with 32 spheres that packing took 29 % of
/// the time, with 128 it takes 11 % (docs/mie.md, "Where the time goes").
pub const BLOCK: usize = 128;
/// Spheres per chunk of the accumulating product (eight blocks, for the threads to share).
const CHUNK: usize = 1024;
/// Columns per parallel panel of the accumulating product (a multiple of the kernel width).
const PANEL: usize = 256;

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
    let mut intensity = vec![0.0; CHUNK * n_ang];
    let mut terms_done = 0;
    for idx in order.chunks(CHUNK) {
        let block_rows = &mut intensity[..idx.len() * n_ang];
        let blocks: Vec<(f64, Vec<Efficiencies>)> = block_rows
            .par_chunks_mut(BLOCK * n_ang)
            .zip(idx.par_chunks(BLOCK))
            .map(|(dst, block_idx)| {
                let block: Vec<Particle> = block_idx.iter().map(|&i| particles[i]).collect();
                block_intensity(&block, basis, dst)
            })
            .collect();
        for ((flops, e), block_idx) in blocks.into_iter().zip(idx.chunks(BLOCK)) {
            work.flops += flops;
            for (&i, e) in block_idx.iter().zip(e) {
                eff[i] = e;
            }
        }
        let terms: usize = idx.iter().map(|&i| n_terms(particles[i].x)).sum();
        work.useful_flops += 8.0 * (terms * n_ang) as f64;
        let (done, useful) = accumulate(&mut out, rows, idx, block_rows, n_ang);
        work.flops += done;
        work.useful_flops += useful;
        terms_done += terms;
        progress(terms_done);
    }
    (out, eff, work)
}

/// Writes the intensities of `block` (sorted by x) into `rows` (b × n_θ); returns the flops
/// and the spheres' efficiencies.
fn block_intensity(
    block: &[Particle],
    basis: &AngleBasis,
    rows: &mut [f64],
) -> (f64, Vec<Efficiencies>) {
    let b = block.len();
    let n_ang = basis.n_angles();
    let k = block.iter().map(|p| n_terms(p.x)).max().unwrap_or(1);
    assert!(
        k <= basis.n_max,
        "angle basis has {} orders, sphere needs {k}",
        basis.n_max
    );
    let mut cp = vec![0.0; 2 * b * k];
    let mut cm = vec![0.0; 2 * b * k];
    let mut eff = Vec::with_capacity(b);
    for (p, part) in block.iter().enumerate() {
        let coef = MieCoefficients::new(part.m, part.x);
        eff.push(coef.efficiencies());
        for (i, (a, bn)) in coef.a.iter().zip(&coef.b).enumerate() {
            let n = (i + 1) as f64;
            let c = (2.0 * n + 1.0) / (n * (n + 1.0));
            let (sp, sm): (Complex64, Complex64) = (c * (a + bn), c * (a - bn));
            cp[2 * p * k + i] = sp.re;
            cp[(2 * p + 1) * k + i] = sp.im;
            cm[2 * p * k + i] = sm.re;
            cm[(2 * p + 1) * k + i] = sm.im;
        }
    }
    SCRATCH.with_borrow_mut(|(sp, sm)| {
        // Reused per thread: fresh multi-megabyte buffers cost more in page faults than the
        // products themselves for small droplets. The products overwrite them completely.
        sp.resize(2 * b * n_ang, 0.0);
        sm.resize(2 * b * n_ang, 0.0);
        gemm_strided(2 * b, k, n_ang, &cp, &basis.u[..k * n_ang], n_ang, sp);
        gemm_strided(2 * b, k, n_ang, &cm, &basis.v[..k * n_ang], n_ang, sm);
        squared_sum(b, n_ang, sp, sm, rows);
    });
    (2.0 * 2.0 * (2 * b * k * n_ang) as f64, eff)
}

thread_local! {
    static SCRATCH: std::cell::RefCell<(Vec<f64>, Vec<f64>)> = const { std::cell::RefCell::new((Vec::new(), Vec::new())) };
}

/// rows[p] = (|S1 + S2|² + |S1 − S2|²)/4 from the [Re; Im] rows of both products.
fn squared_sum(b: usize, n_ang: usize, sp: &[f64], sm: &[f64], rows: &mut [f64]) {
    for p in 0..b {
        let row = &mut rows[p * n_ang..(p + 1) * n_ang];
        let (pr, pi) = (&sp[2 * p * n_ang..], &sp[(2 * p + 1) * n_ang..]);
        let (mr, mi) = (&sm[2 * p * n_ang..], &sm[(2 * p + 1) * n_ang..]);
        for j in 0..n_ang {
            row[j] = 0.25 * (pr[j] * pr[j] + pi[j] * pi[j] + mr[j] * mr[j] + mi[j] * mi[j]);
        }
    }
}

/// `out[r] += Σ_p W[r, idx[p]] · chunk[p]` for the rows that weigh spheres of this chunk, as
/// one matrix product (or sparse row updates) split into column panels; returns the flops
/// done and the flops on non-zero weights.
fn accumulate<R: AsRef<WeightRow>>(
    out: &mut [f64],
    rows: &[R],
    idx: &[usize],
    chunk: &[f64],
    n_ang: usize,
) -> (f64, f64) {
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
    let na = active.len();
    let nnz = w.iter().filter(|&&v| v != 0.0).count();
    // A matrix product does ~4× more flops per second than row updates: below a quarter
    // filled (the product rule puts each sphere in one wavelength row), add the non-zeros one
    // by one. The choice depends on the data only, never on the thread count.
    let sparse = 4 * nnz < na * kc;
    // Panels: each is computed in the same order whatever the split, so splitting the columns
    // does not change a single bit of the result.
    let panels: Vec<(usize, Vec<f64>)> = (0..n_ang.div_ceil(PANEL))
        .into_par_iter()
        .map(|q| {
            let (j0, j1) = (q * PANEL, ((q + 1) * PANEL).min(n_ang));
            let width = j1 - j0;
            let mut c = vec![0.0; na * width];
            if sparse {
                for (a, c_row) in c.chunks_mut(width).enumerate() {
                    for (p, &wp) in w[a * kc..(a + 1) * kc]
                        .iter()
                        .enumerate()
                        .filter(|(_, v)| **v != 0.0)
                    {
                        let src = &chunk[p * n_ang + j0..p * n_ang + j1];
                        c_row.iter_mut().zip(src).for_each(|(d, s)| *d += wp * s);
                    }
                }
            } else {
                gemm_strided(na, kc, width, &w, &chunk[j0..], n_ang, &mut c);
            }
            (j0, c)
        })
        .collect();
    for (j0, c) in panels {
        let width = c.len() / na.max(1);
        for (a, &r) in active.iter().enumerate() {
            let dst = &mut out[r * n_ang + j0..r * n_ang + j0 + width];
            for (d, s) in dst.iter_mut().zip(&c[a * width..(a + 1) * width]) {
                *d += s;
            }
        }
    }
    let useful = 2.0 * (nnz * n_ang) as f64;
    (
        if sparse {
            useful
        } else {
            2.0 * (na * kc * n_ang) as f64
        },
        useful,
    )
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
