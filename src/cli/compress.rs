//! `nephele compress`: fits the compressed form to a slab run's tables and reports its error.

use super::progress::Show;
use anyhow::Result;
use clap::Args;
use nephele::compress::near_beam::NearBeamCheck;
use nephele::compress::report::{CollectorError, GroupError};
use nephele::compress::run::{compress_reporting, Options, Outcome};
use nephele::compress::LogAdditive;
use nephele_runtime::fitting::CollectorForm;
use std::path::{Path, PathBuf};

/// Options of `nephele compress`.
#[derive(Args, Debug)]
pub struct CompressArgs {
    /// tables.npz of `nephele slab` (its tables.json beside it gives the phase function).
    #[arg(long)]
    pub tables: PathBuf,
    /// Output directory (report.json, compressed.npz, transport.ntt).
    #[arg(long)]
    pub out: PathBuf,
    /// Legendre terms in depth.
    #[arg(long, default_value_t = Options::default().form.legendre)]
    pub legendre: usize,
    /// Azimuth harmonics.
    #[arg(long, default_value_t = Options::default().form.harmonics)]
    pub harmonics: usize,
    /// Nodes in the scattering angle.
    #[arg(long, default_value_t = Options::default().form.theta_nodes)]
    pub theta_nodes: usize,
    /// Per-(μ_V, μ_L) γ, offset and depth slope.
    #[arg(long)]
    pub pairs: bool,
    /// Parameters as polynomials of degree Q − 1 in ln t fitted over all thicknesses at once
    /// (interpolates in t); 0 fits each thickness on its own (and writes no transport.ntt).
    #[arg(long, default_value_t = Options::default().smooth_t)]
    pub smooth_t: usize,
    /// Smooth view × sun interaction terms of T: polynomials of degree < A in each cosine
    /// (0: none).
    #[arg(long, default_value_t = Options::default().form.cross)]
    pub cross: usize,
    /// Legendre terms in depth of the collector form (c, σ).
    #[arg(long, default_value_t = Options::default().collector.legendre)]
    pub collector_legendre: usize,
    /// Azimuth harmonics of the collector form.
    #[arg(long, default_value_t = Options::default().collector.harmonics)]
    pub collector_harmonics: usize,
    /// Θ nodes of the collector form.
    #[arg(long, default_value_t = Options::default().collector.theta_nodes)]
    pub collector_theta_nodes: usize,
    /// Legendre terms in ln t of the collector's parameters (0: no collector).
    #[arg(long, default_value_t = Options::default().collector_q)]
    pub collector_smooth_t: usize,
    /// Skip the held-out study (a second fit without two thicknesses and two sun cosines,
    /// evaluated there by interpolation).
    #[arg(long)]
    pub no_held_out: bool,
}

/// Compresses with a spinner naming the stage (a minute and a half on the default tables).
pub(super) fn compress_with_spinner(tables: &Path, out: &Path, opt: &Options) -> Result<Outcome> {
    compress_showing(tables, out, opt, &Show::Own("compress"))
}

/// [`compress_with_spinner`] with its stages shown by `show` (the stages are not timed, so a
/// shared bar stays at the step's start).
pub(super) fn compress_showing(
    tables: &Path,
    out: &Path,
    opt: &Options,
    show: &Show,
) -> Result<Outcome> {
    let shown = show.start();
    let fraction = match show {
        Show::Own(_) => None,
        Show::Share { .. } => Some(0.0),
    };
    compress_reporting(tables, out, opt, &|stage| shown.set(fraction, stage))
}

/// Runs `nephele compress`; `m` tells which flags were given.
pub fn run(args: CompressArgs, m: &clap::ArgMatches) -> Result<()> {
    if args.collector_smooth_t == 0 {
        super::refuse_unused(
            m,
            &[
                "collector_legendre",
                "collector_harmonics",
                "collector_theta_nodes",
            ],
            "with --collector-smooth-t 0 (no collector form is fitted)",
        )?;
    }
    let opt = Options {
        form: LogAdditive {
            legendre: args.legendre,
            harmonics: args.harmonics,
            theta_nodes: args.theta_nodes,
            pairs: args.pairs,
            cross: args.cross,
        },
        smooth_t: args.smooth_t,
        held_out: !args.no_held_out,
        collector: CollectorForm {
            legendre: args.collector_legendre,
            harmonics: args.collector_harmonics,
            theta_nodes: args.collector_theta_nodes,
        },
        collector_q: args.collector_smooth_t,
    };
    opt.check()?;
    nephele::io::check_output_dir(&args.out)?;
    let o = compress_with_spinner(&args.tables, &args.out, &opt)?;
    print_outcome(&o, &args.out);
    Ok(())
}

/// Prints the runtime's T near the beam against the tables there, per group.
fn print_near_beam(nb: &NearBeamCheck, whose: &str) {
    for (what, rows) in [
        ("aureole annuli", &nb.annuli),
        ("view bins near the beam", &nb.bins),
    ] {
        if rows.is_empty() {
            continue;
        }
        outln!("near the beam, {what}, {whose}: group  cells  bias  E (noise), cell means against the tables");
        for r in rows.iter() {
            let name = r.group.map_or("all ≥ 2".to_string(), |g| g.to_string());
            outln!(
                "{name:>40} {:>6} {:>+7.1} % {:>6.1} % ({:.1} %)",
                r.cells,
                100.0 * r.bias,
                100.0 * r.rel_rms,
                100.0 * r.noise
            );
        }
    }
}

/// Prints what a compression measured and wrote.
pub fn print_outcome(o: &Outcome, out: &Path) {
    for w in &o.warnings {
        eprintln!("warning: {w}");
    }
    print_errors("fitted slices", &o.errors);
    print_errors(
        &format!("reference (Bouthors-like, {} parameters)", o.reference.1),
        &o.reference.0,
    );
    print_collector("fitted slices", &o.collector);
    if let Some(h) = &o.held_out {
        print_errors("held-out slices", &h.errors);
        print_collector("held-out slices", &h.collector);
    }
    outln!(
        "{} parameters of T and {} of c, σ ({:.0} KB as f32), fitted in {:.1} s",
        o.params,
        o.collector_params,
        (o.params + o.collector_params) as f64 * 4.0 / 1024.0,
        o.fit_seconds
    );
    outln!(
        "wrote {}/report.json, manifest.json, compressed.npz, fit_vs_tables.png, \
         error_by_thickness.png, error_map.png",
        out.display()
    );
    if let Some(n) = &o.ntt {
        outln!(
            "wrote {} ({:.0} KB); the runtime's f32 evaluation against the fit: T within {:.1e}, \
             σ within {:.1e}, c within {:.1e} σ; order 1 from the stored phase table within {:.1e} \
             of the phase function's; {} cells where only one of them is 0 (T of the cells below \
             10⁻⁶ of their slice's largest within {:.1e}; {} cells below f32's normal range not \
             compared)",
            n.path.display(),
            n.bytes as f64 / 1024.0,
            n.worst_t,
            n.worst_sigma,
            n.worst_c_in_sigma,
            n.worst_order1,
            n.zero_mismatches,
            n.worst_t_faint,
            n.below_f32
        );
        if let Some(nb) = &n.near_beam_form {
            print_near_beam(nb, "the form alone");
        }
        if let Some(nb) = &n.near_beam {
            let whose = if n.near_beam_form.is_some() {
                "with the halo"
            } else {
                "the runtime"
            };
            print_near_beam(nb, whose);
        }
    }
    let (worst, groups) = &o.coverage;
    outln!(
        "coverage over every cell with light: group  orders  dropped (0 or off > 2x)  zero     \
         worst slice   E all cells (noise)"
    );
    for c in groups {
        let (name, orders) = match (c.group, c.first_order) {
            (Some(g), Some(f)) => (g.to_string(), format!("{f}+")),
            _ => ("all".to_string(), "sum ≥ 2".to_string()),
        };
        outln!(
            "{name:>41} {orders:>7}  {:>8.3} %  {:>20.4} %  {:>7.3} %   {:>6.2} % ({:.2} %)",
            100.0 * c.dropped,
            100.0 * c.zero,
            100.0 * c.worst_slice.share,
            100.0 * c.rel_rms_all,
            100.0 * c.noise_all
        );
    }
    outln!(
        "light of orders ≥ 2 the groups drop together: at most {:.3} % of a slice's (t = {}, mu_L = {})",
        100.0 * worst.share,
        worst.t,
        worst.mu_l
    );
}

fn print_errors(what: &str, errors: &[GroupError]) {
    outln!("{what}: group  orders   E (T-weighted rel RMS)   noise    cells");
    for e in errors {
        let name = e
            .first_order
            .map_or("sum ≥ 2".to_string(), |o| format!("{o:>4}+"));
        let group = e.group.map_or("all".into(), |g| g.to_string());
        outln!(
            "{:>w$}  {group:>5}  {name:>7}   {:>8.2} %               {:>5.2} %  {:>7}",
            "",
            100.0 * e.rel_rms,
            100.0 * e.noise,
            e.cells,
            w = what.len()
        );
    }
}

fn print_collector(what: &str, errors: &[CollectorError]) {
    if errors.is_empty() {
        return;
    }
    outln!("{what}: group  orders   σ rel RMS (noise)    |Δc|/σ RMS (noise)   cells");
    for e in errors {
        outln!(
            "{:>w$}  {:>5}  {:>6}+   {:>6.2} % ({:>5.2} %)   {:>6.2} % ({:>5.2} %)  {:>7}",
            "",
            e.group,
            e.first_order,
            100.0 * e.sigma_rel,
            100.0 * e.sigma_noise,
            100.0 * e.c_in_sigma,
            100.0 * e.c_noise,
            e.cells,
            w = what.len()
        );
    }
}
