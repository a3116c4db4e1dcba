//! Legendre polynomials P_0(x), P_1(x), … by Bonnet's recurrence
//!
//!   (n + 1) P_{n+1}(x) = (2n + 1) x P_n(x) − n P_{n−1}(x),   P_0 = 1, P_1 = x,
//!
//! the one recurrence of the project: the depth and ln t terms of the compressed forms, the
//! Legendre moments of phase functions and the Gauss–Legendre nodes all step through it.

use crate::real::Real;

/// P_0(x), P_1(x), … without end.
#[derive(Clone, Copy, Debug)]
pub struct Legendre<F> {
    x: F,
    prev: F,
    cur: F,
    n: usize,
}

impl<F: Real> Legendre<F> {
    /// The polynomials at `x`.
    pub fn new(x: F) -> Self {
        Self {
            x,
            prev: F::of(0.0),
            cur: F::of(1.0),
            n: 0,
        }
    }
}

impl<F: Real> Iterator for Legendre<F> {
    type Item = F;

    fn next(&mut self) -> Option<F> {
        let (p, n) = (self.cur, self.n);
        let next = if n == 0 {
            self.x
        } else {
            // (2n + 1)/(n + 1) and n/(n + 1) as constants: no division on the recurrence's
            // dependent chain (the runtime steps through it on every evaluation).
            let (a, b) = bonnet(n);
            F::of(a) * self.x * self.cur - F::of(b) * self.prev
        };
        (self.prev, self.cur, self.n) = (self.cur, next, n + 1);
        Some(p)
    }
}

/// (2n + 1)/(n + 1) and n/(n + 1): Bonnet's recurrence as P_{n+1} = a x P_n − b P_{n−1}.
#[inline(always)]
fn bonnet(n: usize) -> (f64, f64) {
    match BONNET.get(n) {
        Some(&ab) => ab,
        None => (
            (2 * n + 1) as f64 / (n + 1) as f64,
            n as f64 / (n + 1) as f64,
        ),
    }
}

/// P_0, P_1, … at `L` points side by side, each lane stepping as [`Legendre`] does (the same
/// operations in the same order, so the same bits), with the lanes' values in arrays rather
/// than in `L` separate steppers, so that they share a vector register.
#[derive(Clone, Copy, Debug)]
pub struct LegendreLanes<F, const L: usize> {
    x: [F; L],
    prev: [F; L],
    cur: [F; L],
    n: usize,
}

impl<F: Real, const L: usize> LegendreLanes<F, L> {
    /// The polynomials at the points `x`.
    #[inline(always)]
    pub fn new(x: [F; L]) -> Self {
        Self {
            x,
            prev: [F::of(0.0); L],
            cur: [F::of(1.0); L],
            n: 0,
        }
    }

    /// P_n of every lane, the recurrence then stepped on to P_{n+1}.
    #[inline(always)]
    pub fn next_row(&mut self) -> [F; L] {
        let (p, n) = (self.cur, self.n);
        let next = if n == 0 {
            self.x
        } else {
            let (a, b) = bonnet(n);
            let (a, b) = (F::of(a), F::of(b));
            core::array::from_fn(|i| a * self.x[i] * self.cur[i] - b * self.prev[i])
        };
        (self.prev, self.cur, self.n) = (self.cur, next, n + 1);
        p
    }
}

/// [`bonnet`] for n < 64.
const BONNET: [(f64, f64); 64] = {
    let mut t = [(0.0, 0.0); 64];
    let mut n = 0;
    while n < 64 {
        t[n] = (
            (2 * n + 1) as f64 / (n + 1) as f64,
            n as f64 / (n + 1) as f64,
        );
        n += 1;
    }
    t
};

#[cfg(test)]
mod tests {
    use super::*;

    /// The closed forms of P_2 … P_4, and P_n(1) = 1, P_n(−1) = (−1)ⁿ.
    #[test]
    fn matches_closed_forms_and_end_values() {
        for x in [-0.9f64, -0.3, 0.0, 0.4, 0.77] {
            let p: [f64; 5] = core::array::from_fn({
                let mut it = Legendre::new(x);
                move |_| it.next().unwrap_or(f64::NAN)
            });
            let closed = [
                1.0,
                x,
                0.5 * (3.0 * x * x - 1.0),
                0.5 * (5.0 * x * x * x - 3.0 * x),
                0.125 * (35.0 * x.powi(4) - 30.0 * x * x + 3.0),
            ];
            for (a, b) in p.iter().zip(closed) {
                assert!((a - b).abs() < 1e-14, "x = {x}: {a} vs {b}");
            }
        }
        for (n, (a, b)) in Legendre::new(1.0f64)
            .zip(Legendre::new(-1.0f64))
            .take(50)
            .enumerate()
        {
            assert!((a - 1.0).abs() < 1e-12 && (b - (-1f64).powi(n as i32)).abs() < 1e-12);
        }
    }

    /// Each lane of [`LegendreLanes`] is its own [`Legendre`], bit for bit.
    #[test]
    fn lanes_step_as_one_lane_does() {
        let x = [-1.0f32, -0.73, -0.2, -0.0, 0.0, 0.31, 0.999, 1.0];
        let mut lanes = LegendreLanes::new(x);
        let mut alone = x.map(Legendre::new);
        for _ in 0..40 {
            let row = lanes.next_row();
            for (v, one) in row.iter().zip(alone.iter_mut()) {
                assert_eq!(v.to_bits(), one.next().unwrap_or(f32::NAN).to_bits());
            }
        }
    }
}
