//! Tallies of one slice (t, μ_L) and their statistics.
//!
//! A photon crossing tally plane j with direction ω contributes to its cell (group, j, μ_V bin,
//! ψ_V bin) the vector w/|μ| · (1, x′, z, x′² + z²), where (x′, z) is the crossing point relative
//! to the photon's entry point (x′ across the sun's horizontal direction, mirrored with ψ_V;
//! z along it; below |μ| = ε the weight is 2w/ε, see `SlabGrid::crossing_weight`). With N
//! photons, L/E⊥ = μ_L Σ w/|μ| / (N ΔΩ) (each photon carries E⊥ μ_L per unit area of the lit
//! face, translation invariance turns the crossings of one photon column into a radiance), and
//! the collector is minus the displacement: c = −(X, Z)/W, σ² = Q/W − |c|².
//!
//! Standard errors come from batch means: every batch of B photons gives a vector v_b = (W, X,
//! Z, Q) per cell; the accumulator keeps Σ v_b and Σ v_b v_bᵀ, so a crossing-heavy photon counts
//! once, in its batch, and every output f(v̄) has SE² = ∇fᵀ Cov(v̄) ∇f (the delta method for
//! the ratios c and σ).

use super::grid::SlabGrid;
use crate::io::npz::{read_arrays, read_optional, Npz};
use anyhow::{bail, Result};
use std::path::Path;

/// The sums of one batch.
#[derive(Clone, Debug)]
pub struct BatchTally {
    /// Per cell: Σ w/|μ| · (1, x′, z, x′² + z²).
    pub cells: Vec<[f64; 4]>,
    /// Per aureole cell (group, plane, annulus; [`SlabGrid::aureole_cell`]): Σ w/|μ|.
    pub aureole: Vec<f64>,
    /// Per plane: diffuse photons crossing upward / downward (flux in units of E⊥ μ_L per photon).
    pub up: Vec<f64>,
    /// See `up`.
    pub down: Vec<f64>,
    /// Per plane: unscattered photons crossing it.
    pub direct: Vec<f64>,
    /// Photons that left through the lit face / the far face (scattered or not).
    pub escaped_top: f64,
    /// See `escaped_top`.
    pub escaped_bottom: f64,
    /// Weight lost to absorption (albedo < 1).
    pub absorbed: f64,
    /// Scattering events.
    pub events: u64,
    /// Photons launched.
    pub photons: u64,
}

impl BatchTally {
    /// Empty sums for `grid`.
    pub fn new(grid: &SlabGrid) -> Self {
        let planes = grid.depths.len();
        Self {
            cells: vec![[0.0; 4]; grid.n_cells()],
            aureole: vec![0.0; grid.n_aureole_cells()],
            up: vec![0.0; planes],
            down: vec![0.0; planes],
            direct: vec![0.0; planes],
            escaped_top: 0.0,
            escaped_bottom: 0.0,
            absorbed: 0.0,
            events: 0,
            photons: 0,
        }
    }
}

/// Σ v_b and Σ v_b v_bᵀ over batches (all of the same size), plus plain totals.
#[derive(Clone, Debug)]
pub struct Accumulator {
    /// Batches added.
    pub batches: u64,
    /// Totals of everything (cells included), summed in batch order.
    pub total: BatchTally,
    /// Per cell, the 10 entries of Σ v vᵀ (upper triangle, row-major).
    second: Vec<[f64; 10]>,
    /// Per aureole cell, Σ v².
    aureole_second: Vec<f64>,
}

/// Index pairs of the upper triangle of a 4×4 matrix, row-major.
const PAIRS: [(usize, usize); 10] = [
    (0, 0),
    (0, 1),
    (0, 2),
    (0, 3),
    (1, 1),
    (1, 2),
    (1, 3),
    (2, 2),
    (2, 3),
    (3, 3),
];

impl Accumulator {
    /// Nothing yet.
    pub fn new(grid: &SlabGrid) -> Self {
        Self {
            batches: 0,
            total: BatchTally::new(grid),
            second: vec![[0.0; 10]; grid.n_cells()],
            aureole_second: vec![0.0; grid.n_aureole_cells()],
        }
    }

    /// Adds one batch (call in batch order: the sums are then the same bits for any thread count).
    pub fn add(&mut self, b: &BatchTally) {
        self.batches += 1;
        let t = &mut self.total;
        for ((sum, sec), v) in t.cells.iter_mut().zip(&mut self.second).zip(&b.cells) {
            if v[0] == 0.0 {
                continue;
            }
            for i in 0..4 {
                sum[i] += v[i];
            }
            for (s, (i, j)) in sec.iter_mut().zip(PAIRS) {
                *s += v[i] * v[j];
            }
        }
        for ((sum, sec), v) in t
            .aureole
            .iter_mut()
            .zip(&mut self.aureole_second)
            .zip(&b.aureole)
        {
            *sum += v;
            *sec += v * v;
        }
        for (a, x) in [
            (&mut t.up, &b.up),
            (&mut t.down, &b.down),
            (&mut t.direct, &b.direct),
        ] {
            a.iter_mut().zip(x).for_each(|(a, x)| *a += x);
        }
        t.escaped_top += b.escaped_top;
        t.escaped_bottom += b.escaped_bottom;
        t.absorbed += b.absorbed;
        t.events += b.events;
        t.photons += b.photons;
    }

    /// Adds the raw sums to `npz` under `prefix` (a checkpoint or a shard's result): the sums
    /// are kept exactly, so a run resumed from them ends with the same bits.
    pub fn save(&self, npz: &mut Npz, prefix: &str) {
        let t = &self.total;
        let n = t.cells.len();
        npz.add(&format!("{prefix}cells"), &[n, 4], &t.cells.concat());
        npz.add(&format!("{prefix}second"), &[n, 10], &self.second.concat());
        let na = t.aureole.len();
        npz.add(&format!("{prefix}aureole"), &[na], &t.aureole);
        npz.add(
            &format!("{prefix}aureole_second"),
            &[na],
            &self.aureole_second,
        );
        let p = t.up.len();
        npz.add(
            &format!("{prefix}planes"),
            &[3, p],
            &[t.up.clone(), t.down.clone(), t.direct.clone()].concat(),
        );
        // Counts are below 2⁵³: exact in f64.
        let scalars = [
            self.batches as f64,
            t.escaped_top,
            t.escaped_bottom,
            t.absorbed,
            t.events as f64,
            t.photons as f64,
        ];
        npz.add(&format!("{prefix}scalars"), &[scalars.len()], &scalars);
    }

    /// Reads sums written by [`Self::save`] for `grid`.
    pub fn load(path: &Path, prefix: &str, grid: &SlabGrid) -> Result<Self> {
        let names = ["cells", "second", "planes", "scalars"].map(|n| format!("{prefix}{n}"));
        let refs: Vec<&str> = names.iter().map(String::as_str).collect();
        let a = read_arrays(path, &refs)?;
        let (n, p) = (grid.n_cells(), grid.depths.len());
        if a[0].len() != 4 * n || a[1].len() != 10 * n || a[2].len() != 3 * p || a[3].len() != 6 {
            bail!("'{}': sums {prefix} do not fit this grid", path.display());
        }
        let mut acc = Self::new(grid);
        acc.total.cells = a[0].chunks(4).map(|c| [c[0], c[1], c[2], c[3]]).collect();
        acc.second = a[1]
            .chunks(10)
            .map(|c| std::array::from_fn(|i| c[i]))
            .collect();
        acc.total.up = a[2][..p].to_vec();
        acc.total.down = a[2][p..2 * p].to_vec();
        acc.total.direct = a[2][2 * p..].to_vec();
        let na = grid.n_aureole_cells();
        for (name, dst) in [
            ("aureole", &mut acc.total.aureole),
            ("aureole_second", &mut acc.aureole_second),
        ] {
            match read_optional(path, &format!("{prefix}{name}"))? {
                Some(v) if v.len() == na => *dst = v,
                None if na == 0 => {}
                _ => bail!(
                    "'{}': sums {prefix} have no aureole of this grid's {na} cells (written before the aureole tally, or by another config)",
                    path.display()
                ),
            }
        }
        let s = &a[3];
        acc.batches = s[0] as u64;
        acc.total.escaped_top = s[1];
        acc.total.escaped_bottom = s[2];
        acc.total.absorbed = s[3];
        acc.total.events = s[4] as u64;
        acc.total.photons = s[5] as u64;
        Ok(acc)
    }

    /// The tables of this slice so far (`mu_l`: the sun's cosine).
    pub fn tables(&self, grid: &SlabGrid, mu_l: f64) -> SliceTables {
        let n = self.batches.max(1) as f64;
        let per_batch = self.total.photons as f64 / n;
        let mut out = SliceTables::zeros(grid.n_cells());
        out.aureole = self.aureole_tables(grid, mu_l);
        for (c, (sum, sec)) in self.total.cells.iter().zip(&self.second).enumerate() {
            if sum[0] == 0.0 {
                continue;
            }
            let mean: [f64; 4] = std::array::from_fn(|i| sum[i] / n);
            // Cov(v̄) = (Σ v vᵀ − n v̄ v̄ᵀ) / (n (n − 1)).
            let cov = |i: usize, j: usize| -> f64 {
                let k = PAIRS
                    .iter()
                    .position(|p| *p == (i.min(j), i.max(j)))
                    .unwrap_or(0);
                if n > 1.0 {
                    (sec[k] - n * mean[i] * mean[j]) / (n * (n - 1.0))
                } else {
                    f64::NAN
                }
            };
            let se = |grad: [f64; 4]| -> f64 {
                let mut s = 0.0;
                for i in 0..4 {
                    for j in 0..4 {
                        s += grad[i] * grad[j] * cov(i, j);
                    }
                }
                s.max(0.0).sqrt()
            };
            let (_, _, m, k) = grid.cell_parts(c);
            let scale = mu_l / (per_batch * grid.solid_angle(m, k));
            let [w, x, z, q] = mean;
            out.t[c] = scale * w;
            out.t_se[c] = se([scale, 0.0, 0.0, 0.0]);
            out.collector.cx[c] = -x / w;
            out.collector.cx_se[c] = se([x / (w * w), -1.0 / w, 0.0, 0.0]);
            out.collector.cz[c] = -z / w;
            out.collector.cz_se[c] = se([z / (w * w), 0.0, -1.0 / w, 0.0]);
            let var = (q / w - (x / w).powi(2) - (z / w).powi(2)).max(0.0);
            let sigma = var.sqrt();
            out.collector.sigma[c] = sigma;
            let d_var = [
                -q / (w * w) + 2.0 * (x * x + z * z) / (w * w * w),
                -2.0 * x / (w * w),
                -2.0 * z / (w * w),
                1.0 / w,
            ];
            out.collector.sigma_se[c] = if sigma > 0.0 {
                se(d_var) / (2.0 * sigma)
            } else {
                f64::NAN
            };
        }
        out
    }
}

impl Accumulator {
    /// T and its standard error per aureole cell (group, plane, annulus) so far.
    fn aureole_tables(&self, grid: &SlabGrid, mu_l: f64) -> (Vec<f64>, Vec<f64>) {
        let n = self.batches.max(1) as f64;
        let per_batch = self.total.photons as f64 / n;
        let na = grid.aureole.n_bins();
        let mut t = vec![0.0; grid.n_aureole_cells()];
        let mut se = vec![0.0; t.len()];
        for (c, (sum, sec)) in self
            .total
            .aureole
            .iter()
            .zip(&self.aureole_second)
            .enumerate()
        {
            let scale = mu_l / (per_batch * grid.aureole.solid_angle(c % na.max(1)));
            let mean = sum / n;
            t[c] = scale * mean;
            se[c] = if n > 1.0 {
                scale * ((sec - n * mean * mean) / (n * (n - 1.0))).max(0.0).sqrt()
            } else {
                f64::NAN
            };
        }
        (t, se)
    }
}

/// T and its standard error for every cell of one slice (flat, in [`SlabGrid::cell`] order),
/// with the collector. Cells no photon reached hold T = 0 and NaN elsewhere.
#[derive(Clone, Debug)]
pub struct SliceTables {
    /// L/E⊥ (sr⁻¹).
    pub t: Vec<f64>,
    /// Standard error of `t`.
    pub t_se: Vec<f64>,
    /// c and σ.
    pub collector: Collector,
    /// T and its standard error per aureole cell (group, plane, annulus).
    pub aureole: (Vec<f64>, Vec<f64>),
}

/// The collector c = (c_x, c_z) (mfp, from the viewpoint's horizontal position: x across, z
/// along the sun's horizontal travel) and its spread σ (mfp) per cell, with standard errors;
/// NaN where undefined. The same for one slice and for the tables of a whole run.
#[derive(Clone, Debug, Default)]
pub struct Collector {
    /// c_x (mfp).
    pub cx: Vec<f64>,
    /// Standard error of `cx`.
    pub cx_se: Vec<f64>,
    /// c_z (mfp).
    pub cz: Vec<f64>,
    /// Standard error of `cz`.
    pub cz_se: Vec<f64>,
    /// σ (mfp).
    pub sigma: Vec<f64>,
    /// Standard error of `sigma`.
    pub sigma_se: Vec<f64>,
}

impl SliceTables {
    fn zeros(n: usize) -> Self {
        let nan = vec![f64::NAN; n];
        Self {
            t: vec![0.0; n],
            t_se: vec![0.0; n],
            collector: Collector {
                cx: nan.clone(),
                cx_se: nan.clone(),
                cz: nan.clone(),
                cz_se: nan.clone(),
                sigma: nan.clone(),
                sigma_se: nan,
            },
            aureole: (Vec::new(), Vec::new()),
        }
    }

    /// The largest relative standard errors over cells with T ≥ `fraction` × the largest T:
    /// (over the cells `skip` leaves, over the cells it skips).
    pub fn worst_relative_error(&self, fraction: f64, skip: &dyn Fn(usize) -> bool) -> (f64, f64) {
        let max = self.t.iter().copied().fold(0.0, f64::max);
        let mut worst = (0.0f64, 0.0f64);
        for (c, (t, se)) in self.t.iter().zip(&self.t_se).enumerate() {
            if *t >= fraction * max && *t > 0.0 {
                let r = if se.is_finite() {
                    se / t
                } else {
                    f64::INFINITY
                };
                if skip(c) {
                    worst.1 = worst.1.max(r);
                } else {
                    worst.0 = worst.0.max(r);
                }
            }
        }
        worst
    }
}
