//! `nephele phase`: tabulate a runtime phase model (or a Mie table) on an angle grid, draw
//! samples from it, and export renderer LUTs.

use anyhow::{bail, Context, Result};
use clap::Args;
use nephele::io::{AtomicFiles, Npz};
use nephele::mie::grid::angles_from_spec;
use nephele::phase::mitsuba::Tabphase;
use nephele::phase::{build, Model, ModelParams, Preset};
use nephele_runtime::phase::TabulatedTable;
use nephele_runtime::PhaseFunction;
use rand::{Rng, SeedableRng};
use rand_xoshiro::Xoshiro256PlusPlus;
use serde_json::json;
use std::io::Write;
use std::path::PathBuf;

/// Options of `nephele phase`.
#[derive(Args, Debug)]
pub struct PhaseArgs {
    /// The model (snake_case names work too). Each takes its own parameters; any other one
    /// is an error.
    #[arg(long, value_parser = super::names(&Model::NAMES))]
    model: Model,
    /// Asymmetry g (HG, Draine, Cornette–Shanks, Reynolds–McCormick, XLF; the first lobe of
    /// two-term HG).
    #[arg(long, allow_hyphen_values = true)]
    g: Option<f64>,
    /// The second lobe's g (two-term HG).
    #[arg(long, allow_hyphen_values = true)]
    g2: Option<f64>,
    /// The first lobe's weight in [0, 1] (two-term HG: w HG(g) + (1 − w) HG(g2)).
    #[arg(long)]
    w: Option<f64>,
    /// Draine α ≥ 0 (Draine, HG+Draine); Reynolds–McCormick α > 0.
    #[arg(long, allow_hyphen_values = true)]
    alpha: Option<f64>,
    /// HG+Draine: the HG lobe's g ((1 − w_d) HG(g_hg) + w_d Draine(g_d, α)).
    #[arg(long, allow_hyphen_values = true)]
    g_hg: Option<f64>,
    /// HG+Draine: the Draine lobe's g.
    #[arg(long, allow_hyphen_values = true)]
    g_d: Option<f64>,
    /// HG+Draine: the Draine lobe's weight in [0, 1].
    #[arg(long, allow_hyphen_values = true)]
    w_d: Option<f64>,
    /// Schlick k in (−1, 1).
    #[arg(long, allow_hyphen_values = true)]
    k: Option<f64>,
    /// von Mises–Fisher κ ≥ 0.
    #[arg(long)]
    kappa: Option<f64>,
    /// Droplet diameter in µm for an HG+Draine preset (--preset); also --diameter-um.
    #[arg(
        long,
        value_name = "UM",
        visible_alias = "diameter-um",
        allow_hyphen_values = true
    )]
    diameter: Option<f64>,
    /// Which diameter → parameter curves --diameter uses: the paper's (Jendersie & d'Eon 2023,
    /// the default) or nephele's refit (docs/fit.md).
    #[arg(long, value_parser = super::names(&Preset::NAMES))]
    preset: Option<Preset>,
    /// phase.npz of `nephele mie` (its `phase` on its `theta_deg`) for --model tabulated.
    #[arg(long, value_name = "FILE")]
    table: Option<PathBuf>,
    /// Angle grid in degrees from 0 to 180: "default", a comma-separated list (0,90,180) or a
    /// file of angles, one per line.
    #[arg(long, default_value = "default")]
    angles: String,
    /// Also draw this many sampled cosines (f64 sampler) into samples_mu.
    #[arg(long, default_value_t = 0)]
    samples: usize,
    /// Seed of the samples (with --samples) [default: 1].
    #[arg(long)]
    seed: Option<u64>,
    /// Entries of the renderer LUTs (uniform in θ, and inverse CDF uniform in ξ).
    #[arg(long, default_value_t = 1024)]
    lut: usize,
    /// Output directory.
    #[arg(long, default_value = "outputs/phase")]
    out: PathBuf,
    /// Also write phase.csv (theta_deg, mu, phase) for spreadsheets.
    #[arg(long)]
    csv: bool,
    /// Also write the phase function for another renderer: `mitsuba` writes Mitsuba 3's
    /// tabphase (phase_mitsuba.xml for scene files, phase_mitsuba.json for
    /// `mitsuba.load_dict`) on --export-nodes cosines, with what the table loses in
    /// phase.json.
    #[arg(long, value_enum)]
    export: Option<Export>,
    /// Cosines of the export's table, evenly spaced from −1 to 1 (Mitsuba interpolates linearly
    /// in μ: a narrow forward peak needs many).
    #[arg(long, default_value_t = nephele::phase::mitsuba::DEFAULT_NODES)]
    export_nodes: usize,
}

/// Renderers `nephele phase --export` writes for.
#[derive(Clone, Copy, Debug, PartialEq, Eq, clap::ValueEnum)]
pub enum Export {
    /// Mitsuba 3's `tabphase` plugin.
    Mitsuba,
}

impl PhaseArgs {
    /// The model as a trait object, with its parameters echoed as JSON.
    fn build(&self) -> Result<(Box<dyn PhaseFunction<f64>>, serde_json::Value)> {
        anyhow::ensure!(
            self.table.is_none(),
            "model {} does not take table (only tabulated does)",
            self.model.name()
        );
        let (model, echo) = build(self.model, &self.params())?;
        Ok((model, echo))
    }

    /// The model's parameters as given.
    fn params(&self) -> ModelParams {
        ModelParams {
            g: self.g,
            g2: self.g2,
            alpha: self.alpha,
            w: self.w,
            g_hg: self.g_hg,
            g_d: self.g_d,
            w_d: self.w_d,
            k: self.k,
            kappa: self.kappa,
            diameter: self.diameter,
            preset: self.preset,
        }
    }
}

/// Runs `nephele phase`.
pub fn run(args: PhaseArgs) -> Result<()> {
    let theta_deg = angles_from_spec(&args.angles)?;
    if args.lut < 2 {
        bail!("--lut must be at least 2");
    }
    anyhow::ensure!(
        args.seed.is_none() || args.samples > 0,
        "--seed applies to --samples (the drawn cosines), and none were asked for"
    );
    anyhow::ensure!(
        args.export_nodes >= 2,
        "--export-nodes must be at least 2 (the table's ends μ = −1 and +1)"
    );
    let seed = args.seed.unwrap_or(1);
    let table;
    let (model, params): (Box<dyn PhaseFunction<f64> + '_>, serde_json::Value) =
        if args.model == Model::Tabulated {
            args.params().check_for(Model::Tabulated)?;
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
    let icdf = nephele::phase::lut::inverse_cdf(model.as_ref(), args.lut);
    let mut rng = Xoshiro256PlusPlus::seed_from_u64(seed);
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
    let export = args
        .export
        .map(|Export::Mitsuba| Tabphase::of(model.as_ref(), args.export_nodes));
    let mut sidecar = json!({
        "tool": "nephele", "version": nephele::VERSION, "model": args.model, "params": params,
        "mean_cosine": model.mean_cosine(), "samples": args.samples, "seed": seed,
        "conventions": {
            "phase": "p(mu), normalised over the sphere, 1/sr; mu = cos(theta), theta between incident and scattered propagation directions",
            "lut_phase": "p at lut_theta_deg, uniform in theta from 0 to 180 degrees",
            "icdf_mu": "mu = F^-1(xi) at xi = i/(n-1), F(mu) = 2 pi int_{-1}^{mu} p: increases from -1 (xi = 0, backward) to +1 (xi = 1, forward) for every model; interpolate linearly in xi",
            "samples_mu": "cosines drawn with xi from xoshiro256++ seeded with `seed`"
        }
    });
    if let Some(tab) = &export {
        sidecar["mitsuba"] = json!({
            "files": ["phase_mitsuba.xml", "phase_mitsuba.json"],
            "nodes": tab.values.len(),
            "grid": "p at mu_i = -1 + 2i/(N-1), backward first, as tabphase takes it; Mitsuba interpolates linearly in mu and normalises",
            "normalisation": tab.normalisation,
            "mean_cosine_as_mitsuba_reads_it": tab.mean_cosine,
            "max_rel_error_between_nodes": tab.max_rel_error,
            "worst_mu": tab.worst_mu,
        });
    }
    nephele::io::output_dir(&args.out)?;
    let mut set = AtomicFiles::new();
    if let Some(tab) = &export {
        set.write_bytes(&args.out.join("phase_mitsuba.xml"), tab.xml().as_bytes())?;
        set.write_bytes(
            &args.out.join("phase_mitsuba.json"),
            &serde_json::to_vec_pretty(&tab.dict())?,
        )?;
    }
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
    let mean = model
        .mean_cosine()
        .map_or("not in closed form".to_string(), |g| g.to_string());
    outln!(
        "{}: mean cosine {mean} → {}",
        args.model.name(),
        args.out.display()
    );
    if let Some(tab) = &export {
        outln!(
            "mitsuba tabphase ({} cosines): mean cosine as Mitsuba reads it {:.6}, normalisation \
             {:.6}, at most {:.2e} off the model between nodes (at mu = {:.5})",
            tab.values.len(),
            tab.mean_cosine,
            tab.normalisation,
            tab.max_rel_error,
            tab.worst_mu
        );
        if (tab.normalisation - 1.0).abs() > 0.01 {
            eprintln!(
                "warning: the table holds {:+.1} % of the light (its nodes miss part of the \
                 forward peak): raise --export-nodes",
                100.0 * (tab.normalisation - 1.0)
            );
        }
    }
    Ok(())
}

/// theta_deg and phase of a `nephele mie` npz.
fn read_table(path: &std::path::Path) -> Result<(Vec<f64>, Vec<f64>)> {
    let (theta, mut columns) = nephele::mie::output::read_phase(path, false)
        .context("--table takes the phase.npz of `nephele mie`")?;
    Ok((theta, columns.pop().unwrap_or_default()))
}
