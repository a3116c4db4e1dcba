//! `nephele transport`: the compressed tables evaluated at one point, as JSON, or at every row
//! of a .npy (`--points`), as a .npy.

use anyhow::{bail, Context, Result};
use clap::Args;
use nephele::io::npy::{npy_bytes, read_rows};
use nephele::io::AtomicFiles;
use nephele_runtime::transport::{
    column_names, evaluate_points, Domain, OutsideTally, PointError, Quantities, SlabPoint,
    Transport, TransportTables, POINT_COLUMNS,
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
    /// View azimuth ψ_V from the sun's horizontal travel, in degrees (C, Python and WGSL take
    /// radians).
    #[arg(
        long = "psi-deg",
        allow_hyphen_values = true,
        required_unless_present = "points"
    )]
    pub psi_deg: Option<f32>,
    /// Many points instead of one: an (N, 5) float32 or float64 .npy of t, μ_L, depth, μ_V,
    /// ψ_V (degrees, as --psi-deg), one point per row. Writes --out: an (N, 1 + G) float32 .npy
    /// of order 1 and T per group, (N, 1 + 4G) with --collector, a uint8 .outside.npy beside
    /// it flagging each row outside the tables' grid (1: t past the thickest slab, 2: below
    /// the thinnest, 4: sun below the lowest), and a JSON sidecar naming the columns. A row
    /// outside the slab (t ≤ 0, depth outside [0, t], μ_L outside (0, 1], |μ_V| > 1, NaN, ±∞)
    /// is an error.
    #[arg(long, value_name = "NPY", conflicts_with_all = ["t", "mu_l", "depth", "mu_v", "psi_deg"])]
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
        nephele::io::check_output_file(out)?;
        return nephele::io::tables::with_tables(a.tables.as_deref(), |tab| {
            batch(points, out, a.collector, tab)
        });
    }
    let at = one_point(&a)?;
    nephele::io::tables::with_tables(a.tables.as_deref(), |tab| {
        answer(&at, a.psi_deg.unwrap_or(0.0), tab)
    })
}

/// The point of the single-point flags, checked.
fn one_point(a: &TransportArgs) -> Result<SlabPoint<f32>> {
    let (Some(t), Some(mu_l), Some(depth), Some(mu_v), Some(psi)) =
        (a.t, a.mu_l, a.depth, a.mu_v, a.psi_deg)
    else {
        bail!("give --t, --mu-l, --depth, --mu-v and --psi-deg, or --points FILE.npy");
    };
    let at = SlabPoint {
        depth,
        thickness: t,
        mu_v,
        // Through f64, as --points converts its rows.
        psi_v: f64::from(psi).to_radians() as f32,
        mu_l,
    };
    at.check().map_err(|e| {
        let flag = match e {
            PointError::Thickness(_) => "--t",
            PointError::SunCosine(_) => "--mu-l",
            PointError::Depth { .. } => "--depth",
            PointError::ViewCosine(_) => "--mu-v",
            PointError::Azimuth(_) => "--psi-deg",
        };
        anyhow::anyhow!("{flag}: {e}")
    })?;
    Ok(at)
}

/// Every row of `points` through [`evaluate_points`], written to `out` (.npy and .json).
fn batch(points: &Path, out: &Path, collector: bool, tab: &TransportTables) -> Result<()> {
    let names = "t, mu_L, depth, mu_V, psi_V (degrees)";
    let (rows, n) = read_rows(points, POINT_COLUMNS, names)?;
    let mut flat = Vec::with_capacity(rows.len());
    let dom = tab.domain();
    let mut tally = OutsideTally::default();
    let mut flags = Vec::with_capacity(n);
    for (i, r) in rows.chunks_exact(POINT_COLUMNS).enumerate() {
        let row = [r[0], r[1], r[2], r[3], r[4].to_radians()];
        let at = SlabPoint::from_row(&row.map(|v| v as f32));
        at.check().map_err(|e| {
            anyhow::anyhow!(
                "'{}' row {i}: {e} (columns {names}); every row must be a point of the slab",
                points.display()
            )
        })?;
        let outside = dom.outside(&at);
        tally.add(&outside, &dom);
        flags.push(outside.bits(&dom) as u8);
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
        "outside_the_grid": outside_json(&tally),
        "outside_flags": "the .outside.npy beside this file, one uint8 a row: 1 t past the thickest slab (continued by diffusion theory), 2 t below the thinnest (held), 4 mu_L below the lowest sun (read there, T scaled by mu_L)",
        "domain": {"t": [dom.thickness.0, dom.thickness.1], "mu_l": [dom.mu_l.0, dom.mu_l.1], "mean_cosine": tab.mean_cosine()},
        "seconds": seconds,
        "points_per_second": n as f64 / seconds.max(1e-12),
        "threads": rayon::current_num_threads(),
    });
    if let Some(dir) = out.parent().filter(|d| !d.as_os_str().is_empty()) {
        nephele::io::output_dir(dir)?;
    }
    let mut files = AtomicFiles::new();
    files.write_bytes(out, &npy_bytes(&[n as u64, width as u64], &answers)?)?;
    files.write_bytes(
        &out.with_extension("outside.npy"),
        &npy_bytes(&[n as u64], &flags)?,
    )?;
    files.write_bytes(
        &out.with_extension("json"),
        &serde_json::to_vec_pretty(&sidecar)?,
    )?;
    files.commit()?;
    for line in outside_lines(&tally, &dom) {
        eprintln!("warning: {line}");
    }
    outln!(
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
    let outside = dom.outside(&at);
    let inside = outside.is_within();
    if !inside {
        eprintln!("warning: {}", outside.describe(&dom));
    }
    let out = serde_json::json!({
        "point": {"t": at.thickness, "mu_l": at.mu_l, "depth": at.depth, "mu_v": at.mu_v, "psi_deg": psi_deg},
        "inside_domain": inside,
        "outside": (!inside).then(|| outside.describe(&dom).to_string()),
        "domain": {"t": [dom.thickness.0, dom.thickness.1], "mu_l": [dom.mu_l.0, dom.mu_l.1], "mean_cosine": tab.mean_cosine()},
        "units": "T = L / E_perp (1/sr); c_x, c_z, sigma in mean free paths (the collector: where the light entered, from the viewpoint's horizontal position, z along the sun's horizontal travel; 0 where T is 0); orders >= 2 per group from the compressed form, order 1 (T only) in closed form",
        "order1": tab.order1(&at),
        "groups": groups,
    });
    outln!("{}", serde_json::to_string_pretty(&out)?);
    Ok(())
}

/// The rows outside the grid, per kind, as the sidecar gives them.
fn outside_json(t: &OutsideTally) -> serde_json::Value {
    let kind = |(rows, v): (u64, f32), key: &str| {
        let mut e = serde_json::json!({ "rows": rows });
        if rows > 0 {
            e[key] = v.into();
        }
        e
    };
    serde_json::json!({
        "t_past_thickest": kind(t.thicker, "largest_t"),
        "t_below_thinnest": kind(t.thinner, "smallest_t"),
        "sun_below_lowest": kind(t.lower_sun, "smallest_mu_l"),
    })
}

/// One warning line per kind of point outside the grid: the share of points and the farthest.
pub(crate) fn outside_lines(t: &OutsideTally, d: &Domain) -> Vec<String> {
    let share = |k: u64| 100.0 * k as f64 / t.points.max(1) as f64;
    let mut lines = Vec::new();
    if t.thicker.0 > 0 {
        lines.push(format!(
            "{:.1} % of the points have t past the tables' thickest slab, up to {} mfp against \
             the tables' {}: continued by diffusion theory",
            share(t.thicker.0),
            t.thicker.1,
            d.thickness.1
        ));
    }
    if t.thinner.0 > 0 {
        lines.push(format!(
            "{:.1} % of the points have t below the tables' thinnest slab, down to {} mfp against \
             the tables' {}: held there",
            share(t.thinner.0),
            t.thinner.1,
            d.thickness.0
        ));
    }
    if t.lower_sun.0 > 0 {
        lines.push(format!(
            "{:.1} % of the points have the sun below the tables' lowest, down to mu_L = {} \
             against the tables' {}: held there",
            share(t.lower_sun.0),
            t.lower_sun.1,
            d.mu_l.0
        ));
    }
    lines
}
