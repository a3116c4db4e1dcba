//! Command-line definitions. Without a subcommand, `nephele` runs the main job
//! ([`pipeline`]): the paper's setup (fit-configs/paper.json) — Mie tables for d = 5…50 µm and
//! every model fitted to them — then slab tables of 10 µm droplets and their compression, into
//! outputs/.

/// `println!` for a command's report on stdout. A reader that closes the pipe early
/// (`nephele transport … | head -1`) only ends the report: the command still writes its files
/// and exits 0, as `cat` or `rg` would.
macro_rules! outln {
    ($($arg:tt)*) => {
        $crate::cli::write_out(format_args!($($arg)*))
    };
}

mod compare;
mod compress;
mod export_gpu;
mod fit;
pub mod interrupt;
mod mie;
mod phase;
mod pipeline;
mod progress;
mod render;
mod slab;
mod sphere;
mod tables;
mod transport;

/// Writes one line of [`outln!`]; a closed pipe is ignored, any other failure warned once.
pub(crate) fn write_out(line: std::fmt::Arguments) {
    use std::io::Write;
    use std::sync::atomic::{AtomicBool, Ordering};
    static WARNED: AtomicBool = AtomicBool::new(false);
    let mut out = std::io::stdout().lock();
    let result = out.write_fmt(line).and_then(|()| out.write_all(b"\n"));
    if let Err(e) = result {
        let quiet = e.kind() == std::io::ErrorKind::BrokenPipe;
        if !quiet && !WARNED.swap(true, Ordering::Relaxed) {
            eprintln!(
                "warning: the report on stdout could not be written ({e}); files are still written"
            );
        }
    }
}

use anyhow::Result;
use clap::{ArgMatches, Parser, Subcommand};
use std::process::ExitCode;

/// nephele — light scattering by water droplets, from Mie theory to renderer-ready tables.
///
/// Without a subcommand, `nephele` runs the main job on built-in configs (~2 min on 2 cores):
/// Mie tables and phase-model fits (→ outputs/mie, outputs/fit), quick slab tables of 10 µm
/// droplets (→ outputs/slab-quick), their compression (→ outputs/transport/quick), the
/// path-traced default cloud (→ outputs/render/cloud) and the same cloud by the collector
/// renderer, compared (→ outputs/render/cloud-collector, outputs/compare/cloud), all relative
/// to the current directory.
#[derive(Parser, Debug)]
#[command(version, about)]
pub struct Cli {
    #[command(subcommand)]
    command: Option<Command>,
    /// Worker threads (default: all cores). Results do not depend on it.
    #[arg(long, global = true)]
    threads: Option<usize>,
    /// Main job only: the default slab tables (fit-configs/slab-default.json, ~17 min on 2
    /// cores → outputs/slab) instead of the quick preset, compressed into
    /// outputs/transport/mie10um (the shipped copy in runtime/tables/mie10um is not touched).
    #[arg(long)]
    full: bool,
}

#[derive(Subcommand, Debug)]
enum Command {
    /// Polydisperse, spectral Mie phase functions of water droplets (phase.npz + phase.json).
    #[command(allow_negative_numbers = true)]
    Mie(mie::MieArgs),
    /// Fit HG, two-term HG, Cornette–Shanks, Draine and HG+Draine to Mie tables; diameter curves.
    #[command(allow_negative_numbers = true)]
    Fit(fit::FitArgs),
    /// Slab Monte Carlo: the canonical transport tables ⟨T, c, σ⟩ per order group (docs/slab.md).
    #[command(allow_negative_numbers = true)]
    Slab(slab::SlabArgs),
    /// Fit the compressed form (docs/compress.md) to a slab run's tables and report its error per group.
    #[command(allow_negative_numbers = true)]
    Compress(compress::CompressArgs),
    /// Transport tables for another droplet size in one command: slab Monte Carlo and
    /// compression, ready for `render --method collector --tables DIR`.
    #[command(allow_negative_numbers = true)]
    Tables(tables::TablesArgs),
    /// Evaluate compressed transport tables (transport.ntt) at one point: T per order group, as JSON.
    #[command(allow_negative_numbers = true)]
    Transport(transport::TransportArgs),
    /// Lay transport tables out for the GPU: the WGSL port's storage buffer and index uniform as little-endian files, the WGSL source bound to your group and bindings, and layout.json (for engines in any language).
    #[command(name = "export-gpu")]
    ExportGpu(export_gpu::ExportGpuArgs),
    /// Render a scene (slab, cloud, voxels, fog; lights and a ground for the path tracer) with the path tracer or a fast method (collector, single, octaves): image and per-order AOVs.
    #[command(allow_negative_numbers = true)]
    Render(render::RenderArgs),
    /// Compare renders with a path-traced reference per order group, beside its noise (report.json, figures).
    #[command(allow_negative_numbers = true)]
    Compare(compare::CompareArgs),
    /// Merge the shards of a slab run (`nephele slab --shard K/N`) into its tables.
    #[command(allow_negative_numbers = true)]
    Merge(slab::MergeArgs),
    /// Tabulate and sample a phase model of nephele-runtime (or a Mie table); renderer LUTs.
    #[command(allow_negative_numbers = true)]
    Phase(phase::PhaseArgs),
    /// One sphere: Q_ext, Q_sca, Q_back, g and S1, S2 at given angles, as JSON on stdout.
    #[command(allow_negative_numbers = true)]
    Sphere(sphere::SphereArgs),
}

/// A parser of the names in `names` (kebab-case, shown in `--help`), accepting their
/// snake_case spelling too.
fn names<T: Copy + Send + Sync + 'static>(
    names: &'static [(T, &'static str)],
) -> impl clap::builder::TypedValueParser<Value = T> {
    use clap::builder::{PossibleValue, PossibleValuesParser, TypedValueParser};
    let values = names
        .iter()
        .map(|(_, n)| PossibleValue::new(*n).alias(n.replace('-', "_")));
    PossibleValuesParser::new(values).try_map(move |s: String| {
        let kebab = s.replace('_', "-");
        names
            .iter()
            .find(|(_, n)| *n == kebab)
            .map(|(v, _)| *v)
            .ok_or_else(|| format!("unknown name '{s}'"))
    })
}

/// A parse error as one line, like every other error (`error: …`), with where to look;
/// `--help` and `--version` print as clap prints them.
pub fn parse_error(e: clap::Error) -> ExitCode {
    use clap::error::ErrorKind;
    if matches!(
        e.kind(),
        ErrorKind::DisplayHelp
            | ErrorKind::DisplayVersion
            | ErrorKind::DisplayHelpOnMissingArgumentOrSubcommand
    ) {
        let _ = e.print();
        return ExitCode::from(e.exit_code() as u8);
    }
    let text = e.render().to_string();
    // The first paragraph, on one line: clap lists missing arguments on the lines below it.
    let paragraph: Vec<&str> = text
        .lines()
        .take_while(|l| !l.trim().is_empty())
        .map(str::trim)
        .collect();
    let first = paragraph.join(" ");
    let first = first.trim_start_matches("error: ");
    let tip = text
        .lines()
        .find_map(|l| l.trim().strip_prefix("tip: "))
        .map_or(String::new(), |t| format!("; {t}"));
    eprintln!("error: {first}{tip} (see --help)");
    ExitCode::from(2)
}

/// Seconds with three significant digits (0.570 s, 12.3 s, 135 s): a fast render's 0.57 s
/// must not read "1 s".
pub(crate) fn seconds(s: f64) -> String {
    if !s.is_finite() || s <= 0.0 {
        return "? s".into(); // render.json without its seconds
    }
    let decimals = (2 - s.log10().floor() as i32).clamp(0, 6) as usize;
    format!("{s:.decimals$} s")
}

/// A finite number > 0 (clap parser: negative values reach it and get the range).
fn positive_f64(s: &str) -> std::result::Result<f64, String> {
    let v: f64 = s.parse().map_err(|e| format!("{e}"))?;
    if v.is_finite() && v > 0.0 {
        Ok(v)
    } else {
        Err(format!("{v} is not > 0"))
    }
}

/// Whether the user gave `id` on the command line (not a default).
fn given(m: &ArgMatches, id: &str) -> bool {
    m.try_contains_id(id).unwrap_or(false)
        && m.value_source(id) == Some(clap::parser::ValueSource::CommandLine)
}

/// Refuses the flags among `ids` that were given, where they `do not apply …` (the reason,
/// e.g. "to --method collector (path tracer only)").
fn refuse_unused(m: &ArgMatches, ids: &[&str], reason: &str) -> Result<()> {
    let used: Vec<String> = ids
        .iter()
        .filter(|id| given(m, id))
        .map(|id| format!("--{}", id.replace('_', "-")))
        .collect();
    anyhow::ensure!(
        used.is_empty(),
        "{} {} not apply {reason}",
        used.join(", "),
        if used.len() == 1 { "does" } else { "do" }
    );
    Ok(())
}

/// Runs the parsed command; `matches` tell what was given on the command line.
pub fn run(cli: Cli, matches: &ArgMatches) -> Result<()> {
    let sub = matches.subcommand().map_or(matches, |(_, m)| m);
    if let Some(n) = cli.threads {
        anyhow::ensure!(n >= 1, "--threads must be at least 1");
        rayon::ThreadPoolBuilder::new()
            .num_threads(n)
            .build_global()?;
    }
    anyhow::ensure!(
        !(cli.full && cli.command.is_some()),
        "--full belongs to the main job (no subcommand)"
    );
    match cli.command {
        Some(Command::Mie(args)) => mie::run(args),
        Some(Command::Sphere(args)) => sphere::run(args),
        Some(Command::Phase(args)) => phase::run(args),
        Some(Command::Fit(args)) => fit::run(args),
        Some(Command::Slab(args)) => slab::run(args),
        Some(Command::Merge(args)) => slab::merge_shards(args),
        Some(Command::Compress(args)) => compress::run(args, sub),
        Some(Command::Tables(args)) => tables::run(args),
        Some(Command::Transport(args)) => transport::run(args),
        Some(Command::ExportGpu(args)) => export_gpu::run(args),
        Some(Command::Render(args)) => render::run(args, sub),
        Some(Command::Compare(args)) => compare::run(args),
        None => pipeline::run(cli.full),
    }
}
