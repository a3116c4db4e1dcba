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

/// The angle basis of the batched sums, for orders 1..=`n_max` and the angles `mu`:
/// `u[n−1][j] = π_n(μ_j) + τ_n(μ_j)` and `v[n−1][j] = π_n(μ_j) − τ_n(μ_j)`, row-major with
/// one row per order, so that the first K orders are one contiguous K × n_angles matrix.
///
/// With these, S1 + S2 = Σ c_n (a_n + b_n) u_n and S1 − S2 = Σ c_n (a_n − b_n) v_n, and
/// (|S1|² + |S2|²)/2 = (|S1 + S2|² + |S1 − S2|²)/4: half the work of summing S1 and S2.
pub struct AngleBasis {
    /// μ = cos θ of every angle.
    pub mu: Vec<f64>,
    /// Highest tabulated order.
    pub n_max: usize,
    /// π_n + τ_n, shape n_max × n_angles, row-major.
    pub u: Vec<f64>,
    /// π_n − τ_n, shape n_max × n_angles, row-major.
    pub v: Vec<f64>,
}

impl AngleBasis {
    /// Tabulates orders 1..=n_max at the given μ (in parallel over angles).
    pub fn new(mu: &[f64], n_max: usize) -> Self {
        use rayon::prelude::*;
        let n_ang = mu.len();
        let columns: Vec<(Vec<f64>, Vec<f64>)> = mu
            .par_iter()
            .map(|&m| {
                let mut rec = PiTau::new(m);
                (0..n_max)
                    .map(|_| rec.next_order())
                    .map(|(p, t)| (p + t, p - t))
                    .unzip()
            })
            .collect();
        let mut u = vec![0.0; n_max * n_ang];
        let mut v = vec![0.0; n_max * n_ang];
        for (j, (cu, cv)) in columns.iter().enumerate() {
            for n in 0..n_max {
                u[n * n_ang + j] = cu[n];
                v[n * n_ang + j] = cv[n];
            }
        }
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
}
