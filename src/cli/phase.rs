//! `nephele phase`: tabulate a runtime phase model (or a Mie table) on an angle grid, draw
//! samples from it, and export renderer LUTs.

use anyhow::{bail, Context, Result};
use clap::{Args, ValueEnum};
use nephele::io::{AtomicFiles, Npz};
use nephele::mie::grid::angles_from_spec;
use nephele_runtime::phase::{
    Draine, HenyeyGreenstein, Rayleigh, ReynoldsMcCormick, Schlick, TabulatedTable, TwoTermHg,
    VonMisesFisher, Xlf, XLF_G_MAX,
};
use nephele_runtime::presets::{jendersie_deon, nephele_refit};
use nephele_runtime::PhaseFunction;
use rand::{Rng, SeedableRng};
use rand_xoshiro::Xoshiro256PlusPlus;
use serde::Serialize;
use serde_json::json;
use std::io::Write;
use std::path::PathBuf;

/// The models of nephele-runtime.
#[derive(Clone, Copy, Debug, PartialEq, Eq, ValueEnum, serde::Serialize)]
#[serde(rename_all = "kebab-case")]
pub enum Model {
    /// Henyey–Greenstein (--g).
    Hg,
    /// Draine (--g, --alpha).
    Draine,
    /// Cornette–Shanks (--g): Draine with α = 1.
    CornetteShanks,
    /// Rayleigh (no parameter).
    Rayleigh,
    /// Reynolds–McCormick (--g, --alpha > 0; α = 1/2 is HG).
    ReynoldsMccormick,
    /// Schlick (--k).
    Schlick,
    /// von Mises–Fisher (--kappa).
    Vmf,
    /// Xiao-Lei Fan's function, normalised (--g, |g| ≤ 0.476955 where it stays non-negative).
    Xlf,
    /// w HG(g) + (1 − w) HG(g2) (--g, --g2, --w).
    TwoTermHg,
    /// HG + Draine blend (Jendersie & d'Eon), from --diameter (and --preset) or from --g, --g2 (g_D), --alpha, --w (w_D).
    HgDraine,
    /// A Mie table (--table phase.npz from `nephele mie`).
    Tabulated,
}

/// The HG+Draine diameter presets of nephele-runtime.
#[derive(Clone, Copy, Debug, PartialEq, Eq, ValueEnum, Serialize)]
#[serde(rename_all = "snake_case")]
pub enum Preset {
    /// `presets::jendersie_deon`: the paper's curves and its supplement's branches.
    JendersieDeon,
    /// `presets::nephele_refit`: nephele's refit on the same Mie setup.
    Nephele,
}

/// Options of `nephele phase`.
#[derive(Args, Debug)]
pub struct PhaseArgs {
    /// The model.
    #[arg(long, value_enum)]
    model: Model,
    /// Asymmetry g (HG, Draine, Cornette–Shanks, first lobe of two-term HG, HG lobe of HG+Draine).
    #[arg(long, allow_hyphen_values = true)]
    g: Option<f64>,
    /// Second g (two-term HG; the Draine lobe's g of HG+Draine).
    #[arg(long, allow_hyphen_values = true)]
    g2: Option<f64>,
    /// Draine α ≥ 0.
    #[arg(long)]
    alpha: Option<f64>,
    /// Lobe weight in [0, 1] (first lobe of two-term HG; the Draine lobe of HG+Draine).
    #[arg(long)]
    w: Option<f64>,
    /// Schlick k in (−1, 1).
    #[arg(long, allow_hyphen_values = true)]
    k: Option<f64>,
    /// von Mises–Fisher κ ≥ 0.
    #[arg(long)]
    kappa: Option<f64>,
    /// Droplet diameter in µm for an HG+Draine preset (--preset).
    #[arg(long, value_name = "UM")]
    diameter: Option<f64>,
    /// Which diameter → parameter curves --diameter uses: the paper's (Jendersie & d'Eon 2023)
    /// or nephele's refit (stage 3, docs/fit.md).
    #[arg(long, value_enum, default_value_t = Preset::JendersieDeon)]
    preset: Preset,
    /// phase.npz of `nephele mie` (its `phase` on its `theta_deg`) for --model tabulated.
    #[arg(long, value_name = "FILE")]
    table: Option<PathBuf>,
    /// Angle grid: "default" or a file of angles in degrees from 0 to 180.
    #[arg(long, default_value = "default")]
    angles: String,
    /// Also draw this many sampled cosines (f64 sampler) into samples_mu.
    #[arg(long, default_value_t = 0)]
    samples: usize,
    /// Seed of the samples.
    #[arg(long, default_value_t = 1)]
    seed: u64,
    /// Entries of the renderer LUTs (uniform in θ, and inverse CDF uniform in ξ).
    #[arg(long, default_value_t = 1024)]
    lut: usize,
    /// Output directory.
    #[arg(long, default_value = "outputs/phase")]
    out: PathBuf,
    /// Also write phase.csv (theta_deg, mu, phase) for spreadsheets.
    #[arg(long)]
    csv: bool,
}

fn need(v: Option<f64>, name: &str, model: Model) -> Result<f64> {
    v.with_context(|| format!("--model {model:?} needs --{name}"))
}

fn in_range(v: f64, name: &str, lo: f64, hi: f64, open: bool) -> Result<f64> {
    let ok = if open {
        v > lo && v < hi
    } else {
        v >= lo && v <= hi
    };
    if !(v.is_finite() && ok) {
        let (l, r) = if open { ("(", ")") } else { ("[", "]") };
        bail!("--{name} must lie in {l}{lo}, {hi}{r}, got {v}");
    }
    Ok(v)
}

impl PhaseArgs {
    /// The model as a trait object, with its parameters echoed as JSON.
    fn build(&self) -> Result<(Box<dyn PhaseFunction<f64>>, serde_json::Value)> {
        let m = self.model;
        let g = || in_range(need(self.g, "g", m)?, "g", -1.0, 1.0, true);
        Ok(match m {
            Model::Hg => (Box::new(HenyeyGreenstein::new(g()?)), json!({ "g": g()? })),
            Model::Draine => {
                let a = in_range(need(self.alpha, "alpha", m)?, "alpha", 0.0, 1e6, false)?;
                (
                    Box::new(Draine::new(g()?, a)),
                    json!({ "g": g()?, "alpha": a }),
                )
            }
            Model::CornetteShanks => (
                Box::new(Draine::cornette_shanks(g()?)),
                json!({ "g": g()? }),
            ),
            Model::Rayleigh => (Box::new(Rayleigh), json!({})),
            Model::ReynoldsMccormick => {
                let a = in_range(need(self.alpha, "alpha", m)?, "alpha", 0.0, 1e3, true)?;
                (
                    Box::new(ReynoldsMcCormick::new(g()?, a)),
                    json!({ "g": g()?, "alpha": a }),
                )
            }
            Model::Schlick => {
                let k = in_range(need(self.k, "k", m)?, "k", -1.0, 1.0, true)?;
                (Box::new(Schlick::new(k)), json!({ "k": k }))
            }
            Model::Vmf => {
                let k = in_range(need(self.kappa, "kappa", m)?, "kappa", 0.0, 1e7, false)?;
                (Box::new(VonMisesFisher::new(k)), json!({ "kappa": k }))
            }
            Model::Xlf => {
                let gv = g()?;
                let xlf = Xlf::new(gv).with_context(|| {
                    format!("--g must satisfy |g| ≤ {XLF_G_MAX} for xlf (it turns negative beyond), got {gv}")
                })?;
                (Box::new(xlf), json!({ "g": gv, "normalised": true }))
            }
            Model::TwoTermHg => {
                let g2 = in_range(need(self.g2, "g2", m)?, "g2", -1.0, 1.0, true)?;
                let w = in_range(need(self.w, "w", m)?, "w", 0.0, 1.0, false)?;
                (
                    Box::new(TwoTermHg::two_term(g()?, g2, w)),
                    json!({ "g": g()?, "g2": g2, "w": w }),
                )
            }
            Model::HgDraine => {
                let p = match self.diameter {
                    Some(d) => {
                        let d = in_range(d, "diameter", 0.0, 1e4, true)?;
                        match self.preset {
                            Preset::JendersieDeon => jendersie_deon(d),
                            Preset::Nephele => nephele_refit(d),
                        }
                    }
                    None => nephele_runtime::presets::HgDraineParams {
                        g_hg: g()?,
                        g_d: in_range(need(self.g2, "g2", m)?, "g2", -1.0, 1.0, true)?,
                        alpha: in_range(need(self.alpha, "alpha", m)?, "alpha", 0.0, 1e6, false)?,
                        w_d: in_range(need(self.w, "w", m)?, "w", 0.0, 1.0, false)?,
                    },
                };
                let echo = json!({ "g_hg": p.g_hg, "g_d": p.g_d, "alpha": p.alpha, "w_d": p.w_d, "diameter_um": self.diameter, "preset": self.diameter.map(|_| self.preset) });
                (Box::new(p.phase::<f64>()), echo)
            }
            Model::Tabulated => bail!("internal: tabulated is built from its table"),
        })
    }
}

/// Runs `nephele phase`.
pub fn run(args: PhaseArgs) -> Result<()> {
    let theta_deg = angles_from_spec(&args.angles)?;
    if args.lut < 2 {
        bail!("--lut must be at least 2");
    }
    let table;
    let (model, params): (Box<dyn PhaseFunction<f64> + '_>, serde_json::Value) =
        if args.model == Model::Tabulated {
            let path = args
                .table
                .as_ref()
                .context("--model tabulated needs --table phase.npz")?;
            let (th, p) = read_table(path)?;
            table = TabulatedTable::<f64>::from_phase(&th, &p)
                .map_err(|e| anyhow::anyhow!("table '{}': {e:?}", path.display()))?;
            (
                Box::new(table.view()),
                json!({ "table": path.display().to_string(), "nodes": th.len() }),
            )
        } else {
            args.build()?
        };
    let mu: Vec<f64> = theta_deg.iter().map(|d| d.to_radians().cos()).collect();
    let phase: Vec<f64> = mu.iter().map(|&m| model.eval(m)).collect();
    let lut_theta: Vec<f64> = (0..args.lut)
        .map(|i| 180.0 * i as f64 / (args.lut - 1) as f64)
        .collect();
    let lut_phase: Vec<f64> = lut_theta
        .iter()
        .map(|d| model.eval(d.to_radians().cos()))
        .collect();
    let icdf: Vec<f64> = (0..args.lut)
        .map(|i| model.sample_mu(i as f64 / (args.lut - 1) as f64))
        .collect();
    let mut rng = Xoshiro256PlusPlus::seed_from_u64(args.seed);
    let samples: Vec<f64> = (0..args.samples)
        .map(|_| model.sample_mu(rng.random::<f64>()))
        .collect();
    let mut npz = Npz::new();
    npz.add("theta_deg", &[mu.len()], &theta_deg)
        .add("mu", &[mu.len()], &mu)
        .add("phase", &[mu.len()], &phase)
        .add("lut_theta_deg", &[args.lut], &lut_theta)
        .add("lut_phase", &[args.lut], &lut_phase)
        .add("icdf_mu", &[args.lut], &icdf)
        .add("samples_mu", &[samples.len()], &samples);
    let sidecar = json!({
        "tool": "nephele", "version": nephele::VERSION, "model": args.model, "params": params,
        "mean_cosine": model.mean_cosine(), "samples": args.samples, "seed": args.seed,
        "conventions": {
            "phase": "p(mu), normalised over the sphere, 1/sr; mu = cos(theta), theta between incident and scattered propagation directions",
            "lut_phase": "p at lut_theta_deg, uniform in theta from 0 to 180 degrees",
            "icdf_mu": "mu = sample_mu(xi) at xi uniform from 0 to 1 (inverse CDF for single-lobe models)",
            "samples_mu": "cosines drawn with xi from xoshiro256++ seeded with `seed`"
        }
    });
    std::fs::create_dir_all(&args.out)?;
    let mut set = AtomicFiles::new();
    set.write(&args.out.join("phase.npz"), |w| npz.write_to(w))?;
    set.write_bytes(
        &args.out.join("phase.json"),
        &serde_json::to_vec_pretty(&sidecar)?,
    )?;
    if args.csv {
        set.write(&args.out.join("phase.csv"), |w| {
            writeln!(w, "theta_deg,mu,phase")?;
            for i in 0..mu.len() {
                writeln!(w, "{},{:.17e},{:.17e}", theta_deg[i], mu[i], phase[i])?;
            }
            Ok(())
        })?;
    }
    set.commit()?;
    println!(
        "{:?}: mean cosine {:?} → {}",
        args.model,
        model.mean_cosine(),
        args.out.display()
    );
    Ok(())
}

/// theta_deg and phase of a `nephele mie` npz.
fn read_table(path: &std::path::Path) -> Result<(Vec<f64>, Vec<f64>)> {
    let mut arrays = nephele::io::npz::read_arrays(path, &["theta_deg", "phase"])?;
    let phase = arrays.pop().unwrap_or_default();
    Ok((arrays.pop().unwrap_or_default(), phase))
}
