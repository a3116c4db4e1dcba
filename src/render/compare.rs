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

use super::image::GROUP_FIRST;
use super::output::{exposure as auto_exposure, png_bytes, tone_map_with, CLOUD_OPACITY};
use crate::io::npy::read_npy;
use crate::io::plot::{image_grid, image_grid_with_bar, text_width, ColourBar, Tile};
use crate::io::AtomicFiles;
use anyhow::{bail, ensure, Context, Result};
use serde::Serialize;
use serde_json::Value;
use std::path::{Path, PathBuf};

/// A render directory's arrays.
pub struct RenderDir {
    /// The directory.
    pub dir: PathBuf,
    /// Method ("path_tracer", "collector", ...).
    pub method: String,
    /// render.json.
    pub meta: serde_json::Value,
    /// Width and height.
    pub size: (usize, usize),
    /// [group, H, W, 3].
    pub groups: Vec<f32>,
    /// [H, W, 3].
    pub beauty: Vec<f32>,
    /// [H, W].
    pub opacity: Vec<f32>,
    /// [2, group, H, W, 3], if written.
    pub halves: Option<Vec<f32>>,
    /// [H, W], if written.
    pub regions: Option<Vec<u8>>,
}

/// Whether render.json lists `name` among the files its render wrote: a file of an earlier
/// render left in the same folder is not this render's.
fn listed(meta: &serde_json::Value, name: &str) -> bool {
    meta["files"].get(name).is_some()
}

/// A render directory's render.json.
fn read_meta(dir: &Path) -> Result<serde_json::Value> {
    let json = dir.join("render.json");
    let text = std::fs::read_to_string(&json)
        .with_context(|| format!("cannot read '{}' (a render directory?)", json.display()))?;
    serde_json::from_str(&text).with_context(|| format!("'{}'", json.display()))
}

/// Width and height in render.json.
fn meta_size(meta: &serde_json::Value) -> (u64, u64) {
    let dim = |key: &str| meta[key].as_u64().unwrap_or(0);
    (dim("width"), dim("height"))
}

impl RenderDir {
    /// Reads a directory `nephele render` wrote.
    pub fn read(dir: &Path) -> Result<Self> {
        let meta = read_meta(dir)?;
        let (w, h) = meta_size(&meta);
        ensure!(
            w > 0 && h > 0,
            "'{}': no image size",
            dir.join("render.json").display()
        );
        let ng = GROUP_FIRST.len() as u64;
        let halves = dir.join("halves.npy");
        let regions = dir.join("regions.npy");
        Ok(Self {
            dir: dir.to_path_buf(),
            method: method_name(&meta),
            size: (w as usize, h as usize),
            groups: read_npy(&dir.join("groups.npy"), &[ng, h, w, 3])?,
            beauty: read_npy(&dir.join("beauty.npy"), &[h, w, 3])?,
            opacity: read_npy(&dir.join("opacity.npy"), &[h, w])?,
            halves: if listed(&meta, "halves.npy") && halves.exists() {
                Some(read_npy(&halves, &[2, ng, h, w, 3])?)
            } else {
                None
            },
            regions: if listed(&meta, "regions.npy") && regions.exists() {
                Some(read_npy(&regions, &[h, w])?)
            } else {
                None
            },
            meta,
        })
    }

    fn pixels(&self) -> usize {
        self.size.0 * self.size.1
    }

    /// Whether its groups of orders ≥ 2 are resolved (the octaves write their sum as one).
    fn splits_orders(&self) -> bool {
        self.method != "octaves"
    }
}

fn luminance(p: &[f32]) -> f64 {
    0.2126 * p[0] as f64 + 0.7152 * p[1] as f64 + 0.0722 * p[2] as f64
}

/// A per-pixel quantity: the luminance of a sum of groups (or the beauty image).
#[derive(Clone, Copy, Debug)]
enum Quantity {
    Groups(usize, usize),
    Beauty,
}

impl Quantity {
    fn name(self) -> String {
        match self {
            Quantity::Beauty => "beauty".into(),
            Quantity::Groups(0, 1) => "order 1".into(),
            Quantity::Groups(1, e) if e == GROUP_FIRST.len() => "orders >= 2".into(),
            Quantity::Groups(g, _) => match GROUP_FIRST.get(g + 1) {
                Some(&next) if next > GROUP_FIRST[g] + 1 => {
                    format!("orders {}-{}", GROUP_FIRST[g], next - 1)
                }
                Some(_) => format!("order {}", GROUP_FIRST[g]),
                None => format!("orders {}+", GROUP_FIRST[g]),
            },
        }
    }

    /// The values of an image of `n` pixels with groups `groups` [group, n, 3].
    fn of(self, groups: &[f32], beauty: &[f32], n: usize) -> Vec<f64> {
        (0..n)
            .map(|px| match self {
                Quantity::Beauty => luminance(&beauty[px * 3..px * 3 + 3]),
                Quantity::Groups(a, b) => (a..b)
                    .map(|g| luminance(&groups[(g * n + px) * 3..(g * n + px) * 3 + 3]))
                    .sum(),
            })
            .collect()
    }
}

/// The statistics of one quantity over one set of pixels.
#[derive(Clone, Debug, Serialize)]
pub struct Stats {
    /// Pixels.
    pub pixels: usize,
    /// ⟨r⟩, ⟨c⟩ (luminance).
    pub mean_reference: f64,
    /// See `mean_reference`.
    pub mean_candidate: f64,
    /// ⟨c⟩/⟨r⟩ − 1.
    pub bias: f64,
    /// The reference mean's relative standard error.
    pub bias_noise: f64,
    /// √⟨(c − r)²⟩/⟨r⟩.
    pub rel_rmse: f64,
    /// √⟨v⟩/⟨r⟩.
    pub reference_noise: f64,
    /// √max(0, ⟨(c − r)² − v⟩)/⟨r⟩.
    pub rel_rmse_corrected: f64,
    /// Its standard error.
    pub rel_rmse_corrected_se: f64,
}

fn stats(c: &[f64], r: &[f64], v: Option<&[f64]>, mask: &[bool]) -> Option<Stats> {
    let idx: Vec<usize> = (0..r.len()).filter(|&i| mask[i]).collect();
    let n = idx.len();
    if n == 0 {
        return None;
    }
    let nf = n as f64;
    let mr = idx.iter().map(|&i| r[i]).sum::<f64>() / nf;
    let mc = idx.iter().map(|&i| c[i]).sum::<f64>() / nf;
    let var = |i: usize| v.map_or(0.0, |v| v[i]);
    let msq = idx.iter().map(|&i| (c[i] - r[i]).powi(2)).sum::<f64>() / nf;
    let mv = idx.iter().map(|&i| var(i)).sum::<f64>() / nf;
    let d: Vec<f64> = idx
        .iter()
        .map(|&i| (c[i] - r[i]).powi(2) - var(i))
        .collect();
    let md = d.iter().sum::<f64>() / nf;
    let sd = (d.iter().map(|x| (x - md).powi(2)).sum::<f64>() / (nf - 1.0).max(1.0)).sqrt();
    let se = sd / nf.sqrt();
    let scale = mr.abs().max(1e-300);
    let corrected = md.max(0.0).sqrt() / scale;
    let corrected_se = if md > 0.0 {
        se / (2.0 * md.sqrt() * scale)
    } else {
        se.sqrt() / scale
    };
    Some(Stats {
        pixels: n,
        mean_reference: mr,
        mean_candidate: mc,
        bias: mc / scale - 1.0,
        bias_noise: (mv / nf).sqrt() / scale,
        rel_rmse: msq.sqrt() / scale,
        reference_noise: mv.sqrt() / scale,
        rel_rmse_corrected: corrected,
        rel_rmse_corrected_se: corrected_se,
    })
}

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
fn units() -> std::collections::BTreeMap<&'static str, &'static str> {
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
    ]
    .into_iter()
    .collect()
}

const DEFINITIONS: &str = "luminance per pixel; pixels with reference opacity > 0.5 ('opaque'), \
    and apart the candidate's regions (lit: sun optical depth < 2 at the visible surface point, \
    shadowed, silhouette: 0.5 < opacity < 0.99); bias = <c>/<r> - 1 with bias_noise the \
    reference mean's relative standard error; rel_rmse = sqrt<(c - r)^2>/<r>, reference_noise = \
    sqrt<v>/<r> with v = (A - B)^2/4 the split-sample variance of a reference pixel (halves.npy; \
    for the beauty image that of the scattered light, the unscattered sky's own noise left out), \
    rel_rmse_corrected = sqrt(max(0, <(c - r)^2 - v>))/<r> and its standard error; psnr_db on the \
    beauty images tone-mapped with the reference's exposure (8-bit sRGB); flip_mean from \
    scripts/compare_flip.py on the same images";

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
        files.write_bytes(
            &out.join(format!("candidate{ci}.png")),
            &png_bytes(&ldr, r.size)?,
        )?;
        reports.push(CandidateReport {
            dir: c.dir.display().to_string(),
            method: c.method.clone(),
            seconds: c.meta["seconds"].as_f64().unwrap_or(f64::NAN),
            quantities,
            psnr_db: psnr_db(&ldr, &ref_ldr),
            flip_mean: None,
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
    figures(&mut files, out, &r, &cands, k, &error_rows)?;
    files.commit()?;
    Ok(report)
}

/// Refuses what cannot be compared: a reference without the path tracer's halves.npy (its
/// noise estimate), and candidates of another scene, camera or image size than the
/// reference's (from render.json, before any array is read).
fn check_inputs(reference: &Path, candidates: &[PathBuf]) -> Result<()> {
    let r = read_meta(reference)?;
    ensure!(
        listed(&r, "halves.npy") && reference.join("halves.npy").exists(),
        "'{}' holds a {} render without halves.npy: the reference must be a path-traced render \
         (its render.json lists halves.npy); did you swap --reference and --candidate?",
        reference.display(),
        method_name(&r)
    );
    let (r_scene, r_camera) = scene_and_camera(&r, reference)?;
    for c in candidates {
        let m = read_meta(c)?;
        let (c_scene, c_camera) = scene_and_camera(&m, c)?;
        let pair = format!(
            "'{}' and the reference '{}'",
            c.display(),
            reference.display()
        );
        if let Some(d) = first_difference(&r_scene, &c_scene, "") {
            bail!("{pair} are renders of different scenes ({d}): compare renders of one scene");
        }
        if let Some(d) = first_difference(&r_camera, &c_camera, "camera") {
            bail!("{pair} are seen from different cameras ({d}): compare renders of one scene");
        }
        let ((rw, rh), (cw, ch)) = (meta_size(&r), meta_size(&m));
        ensure!(
            (rw, rh) == (cw, ch),
            "{pair} differ in image size ({cw}×{ch} against {rw}×{rh} pixels): render both at \
             one --size"
        );
    }
    Ok(())
}

/// render.json's scene without its render settings, and its camera without the image size.
fn scene_and_camera(meta: &Value, dir: &Path) -> Result<(Value, Value)> {
    let Some(Value::Object(scene)) = meta.get("scene") else {
        bail!(
            "'{}' records no scene (written by an older nephele?): render it again",
            dir.join("render.json").display()
        );
    };
    let mut scene = scene.clone();
    // Free text: renders of one scene may describe it differently.
    scene.remove("description");
    let mut camera = scene.remove("camera").unwrap_or_default();
    if let Some(c) = camera.as_object_mut() {
        c.remove("width");
        c.remove("height");
    }
    Ok((Value::Object(scene), camera))
}

/// The first place where the reference's `r` and a candidate's `c` differ, as "path: c
/// against the reference's r" (a "kind" first: a slab against a cloud says so, not their
/// first field). Numbers count as equal within 1e-9 relative: one scene file echoed twice
/// gives the same bits, but one rewritten by a script need not.
fn first_difference(r: &Value, c: &Value, path: &str) -> Option<String> {
    let at = |k: &str| match path {
        "" => k.to_string(),
        p => format!("{p}.{k}"),
    };
    match (r, c) {
        (Value::Object(x), Value::Object(y)) => {
            let mut keys: Vec<&String> = x.keys().chain(y.keys()).collect();
            keys.sort_by_key(|k| (k.as_str() != "kind", k.as_str()));
            keys.dedup();
            keys.into_iter().find_map(|k| {
                let get =
                    |o: &serde_json::Map<String, Value>| o.get(k).cloned().unwrap_or_default();
                first_difference(&get(x), &get(y), &at(k))
            })
        }
        (Value::Array(x), Value::Array(y)) if x.len() == y.len() => x
            .iter()
            .zip(y)
            .enumerate()
            .find_map(|(i, (p, q))| first_difference(p, q, &format!("{path}[{i}]"))),
        (Value::Number(x), Value::Number(y)) => match (x.as_f64(), y.as_f64()) {
            (Some(p), Some(q)) if (p - q).abs() <= 1e-9 * p.abs().max(q.abs()) => None,
            _ => Some(format!("{path}: {c} against the reference's {r}")),
        },
        _ => (r != c).then(|| format!("{path}: {} against the reference's {}", short(c), short(r))),
    }
}

/// A JSON value for a one-line message: at most 40 characters.
fn short(v: &Value) -> String {
    let s = v.to_string();
    match s.char_indices().nth(40) {
        Some((i, _)) => format!("{}…", &s[..i]),
        None => s,
    }
}

/// The pixel sets the statistics are taken over: the reference's opaque pixels, and apart
/// the lit face, the shadowed face and the silhouette where a render has regions.
fn masks(r: &RenderDir, cands: &[RenderDir]) -> Vec<(String, Vec<bool>)> {
    let opaque: Vec<bool> = r.opacity.iter().map(|&a| a > CLOUD_OPACITY).collect();
    let regions = r
        .regions
        .as_ref()
        .or_else(|| cands.iter().find_map(|c| c.regions.as_ref()));
    let mut masks = vec![("opaque".to_string(), opaque.clone())];
    if let Some(reg) = regions {
        for (name, code) in [
            ("lit", super::regions::LIT),
            ("shadowed", super::regions::SHADOWED),
            ("silhouette", super::regions::SILHOUETTE),
        ] {
            let mask = opaque
                .iter()
                .zip(reg)
                .map(|(&o, &g)| o && g == code)
                .collect();
            masks.push((name.to_string(), mask));
        }
    }
    masks
}

/// Order 1, orders ≥ 2 and each group of orders ≥ 2 (without the beauty image).
fn group_quantities() -> Vec<Quantity> {
    let ng = GROUP_FIRST.len();
    let mut qs = vec![Quantity::Groups(0, 1), Quantity::Groups(1, ng)];
    qs.extend((1..ng).map(|g| Quantity::Groups(g, g + 1)));
    qs
}

/// One candidate's statistics per quantity and mask, and the error images of order 1 and
/// orders ≥ 2 (by quantity name).
fn judge(
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
            .filter_map(|(name, mask)| Some((name.clone(), stats(&cv, &rv, var.as_deref(), mask)?)))
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
fn psnr_db(a: &[u8], b: &[u8]) -> f64 {
    let mse = a
        .iter()
        .zip(b)
        .map(|(&x, &y)| ((x as f64 - y as f64) / 255.0).powi(2))
        .sum::<f64>()
        / a.len().max(1) as f64;
    10.0 * (1.0 / mse.max(1e-12)).log10()
}

/// v = (A − B)²/4 per pixel for quantity `q` from the halves [2, group, n, 3].
fn split_variance(q: Quantity, halves: &[f32], n: usize) -> Vec<f64> {
    let ng = GROUP_FIRST.len();
    let half = |k: usize| &halves[k * ng * n * 3..(k + 1) * ng * n * 3];
    let (a, b) = (half(0), half(1));
    let all = Quantity::Groups(0, ng);
    let (qa, qb) = match q {
        Quantity::Beauty => (all.of(a, &[], n), all.of(b, &[], n)),
        q => (q.of(a, &[], n), q.of(b, &[], n)),
    };
    qa.iter()
        .zip(&qb)
        .map(|(x, y)| 0.25 * (x - y).powi(2))
        .collect()
}

/// A render's method as render.json names it, with what tells two renders of one method
/// apart: the collector's finite-cloud correction ("collector (leakage)"), the octaves' a, b
/// and c ("octaves (a 0.28, b 0.96, c 0.81)").
fn method_name(meta: &serde_json::Value) -> String {
    let method = meta["method"].as_str().unwrap_or("path_tracer");
    let details = &meta["details"];
    match method {
        "collector" => match details["correction"].as_str() {
            Some(c) => format!("{method} ({c})"),
            None => method.to_string(),
        },
        "octaves" => {
            let o = &details["options"]["octaves"];
            match (o["a"].as_f64(), o["b"].as_f64(), o["c"].as_f64()) {
                (Some(a), Some(b), Some(c)) => format!("{method} (a {a:.2}, b {b:.2}, c {c:.2})"),
                _ => method.to_string(),
            }
        }
        _ => method.to_string(),
    }
}

/// The colour bar of [`error_image`]: −50 % on the left, +50 % on the right, `w` pixels wide,
/// with its ticks at −50, −25, 0, +25 and +50 %.
fn colour_bar(w: usize) -> ColourBar {
    let error = |i: usize| (i as f64 + 0.5) / w as f64 - 0.5;
    let c: Vec<f64> = (0..w).map(|i| 1.0 + error(i)).collect();
    ColourBar {
        rgb: error_image(&c, &vec![1.0; w], &vec![true; w]),
        label: "(c − r)/⟨r⟩".into(),
        ticks: ["−50 %", "−25 %", "0", "+25 %", "+50 %"]
            .iter()
            .enumerate()
            .map(|(k, t)| (k as f64 / 4.0, t.to_string()))
            .collect(),
    }
}

/// The signed relative error (c − r)/r̄ per pixel as false colour: blue −50 %, white 0, red
/// +50 % (r̄ the reference's opaque mean; transparent pixels grey).
fn error_image(c: &[f64], r: &[f64], opaque: &[bool]) -> Vec<u8> {
    let m = r
        .iter()
        .zip(opaque)
        .filter(|(_, &o)| o)
        .map(|(v, _)| v)
        .sum::<f64>()
        / opaque.iter().filter(|&&o| o).count().max(1) as f64;
    let mut out = Vec::with_capacity(c.len() * 3);
    for i in 0..c.len() {
        if !opaque[i] {
            out.extend_from_slice(&[90, 90, 90]);
            continue;
        }
        let e = ((c[i] - r[i]) / m.max(1e-300) / 0.5).clamp(-1.0, 1.0);
        let fade = |x: f64| (255.0 * (1.0 - x.abs())).round() as u8;
        out.extend_from_slice(&if e >= 0.0 {
            [255, fade(e), fade(e)]
        } else {
            [fade(e), fade(e), 255]
        });
    }
    out
}

/// The integer factor that tiles w pixels wide are enlarged by so that every one of `titles`
/// fits over its column: `image_grid` draws them on one line at one size, 2 pixels into a
/// column, and a 40-pixel column would print them over each other (at most 8×).
fn tile_scale(titles: &[String], w: usize) -> usize {
    let need = titles.iter().map(|t| text_width(t)).max().unwrap_or(0) + 2;
    need.div_ceil(w.max(1)).clamp(1, 8)
}

/// `rgb` of w × h pixels enlarged s times (each pixel an s × s block), as a tile.
fn tile(rgb: &[u8], (w, h): (usize, usize), s: usize) -> Tile {
    let mut out = Vec::with_capacity(rgb.len() * s * s);
    for y in 0..h * s {
        for x in 0..w * s {
            let i = ((y / s) * w + x / s) * 3;
            out.extend_from_slice(&rgb[i..i + 3]);
        }
    }
    Tile::new(out, w * s, h * s)
}

/// panel.png (rows: beauty at exposure `k_beauty`, then order 1, orders ≥ 2 and each group,
/// each at the automatic exposure of the reference's image of that row; columns: reference,
/// candidates) and errors.png (signed relative error of order 1 and orders ≥ 2 per
/// candidate, and the colour bar), into `files`. Tiles are enlarged so that the column titles
/// fit.
fn figures(
    files: &mut AtomicFiles,
    out: &Path,
    r: &RenderDir,
    cands: &[RenderDir],
    k_beauty: f32,
    errors: &[(usize, String, Vec<u8>)],
) -> Result<()> {
    let n = r.pixels();
    let mut cols = vec!["reference".to_string()];
    cols.extend(cands.iter().map(|c| c.method.clone()));
    let s = tile_scale(&cols, r.size.0);
    let mut rows: Vec<(String, Vec<Option<Tile>>)> = Vec::new();
    let beauty = |d: &RenderDir| Some(tile(&tone_map_with(&d.beauty, k_beauty), r.size, s));
    rows.push((
        "beauty".into(),
        std::iter::once(r).chain(cands).map(beauty).collect(),
    ));
    for q in group_quantities() {
        let Quantity::Groups(a, b) = q else { continue };
        let img = |d: &RenderDir| -> Vec<f32> {
            let mut v = vec![0f32; n * 3];
            for g in a..b {
                for (i, x) in v.iter_mut().enumerate() {
                    *x += d.groups[g * n * 3 + i];
                }
            }
            v
        };
        let ri = img(r);
        let k = auto_exposure(&ri, &r.opacity).k;
        let mut tiles = vec![Some(tile(&tone_map_with(&ri, k), r.size, s))];
        for c in cands {
            let split = b - a > 1 || a == 0 || c.splits_orders();
            tiles.push(split.then(|| tile(&tone_map_with(&img(c), k), r.size, s)));
        }
        rows.push((q.name(), tiles));
    }
    files.write_via_path(&out.join("panel.png"), |p| image_grid(p, &cols, &rows))?;
    let err_rows = error_rows(r.size, s, cands.len(), errors);
    let bar = colour_bar(r.size.0 * s);
    files.write_via_path(&out.join("errors.png"), |p| {
        image_grid_with_bar(p, &cols[1..], &err_rows, Some(&bar))
    })
}

/// errors.png's rows: order 1 and orders ≥ 2 per candidate (tiles of `size` enlarged `s`
/// times).
fn error_rows(
    size: (usize, usize),
    s: usize,
    candidates: usize,
    errors: &[(usize, String, Vec<u8>)],
) -> Vec<(String, Vec<Option<Tile>>)> {
    let mut rows: Vec<(String, Vec<Option<Tile>>)> = Vec::new();
    for name in ["order 1", "orders >= 2"] {
        let tiles = (0..candidates)
            .map(|ci| {
                errors
                    .iter()
                    .find(|(c, q, _)| *c == ci && q == name)
                    .map(|(_, _, img)| tile(img, size, s))
            })
            .collect();
        rows.push((format!("{}: (c−r)/⟨r⟩", name.replace(">=", "≥")), tiles));
    }
    rows
}

#[cfg(test)]
mod tests {
    use super::colour_bar;

    /// The bar runs from pure blue (−50 %) through white (0) to pure red (+50 %), one colour
    /// per pixel, its five ticks evenly spaced from end to end.
    #[test]
    fn the_colour_bar_spans_the_error_scale() {
        let bar = colour_bar(200);
        assert_eq!(bar.rgb.len(), 200 * 3);
        let px = |i: usize| &bar.rgb[3 * i..3 * i + 3];
        let (blue, red) = (px(0), px(199));
        assert!(blue[0] <= 3 && blue[1] <= 3 && blue[2] == 255, "{blue:?}");
        assert!(red[0] == 255 && red[1] <= 3 && red[2] <= 3, "{red:?}");
        assert!(px(100).iter().all(|&c| c >= 250), "{:?}", px(100));
        let at: Vec<f64> = bar.ticks.iter().map(|t| t.0).collect();
        assert_eq!(at, [0.0, 0.25, 0.5, 0.75, 1.0]);
        assert_eq!(bar.ticks[2].1, "0");
    }
}
