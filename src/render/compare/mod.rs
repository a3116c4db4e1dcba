//! `nephele compare`: how far a candidate render is from a path-traced reference, per order
//! group, beside the reference's own noise (docs/collector.md).
//!
//! Quantities, per pixel, on the luminance Y = 0.2126 R + 0.7152 G + 0.0722 B: order 1, each
//! group of orders ≥ 2 (where the candidate splits them), the sum of orders ≥ 2, the beauty
//! image. Over the reference's opaque pixels (opacity > 0.5), and apart over the lit face, the
//! shadowed face and the silhouette (the candidate's regions.npy, from its light maps):
//!
//! - bias = ⟨c⟩/⟨r⟩ − 1, beside the reference mean's own relative standard error;
//! - relative RMSE = √⟨(c − r)²⟩ / ⟨r⟩, beside the reference's noise √⟨v⟩ / ⟨r⟩ and corrected
//!   for it: √(⟨(c − r)² − v⟩) / ⟨r⟩ with its standard error, where v = (A − B)²/4 is the
//!   split-sample variance of a reference pixel's mean (A, B the means of its even and odd
//!   samples, halves.npy) — E[(c − r)²] = (c − E r)² + Var r, so what is left is the error of
//!   the candidate, not the reference's grain;
//! - PSNR of the beauty images tone-mapped with the reference's exposure (8-bit sRGB, what
//!   people look at; FLIP on the same images by scripts/compare_flip.py).
//!
//! The folders are read by `load.rs`, judged by `stats.rs` and drawn by `figures.rs`; this file
//! runs them and writes the report.

mod figures;
mod load;
mod stats;

pub use load::RenderDir;
pub use stats::Stats;

use figures::error_image;
use load::check_inputs;
use stats::{group_quantities, masks, split_variance, Quantity};

use super::output::{exposure as auto_exposure, png_bytes, tone_map_with, CLOUD_OPACITY};
use crate::io::AtomicFiles;
use anyhow::{ensure, Context, Result};
use serde::Serialize;
use std::path::{Path, PathBuf};

/// One quantity over every region.
#[derive(Clone, Debug, Serialize)]
pub struct QuantityReport {
    /// Its name.
    pub quantity: String,
    /// Over the opaque pixels, and per region (lit, shadowed, silhouette) where known.
    pub regions: std::collections::BTreeMap<String, Stats>,
}

/// One candidate against the reference.
#[derive(Clone, Debug, Serialize)]
pub struct CandidateReport {
    /// Its directory.
    pub dir: String,
    /// Its method.
    pub method: String,
    /// Its seconds a frame (render.json).
    pub seconds: f64,
    /// Per quantity.
    pub quantities: Vec<QuantityReport>,
    /// PSNR (dB) of the tone-mapped beauty images.
    pub psnr_db: f64,
    /// Mean FLIP, filled in by scripts/compare_flip.py.
    pub flip_mean: Option<f64>,
    /// What the candidate is worth against the reference's method, if measurable.
    pub equal_quality: Option<EqualQuality>,
}

/// The figure of merit of a fast method: how long the reference's method (the path tracer)
/// would need to reach the candidate's beauty error, against the candidate's frame.
///
/// The reference's noise N (relative, over the opaque pixels) falls as 1/√time, so it reaches
/// the candidate's noise-corrected relative RMSE E after `path_seconds` = T_ref (N/E)², T_ref
/// its own render time; `speedup` = that over the candidate's seconds a frame.
#[derive(Clone, Copy, Debug, Serialize)]
pub struct EqualQuality {
    /// s the reference's method needs to match the candidate's beauty error.
    pub path_seconds: f64,
    /// `path_seconds` over the candidate's seconds a frame.
    pub speedup: f64,
}

impl EqualQuality {
    /// From the beauty image's statistics over the opaque pixels, the reference's seconds and
    /// the candidate's; None without a reference noise, a time, or an error above the noise.
    pub fn new(beauty: &Stats, reference_seconds: f64, seconds: f64) -> Option<Self> {
        let (noise, error) = (beauty.reference_noise, beauty.rel_rmse_corrected);
        let usable = |x: f64| x.is_finite() && x > 0.0;
        if !(usable(noise) && usable(error) && usable(reference_seconds) && usable(seconds)) {
            return None;
        }
        let path_seconds = reference_seconds * (noise / error).powi(2);
        Some(Self {
            path_seconds,
            speedup: path_seconds / seconds,
        })
    }
}

/// The whole comparison.
#[derive(Clone, Debug, Serialize)]
pub struct Report {
    /// The reference's directory, method, samples per pixel and seconds.
    pub reference: String,
    /// See `reference`.
    pub reference_method: String,
    /// See `reference`.
    pub reference_spp: u64,
    /// See `reference`.
    pub reference_seconds: f64,
    /// The exposure k (1 / radiance) of the tone-mapped images: 1 − e^{−k x}, then sRGB.
    pub exposure: f32,
    /// Per candidate.
    pub candidates: Vec<CandidateReport>,
    /// What the numbers mean, in one line (as on stdout).
    pub legend: &'static str,
    /// The unit of each field.
    pub units: std::collections::BTreeMap<&'static str, &'static str>,
    /// What the numbers mean, in full.
    pub definitions: &'static str,
}

/// The table's legend: which number is which, and in what unit.
pub const LEGEND: &str = "bias = <c>/<r> - 1 and rel RMSE = sqrt<(c - r)^2>/<r>, in % of the \
    reference's mean luminance over the row's pixels, each beside the reference's own noise; \
    corrected = rel RMSE less that noise (± its standard error); PSNR (dB, higher is closer) of \
    the 8-bit tone-mapped beauty images";

/// The unit of each field of report.json.
pub(super) fn units() -> std::collections::BTreeMap<&'static str, &'static str> {
    let fraction = "fraction of the reference's mean luminance over the pixels (0.01 = 1 %)";
    [
        ("bias", fraction),
        ("bias_noise", fraction),
        ("rel_rmse", fraction),
        ("reference_noise", fraction),
        ("rel_rmse_corrected", fraction),
        ("rel_rmse_corrected_se", fraction),
        (
            "mean_reference",
            "luminance of the linear radiance (the scene's units)",
        ),
        (
            "mean_candidate",
            "luminance of the linear radiance (the scene's units)",
        ),
        ("pixels", "count"),
        (
            "psnr_db",
            "dB of the 8-bit tone-mapped beauty images, higher is closer",
        ),
        ("flip_mean", "mean FLIP, 0 (identical) to 1"),
        ("seconds", "s of wall-clock time a frame"),
        ("reference_seconds", "s of wall-clock time"),
        ("exposure", "1 / radiance: the tone curve is 1 - exp(-k x)"),
        (
            "path_seconds",
            "s the reference's method needs to reach the candidate's beauty error",
        ),
        (
            "speedup",
            "path_seconds over the candidate's seconds a frame",
        ),
    ]
    .into_iter()
    .collect()
}

pub(super) const DEFINITIONS: &str =
    "luminance per pixel; pixels with reference opacity > 0.5 ('opaque'), \
    and apart the candidate's regions (lit: sun optical depth < 2 at the visible surface point, \
    shadowed, silhouette: 0.5 < opacity < 0.99); bias = <c>/<r> - 1 with bias_noise the \
    reference mean's relative standard error; rel_rmse = sqrt<(c - r)^2>/<r>, reference_noise = \
    sqrt<v>/<r> with v = (A - B)^2/4 the split-sample variance of a reference pixel (halves.npy; \
    for the beauty image that of the scattered light, the unscattered sky's own noise left out), \
    rel_rmse_corrected = sqrt(max(0, <(c - r)^2 - v>))/<r> and its standard error; psnr_db on the \
    beauty images tone-mapped with the reference's exposure (8-bit sRGB); flip_mean from \
    scripts/compare_flip.py on the same images; equal_quality: path_seconds = reference_seconds \
    * (reference_noise / rel_rmse_corrected)^2 of the beauty image over the opaque pixels (the \
    reference's noise falls as 1/sqrt(time)), speedup = path_seconds / seconds";

/// Compares `candidates` with `reference`; writes report.json, the tone-mapped images and the
/// figures into `out` (at the reference's exposure).
pub fn compare(reference: &Path, candidates: &[PathBuf], out: &Path) -> Result<Report> {
    compare_with(reference, candidates, out, None)
}

/// [`compare`] with the images' exposure k (1 / radiance) given; None: the reference's (its
/// render.json's, or chosen as `nephele render` chooses it).
pub fn compare_with(
    reference: &Path,
    candidates: &[PathBuf],
    out: &Path,
    exposure: Option<f32>,
) -> Result<Report> {
    check_inputs(reference, candidates)?;
    let r = RenderDir::read(reference)?;
    let cands: Vec<RenderDir> = candidates
        .iter()
        .map(|c| RenderDir::read(c))
        .collect::<Result<_>>()?;
    let masks = masks(&r, &cands);
    let opaque = masks[0].1.iter().filter(|&&o| o).count();
    ensure!(
        opaque > 0,
        "no pixel of the reference '{}' is opaque (opacity > {CLOUD_OPACITY}): its camera sees \
         no cloud, so there is nothing to compare; render a view of the medium",
        reference.display()
    );
    let k = exposure
        .or_else(|| r.meta["exposure"].as_f64().map(|k| k as f32))
        .unwrap_or_else(|| auto_exposure(&r.beauty, &r.opacity).k);
    let ref_ldr = tone_map_with(&r.beauty, k);
    let mut files = AtomicFiles::new();
    std::fs::create_dir_all(out).with_context(|| format!("cannot create '{}'", out.display()))?;
    files.write_bytes(&out.join("reference.png"), &png_bytes(&ref_ldr, r.size)?)?;
    let mut reports = Vec::new();
    let mut error_rows = Vec::new();
    for (ci, c) in cands.iter().enumerate() {
        let (quantities, errors) = judge(&r, c, &masks);
        error_rows.extend(errors.into_iter().map(|(q, img)| (ci, q, img)));
        let ldr = tone_map_with(&c.beauty, k);
        let seconds = c.meta["seconds"].as_f64().unwrap_or(f64::NAN);
        let beauty = quantities
            .iter()
            .find(|q| q.quantity == Quantity::Beauty.name())
            .and_then(|q| q.regions.get("opaque"));
        let reference_seconds = r.meta["seconds"].as_f64().unwrap_or(f64::NAN);
        let equal_quality = beauty.and_then(|b| EqualQuality::new(b, reference_seconds, seconds));
        files.write_bytes(
            &out.join(format!("candidate{ci}.png")),
            &png_bytes(&ldr, r.size)?,
        )?;
        reports.push(CandidateReport {
            dir: c.dir.display().to_string(),
            method: c.method.clone(),
            seconds,
            quantities,
            psnr_db: psnr_db(&ldr, &ref_ldr),
            flip_mean: None,
            equal_quality,
        });
    }
    let report = Report {
        reference: r.dir.display().to_string(),
        reference_method: r.method.clone(),
        reference_spp: r.meta["spp"].as_u64().unwrap_or(0),
        reference_seconds: r.meta["seconds"].as_f64().unwrap_or(f64::NAN),
        exposure: k,
        candidates: reports,
        legend: LEGEND,
        units: units(),
        definitions: DEFINITIONS,
    };
    let mut json = serde_json::to_vec_pretty(&report)?;
    json.push(b'\n');
    files.write_bytes(&out.join("report.json"), &json)?;
    figures::figures(&mut files, out, &r, &cands, k, &error_rows)?;
    files.commit()?;
    Ok(report)
}

/// One candidate's statistics per quantity and mask, and the error images of order 1 and
/// orders ≥ 2 (by quantity name).
pub(super) fn judge(
    r: &RenderDir,
    c: &RenderDir,
    masks: &[(String, Vec<bool>)],
) -> (Vec<QuantityReport>, Vec<(String, Vec<u8>)>) {
    let n = r.pixels();
    let opaque = &masks[0].1;
    let mut quantities = group_quantities();
    quantities.push(Quantity::Beauty);
    let mut reports = Vec::new();
    let mut errors = Vec::new();
    for q in quantities {
        if let Quantity::Groups(a, b) = q {
            if b - a == 1 && a >= 1 && !c.splits_orders() {
                continue;
            }
        }
        let rv = q.of(&r.groups, &r.beauty, n);
        let cv = q.of(&c.groups, &c.beauty, n);
        let var = r.halves.as_ref().map(|h| split_variance(q, h, n));
        let regions = masks
            .iter()
            .filter_map(|(name, mask)| {
                Some((name.clone(), stats::stats(&cv, &rv, var.as_deref(), mask)?))
            })
            .collect();
        if matches!(q, Quantity::Groups(1, _) | Quantity::Groups(0, 1)) {
            errors.push((q.name(), error_image(&cv, &rv, opaque)));
        }
        reports.push(QuantityReport {
            quantity: q.name(),
            regions,
        });
    }
    (reports, errors)
}

/// PSNR (dB) of 8-bit images `a` against `b`.
pub(super) fn psnr_db(a: &[u8], b: &[u8]) -> f64 {
    let mse = a
        .iter()
        .zip(b)
        .map(|(&x, &y)| ((x as f64 - y as f64) / 255.0).powi(2))
        .sum::<f64>()
        / a.len().max(1) as f64;
    10.0 * (1.0 / mse.max(1e-12)).log10()
}
