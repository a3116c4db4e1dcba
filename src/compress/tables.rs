//! The 5D tables of `nephele slab` (tables.npz) as the compressor reads them.

use crate::io::npz::read_arrays;
use anyhow::{ensure, Result};
use nephele_runtime::transport::SlabPoint;
use std::path::Path;

/// T and its standard error over [group, t, μ_L, depth, μ_V, ψ_V], with the grids.
pub struct SlabTables {
    /// [groups, thicknesses, μ_L, depths, μ_V bins, ψ_V bins].
    pub shape: [usize; 6],
    /// T = L/E⊥ (sr⁻¹), row-major over `shape`.
    pub t: Vec<f64>,
    /// Its standard error.
    pub t_se: Vec<f64>,
    /// Slab thicknesses (mfp).
    pub thickness: Vec<f64>,
    /// Sun cosines.
    pub mu_l: Vec<f64>,
    /// Plane depths per thickness, [t, depth] (mfp).
    pub depth: Vec<f64>,
    /// μ_V bin edges.
    pub mu_v_edges: Vec<f64>,
    /// ψ_V bin edges (radians).
    pub psi_v_edges: Vec<f64>,
    /// First order of each group.
    pub group_first: Vec<f64>,
    /// The collector statistics over the same layout (NaN where undefined).
    pub collector: Collector,
}

/// The collector (mfp) and its spread σ (mfp) per cell, with standard errors (spec 40).
#[derive(Clone, Debug, Default)]
pub struct Collector {
    /// c_x, across the sun's horizontal travel.
    pub cx: Vec<f64>,
    /// Its standard error.
    pub cx_se: Vec<f64>,
    /// c_z, along the sun's horizontal travel.
    pub cz: Vec<f64>,
    /// Its standard error.
    pub cz_se: Vec<f64>,
    /// σ.
    pub sigma: Vec<f64>,
    /// Its standard error.
    pub sigma_se: Vec<f64>,
}

impl SlabTables {
    /// Reads `tables.npz`, checking that the arrays agree in shape.
    pub fn load(path: &Path) -> Result<Self> {
        let names = [
            "T",
            "T_se",
            "thickness",
            "mu_l",
            "depth",
            "mu_v_edges",
            "psi_v_edges",
            "group_first",
            "cx",
            "cx_se",
            "cz",
            "cz_se",
            "sigma",
            "sigma_se",
        ];
        let mut a = read_arrays(path, &names)?.into_iter();
        let mut next = || a.next().unwrap_or_default();
        let (t, t_se, thickness, mu_l, depth) = (next(), next(), next(), next(), next());
        let (mu_v_edges, psi_v_edges, group_first) = (next(), next(), next());
        let collector = Collector {
            cx: next(),
            cx_se: next(),
            cz: next(),
            cz_se: next(),
            sigma: next(),
            sigma_se: next(),
        };
        let (nt, nl) = (thickness.len(), mu_l.len());
        ensure!(
            nt > 0 && nl > 0 && depth.len() % nt == 0,
            "'{}': empty or ragged grids",
            path.display()
        );
        let shape = [
            group_first.len(),
            nt,
            nl,
            depth.len() / nt,
            mu_v_edges.len().saturating_sub(1),
            psi_v_edges.len().saturating_sub(1),
        ];
        let n: usize = shape.iter().product();
        let c = &collector;
        ensure!(
            n > 0
                && [
                    &t,
                    &t_se,
                    &c.cx,
                    &c.cx_se,
                    &c.cz,
                    &c.cz_se,
                    &c.sigma,
                    &c.sigma_se
                ]
                .iter()
                .all(|a| a.len() == n),
            "'{}': T has {} values, the grids say {shape:?} (or a collector array differs)",
            path.display(),
            t.len()
        );
        Ok(Self {
            shape,
            t,
            t_se,
            thickness,
            mu_l,
            depth,
            mu_v_edges,
            psi_v_edges,
            group_first,
            collector,
        })
    }

    /// Flat index of cell (group, t, μ_L, depth, μ_V, ψ_V).
    pub fn index(&self, g: usize, it: usize, il: usize, j: usize, m: usize, k: usize) -> usize {
        let s = &self.shape;
        ((((g * s[1] + it) * s[2] + il) * s[3] + j) * s[4] + m) * s[5] + k
    }

    /// The slab point of cell (thickness `it`, sun `il`, plane `j`, view `m`, `k`), at the
    /// bin centres.
    pub fn point(&self, it: usize, il: usize, j: usize, m: usize, k: usize) -> SlabPoint<f64> {
        let nd = self.shape[3];
        SlabPoint {
            depth: self.depth[it * nd + j],
            thickness: self.thickness[it],
            mu_v: self.mu_v(m),
            psi_v: self.psi_v(k),
            mu_l: self.mu_l[il],
        }
    }

    /// Centre of μ_V bin `m`.
    pub fn mu_v(&self, m: usize) -> f64 {
        0.5 * (self.mu_v_edges[m] + self.mu_v_edges[m + 1])
    }

    /// Centre of ψ_V bin `k`.
    pub fn psi_v(&self, k: usize) -> f64 {
        0.5 * (self.psi_v_edges[k] + self.psi_v_edges[k + 1])
    }
}
