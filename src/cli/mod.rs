//! Command-line definitions. Without a subcommand, `nephele` runs the main job
//! ([`pipeline`]): the paper's setup (fit-configs/paper.json) — Mie tables for d = 5…50 µm and
//! every model fitted to them — then slab tables of 10 µm droplets and their compression, into
//! outputs/.

mod compare;
mod compress;
mod fit;
mod mie;
mod phase;
mod pipeline;
mod render;
mod slab;
mod sphere;
mod transport;

use anyhow::Result;
use clap::{Parser, Subcommand};

/// nephele — light scattering by water droplets, from Mie theory to renderer-ready tables.
///
/// Without a subcommand, `nephele` runs the main job on built-in configs (~4 min on 2 cores):
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
    Mie(mie::MieArgs),
    /// Fit HG, two-term HG, Cornette–Shanks, Draine and HG+Draine to Mie tables; diameter curves.
    Fit(fit::FitArgs),
    /// Slab Monte Carlo: the canonical transport tables ⟨T, c, σ⟩ per order group (docs/slab.md).
    Slab(slab::SlabArgs),
    /// Fit the compressed form (docs/compress.md) to a slab run's tables and report its error per group.
    Compress(compress::CompressArgs),
    /// Evaluate compressed transport tables (transport.ntt) at one point: T per order group, as JSON.
    Transport(transport::TransportArgs),
    /// Render a scene (slab, cloud, voxels) with the path tracer or a fast method (collector, single, octaves): image and per-order AOVs.
    Render(render::RenderArgs),
    /// Compare renders with a path-traced reference per order group, beside its noise (report.json, figures).
    Compare(compare::CompareArgs),
    /// Merge the shards of a slab run (`nephele slab --shard K/N`) into its tables.
    Merge(slab::MergeArgs),
    /// Tabulate and sample a phase model of nephele-runtime (or a Mie table); renderer LUTs.
    Phase(phase::PhaseArgs),
    /// One sphere: Q_ext, Q_sca, Q_back, g and S1, S2 at given angles, as JSON on stdout.
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

/// Runs the parsed command.
pub fn run(cli: Cli) -> Result<()> {
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
        Some(Command::Compress(args)) => compress::run(args),
        Some(Command::Transport(args)) => transport::run(args),
        Some(Command::Render(args)) => render::run(args),
        Some(Command::Compare(args)) => compare::run(args),
        None => pipeline::run(cli.full),
    }
}
