//! Where a pixel's rays go (antialiasing): the path tracer integrates the radiance over each
//! pixel, so a fast render's pixel is a quadrature of that integral over the rays it marches.
//!
//! - `grid`: n × n rays at the centres of an n × n grid of sub-pixels, weighed equally (the
//!   midpoint rule); n² marches a pixel.
//! - `rooks`: n of those cells, one in each row and each column; n marches a pixel.
//! - `quincunx`: one ray through each pixel corner, shared by the four pixels that meet there
//!   (⅛ each), and one through the pixel's centre (½); about two marches a pixel. (The corners
//!   alone, the trapezoid rule at one march a pixel, measured worse than one ray through the
//!   centre: docs/collector.md, "Frame cost".)

use serde::Serialize;

/// Where a pixel's rays go, with n = `rays`.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize)]
#[serde(rename_all = "snake_case")]
pub enum RayPattern {
    /// n² rays, at the centres of an n × n grid of sub-pixels.
    Grid,
    /// n rays, one in each row and each column of that grid (n-rooks): ray k in column k and
    /// row k·s mod n, s the largest step below n/2 + 1 coprime with n (n = 2: the diagonal).
    /// Half the march of the 2 × 2 grid.
    Rooks,
    /// A ray through each pixel corner, shared by the four pixels that meet there (⅛ each),
    /// and one through the pixel's centre (½): about two marches a pixel (n is not used).
    Quincunx,
}

impl RayPattern {
    /// The sub-pixel offsets (u, v) ∈ (0, 1)² of the rays a pixel marches alone, for n = `n`.
    pub(super) fn offsets(self, n: usize) -> Vec<(f64, f64)> {
        let at =
            |col: usize, row: usize| ((col as f64 + 0.5) / n as f64, (row as f64 + 0.5) / n as f64);
        match self {
            RayPattern::Grid => (0..n * n).map(|k| at(k % n, k / n)).collect(),
            RayPattern::Rooks => {
                let step = (1..=n / 2 + 1).rev().find(|&s| gcd(s, n) == 1).unwrap_or(1);
                (0..n).map(|k| at(k, k * step % n)).collect()
            }
            RayPattern::Quincunx => vec![(0.5, 0.5)],
        }
    }

    /// The weight of each of a pixel's own rays and of each of its four corner rays, for
    /// `own` rays of its own.
    pub(super) fn weights(self, own: usize) -> (f64, f64) {
        match self {
            RayPattern::Grid | RayPattern::Rooks => (1.0 / own as f64, 0.0),
            RayPattern::Quincunx => (0.5, 0.125),
        }
    }

    /// Whether pixels share rays at their corners.
    pub(super) fn corners(self) -> bool {
        self == RayPattern::Quincunx
    }
}

fn gcd(a: usize, b: usize) -> usize {
    if b == 0 {
        a
    } else {
        gcd(b, a % b)
    }
}

#[cfg(test)]
mod tests {
    use super::RayPattern;

    /// The rooks put one ray in each row and each column of the n × n grid (n = 2: the
    /// diagonal), at the grid's cell centres; the grid takes every cell once.
    #[test]
    fn the_rooks_take_each_row_and_column_once() {
        assert_eq!(
            RayPattern::Rooks.offsets(2),
            vec![(0.25, 0.25), (0.75, 0.75)]
        );
        for n in 1..=8 {
            let cell = |x: f64| (x * n as f64 - 0.5).round() as usize;
            let rooks = RayPattern::Rooks.offsets(n);
            assert_eq!(rooks.len(), n);
            let mut rows: Vec<usize> = rooks.iter().map(|&(_, v)| cell(v)).collect();
            let cols: Vec<usize> = rooks.iter().map(|&(u, _)| cell(u)).collect();
            rows.sort_unstable();
            assert_eq!(rows, (0..n).collect::<Vec<_>>(), "n = {n}: rows");
            assert_eq!(cols, (0..n).collect::<Vec<_>>(), "n = {n}: columns");
            let mut grid: Vec<(usize, usize)> = RayPattern::Grid
                .offsets(n)
                .iter()
                .map(|&(u, v)| (cell(u), cell(v)))
                .collect();
            grid.sort_unstable();
            grid.dedup();
            assert_eq!(grid.len(), n * n, "n = {n}: grid");
        }
    }

    /// Every pattern's weights sum to one over a pixel's rays (its own and four corners).
    #[test]
    fn the_weights_sum_to_one() {
        for p in [RayPattern::Grid, RayPattern::Rooks, RayPattern::Quincunx] {
            for n in 1..=4 {
                let own = p.offsets(n).len();
                let (w_own, w_corner) = p.weights(own);
                let total = own as f64 * w_own + 4.0 * w_corner;
                assert!((total - 1.0).abs() < 1e-15, "{p:?}, n = {n}: {total}");
            }
        }
    }
}
