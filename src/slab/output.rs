//! A slab run's artefacts, written and read here: `tables.npz` (the 5D tables ⟨T, c, σ⟩ with
//! their standard errors over [group, t, μ_L, depth, μ_V, ψ_V], the grids, the order groups,
//! the diffuse fluxes and the phase table the run sampled), `tables.json` (config, seed, every
//! slice's report, timings) and `slab.png`. `nephele slab` and `nephele merge` write them; the
//! compressor reads them.

use super::aureole::Aureole;
use super::config::SlabConfig;
use super::tables::SlabRun;
pub use super::tally::Collector;
use crate::io::npz::{read_arrays, read_optional};
use crate::io::plot::{panels_plot, Panel, Series, Style};
use crate::io::{AtomicFiles, Npz};
use crate::phase::{Phase, Source};
use anyhow::{bail, ensure, Context, Result};
use nephele_runtime::transport::SlabPoint;
use serde_json::json;
use std::path::Path;

/// The name of the stored phase table's angles (degrees) in tables.npz.
pub const PHASE_THETA: &str = "phase_theta_deg";
/// The name of its values p (sr⁻¹).
pub const PHASE: &str = "phase";
/// The aureole's T over [group, t, μ_L, depth, annulus] in tables.npz.
pub const AUREOLE_T: &str = "T_aureole";
/// Its standard error.
pub const AUREOLE_SE: &str = "T_aureole_se";
/// The annuli's edges (degrees from the beam).
pub const AUREOLE_EDGES: &str = "aureole_edges_deg";

/// Writes tables.npz and tables.json (and slab.png if `plot`) into `out`, atomically: the 5D
/// tables of a whole run, its grids and groups, the phase function it sampled where it is a
/// table (and given), and the run's report (config, seed, slices, `timings`).
pub fn write_tables(
    cfg: &SlabConfig,
    run: &SlabRun,
    phase: Option<&Phase>,
    out: &Path,
    plot: bool,
    timings: serde_json::Value,
) -> Result<()> {
    std::fs::create_dir_all(out).with_context(|| format!("cannot create '{}'", out.display()))?;
    let mut set = AtomicFiles::new();
    set.write(&out.join("tables.json"), |w| {
        serde_json::to_writer_pretty(&mut *w, &report(cfg, run, timings))?;
        Ok(())
    })?;
    set.write(&out.join("tables.npz"), |w| {
        arrays(cfg, run, phase).write_to(w)
    })?;
    if plot {
        set.write_via_path(&out.join("slab.png"), |p| figure(p, cfg, run))?;
    }
    set.commit()
}

fn report(cfg: &SlabConfig, run: &SlabRun, timings: serde_json::Value) -> serde_json::Value {
    let slices: Vec<_> = run.done().map(|(r, _)| r).collect();
    json!({
        "version": crate::VERSION,
        "git_commit": option_env!("NEPHELE_GIT_COMMIT"),
        "config": cfg,
        "seed": cfg.seed,
        "shape": "[group, t, mu_L, depth, mu_V, psi_V]",
        "units": {"T": "L / E_perp (1/sr), E_perp the sun's irradiance on a surface facing it", "cx, cz, sigma": "mean free paths; c = collector entry point minus the viewpoint's projection, z along the sun's horizontal travel, x across", "flux_up, flux_down": "diffuse flux / E_perp"},
        "photons": slices.iter().map(|s| s.photons).sum::<u64>(),
        "events": slices.iter().map(|s| s.events).sum::<u64>(),
        "converged_slices": slices.iter().filter(|s| s.converged).count(),
        "slices": slices,
        "timings": timings,
    })
}

/// The 5D tables, their grids and groups, and the phase function's table if it has one.
fn arrays(cfg: &SlabConfig, run: &SlabRun, phase: Option<&Phase>) -> Npz {
    let (nt, nl, np) = (cfg.thicknesses.len(), cfg.mu_l.len(), cfg.planes);
    let (ng, nm, nk) = (cfg.group_starts.len(), cfg.mu_v_bins, cfg.psi_v_bins);
    let n = ng * nt * nl * np * nm * nk;
    let names = [
        "T", "T_se", "cx", "cx_se", "cz", "cz_se", "sigma", "sigma_se",
    ];
    let mut out: Vec<Vec<f64>> = vec![vec![f64::NAN; n]; names.len()];
    let mut flux = [
        vec![0.0; nt * nl * np],
        vec![0.0; nt * nl * np],
        vec![0.0; nt * nl * np],
        vec![0.0; nt * nl * np],
    ];
    for (s, (report, slice)) in run
        .slices
        .iter()
        .enumerate()
        .filter_map(|(s, x)| Some((s, x.as_ref()?)))
    {
        let (it, il) = (s / nl, s % nl);
        let grid = cfg.grid(report.t).expect("validated");
        let t = &slice.tables;
        let src = [
            &t.t,
            &t.t_se,
            &t.collector.cx,
            &t.collector.cx_se,
            &t.collector.cz,
            &t.collector.cz_se,
            &t.collector.sigma,
            &t.collector.sigma_se,
        ];
        for c in 0..grid.n_cells() {
            let (g, j, m, k) = grid.cell_parts(c);
            let at = ((((g * nt + it) * nl + il) * np + j) * nm + m) * nk + k;
            for (dst, v) in out.iter_mut().zip(src) {
                dst[at] = v[c];
            }
        }
        let tot = &slice.acc.total;
        let per = report.mu_l / tot.photons as f64;
        for j in 0..np {
            let at = (it * nl + il) * np + j;
            flux[0][at] = per * tot.up[j];
            flux[1][at] = per * tot.down[j];
            flux[2][at] = (-run.depths[it][j] / report.mu_l).exp();
            flux[3][at] = tot.direct[j] / tot.photons as f64;
        }
    }
    let mut z = Npz::new();
    add_aureole(&mut z, cfg, run);
    let shape = [ng, nt, nl, np, nm, nk];
    for (name, data) in names.iter().zip(&out) {
        z.add(name, &shape, data);
    }
    z.add("flux_up", &[nt, nl, np], &flux[0]);
    z.add("flux_down", &[nt, nl, np], &flux[1]);
    z.add("direct", &[nt, nl, np], &flux[2]);
    z.add("direct_mc", &[nt, nl, np], &flux[3]);
    z.add("thickness", &[nt], &cfg.thicknesses);
    z.add("mu_l", &[nl], &cfg.mu_l);
    z.add("depth", &[nt, np], &run.depths.concat());
    let grid = cfg.grid(cfg.thicknesses[0]).expect("validated");
    z.add("mu_v_edges", &[nm + 1], &grid.mu_edges);
    z.add("psi_v_edges", &[nk + 1], &grid.psi_edges);
    let groups = cfg.groups();
    let first: Vec<f64> = groups.iter().map(|g| g.0 as f64).collect();
    let last: Vec<f64> = groups
        .iter()
        .map(|g| {
            if g.1 == u32::MAX {
                f64::INFINITY
            } else {
                g.1 as f64
            }
        })
        .collect();
    z.add("group_first", &[ng], &first);
    z.add("group_last", &[ng], &last);
    if let Some(s) = phase.and_then(Phase::source) {
        z.add(PHASE_THETA, &[s.theta_deg.len()], &s.theta_deg);
        z.add(PHASE, &[s.phase.len()], &s.phase);
    }
    z
}

/// The aureole's T and its standard error over [group, t, μ_L, depth, annulus] and the
/// annuli's edges (degrees), if the run tallied one.
fn add_aureole(z: &mut Npz, cfg: &SlabConfig, run: &SlabRun) {
    let na = cfg.aureole_deg.len().saturating_sub(1);
    if na == 0 {
        return;
    }
    let (nt, nl, np, ng) = (
        cfg.thicknesses.len(),
        cfg.mu_l.len(),
        cfg.planes,
        cfg.group_starts.len(),
    );
    let mut t = vec![f64::NAN; ng * nt * nl * np * na];
    let mut se = t.clone();
    for (s, (_, slice)) in run
        .slices
        .iter()
        .enumerate()
        .filter_map(|(s, x)| Some((s, x.as_ref()?)))
    {
        let (it, il) = (s / nl, s % nl);
        let (at, ase) = &slice.tables.aureole;
        for g in 0..ng {
            for j in 0..np {
                let src = (g * np + j) * na;
                let dst = (((g * nt + it) * nl + il) * np + j) * na;
                t[dst..dst + na].copy_from_slice(&at[src..src + na]);
                se[dst..dst + na].copy_from_slice(&ase[src..src + na]);
            }
        }
    }
    let shape = [ng, nt, nl, np, na];
    z.add(AUREOLE_T, &shape, &t);
    z.add(AUREOLE_SE, &shape, &se);
    z.add(AUREOLE_EDGES, &[na + 1], &cfg.aureole_deg);
}

/// T (up and down), c_z and σ against depth per order group, for the slice nearest t = 8,
/// μ_L = 0.5, in the view bins nearest straight up / down and ψ_V = 0.
fn figure(path: &Path, cfg: &SlabConfig, run: &SlabRun) -> Result<()> {
    let nearest = |v: &[f64], x: f64| {
        (0..v.len())
            .min_by(|&a, &b| (v[a] - x).abs().total_cmp(&(v[b] - x).abs()))
            .unwrap_or(0)
    };
    let (it, il) = (nearest(&cfg.thicknesses, 8.0), nearest(&cfg.mu_l, 0.5));
    let (report, slice) = run.slices[it * cfg.mu_l.len() + il]
        .as_ref()
        .context("slice not run")?;
    let grid = cfg.grid(report.t)?;
    let d = &grid.depths;
    let (up, down) = (grid.n_mu() - 1, 0);
    let label = |g: usize| {
        let (a, b) = grid.groups[g];
        match (a, b) {
            (a, u32::MAX) => format!("orders ≥ {a}"),
            (a, b) if a == b => format!("order {a}"),
            (a, b) => format!("orders {a}–{b}"),
        }
    };
    let column = |v: &[f64], g: usize, m: usize| -> Vec<f64> {
        (0..d.len()).map(|j| v[grid.cell(g, j, m, 0)]).collect()
    };
    let t = &slice.tables;
    let data: Vec<Vec<(String, Vec<f64>)>> = [
        (&t.t, up),
        (&t.t, down),
        (&t.collector.cz, down),
        (&t.collector.sigma, down),
    ]
    .iter()
    .map(|(v, m)| {
        (0..grid.groups.len())
            .map(|g| (label(g), column(v, g, *m)))
            .collect()
    })
    .collect();
    let titles = [
        format!(
            "T, light going up (μ_V bin nearest 1), t = {}, μ_L = {}",
            report.t, report.mu_l
        ),
        "T, light going down (μ_V bin nearest −1)".to_string(),
        "collector mean c_z, light going down".to_string(),
        "collector width σ, light going down".to_string(),
    ];
    let y_labels = ["T = L/E⊥ (1/sr)", "T = L/E⊥ (1/sr)", "c_z (mfp)", "σ (mfp)"];
    let panels: Vec<Panel> = data
        .iter()
        .enumerate()
        .map(|(i, series)| Panel {
            title: titles[i].clone(),
            x_label: "depth d (mfp)".into(),
            y_label: y_labels[i].into(),
            log_y: i < 2,
            log_x: false,
            series: series
                .iter()
                .enumerate()
                .map(|(g, (l, y))| Series {
                    label: l.clone(),
                    x: d,
                    y,
                    style: Style::Line,
                    colour: g + 1,
                })
                .collect(),
        })
        .collect();
    panels_plot(path, (1600, 1200), 2, &panels)
}

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
    /// The phase function the run sampled, where it is a table (files of runs before it was
    /// stored have none).
    pub phase: Option<Source>,
    /// The aureole, if the run tallied one.
    pub aureole: Option<AureoleTables>,
}

/// T and its standard error in cones around the transmitted beam (src/slab/aureole.rs) over
/// [group, t, μ_L, depth, annulus].
#[derive(Clone, Debug)]
pub struct AureoleTables {
    /// The annuli.
    pub annuli: Aureole,
    /// T = L/E⊥ (sr⁻¹), the mean over the annulus.
    pub t: Vec<f64>,
    /// Its standard error.
    pub t_se: Vec<f64>,
}

impl AureoleTables {
    /// Flat index of cell (group, t, μ_L, depth, annulus) of tables of `shape`.
    pub fn index(
        &self,
        shape: &[usize; 6],
        g: usize,
        it: usize,
        il: usize,
        j: usize,
        b: usize,
    ) -> usize {
        (((g * shape[1] + it) * shape[2] + il) * shape[3] + j) * self.annuli.n_bins() + b
    }
}

/// The aureole of a tables.npz, if it has one, checked against the tables' `shape`.
fn read_aureole(path: &Path, shape: &[usize; 6]) -> Result<Option<AureoleTables>> {
    let Some(edges) = read_optional(path, AUREOLE_EDGES)? else {
        return Ok(None);
    };
    let annuli = Aureole::new(edges).with_context(|| format!("'{}'", path.display()))?;
    let a = read_arrays(path, &[AUREOLE_T, AUREOLE_SE])?;
    let n = shape[..4].iter().product::<usize>() * annuli.n_bins();
    ensure!(
        a[0].len() == n && a[1].len() == n,
        "'{}': {AUREOLE_T} has {} values, the grids say {n}",
        path.display(),
        a[0].len()
    );
    let mut a = a.into_iter();
    Ok(Some(AureoleTables {
        annuli,
        t: a.next().unwrap_or_default(),
        t_se: a.next().unwrap_or_default(),
    }))
}

impl SlabTables {
    /// Reads `tables.npz` (written by [`write_tables`]), checking that the arrays agree in
    /// shape.
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
            phase: read_phase(path)?,
            aureole: read_aureole(path, &shape)?,
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

/// The stored phase table of a tables.npz, if any.
fn read_phase(path: &Path) -> Result<Option<Source>> {
    let theta = read_optional(path, PHASE_THETA)?;
    let phase = read_optional(path, PHASE)?;
    match (theta, phase) {
        (Some(theta_deg), Some(phase)) => {
            ensure!(
                theta_deg.len() == phase.len(),
                "'{}': {PHASE} does not match {PHASE_THETA}",
                path.display()
            );
            Ok(Some(Source { theta_deg, phase }))
        }
        (None, None) => Ok(None),
        _ => bail!(
            "'{}': {PHASE_THETA} and {PHASE} go together",
            path.display()
        ),
    }
}
