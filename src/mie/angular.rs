//! Angular functions π_n(μ), τ_n(μ) and the tabulated angle basis of the batched sums.
//!
//! π_n = P_n¹(μ)/sin θ and τ_n = dP_n¹/dθ obey (Bohren & Huffman eq. 4.47)
//!   π_n = ((2n − 1)/(n − 1)) μ π_{n−1} − (n/(n − 1)) π_{n−2},  π_0 = 0, π_1 = 1,
//!   τ_n = n μ π_n − (n + 1) π_{n−1}.
//! They depend on angle and order only, so for many spheres they are tabulated once.

/// Upward recurrence of (π_n, τ_n) at a fixed μ, one order per call, starting at n = 1.
pub struct PiTau {
    mu: f64,
    n: usize,
    pi_prev: f64,
    pi: f64,
}

impl PiTau {
    /// Starts the recurrence at μ = cos θ.
    pub fn new(mu: f64) -> Self {
        Self {
            mu,
            n: 0,
            pi_prev: 0.0,
            pi: 0.0,
        }
    }

    /// Returns (π_n, τ_n) for the next order n = 1, 2, ….
    pub fn next_order(&mut self) -> (f64, f64) {
        self.n += 1;
        let n = self.n as f64;
        let pi_n = if self.n == 1 {
            1.0
        } else {
            ((2.0 * n - 1.0) * self.mu * self.pi - n * self.pi_prev) / (n - 1.0)
        };
        let tau_n = n * self.mu * pi_n - (n + 1.0) * self.pi;
        self.pi_prev = self.pi;
        self.pi = pi_n;
        (pi_n, tau_n)
    }
}

/// Angles per panel of the basis: the batched sums run panel by panel (`batch.rs`), each on
/// one thread, so that a panel's rows stay in that core's cache (docs/mie.md, "Panels"). A
/// multiple of the GEMM kernels' widths.
pub const PANEL: usize = 128;

/// The angle basis of the batched sums, for orders 1..=`n_max` and the angles `mu`, in panels
/// of [`PANEL`] angles: within panel q (angles q·PANEL …, the last panel narrower), `u[n−1][j]
/// = π_n(μ_j) + τ_n(μ_j)` and `v[n−1][j] = π_n(μ_j) − τ_n(μ_j)`, row-major with one row per
/// order, so that a panel's first K orders are one contiguous K × width matrix.
///
/// With these, S1 + S2 = Σ c_n (a_n + b_n) u_n and S1 − S2 = Σ c_n (a_n − b_n) v_n, and
/// (|S1|² + |S2|²)/2 = (|S1 + S2|² + |S1 − S2|²)/4: half the work of summing S1 and S2.
pub struct AngleBasis {
    /// μ = cos θ of every angle.
    pub mu: Vec<f64>,
    /// Highest tabulated order.
    pub n_max: usize,
    /// π_n + τ_n, panel after panel, each n_max × width row-major.
    u: Vec<f64>,
    /// π_n − τ_n, the same layout.
    v: Vec<f64>,
}

impl AngleBasis {
    /// Tabulates orders 1..=n_max at the given μ (in parallel over panels; each panel's
    /// angles take the recurrence of [`PiTau`] side by side, order by order, the same
    /// operations in the same order).
    pub fn new(mu: &[f64], n_max: usize) -> Self {
        use rayon::prelude::*;
        let size = n_max * mu.len();
        let (mut u, mut v) = (vec![0.0; size], vec![0.0; size]);
        let per_panel = (n_max * PANEL).max(1);
        u.par_chunks_mut(per_panel)
            .zip(v.par_chunks_mut(per_panel))
            .zip(mu.par_chunks(PANEL))
            .for_each(|((u, v), mu)| tabulate_panel(mu, u, v));
        Self {
            mu: mu.to_vec(),
            n_max,
            u,
            v,
        }
    }

    /// Number of angles.
    pub fn n_angles(&self) -> usize {
        self.mu.len()
    }

    /// Number of panels.
    pub fn panels(&self) -> usize {
        self.mu.len().div_ceil(PANEL)
    }

    /// Panel `q`: its angles (indices into `mu`) and its u and v (n_max × width each).
    pub fn panel(&self, q: usize) -> (std::ops::Range<usize>, &[f64], &[f64]) {
        let columns = q * PANEL..((q + 1) * PANEL).min(self.mu.len());
        let at = q * PANEL * self.n_max..(q * PANEL + columns.len()) * self.n_max;
        (columns, &self.u[at.clone()], &self.v[at])
    }
}

/// π_n ± τ_n of the angles `mu` (one panel) for n = 1 … into the rows of `u` and `v`
/// (mu.len() wide): [`PiTau::next_order`] for every angle at once.
fn tabulate_panel(mu: &[f64], u: &mut [f64], v: &mut [f64]) {
    let width = mu.len();
    let (mut pi_prev, mut pi) = (vec![0.0; width], vec![0.0; width]);
    for (row, (u, v)) in u
        .chunks_exact_mut(width)
        .zip(v.chunks_exact_mut(width))
        .enumerate()
    {
        let n = (row + 1) as f64;
        for j in 0..width {
            let pi_n = if row == 0 {
                1.0
            } else {
                ((2.0 * n - 1.0) * mu[j] * pi[j] - n * pi_prev[j]) / (n - 1.0)
            };
            let tau_n = n * mu[j] * pi_n - (n + 1.0) * pi[j];
            pi_prev[j] = pi[j];
            pi[j] = pi_n;
            u[j] = pi_n + tau_n;
            v[j] = pi_n - tau_n;
        }
    }
}
