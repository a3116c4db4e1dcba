//! `nephele transport`: the compressed tables evaluated at one point, as JSON, or at every row
//! of a .npy (`--points`), as a .npy.

use anyhow::{bail, ensure, Context, Result};
use clap::Args;
use nephele::io::npy::{npy_bytes, read_rows};
use nephele::io::AtomicFiles;
use nephele_runtime::transport::{
    column_names, evaluate_points, Quantities, SlabPoint, Transport, TransportTables, POINT_COLUMNS,
};
use std::path::{Path, PathBuf};

/// Options of `nephele transport`.
#[derive(Args, Debug)]
pub struct TransportArgs {
    /// transport.ntt of `nephele compress` [default: the embedded Mie 10 µm tables, as
    /// `nephele render` uses].
    #[arg(long, value_name = "FILE")]
    pub tables: Option<PathBuf>,
    /// Slab thickness t (mean free paths).
    #[arg(long, required_unless_present = "points")]
    pub t: Option<f32>,
    /// Sun cosine μ_L in (0, 1].
    #[arg(
        long = "mu-l",
        allow_hyphen_values = true,
        required_unless_present = "points"
    )]
    pub mu_l: Option<f32>,
    /// Depth of the viewpoint below the lit face (mfp), in [0, t].
    #[arg(long, required_unless_present = "points")]
    pub depth: Option<f32>,
    /// View cosine μ_V in [−1, 1] (> 0: light going up).
    #[arg(
        long = "mu-v",
        allow_hyphen_values = true,
        required_unless_present = "points"
    )]
    pub mu_v: Option<f32>,
    /// View azimuth ψ_V from the sun's horizontal travel, degrees.
    #[arg(long, allow_hyphen_values = true, required_unless_present = "points")]
    pub psi: Option<f32>,
    /// Many points instead of one: an (N, 5) float32 or float64 .npy of t, μ_L, depth, μ_V,
    /// ψ_V (degrees, as --psi), one point per row. Writes --out: an (N, 1 + G) float32 .npy of
    /// order 1 and T per group, (N, 1 + 4G) with --collector, and a JSON sidecar naming the
    /// columns.
    #[arg(long, value_name = "NPY", conflicts_with_all = ["t", "mu_l", "depth", "mu_v", "psi"])]
    pub points: Option<PathBuf>,
    /// Where --points writes its answers (.npy; the sidecar beside it, .json).
    #[arg(long, value_name = "NPY", requires = "points")]
    pub out: Option<PathBuf>,
    /// With --points: c_x, c_z and σ of every group as well as T.
    #[arg(long, requires = "points")]
    pub collector: bool,
}

/// Runs `nephele transport`.
pub fn run(a: TransportArgs) -> Result<()> {
    if let Some(points) = &a.points {
        let out = a
            .out
            .as_deref()
            .context("--points needs --out FILE.npy for the answers")?;
        return super::with_tables(a.tables.as_deref(), |tab| {
            batch(points, out, a.collector, tab)
        });
    }
    let at = one_point(&a)?;
    super::with_tables(a.tables.as_deref(), |tab| {
        answer(&at, a.psi.unwrap_or(0.0), tab)
    })
}

/// The point of the single-point flags, checked.
fn one_point(a: &TransportArgs) -> Result<SlabPoint<f32>> {
    let (Some(t), Some(mu_l), Some(depth), Some(mu_v), Some(psi)) =
        (a.t, a.mu_l, a.depth, a.mu_v, a.psi)
    else {
        bail!("give --t, --mu-l, --depth, --mu-v and --psi, or --points FILE.npy");
    };
    ensure!(t > 0.0 && t.is_finite(), "--t must be a positive thickness");
    ensure!(mu_l > 0.0 && mu_l <= 1.0, "--mu-l must be in (0, 1]");
    ensure!((0.0..=t).contains(&depth), "--depth must be in [0, t]");
    ensure!((-1.0..=1.0).contains(&mu_v), "--mu-v must be in [-1, 1]");
    ensure!(psi.is_finite(), "--psi must be a number of degrees");
    Ok(SlabPoint {
        depth,
        thickness: t,
        mu_v,
        // Through f64, as --points converts its rows.
        psi_v: f64::from(psi).to_radians() as f32,
        mu_l,
    })
}

/// Every row of `points` through [`evaluate_points`], written to `out` (.npy and .json).
fn batch(points: &Path, out: &Path, collector: bool, tab: &TransportTables) -> Result<()> {
    let names = "t, mu_L, depth, mu_V, psi_V (degrees)";
    let (rows, n) = read_rows(points, POINT_COLUMNS, names)?;
    let mut flat = Vec::with_capacity(rows.len());
    let dom = tab.domain();
    let (mut outside_slab, mut outside_grid) = (0usize, 0usize);
    for (i, r) in rows.chunks_exact(POINT_COLUMNS).enumerate() {
        ensure!(
            r.iter().all(|v| v.is_finite()),
            "'{}' row {i}: {r:?} is not finite (columns {names})",
            points.display()
        );
        let row = [r[0], r[1], r[2], r[3], r[4].to_radians()];
        let at = SlabPoint::from_row(&row.map(|v| v as f32));
        let valid = at.thickness > 0.0
            && (0.0..=at.thickness).contains(&at.depth)
            && at.mu_l > 0.0
            && at.mu_l <= 1.0
            && (-1.0..=1.0).contains(&at.mu_v);
        outside_slab += usize::from(!valid);
        outside_grid += usize::from(valid && !dom.contains(&at));
        flat.extend([at.thickness, at.mu_l, at.depth, at.mu_v, at.psi_v]);
    }
    let what = if collector {
        Quantities::WithCollector
    } else {
        Quantities::Transport
    };
    let width = what.columns(tab.groups());
    let mut answers = vec![0.0f32; n * width];
    let start = std::time::Instant::now();
    evaluate_points(tab, &flat, what, &mut answers).map_err(|e| anyhow::anyhow!("{e}"))?;
    let seconds = start.elapsed().as_secs_f64();
    let columns = column_names(tab, what);
    let sidecar = serde_json::json!({
        "points": points.display().to_string(),
        "rows": n,
        "columns": columns,
        "units": "T = L / E_perp (1/sr); c_x, c_z, sigma in mean free paths (0 where T is 0); order 1 in closed form, orders >= 2 per group from the compressed form",
        "input_columns": names,
        "rows_outside_the_slab_answered_0": outside_slab,
        "rows_outside_the_tables_grid": outside_grid,
        "domain": {"t": [dom.thickness.0, dom.thickness.1], "mu_l": [dom.mu_l.0, dom.mu_l.1]},
        "seconds": seconds,
        "points_per_second": n as f64 / seconds.max(1e-12),
        "threads": rayon::current_num_threads(),
    });
    let mut files = AtomicFiles::new();
    files.write_bytes(out, &npy_bytes(&[n as u64, width as u64], &answers)?)?;
    files.write_bytes(
        &out.with_extension("json"),
        &serde_json::to_vec_pretty(&sidecar)?,
    )?;
    files.commit()?;
    if outside_slab > 0 {
        eprintln!(
            "warning: {outside_slab} rows lie outside the slab (t <= 0, depth outside [0, t], \
             mu_L outside (0, 1] or |mu_V| > 1): answered 0"
        );
    }
    if outside_grid > 0 {
        eprintln!(
            "warning: {outside_grid} rows have t or mu_L outside the tables' grid (t {}..{}, \
             mu_L {}..{}): their parameters are held at the grid's nearest end",
            dom.thickness.0, dom.thickness.1, dom.mu_l.0, dom.mu_l.1
        );
    }
    println!(
        "{n} points in {seconds:.3} s ({:.2e} points/s, {} threads) → {} ({width} columns)",
        n as f64 / seconds.max(1e-12),
        rayon::current_num_threads(),
        out.display()
    );
    Ok(())
}

/// T of every group at `at` (ψ_V given as `psi_deg`), as JSON on stdout.
fn answer(at: &SlabPoint<f32>, psi_deg: f32, tab: &TransportTables) -> Result<()> {
    let at = *at;
    let mut all = vec![Transport::default(); tab.groups()];
    tab.evaluate_all(&at, &mut all);
    let groups: Vec<serde_json::Value> = all
        .iter()
        .enumerate()
        .map(|(g, v)| {
            let mut e = serde_json::json!({
                "first_order": tab.group_first_order(g),
                "T": v.t,
            });
            if tab.has_collector() {
                e["c_x"] = v.c_x.into();
                e["c_z"] = v.c_z.into();
                e["sigma"] = v.sigma.into();
            }
            e
        })
        .collect();
    let dom = tab.domain();
    let inside = dom.contains(&at);
    if !inside {
        eprintln!(
            "warning: t = {} or mu_L = {} is outside the tables' grid (t {}..{}, mu_L {}..{}): \
             their parameters are held at the grid's nearest end",
            at.thickness, at.mu_l, dom.thickness.0, dom.thickness.1, dom.mu_l.0, dom.mu_l.1
        );
    }
    let out = serde_json::json!({
        "point": {"t": at.thickness, "mu_l": at.mu_l, "depth": at.depth, "mu_v": at.mu_v, "psi_deg": psi_deg},
        "inside_domain": inside,
        "domain": {"t": [dom.thickness.0, dom.thickness.1], "mu_l": [dom.mu_l.0, dom.mu_l.1]},
        "units": "T = L / E_perp (1/sr); c_x, c_z, sigma in mean free paths (the collector: where the light entered, from the viewpoint's horizontal position, z along the sun's horizontal travel; 0 where T is 0); orders >= 2 per group from the compressed form, order 1 (T only) in closed form",
        "order1": tab.order1(&at),
        "groups": groups,
    });
    println!("{}", serde_json::to_string_pretty(&out)?);
    Ok(())
}
