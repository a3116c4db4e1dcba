//! Lorenz–Mie scattering by one homogeneous sphere.
//!
//! Conventions (Bohren & Huffman 1983, time dependence e^{−iωt}):
//! - relative refractive index `m = n + i k`, with `k ≥ 0` meaning absorption. MIEV0 and
//!   miepython write `m = n − i k`; their a_n, b_n, S1, S2 are the complex conjugates of ours;
//!   every real quantity (Q, g, |S|²) is identical;
//! - size parameter `x = π d n_medium / λ`;
//! - `S1, S2` are the dimensionless amplitudes of Bohren & Huffman: the differential scattering
//!   cross-section of unpolarised light is `(|S1|² + |S2|²) / (2 k²)`.
//!
//! Numerics: logarithmic derivatives D_n(z) = ψ_n'(z)/ψ_n(z) by downward recurrence, for the
//! sphere (z = m x) and for the medium (z = x); ψ_n(x) by Miller's downward recurrence,
//! normalised to the exact ψ_0 or ψ_1, which keeps full relative precision for tiny x, for
//! n > x and at the zeros of ψ_n (x = kπ makes ψ_0 vanish: ratio methods fail there);
//! the growing Riccati–Bessel η_n = x y_n(x) by upward recurrence. The numerators of a_n, b_n
//! are written as ψ_n (D_n(mx)/m − D_n(x)) and ψ_n (m D_n(mx) − D_n(x)), which removes the
//! cancellation of the textbook form at small x.

use num_complex::Complex64;
use std::array::from_fn;

/// Number of terms of the Mie series: Wiscombe (1980), N = x + 4.05 x^{1/3} + 2.
///
/// This is the larger of Wiscombe's two rules (it also covers x ≤ 8, where
/// x + 4 x^{1/3} + 1 would do) and the one miepython uses, so the series agree term for term.
pub fn n_terms(x: f64) -> usize {
    ((x + 4.05 * x.cbrt() + 2.0) as usize).max(1)
}

/// The Mie coefficients a_n, b_n (n = 1..=N, stored at index n − 1) of one sphere.
#[derive(Clone, Debug)]
pub struct MieCoefficients {
    /// Size parameter x = π d / λ (medium wavelength).
    pub x: f64,
    /// Electric multipole coefficients a_n.
    pub a: Vec<Complex64>,
    /// Magnetic multipole coefficients b_n.
    pub b: Vec<Complex64>,
}

/// Integral quantities of one sphere; efficiencies are cross-sections over π r².
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct Efficiencies {
    /// Extinction efficiency Q_ext.
    pub q_ext: f64,
    /// Scattering efficiency Q_sca.
    pub q_sca: f64,
    /// Backscattering efficiency Q_back = 4 |S(180°)|² / x² (radar convention of B&H).
    pub q_back: f64,
    /// Asymmetry parameter g = ⟨cos θ⟩.
    pub g: f64,
}

/// Logarithmic derivatives D_n(z) for n = 0..=n_max, by downward recurrence
/// D_{n−1} = n/z − 1/(D_n + n/z) from D_start = 0, started `start − n_max` orders above; for L
/// arguments at once, each with its own n_max (the recurrences are chains of divisions: side by
/// side, their latencies overlap; each lane's operations are those of a lone call).
///
/// The recurrence is stable downward, and the error of the arbitrary start value shrinks like
/// ψ_start/χ_start, which only becomes tiny some turning-point widths (|z|/2)^{1/3} above |z|:
/// BHMIE's classic "max(N, |z|) + 15" leaves errors of 1e-6 at |z| ≈ 130 with Im z ≈ 0. We
/// start [`start_order`] orders up, where that ratio is below 1e-17.
fn log_derivative<const L: usize>(z: [Complex64; L], n_max: [usize; L]) -> [Vec<Complex64>; L] {
    let start: [usize; L] = from_fn(|l| start_order(n_max[l], z[l].norm()));
    let mut d: [Vec<Complex64>; L] = from_fn(|l| vec![Complex64::new(0.0, 0.0); n_max[l] + 1]);
    let mut dn = [Complex64::new(0.0, 0.0); L];
    let inv_z: [Complex64; L] = from_fn(|l| 1.0 / z[l]);
    for n in (1..=start.into_iter().max().unwrap_or(0)).rev() {
        for l in (0..L).filter(|&l| n <= start[l]) {
            let nz = inv_z[l] * n as f64;
            dn[l] = nz - 1.0 / (dn[l] + nz);
            if n - 1 <= n_max[l] {
                d[l][n - 1] = dn[l];
            }
        }
    }
    d
}

/// First order of the downward recurrences: max(N, |z|) + 16 + 10 (|z|/2)^{1/3}.
///
/// Above the turning point n ≈ |z| the Debye asymptotics give ψ_n/χ_n ≈ exp(−(4/3) t^{3/2})
/// with t = (n − |z|)/(|z|/2)^{1/3}; t ≥ 10 puts it below 1e-18.
fn start_order(n_max: usize, z_abs: f64) -> usize {
    let width = (0.5 * z_abs).cbrt();
    n_max.max(z_abs.ceil() as usize) + 16 + (10.0 * width).ceil() as usize
}

/// Riccati–Bessel ψ_n(x) = x j_n(x) for n = 0..=n_max by Miller's algorithm: the downward
/// recurrence ψ_{n−1} = ((2n + 1)/x) ψ_n − ψ_{n+1} from an arbitrary start far above
/// max(n_max, x), rescaled on the way to stay in range, then normalised by whichever of the
/// exact ψ_0 = sin x and ψ_1 = sin x / x − cos x is larger in magnitude (both never vanish
/// together, and ψ_0 is the larger one for small x, where ψ_1 would lose digits). L arguments
/// side by side, as [`log_derivative`].
fn riccati_psi<const L: usize>(x: [f64; L], n_max: [usize; L]) -> [Vec<f64>; L] {
    let start: [usize; L] = from_fn(|l| start_order(n_max[l], x[l]));
    let mut psi: [Vec<f64>; L] = from_fn(|l| vec![0.0; n_max[l] + 1]);
    let (mut above, mut here) = ([0.0; L], [1e-200; L]);
    for n in (1..=start.into_iter().max().unwrap_or(0)).rev() {
        for l in (0..L).filter(|&l| n <= start[l]) {
            let below = (2 * n + 1) as f64 / x[l] * here[l] - above[l];
            (above[l], here[l]) = (here[l], below);
            if here[l].abs() > 1e200 {
                (above[l], here[l]) = (above[l] * 1e-200, here[l] * 1e-200);
                psi[l].iter_mut().for_each(|p| *p *= 1e-200);
            }
            if n - 1 <= n_max[l] {
                psi[l][n - 1] = here[l];
            }
        }
    }
    for (psi, x) in psi.iter_mut().zip(x) {
        let (s, c) = x.sin_cos();
        let psi1 = s / x - c;
        let scale = if s.abs() >= psi1.abs() {
            s / psi[0]
        } else {
            psi1 / psi[1]
        };
        psi.iter_mut().for_each(|p| *p *= scale);
    }
    psi
}

/// Real-argument version of [`log_derivative`] (for the medium side, z = x).
fn log_derivative_real<const L: usize>(x: [f64; L], n_max: [usize; L]) -> [Vec<f64>; L] {
    let start: [usize; L] = from_fn(|l| start_order(n_max[l], x[l]));
    let mut d: [Vec<f64>; L] = from_fn(|l| vec![0.0; n_max[l] + 1]);
    let mut dn = [0.0; L];
    for n in (1..=start.into_iter().max().unwrap_or(0)).rev() {
        for l in (0..L).filter(|&l| n <= start[l]) {
            let nx = n as f64 / x[l];
            dn[l] = nx - 1.0 / (dn[l] + nx);
            if n - 1 <= n_max[l] {
                d[l][n - 1] = dn[l];
            }
        }
    }
    d
}

impl MieCoefficients {
    /// Computes a_n, b_n for size parameter `x > 0` and relative index `m` (Im m ≥ 0).
    pub fn new(m: Complex64, x: f64) -> Self {
        Self::with_terms(m, x, n_terms(x))
    }

    /// Computes the first `n` coefficients (n ≥ 1).
    pub fn with_terms(m: Complex64, x: f64, n: usize) -> Self {
        let [coefficients] = Self::side_by_side([(m, x)], [n]);
        coefficients
    }

    /// [`Self::new`] of L spheres (m, x) at once: their downward recurrences run side by
    /// side, so that one sphere's chain of divisions overlaps another's (the same values, bit
    /// for bit, as one at a time).
    pub fn many<const L: usize>(spheres: [(Complex64, f64); L]) -> [Self; L] {
        Self::side_by_side(spheres, from_fn(|l| n_terms(spheres[l].1)))
    }

    fn side_by_side<const L: usize>(spheres: [(Complex64, f64); L], n: [usize; L]) -> [Self; L] {
        let x: [f64; L] = from_fn(|l| spheres[l].1);
        let dm = log_derivative(from_fn(|l| spheres[l].0 * x[l]), n);
        let dx = log_derivative_real(x, n);
        let psi = riccati_psi(x, n);
        from_fn(|l| Self::from_recurrences(spheres[l].0, x[l], &dm[l], &dx[l], &psi[l]))
    }

    /// a_n, b_n (n = 1 … dm.len() − 1) from D_n(mx), D_n(x) and ψ_n(x), with the growing
    /// η_n = x y_n(x) by upward recurrence.
    fn from_recurrences(m: Complex64, x: f64, dm: &[Complex64], dx: &[f64], psi: &[f64]) -> Self {
        let n = dm.len() - 1;
        let (sin_x, cos_x) = x.sin_cos();
        // ψ_{n−1}, ψ_n and η = x y: η_{−1}... start at n = 0: η_0 = −cos x, η_1 = −cos x / x − sin x.
        let mut psi_prev = psi[0];
        let mut eta_prev = -cos_x;
        let mut eta = -cos_x / x - sin_x;
        let mut a = Vec::with_capacity(n);
        let mut b = Vec::with_capacity(n);
        for k in 1..=n {
            let nx = k as f64 / x;
            let psi = psi[k];
            let xi = Complex64::new(psi, eta);
            let xi_prev = Complex64::new(psi_prev, eta_prev);
            let da = dm[k] / m;
            let db = dm[k] * m;
            a.push(psi * (da - dx[k]) / ((da + nx) * xi - xi_prev));
            b.push(psi * (db - dx[k]) / ((db + nx) * xi - xi_prev));
            let eta_next = (2 * k + 1) as f64 / x * eta - eta_prev;
            (psi_prev, eta_prev, eta) = (psi, eta, eta_next);
        }
        Self { x, a, b }
    }

    /// Q_ext, Q_sca, Q_back and g from the standard series (Bohren & Huffman §4.4–4.5).
    pub fn efficiencies(&self) -> Efficiencies {
        let (a, b) = (&self.a, &self.b);
        let inv_x2 = 1.0 / (self.x * self.x);
        let mut ext = 0.0;
        let mut sca = 0.0;
        let mut asym = 0.0;
        let mut back = Complex64::new(0.0, 0.0);
        for i in 0..a.len() {
            let n = (i + 1) as f64;
            let w = 2.0 * n + 1.0;
            ext += w * (a[i] + b[i]).re;
            sca += w * (a[i].norm_sqr() + b[i].norm_sqr());
            let sign = if i % 2 == 0 { -1.0 } else { 1.0 };
            back += sign * w * (a[i] - b[i]);
            asym += w / (n * (n + 1.0)) * (a[i] * b[i].conj()).re;
            if i + 1 < a.len() {
                asym += n * (n + 2.0) / (n + 1.0)
                    * (a[i] * a[i + 1].conj() + b[i] * b[i + 1].conj()).re;
            }
        }
        let q_sca = 2.0 * inv_x2 * sca;
        Efficiencies {
            q_ext: 2.0 * inv_x2 * ext,
            q_sca,
            q_back: inv_x2 * back.norm_sqr(),
            g: 4.0 * inv_x2 * asym / q_sca,
        }
    }

    /// Amplitudes (S1, S2) at μ = cos θ, by direct summation with the π_n, τ_n recurrence.
    ///
    /// For many angles and many spheres use [`crate::mie::batch`], which does the same sum as
    /// a matrix product.
    pub fn amplitudes(&self, mu: f64) -> (Complex64, Complex64) {
        let mut s1 = Complex64::new(0.0, 0.0);
        let mut s2 = Complex64::new(0.0, 0.0);
        let mut pi = crate::mie::angular::PiTau::new(mu);
        for i in 0..self.a.len() {
            let (p, t) = pi.next_order();
            let n = (i + 1) as f64;
            let c = (2.0 * n + 1.0) / (n * (n + 1.0));
            s1 += c * (self.a[i] * p + self.b[i] * t);
            s2 += c * (self.a[i] * t + self.b[i] * p);
        }
        (s1, s2)
    }
}
