//! Majorants for delta and ratio tracking: one constant, or a coarse grid of per-cell bounds
//! σ̄_c ≥ max σ_t over cell c, walked cell by cell along a ray (a 3D DDA).
//!
//! Why a grid: with one global σ̄ a ray through empty space or thin edges still stops every
//! 1/σ̄ metres to evaluate σ_t (for the implicit cloud, five octaves of noise each time). Free
//! flights are memoryless, so a flight may be restarted at every cell boundary with the next
//! cell's σ̄: on a segment [a, b] with bound σ̄ the tentative collisions are a Poisson process of
//! rate σ̄, and a cell with σ̄ = 0 is skipped outright. Any σ̄_c ≥ σ_t keeps both estimators
//! unbiased; tighter bounds only make them cheaper.
//!
//! Each cell also holds a minorant σ_c ≤ min σ_t. Where σ_c = σ̄_c the cell is homogeneous:
//! every tentative collision there is real and its transmittance is exp(−σ̄ Δt) in closed form,
//! with no σ_t lookups at all (the deep interior of the implicit cloud, a homogeneous slab).

use super::geometry::{Affine, Vec3};
use std::ops::ControlFlow;

/// Bounds on σ_t over a cell (1/m).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Bounds {
    /// σ_c ≤ σ_t.
    pub min: f64,
    /// σ̄_c ≥ σ_t.
    pub max: f64,
}

impl Bounds {
    /// Whether σ_t is known exactly (= max) in the cell.
    pub fn homogeneous(&self) -> bool {
        self.min >= self.max
    }
}

/// The majorants of a medium.
pub enum Majorants<'a> {
    /// One pair of bounds everywhere.
    Constant(Bounds),
    /// Per-cell bounds.
    Grid(&'a MajorantGrid),
}

impl Majorants<'_> {
    /// Calls `f(a, b, bounds)` on consecutive segments [a, b] of [t0, t1] along o + t w, in
    /// order, until it breaks; returns the break value.
    pub fn walk<B>(
        &self,
        o: Vec3,
        w: Vec3,
        (t0, t1): (f64, f64),
        mut f: impl FnMut(f64, f64, Bounds) -> ControlFlow<B>,
    ) -> Option<B> {
        match self {
            Majorants::Constant(m) => f(t0, t1, *m).break_value(),
            Majorants::Grid(g) => g.walk(o, w, (t0, t1), f),
        }
    }
}

/// Bounds on a regular grid of cells over the box [lo, hi] (m).
pub struct MajorantGrid {
    lo: Vec3,
    cell: Vec3,
    n: [usize; 3],
    /// Bounds per cell, x fastest.
    values: Vec<Bounds>,
    /// The map of the grid's coordinates to the world, if they differ.
    to_world: Option<Affine>,
}

impl MajorantGrid {
    /// The grid of n[0] × n[1] × n[2] cells over [lo, hi], cell c's bounds `bound(c_lo, c_hi)`.
    pub fn build(
        lo: Vec3,
        hi: Vec3,
        n: [usize; 3],
        bound: impl Fn(Vec3, Vec3) -> Bounds + Sync,
    ) -> Self {
        use rayon::prelude::*;
        let cell: Vec3 = std::array::from_fn(|k| (hi[k] - lo[k]) / n[k] as f64);
        // Rows in parallel, collected in order: the same grid for any thread count.
        let values: Vec<Bounds> = (0..n[1] * n[2])
            .into_par_iter()
            .flat_map_iter(|row| {
                let (y, z) = (row % n[1], row / n[1]);
                let bound = &bound;
                (0..n[0]).map(move |x| {
                    let i = [x, y, z];
                    let c_lo: Vec3 = std::array::from_fn(|k| lo[k] + i[k] as f64 * cell[k]);
                    let c_hi: Vec3 = std::array::from_fn(|k| lo[k] + (i[k] + 1) as f64 * cell[k]);
                    bound(c_lo, c_hi)
                })
            })
            .collect();
        Self {
            lo,
            cell,
            n,
            values,
            to_world: None,
        }
    }

    /// The same grid placed in the world by `to_world` (rays are walked in grid coordinates).
    pub fn with_transform(self, to_world: Affine) -> Self {
        Self {
            to_world: Some(to_world),
            ..self
        }
    }

    /// The grid of blocks of `factor`³ cells (the last block along an axis may hold fewer),
    /// each bounded by the loosest bounds of its cells: the same medium bounded on fewer,
    /// larger cells (fewer cell faces along a ray, and a grid that stays in cache).
    pub fn coarsened(&self, factor: usize) -> Self {
        let factor = factor.max(1);
        let n = self.n.map(|m| m.div_ceil(factor));
        let empty = Bounds {
            min: f64::INFINITY,
            max: 0.0,
        };
        let mut blocks = Self {
            lo: self.lo,
            cell: self.cell.map(|c| c * factor as f64),
            n,
            values: vec![empty; n[0] * n[1] * n[2]],
            to_world: self.to_world,
        };
        for z in 0..self.n[2] {
            for y in 0..self.n[1] {
                for x in 0..self.n[0] {
                    let fine = self.values[self.index([x, y, z])];
                    let at = blocks.index([x, y, z].map(|i| i / factor));
                    let block = &mut blocks.values[at];
                    block.min = block.min.min(fine.min);
                    block.max = block.max.max(fine.max);
                }
            }
        }
        blocks
    }

    /// The cells along each axis.
    pub fn cells(&self) -> [usize; 3] {
        self.n
    }

    /// The bounds of the cell holding the world point `p` (clamped to the grid).
    pub fn at(&self, p: Vec3) -> Bounds {
        let p = self.to_world.map_or(p, |a| a.local_point(p));
        self.values[self.index(self.cell_of(p))]
    }

    /// The fractions of cells that are empty (σ̄ = 0) and homogeneous but not empty.
    pub fn fractions(&self) -> (f64, f64) {
        let n = self.values.len() as f64;
        let empty = self.values.iter().filter(|v| v.max == 0.0).count() as f64;
        let full = self
            .values
            .iter()
            .filter(|v| v.max > 0.0 && v.homogeneous())
            .count() as f64;
        (empty / n, full / n)
    }

    fn cell_of(&self, p: Vec3) -> [usize; 3] {
        std::array::from_fn(|k| {
            let x = ((p[k] - self.lo[k]) / self.cell[k]).floor();
            x.clamp(0.0, (self.n[k] - 1) as f64) as usize
        })
    }

    fn index(&self, i: [usize; 3]) -> usize {
        (i[2] * self.n[1] + i[1]) * self.n[0] + i[0]
    }

    /// The DDA: the cells o + t w crosses on [t0, t1] (which lies in the grid's box).
    fn walk<B>(
        &self,
        o: Vec3,
        w: Vec3,
        (t0, t1): (f64, f64),
        mut f: impl FnMut(f64, f64, Bounds) -> ControlFlow<B>,
    ) -> Option<B> {
        let (o, w) = match &self.to_world {
            Some(a) => (a.local_point(o), a.local_dir(w)),
            None => (o, w),
        };
        // The entry point may round to just outside the box: cell_of clamps it.
        let entry: Vec3 = std::array::from_fn(|k| o[k] + t0 * w[k]);
        let mut i = self.cell_of(entry);
        // Per axis, fixed along the ray: the face ahead of cell i is at i + ahead, a step adds
        // `step`, and the walk ends on leaving through `last` (so no branch on the direction
        // inside the loop; which axis steps next is the one thing left to chance).
        let ahead: [usize; 3] = std::array::from_fn(|k| usize::from(w[k] > 0.0));
        let step: [isize; 3] = std::array::from_fn(|k| if w[k] > 0.0 { 1 } else { -1 });
        let last: [usize; 3] = std::array::from_fn(|k| if w[k] > 0.0 { self.n[k] - 1 } else { 0 });
        // The t at which the ray leaves the current cell through each axis's next face.
        let next_face = |k: usize, i: usize| -> f64 {
            if w[k] == 0.0 {
                f64::INFINITY
            } else {
                (self.lo[k] + (i + ahead[k]) as f64 * self.cell[k] - o[k]) / w[k]
            }
        };
        let mut t_exit: Vec3 = std::array::from_fn(|k| next_face(k, i[k]));
        // And through the face after that: computed one step ahead, so that a step does not
        // wait for its division (unused past the last cell).
        let mut t_after: Vec3 =
            std::array::from_fn(|k| next_face(k, i[k].wrapping_add_signed(step[k])));
        let mut t = t0;
        loop {
            let k = first_exit(&t_exit);
            let end = t_exit[k].min(t1);
            if end > t {
                if let ControlFlow::Break(b) = f(t, end, self.values[self.index(i)]) {
                    return Some(b);
                }
                t = end;
            }
            // Past the segment's end, or about to step out of the grid.
            if t >= t1 || i[k] == last[k] {
                return None;
            }
            i[k] = i[k].wrapping_add_signed(step[k]);
            t_exit[k] = t_after[k];
            t_after[k] = next_face(k, i[k].wrapping_add_signed(step[k]));
        }
    }
}

/// The axis whose face the ray reaches first: the smallest t in f64's total order, the lowest
/// axis on a tie (as `min_by(total_cmp)`); total_cmp compares integers, without a branch.
#[inline(always)]
fn first_exit(t: &Vec3) -> usize {
    let ab = usize::from(t[1].total_cmp(&t[0]).is_lt());
    if t[2].total_cmp(&t[ab]).is_lt() {
        2
    } else {
        ab
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The walk covers [t0, t1] without gaps or overlaps and visits the cells the ray's points
    /// lie in.
    #[test]
    fn walk_tiles_the_segment_through_the_right_cells() {
        let g = MajorantGrid::build([0.0; 3], [4.0, 2.0, 3.0], [4, 3, 5], |lo, _| Bounds {
            min: 0.0,
            max: lo[0] * 100.0 + lo[1] * 10.0 + lo[2],
        });
        let rays = [
            ([-1.0, 0.3, 0.2], [1.0, 0.5, 0.7]),
            ([5.0, 1.9, 2.9], [-0.8, -0.3, -0.5]),
            ([2.0, 1.0, -1.0], [0.0, 0.0, 1.0]),
            ([0.5, -1.0, 1.5], [0.3, 1.0, 0.0]),
        ];
        for (o, w) in rays {
            let w = super::super::geometry::normalize(w);
            let (t0, t1) = super::super::geometry::box_clip(o, w, [0.0; 3], [4.0, 2.0, 3.0])
                .expect("the ray meets the box");
            let mut t = t0;
            let mut segments = 0;
            g.walk(o, w, (t0, t1), |a, b, v| {
                assert!(
                    (a - t).abs() < 1e-12 && b > a,
                    "gap or overlap at {a} after {t}"
                );
                // (Segments of a rounding error's length, where the ray crosses an edge, may
                // have their midpoint in the neighbouring cell.)
                let mid: Vec3 = std::array::from_fn(|k| o[k] + 0.5 * (a + b) * w[k]);
                if b - a > 1e-9 {
                    assert_eq!(v, g.at(mid), "segment [{a}, {b}] has another cell's bound");
                }
                t = b;
                segments += 1;
                ControlFlow::<()>::Continue(())
            });
            assert!((t - t1).abs() < 1e-9, "the walk stopped at {t} before {t1}");
            assert!(segments >= 2);
        }
    }

    /// Each block of the coarsened grid bounds every cell it holds, by the loosest of their
    /// bounds, partial blocks at the ends included; blocks of one cell are the grid itself.
    #[test]
    fn coarsened_blocks_hold_their_cells_bounds() {
        let g = MajorantGrid::build([0.0; 3], [7.0, 5.0, 3.0], [7, 5, 3], |lo, _| Bounds {
            min: lo[0] + lo[1],
            max: 1.0 + lo[0] * lo[1] + lo[2],
        });
        let same = g.coarsened(1);
        assert_eq!((same.n, &same.values), (g.n, &g.values));
        let c = g.coarsened(2);
        assert_eq!(c.cells(), [4, 3, 2]);
        for z in 0..3 {
            for y in 0..5 {
                for x in 0..7 {
                    let p = [x as f64 + 0.5, y as f64 + 0.5, z as f64 + 0.5];
                    let (fine, block) = (g.at(p), c.at(p));
                    assert!(block.min <= fine.min && fine.max <= block.max);
                }
            }
        }
        // The block of cells x ∈ {2, 3}, y ∈ {0, 1}, z ∈ {2}: its loosest bounds.
        let block = c.at([3.0, 1.0, 2.5]);
        assert_eq!((block.min, block.max), (2.0, 1.0 + 3.0 + 2.0));
    }
}
