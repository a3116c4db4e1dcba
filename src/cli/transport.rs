//! `nephele transport`: the compressed tables evaluated at one point, as JSON.

use anyhow::{ensure, Result};
use clap::Args;
use nephele_runtime::transport::{SlabPoint, Transport, TransportTables};
use std::path::PathBuf;

/// Options of `nephele transport`.
#[derive(Args, Debug)]
pub struct TransportArgs {
    /// transport.ntt of `nephele compress` [default: the embedded Mie 10 µm tables, as
    /// `nephele render` uses].
    #[arg(long, value_name = "FILE")]
    pub tables: Option<PathBuf>,
    /// Slab thickness t (mean free paths).
    #[arg(long)]
    pub t: f32,
    /// Sun cosine μ_L in (0, 1].
    #[arg(long = "mu-l", allow_hyphen_values = true)]
    pub mu_l: f32,
    /// Depth of the viewpoint below the lit face (mfp), in [0, t].
    #[arg(long)]
    pub depth: f32,
    /// View cosine μ_V in [−1, 1] (> 0: light going up).
    #[arg(long = "mu-v", allow_hyphen_values = true)]
    pub mu_v: f32,
    /// View azimuth ψ_V from the sun's horizontal travel, degrees.
    #[arg(long, allow_hyphen_values = true)]
    pub psi: f32,
}

/// Runs `nephele transport`.
pub fn run(a: TransportArgs) -> Result<()> {
    ensure!(
        a.t > 0.0 && a.t.is_finite(),
        "--t must be a positive thickness"
    );
    ensure!(a.mu_l > 0.0 && a.mu_l <= 1.0, "--mu-l must be in (0, 1]");
    ensure!((0.0..=a.t).contains(&a.depth), "--depth must be in [0, t]");
    ensure!((-1.0..=1.0).contains(&a.mu_v), "--mu-v must be in [-1, 1]");
    ensure!(a.psi.is_finite(), "--psi must be a number of degrees");
    super::with_tables(a.tables.as_deref(), |tab| answer(&a, tab))
}

/// T of every group at `a`'s point, as JSON on stdout.
fn answer(a: &TransportArgs, tab: &TransportTables) -> Result<()> {
    let at = SlabPoint {
        depth: a.depth,
        thickness: a.t,
        mu_v: a.mu_v,
        psi_v: a.psi.to_radians(),
        mu_l: a.mu_l,
    };
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
            a.t, a.mu_l, dom.thickness.0, dom.thickness.1, dom.mu_l.0, dom.mu_l.1
        );
    }
    let out = serde_json::json!({
        "point": {"t": a.t, "mu_l": a.mu_l, "depth": a.depth, "mu_v": a.mu_v, "psi_deg": a.psi},
        "inside_domain": inside,
        "domain": {"t": [dom.thickness.0, dom.thickness.1], "mu_l": [dom.mu_l.0, dom.mu_l.1]},
        "units": "T = L / E_perp (1/sr); c_x, c_z, sigma in mean free paths (the collector: where the light entered, from the viewpoint's horizontal position, z along the sun's horizontal travel; 0 where T is 0); orders >= 2 per group from the compressed form, order 1 (T only) in closed form",
        "order1": tab.order1(&at),
        "groups": groups,
    });
    println!("{}", serde_json::to_string_pretty(&out)?);
    Ok(())
}
