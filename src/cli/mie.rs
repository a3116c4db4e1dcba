//! `nephele mie` and the main job.

use anyhow::{bail, Context, Result};
use clap::Args;
use nephele::io::text::short;
use nephele::io::{plot, AtomicFiles};
use nephele::mie::colour::Illuminant;
use nephele::mie::distribution::SizeDistribution;
use nephele::mie::grid::angles_from_spec;
use nephele::mie::index::RefractiveIndex;
use nephele::mie::output::write_table;
use nephele::mie::polydisperse::{JobStats, CONVERGED_DEFAULT, DEFAULT_WAVELENGTHS};
use nephele::mie::{MieJob, PhaseTable, SizeRule};
use serde::{Deserialize, Deserializer, Serialize};
use serde_json::json;
use std::path::{Path, PathBuf};
use std::time::Instant;

/// Options of `nephele mie`; a JSON config (--config) takes the same keys, flags win. Keys are
/// the flags' names in snake_case (`medium_index`; the kebab-case spelling works too).
#[derive(Args, Debug, Default, Clone, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct MieArgs {
    /// JSON file with any of the options below as keys (e.g. {"diameter": 10, "sigma": 0.25}).
    #[arg(long, value_name = "FILE")]
    #[serde(skip)]
    config: Option<PathBuf>,
    /// Median diameter in µm (mode diameter for gamma, the size for mono); a list "5,10,20"
    /// or a range "5:50:46" (or log-spaced "log:0.1:5:30") computes several tables sharing one
    /// ln-x table. [default: 10]
    #[arg(long, value_name = "UM", allow_hyphen_values = true)]
    #[serde(default, alias = "diameter_um", deserialize_with = "str_or_num")]
    diameter: Option<String>,
    /// σ of ln d of the log-normal distribution.
    #[arg(long, value_name = "S", allow_hyphen_values = true)]
    sigma: Option<f64>,
    /// Size distribution: lognormal, mono, or gamma:ALPHA:GAMMA (n(d) ∝ d^α e^{−(α/γ)(d/d_mode)^γ}).
    #[arg(long, value_name = "KIND")]
    distribution: Option<String>,
    /// Vacuum wavelengths MIN:MAX:N in nm, uniform and inclusive. [default: 400:700:61]
    #[arg(long, value_name = "MIN:MAX:N", allow_hyphen_values = true)]
    wavelengths: Option<String>,
    /// Use the explicit product rule (docs/mie.md) with N sizes (z uniform in [−4, 4]) instead of
    /// the converged default.
    #[arg(long, value_name = "N")]
    sizes: Option<usize>,
    /// Droplet index: a number (1.333), complex (1.33+1e-5i), water[:TEMP_C] (IAPWS R9-97) or a
    /// CSV file of wavelength_nm,n,k. [default: 1.333]
    #[arg(long, value_name = "M", allow_hyphen_values = true)]
    #[serde(default, deserialize_with = "str_or_num")]
    index: Option<String>,
    /// Refractive index of the medium. [default: 1]
    #[arg(long, value_name = "N")]
    #[serde(alias = "medium-index")]
    medium_index: Option<f64>,
    /// Angle grid: "default" (0–5° by 0.01°, 5–180° by 0.1°), a comma-separated list or a file
    /// of angles in degrees, one per line, increasing from 0 to 180.
    #[arg(long, value_name = "default|LIST|FILE")]
    angles: Option<String>,
    /// Illuminant of the sRGB channel phase functions.
    #[arg(long, value_parser = super::names(&Illuminant::NAMES))]
    illuminant: Option<Illuminant>,
    /// Number of Legendre moments beyond χ_0 to write. [default: 64]
    #[arg(long, value_name = "K")]
    legendre: Option<usize>,
    /// Largest step in ln x of the converged size grid (small droplets). [default: 2.5e-4]
    #[arg(long, value_name = "H")]
    #[serde(alias = "ln-step")]
    ln_step: Option<f64>,
    /// Largest step in x = πd/λ of the converged size grid (large droplets). [default: 0.01]
    #[arg(long, value_name = "DX")]
    #[serde(alias = "x-step")]
    x_step: Option<f64>,
    /// Half-width of the size support of the converged rule, in σ. [default: 5]
    #[arg(long, value_name = "Z")]
    #[serde(alias = "z-max")]
    z_max: Option<f64>,
    /// Output directory. [default: outputs/mie]
    #[arg(long, value_name = "DIR")]
    out: Option<PathBuf>,
    /// Also write phase.csv for spreadsheets.
    #[arg(long)]
    #[serde(default)]
    csv: bool,
    /// Do not draw phase.png.
    #[arg(long)]
    #[serde(default)]
    #[serde(alias = "no-plot")]
    no_plot: bool,
}

/// Accepts `"10"` or `10` for options that are strings on the command line.
fn str_or_num<'de, D: Deserializer<'de>>(d: D) -> Result<Option<String>, D::Error> {
    #[derive(Deserialize)]
    #[serde(untagged)]
    enum V {
        S(String),
        N(f64),
    }
    Ok(Option::<V>::deserialize(d)?.map(|v| match v {
        V::S(s) => s,
        V::N(n) => n.to_string(),
    }))
}

impl MieArgs {
    /// Flags first, then the config file's keys.
    fn merged(self) -> Result<Self> {
        let Some(path) = &self.config else {
            return Ok(self);
        };
        let text = std::fs::read_to_string(path)
            .with_context(|| format!("cannot read config '{}'", path.display()))?;
        let file: MieArgs =
            serde_json::from_str(&text).with_context(|| format!("config '{}'", path.display()))?;
        Ok(MieArgs {
            config: None,
            diameter: self.diameter.or(file.diameter),
            sigma: self.sigma.or(file.sigma),
            distribution: self.distribution.or(file.distribution),
            wavelengths: self.wavelengths.or(file.wavelengths),
            sizes: self.sizes.or(file.sizes),
            index: self.index.or(file.index),
            medium_index: self.medium_index.or(file.medium_index),
            angles: self.angles.or(file.angles),
            illuminant: self.illuminant.or(file.illuminant),
            legendre: self.legendre.or(file.legendre),
            ln_step: self.ln_step.or(file.ln_step),
            x_step: self.x_step.or(file.x_step),
            z_max: self.z_max.or(file.z_max),
            out: self.out.or(file.out),
            csv: self.csv || file.csv,
            no_plot: self.no_plot || file.no_plot,
        })
    }

    /// Refuses options that the job would ignore (docs/phase.md: a flag or key a command does
    /// not take is an error): σ belongs to the log-normal distribution, the converged rule's
    /// steps not to `sizes` (the product rule) nor to one size (`mono`).
    fn refuse_unused(&self) -> Result<()> {
        let kind = self.distribution.as_deref().unwrap_or("lognormal");
        let lognormal = kind == "lognormal";
        anyhow::ensure!(
            lognormal || self.sigma.is_none(),
            "--sigma (sigma) applies to the log-normal distribution only, not to '{kind}'"
        );
        let steps: Vec<&str> = [
            ("--ln-step", self.ln_step.is_some()),
            ("--x-step", self.x_step.is_some()),
            ("--z-max", self.z_max.is_some()),
        ]
        .iter()
        .filter(|(_, given)| *given)
        .map(|(name, _)| *name)
        .collect();
        let rule_of = |what: &str| {
            format!(
                "{} set{} the converged size rule, which {what} does not use",
                steps.join(", "),
                if steps.len() == 1 { "s" } else { "" }
            )
        };
        anyhow::ensure!(
            steps.is_empty() || self.sizes.is_none(),
            "{}",
            rule_of("--sizes")
        );
        anyhow::ensure!(
            steps.is_empty() || kind != "mono",
            "{}",
            rule_of("a mono distribution")
        );
        anyhow::ensure!(
            self.sizes.is_none() || kind != "mono",
            "--sizes (sizes) sets the size quadrature, which a mono distribution (one size) does not use"
        );
        Ok(())
    }

    /// The typed job these options describe.
    pub(super) fn job(&self) -> Result<MieJob> {
        self.refuse_unused()?;
        let diameters = parse_list(self.diameter.as_deref().unwrap_or("10"), "--diameter")?;
        let sigma = self.sigma.unwrap_or(0.25);
        let distributions = diameters
            .iter()
            .map(|&d| {
                distribution(
                    self.distribution.as_deref().unwrap_or("lognormal"),
                    d,
                    sigma,
                )
            })
            .collect::<Result<Vec<_>>>()?;
        let default_wl = format!("400:700:{DEFAULT_WAVELENGTHS}");
        let wavelengths_nm = parse_range(
            self.wavelengths.as_deref().unwrap_or(&default_wl),
            "--wavelengths",
        )?;
        let rule = match (self.sizes, CONVERGED_DEFAULT) {
            (Some(sizes), _) => SizeRule::Product { sizes },
            (
                None,
                SizeRule::Converged {
                    ln_step,
                    x_step,
                    z_max,
                },
            ) => SizeRule::Converged {
                ln_step: self.ln_step.unwrap_or(ln_step),
                x_step: self.x_step.unwrap_or(x_step),
                z_max: self.z_max.unwrap_or(z_max),
            },
            (None, rule) => rule,
        };
        let job = MieJob {
            distributions,
            wavelengths_nm,
            rule,
            index: RefractiveIndex::parse(self.index.as_deref().unwrap_or("1.333"))?,
            medium_index: self.medium_index.unwrap_or(1.0),
            angles_deg: angles_from_spec(self.angles.as_deref().unwrap_or("default"))?,
            illuminant: self.illuminant.unwrap_or(Illuminant::D65),
            legendre: self.legendre.unwrap_or(64),
        };
        job.validate()?;
        Ok(job)
    }
}

/// `lognormal`, `mono` or `gamma:ALPHA:GAMMA` at diameter `d`.
fn distribution(kind: &str, d: f64, sigma: f64) -> Result<SizeDistribution> {
    let dist = match kind.split(':').collect::<Vec<_>>().as_slice() {
        ["lognormal"] => SizeDistribution::LogNormal {
            d_median_um: d,
            sigma,
        },
        ["mono"] => SizeDistribution::Mono { d_um: d },
        ["gamma", a, g] => SizeDistribution::ModifiedGamma {
            d_mode_um: d,
            alpha: a
                .parse()
                .with_context(|| format!("--distribution: bad alpha '{a}'"))?,
            gamma: g
                .parse()
                .with_context(|| format!("--distribution: bad gamma '{g}'"))?,
        },
        _ => bail!("--distribution must be lognormal, mono or gamma:ALPHA:GAMMA, got '{kind}'"),
    };
    dist.validate()?;
    Ok(dist)
}

/// `MIN:MAX:N` → N uniform values from MIN to MAX inclusive.
fn parse_range(s: &str, what: &str) -> Result<Vec<f64>> {
    let parts: Vec<&str> = s.split(':').collect();
    let [lo, hi, n] = parts.as_slice() else {
        bail!("{what} must be MIN:MAX:N, got '{s}'")
    };
    let lo: f64 = lo
        .parse()
        .with_context(|| format!("{what}: bad MIN '{lo}'"))?;
    let hi: f64 = hi
        .parse()
        .with_context(|| format!("{what}: bad MAX '{hi}'"))?;
    let n: usize = n.parse().with_context(|| format!("{what}: bad N '{n}'"))?;
    if !(lo.is_finite() && hi.is_finite()) || n == 0 {
        bail!("{what}: empty range '{s}'");
    }
    if hi < lo {
        bail!("{what}: reversed range '{s}' (MIN > MAX)");
    }
    if (n == 1) != (hi == lo) {
        bail!("{what}: '{s}' needs N = 1 exactly when MIN = MAX");
    }
    Ok((0..n)
        .map(|i| {
            if n == 1 {
                lo
            } else {
                lo + (hi - lo) * i as f64 / (n - 1) as f64
            }
        })
        .collect())
}

/// `10`, `5,10,20` or `5:50:46`.
fn parse_list(s: &str, what: &str) -> Result<Vec<f64>> {
    if let Some(range) = s.strip_prefix("log:") {
        let v = parse_range(range, what)?;
        if v[0] <= 0.0 {
            bail!("{what}: 'log:{range}' needs MIN > 0");
        }
        let (lo, hi, n) = (v[0].ln(), v[v.len() - 1].ln(), v.len());
        let step = if n > 1 {
            (hi - lo) / (n - 1) as f64
        } else {
            0.0
        };
        return Ok((0..n).map(|i| (lo + step * i as f64).exp()).collect());
    }
    if s.contains(':') {
        return parse_range(s, what);
    }
    s.split(',')
        .map(|v| {
            v.trim()
                .parse::<f64>()
                .with_context(|| format!("{what}: '{v}' is not a number"))
        })
        .collect()
}

/// Runs `nephele mie`.
pub fn run(args: MieArgs) -> Result<()> {
    let args = args.merged()?;
    let job = args.job()?;
    let out = args
        .out
        .clone()
        .unwrap_or_else(|| PathBuf::from("outputs/mie"));
    nephele::io::check_output_dir(&out)?;
    compute_and_write(&job, &args, &out)
}

/// Computes a job with a progress bar: the tables, their statistics and the seconds taken.
/// Refuses first a job that would not fit in the memory available.
pub(super) fn compute_with_bar(job: &MieJob) -> Result<(Vec<PhaseTable>, JobStats, f64)> {
    job.validate()?;
    if let Some(bytes) = nephele::io::available_memory() {
        job.check_memory(bytes)?;
    }
    let bar = super::progress::work_bar("Mie", 0);
    bar.set_message(format!("{} spheres", short(job.footprint().spheres)));
    let t0 = Instant::now();
    // Positions count Mie terms: a sphere's cost grows with its size, so spheres alone would
    // run the estimate far ahead of the large, slow ones that come last.
    let (tables, stats) = job.compute(&|done, total| {
        bar.set_length(total as u64);
        bar.set_position(done as u64);
    })?;
    bar.finish_and_clear();
    Ok((tables, stats, t0.elapsed().as_secs_f64()))
}

fn compute_and_write(job: &MieJob, args: &MieArgs, out: &Path) -> Result<()> {
    let (tables, stats, compute_s) = compute_with_bar(job)?;
    let t1 = Instant::now();
    write_outputs(job, args, &tables, &stats, compute_s, out)?;
    report(&tables, &stats, compute_s, t1.elapsed().as_secs_f64(), out);
    Ok(())
}

/// Writes tables (phase.npz/json per table, phase.png) as `nephele mie` does.
pub(super) fn write_outputs(
    job: &MieJob,
    args: &MieArgs,
    tables: &[PhaseTable],
    stats: &JobStats,
    compute_s: f64,
    out: &Path,
) -> Result<()> {
    let mut set = AtomicFiles::new();
    let extra = json!({
        "config": { "options": args, "job": job_echo(job) },
        "timings": {
            "compute_s": compute_s,
            "threads": rayon::current_num_threads(),
            "spheres": stats.spheres,
            "max_terms": stats.max_terms,
            "gflop": stats.useful_flops * 1e-9,
            "gflop_per_s": stats.useful_flops * 1e-9 / compute_s,
            "gflop_with_padding": stats.flops * 1e-9,
            "flops_note": "matrix-product flops without the zero padding of short series (8 N n_theta per sphere + accumulation), over the whole compute time",
            "gemm_seconds": stats.gemm_seconds,
            "gemm_gflop_per_s": stats.gemm_flops * 1e-9 / stats.gemm_seconds.max(1e-12),
            "gemm_note": "the GEMM part alone: the flops the GEMM calls do (padding included) over the seconds spent inside them, summed over threads (a rate per thread)",
            "note": "one computation for all tables of this run"
        }
    });
    for t in tables {
        let dir = table_dir(out, t, tables.len());
        write_table(&mut set, &dir, t, extra.clone(), args.csv)?;
    }
    if !args.no_plot {
        std::fs::create_dir_all(out)?;
        let curves: Vec<plot::Curve> = tables
            .iter()
            .map(|t| plot::Curve {
                label: format!("d = {} µm", t.distribution.nominal_diameter_um()),
                x: &t.theta_deg,
                y: &t.phase,
            })
            .collect();
        let title = "Mie phase functions of water droplets (400–700 nm mean)";
        set.write_via_path(&out.join("phase.png"), |p| {
            plot::log_y_plot(
                p,
                title,
                "scattering angle θ (degrees)",
                "p(θ) (1/sr)",
                &curves,
            )
        })?;
    }
    set.commit()
}

/// The job without its long arrays (angles are summarised).
fn job_echo(job: &MieJob) -> serde_json::Value {
    let mut v = serde_json::to_value(job).expect("job serialises");
    let a = &job.angles_deg;
    v["angles_deg"] = json!({ "n": a.len(), "first": a[0], "last": a[a.len() - 1] });
    v
}

/// `out` for a single table, `out/d010.0um` for several.
fn table_dir(out: &Path, t: &PhaseTable, n_tables: usize) -> PathBuf {
    if n_tables == 1 {
        out.to_path_buf()
    } else {
        out.join(format!("d{:05.1}um", t.distribution.nominal_diameter_um()))
    }
}

fn report(tables: &[PhaseTable], stats: &JobStats, compute_s: f64, write_s: f64, out: &Path) {
    outln!(
        "{:>10} {:>10} {:>12} {:>10} {:>12}",
        "d (µm)",
        "g",
        "C_sca (µm²)",
        "Q_sca",
        "d_eff (µm)"
    );
    for t in tables {
        // Significant digits: tiny droplets' cross-sections would print as 0.0000.
        outln!(
            "{:>10} {:>10.6} {:>12} {:>10} {:>12}",
            short(t.distribution.nominal_diameter_um()),
            t.g,
            short(t.c_sca_um2),
            short(t.q_sca),
            short(t.effective_diameter_um)
        );
    }
    outln!(
        "{} spheres, {:.2} s compute ({:.1} GFLOP/s), {:.2} s writing → {}",
        stats.spheres,
        compute_s,
        stats.useful_flops * 1e-9 / compute_s,
        write_s,
        out.display()
    );
}
