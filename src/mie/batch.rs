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
use super::sphere::{n_terms, MieCoefficients};
use num_complex::Complex64;
use rayon::prelude::*;

/// Spheres per block of the first product (2 rows each per matrix, so M = 128).
const BLOCK: usize = 64;
/// Spheres per chunk of the accumulating product.
const CHUNK: usize = 512;
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
    /// Multiply–adds × 2 spent in the matrix products.
    pub flops: f64,
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

impl WeightRow {
    fn end(&self) -> usize {
        self.start + self.weights.len()
    }
}

/// `out (n_rows × n_θ) = W · I` with I the intensities (|S1|² + |S2|²)/2 of `particles` at
/// the angles of `basis` and W the sparse `rows`. Particles are processed in the order given,
/// in blocks of [`BLOCK`]: consecutive particles should have similar x (each block pays for
/// its largest). `progress` is called with the number of spheres finished so far.
pub fn weighted_intensity(
    particles: &[Particle],
    rows: &[WeightRow],
    basis: &AngleBasis,
    progress: &(dyn Fn(usize) + Sync),
) -> (Vec<f64>, Work) {
    let n_p = particles.len();
    let n_ang = basis.n_angles();
    assert!(
        rows.iter().all(|r| r.end() <= n_p),
        "weight rows must lie within the particles"
    );
    let mut out = vec![0.0; rows.len() * n_ang];
    let mut work = Work {
        flops: 0.0,
        spheres: n_p,
    };
    let mut intensity = vec![0.0; CHUNK * n_ang];
    for c0 in (0..n_p).step_by(CHUNK) {
        let chunk = &particles[c0..(c0 + CHUNK).min(n_p)];
        let block_rows = &mut intensity[..chunk.len() * n_ang];
        work.flops += block_rows
            .par_chunks_mut(BLOCK * n_ang)
            .zip(chunk.par_chunks(BLOCK))
            .map(|(dst, block)| block_intensity(block, basis, dst))
            .sum::<f64>();
        work.flops += accumulate(&mut out, rows, c0, block_rows, n_ang);
        progress(c0 + chunk.len());
    }
    (out, work)
}

/// Writes the intensities of `block` (sorted by x) into `rows` (b × n_θ); returns the flops.
fn block_intensity(block: &[Particle], basis: &AngleBasis, rows: &mut [f64]) -> f64 {
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
    for (p, part) in block.iter().enumerate() {
        let coef = MieCoefficients::new(part.m, part.x);
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
    let mut sp = vec![0.0; 2 * b * n_ang];
    let mut sm = vec![0.0; 2 * b * n_ang];
    gemm(2 * b, k, n_ang, &cp, &basis.u[..k * n_ang], &mut sp, 0.0);
    gemm(2 * b, k, n_ang, &cm, &basis.v[..k * n_ang], &mut sm, 0.0);
    for p in 0..b {
        let row = &mut rows[p * n_ang..(p + 1) * n_ang];
        let (pr, pi) = (&sp[2 * p * n_ang..], &sp[(2 * p + 1) * n_ang..]);
        let (mr, mi) = (&sm[2 * p * n_ang..], &sm[(2 * p + 1) * n_ang..]);
        for j in 0..n_ang {
            row[j] = 0.25 * (pr[j] * pr[j] + pi[j] * pi[j] + mr[j] * mr[j] + mi[j] * mi[j]);
        }
    }
    2.0 * 2.0 * (2 * b * k * n_ang) as f64
}

/// `out[r] += Σ_p W[r, c0 + p] · chunk[p]` for the rows that weigh particles of this chunk,
/// as one matrix product split into column panels; returns the flops.
fn accumulate(out: &mut [f64], rows: &[WeightRow], c0: usize, chunk: &[f64], n_ang: usize) -> f64 {
    let kc = chunk.len() / n_ang;
    let c1 = c0 + kc;
    let active: Vec<usize> = (0..rows.len())
        .filter(|&r| rows[r].start < c1 && rows[r].end() > c0)
        .collect();
    let na = active.len();
    let mut w = vec![0.0; na * kc];
    for (a, &r) in active.iter().enumerate() {
        let row = &rows[r];
        for p in row.start.max(c0)..row.end().min(c1) {
            w[a * kc + p - c0] = row.weights[p - row.start];
        }
    }
    // Panels: each is a product over the same K in the same order, so splitting the columns
    // does not change a single bit of the result.
    let panels: Vec<(usize, Vec<f64>)> = (0..n_ang.div_ceil(PANEL))
        .into_par_iter()
        .map(|q| {
            let (j0, j1) = (q * PANEL, ((q + 1) * PANEL).min(n_ang));
            let mut c = vec![0.0; na * (j1 - j0)];
            gemm_strided(na, kc, j1 - j0, &w, &chunk[j0..], n_ang, &mut c);
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
    2.0 * (na * kc * n_ang) as f64
}

/// C (m × n) = A (m × k) · B (k × n) + beta C, all row-major and contiguous.
fn gemm(m: usize, k: usize, n: usize, a: &[f64], b: &[f64], c: &mut [f64], beta: f64) {
    assert!(a.len() >= m * k && b.len() >= k * n && c.len() >= m * n);
    // SAFETY: the slices hold m×k, k×n and m×n elements with the strides given.
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
            n as isize,
            1,
            beta,
            c.as_mut_ptr(),
            n as isize,
            1,
        );
    }
}

/// C (m × n, contiguous) = A (m × k, contiguous) · B (k × n with row stride `ldb`).
fn gemm_strided(m: usize, k: usize, n: usize, a: &[f64], b: &[f64], ldb: usize, c: &mut [f64]) {
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
