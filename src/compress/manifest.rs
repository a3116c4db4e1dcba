//! manifest.json: what shipped tables are — the slab run they come from, the compressor's
//! options, the domain, the errors and coverage measured, and the file's size and CRC.

use super::coverage::SliceShare;
use super::ntt::NttCheck;
use super::report::{CollectorError, GroupError};
use super::run::{CollectorOptions, Measured, Options};
use super::SlabTables;
use anyhow::Result;
use serde::Serialize;
use std::path::Path;

/// manifest.json, what shipped tables are: the slab run they come from (its config, seed,
/// photons, tool version), the compressor's version and options, the file's size and CRC-32,
/// and the error summary (per group, fitted and held out, T and the collector).
#[derive(Serialize)]
pub(super) struct Manifest {
    what: &'static str,
    file: Option<FileId>,
    slab_run: serde_json::Map<String, serde_json::Value>,
    compressor: Compressor,
    errors: ErrorSummary,
    coverage: CoverageSummary,
    domain: Domain,
}

/// What a renderer may ask and what the tables answer outside their grid.
#[derive(Serialize)]
struct Domain {
    thickness: [f64; 2],
    mu_l: [f64; 2],
    mu_v: [f64; 2],
    psi_v: [f64; 2],
    depth: &'static str,
    outside: &'static str,
}

#[derive(Serialize)]
struct CoverageSummary {
    definition: &'static str,
    worst_slice_all_groups: SliceShare,
    /// Every (t, μ_L) slice's share dropped by the groups together (t outer).
    slices_all_groups: Vec<SliceShare>,
    /// Per group then the sum: dropped share, zero share, relative RMS over every cell.
    dropped: Vec<f64>,
    zero: Vec<f64>,
    rel_rms_all: Vec<f64>,
    noise_all: Vec<f64>,
}

#[derive(Serialize)]
struct FileId {
    name: &'static str,
    bytes: usize,
    crc32: String,
}

#[derive(Serialize)]
struct Compressor {
    version: &'static str,
    git_commit: Option<&'static str>,
    form: serde_json::Value,
    smooth_t: usize,
    collector: CollectorOptions,
}

#[derive(Serialize)]
struct ErrorSummary {
    definition: &'static str,
    fitted: Summary,
    held_out: Option<HeldOutSummary>,
}

#[derive(Serialize)]
struct Summary {
    #[serde(rename = "T")]
    t: Vec<TSummary>,
    collector: Vec<CollectorSummary>,
}

#[derive(Serialize)]
struct HeldOutSummary {
    thicknesses: Vec<f64>,
    mu_l: Vec<f64>,
    #[serde(flatten)]
    summary: Summary,
}

#[derive(Serialize)]
struct TSummary {
    first_order: Option<f64>,
    rel_rms: f64,
    noise: f64,
}

#[derive(Serialize)]
struct CollectorSummary {
    first_order: f64,
    sigma_rel: f64,
    c_in_sigma: f64,
    sigma_noise: f64,
    c_noise: f64,
}

impl Summary {
    fn of(errors: &[GroupError], collector: &[CollectorError]) -> Self {
        Summary {
            t: errors
                .iter()
                .map(|e| TSummary {
                    first_order: e.first_order,
                    rel_rms: e.rel_rms,
                    noise: e.noise,
                })
                .collect(),
            collector: collector
                .iter()
                .map(|c| CollectorSummary {
                    first_order: c.first_order,
                    sigma_rel: c.sigma_rel,
                    c_in_sigma: c.c_in_sigma,
                    sigma_noise: c.sigma_noise,
                    c_noise: c.c_noise,
                })
                .collect(),
        }
    }
}

pub(super) fn manifest(
    tables: &Path,
    tab: &SlabTables,
    opt: &Options,
    m: &Measured,
    ntt: Option<&NttCheck>,
) -> Result<Manifest> {
    let slab: serde_json::Value = std::fs::read_to_string(tables.with_extension("json"))
        .ok()
        .and_then(|t| serde_json::from_str(&t).ok())
        .unwrap_or_default();
    let keys = [
        "config",
        "seed",
        "photons",
        "events",
        "converged_slices",
        "version",
        "git_commit",
    ];
    let file = match ntt {
        Some(n) => {
            let bytes = std::fs::read(&n.path)?;
            Some(FileId {
                name: "transport.ntt",
                bytes: bytes.len(),
                // The CRC of the body (the file's own trailer): the CRC of the whole file,
                // trailer included, is the same constant for every file (CRC-32's residue).
                crc32: format!(
                    "{:08x}",
                    nephele_runtime::fitting::crc32(&bytes[..bytes.len().saturating_sub(4)])
                ),
            })
        }
        None => None,
    };
    Ok(Manifest {
        what: "compressed slab transport tables: T, c, sigma per order group of orders >= 2 (docs/compress.md); order 1 in closed form from the stored phase function",
        file,
        slab_run: keys.iter().map(|k| (k.to_string(), slab[*k].clone())).collect(),
        compressor: Compressor {
            version: crate::VERSION,
            git_commit: option_env!("NEPHELE_GIT_COMMIT"),
            form: super::form::to_json(&opt.form),
            smooth_t: opt.smooth_t,
            collector: CollectorOptions::of(opt),
        },
        errors: ErrorSummary {
            definition: "T-weighted relative RMS of T per group and for the sum of groups (last); sigma relative, c in units of sigma; noise = the tables' own on the same cells",
            fitted: Summary::of(&m.errors, &m.collector),
            held_out: m.held_out.as_ref().map(|h| HeldOutSummary {
                thicknesses: h.thicknesses.clone(),
                mu_l: h.mu_l.clone(),
                summary: Summary::of(&h.errors, &h.collector),
            }),
        },
        coverage: CoverageSummary {
            definition: m.coverage.definition,
            worst_slice_all_groups: m.coverage.worst_slice_all_groups,
            slices_all_groups: m.coverage.slices_all_groups.clone(),
            dropped: m.coverage.groups.iter().map(|c| c.dropped).collect(),
            zero: m.coverage.groups.iter().map(|c| c.zero).collect(),
            rel_rms_all: m.coverage.groups.iter().map(|c| c.rel_rms_all).collect(),
            noise_all: m.coverage.groups.iter().map(|c| c.noise_all).collect(),
        },
        domain: Domain {
            thickness: [tab.thickness[0], tab.thickness[tab.thickness.len() - 1]],
            mu_l: [tab.mu_l[0], tab.mu_l[tab.mu_l.len() - 1]],
            mu_v: [-1.0, 1.0],
            psi_v: [0.0, std::f64::consts::PI],
            depth: "[0, t]",
            outside: "t or mu_L outside their ranges: past the thickest slab the tables continue by diffusion theory (docs/compress.md, 'Past the thickest slab'); below the thinnest slab the form's parameters are held at the grid's end while the geometry (boundary factor, single-scattering factor, scattering angle) follows the point; below the lowest sun mu_0 the point is read under mu_0 and T scaled by mu_L/mu_0 (T/mu_L held); Domain::outside tells a caller which coordinate and by how much",
        },
    })
}
