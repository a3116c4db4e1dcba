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
use super::output::{exposure, tone_map_with};
use crate::io::plot::{image_grid, Tile};
use crate::io::AtomicFiles;
use anyhow::{bail, ensure, Context, Result};
use serde::Serialize;
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

fn read_npy<T: npyz::Deserialize>(path: &Path, shape: &[u64]) -> Result<Vec<T>> {
    let what = || format!("'{}'", path.display());
    let file = std::fs::File::open(path).with_context(|| format!("cannot read {}", what()))?;
    let npy = npyz::NpyFile::new(std::io::BufReader::new(file)).with_context(what)?;
    ensure!(
        npy.shape() == shape,
        "{}: shape {:?}, expected {:?}",
        what(),
        npy.shape(),
        shape
    );
    npy.into_vec::<T>().with_context(what)
}

impl RenderDir {
    /// Reads a directory `nephele render` wrote.
    pub fn read(dir: &Path) -> Result<Self> {
        let json = dir.join("render.json");
        let meta: serde_json::Value =
            serde_json::from_str(&std::fs::read_to_string(&json).with_context(|| {
                format!("cannot read '{}' (a render directory?)", json.display())
            })?)
            .with_context(|| format!("'{}'", json.display()))?;
        let (w, h) = (
            meta["width"].as_u64().unwrap_or(0),
            meta["height"].as_u64().unwrap_or(0),
        );
        ensure!(w > 0 && h > 0, "'{}': no image size", json.display());
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
            halves: if halves.exists() {
                Some(read_npy(&halves, &[2, ng, h, w, 3])?)
            } else {
                None
            },
            regions: if regions.exists() {
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
    /// Per candidate.
    pub candidates: Vec<CandidateReport>,
    /// What the numbers mean.
    pub definitions: &'static str,
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
/// figures into `out`.
pub fn compare(reference: &Path, candidates: &[PathBuf], out: &Path) -> Result<Report> {
    let r = RenderDir::read(reference)?;
    let cands: Vec<RenderDir> = candidates
        .iter()
        .map(|c| RenderDir::read(c))
        .collect::<Result<_>>()?;
    for c in &cands {
        if c.size != r.size {
            bail!(
                "'{}' is {}×{} pixels, the reference '{}' {}×{}",
                c.dir.display(),
                c.size.0,
                c.size.1,
                r.dir.display(),
                r.size.0,
                r.size.1
            );
        }
    }
    let n = r.pixels();
    let ng = GROUP_FIRST.len();
    let regions = r
        .regions
        .clone()
        .or_else(|| cands.iter().find_map(|c| c.regions.clone()));
    let opaque: Vec<bool> = r.opacity.iter().map(|&a| a > 0.5).collect();
    let mut masks = vec![("opaque".to_string(), opaque.clone())];
    if let Some(reg) = &regions {
        for (name, code) in [
            ("lit", super::regions::LIT),
            ("shadowed", super::regions::SHADOWED),
            ("silhouette", super::regions::SILHOUETTE),
        ] {
            masks.push((
                name.to_string(),
                (0..n).map(|i| opaque[i] && reg[i] == code).collect(),
            ));
        }
    }
    let mut quantities = vec![Quantity::Groups(0, 1), Quantity::Groups(1, ng)];
    quantities.extend((1..ng).map(|g| Quantity::Groups(g, g + 1)));
    quantities.push(Quantity::Beauty);
    let k = exposure(&r.beauty);
    let ref_ldr = tone_map_with(&r.beauty, k);
    let mut files = AtomicFiles::new();
    std::fs::create_dir_all(out).with_context(|| format!("cannot create '{}'", out.display()))?;
    files.write_bytes(&out.join("reference.png"), &png(&ref_ldr, r.size)?)?;
    let mut reports = Vec::new();
    let mut error_rows = Vec::new();
    for (ci, c) in cands.iter().enumerate() {
        let mut qs = Vec::new();
        for &q in &quantities {
            if let Quantity::Groups(a, b) = q {
                if b - a == 1 && a >= 1 && !c.splits_orders() {
                    continue;
                }
            }
            let rv = q.of(&r.groups, &r.beauty, n);
            let cv = q.of(&c.groups, &c.beauty, n);
            let var = r.halves.as_ref().map(|h| split_variance(q, h, n));
            let mut regions = std::collections::BTreeMap::new();
            for (name, mask) in &masks {
                if let Some(s) = stats(&cv, &rv, var.as_deref(), mask) {
                    regions.insert(name.clone(), s);
                }
            }
            if matches!(q, Quantity::Groups(1, _) | Quantity::Groups(0, 1)) {
                error_rows.push((ci, q.name(), error_image(&cv, &rv, &opaque)));
            }
            qs.push(QuantityReport {
                quantity: q.name(),
                regions,
            });
        }
        let ldr = tone_map_with(&c.beauty, k);
        let mse = ldr
            .iter()
            .zip(&ref_ldr)
            .map(|(&a, &b)| ((a as f64 - b as f64) / 255.0).powi(2))
            .sum::<f64>()
            / ldr.len() as f64;
        files.write_bytes(&out.join(format!("candidate{ci}.png")), &png(&ldr, r.size)?)?;
        reports.push(CandidateReport {
            dir: c.dir.display().to_string(),
            method: c.method.clone(),
            seconds: c.meta["seconds"].as_f64().unwrap_or(f64::NAN),
            quantities: qs,
            psnr_db: 10.0 * (1.0 / mse.max(1e-12)).log10(),
            flip_mean: None,
        });
    }
    let report = Report {
        reference: r.dir.display().to_string(),
        reference_method: r.method.clone(),
        reference_spp: r.meta["spp"].as_u64().unwrap_or(0),
        reference_seconds: r.meta["seconds"].as_f64().unwrap_or(f64::NAN),
        candidates: reports,
        definitions: DEFINITIONS,
    };
    let mut json = serde_json::to_vec_pretty(&report)?;
    json.push(b'\n');
    files.write_bytes(&out.join("report.json"), &json)?;
    files.commit()?;
    figures(out, &r, &cands, k, &error_rows)?;
    Ok(report)
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

/// A render's method as render.json names it, with the collector's finite-cloud correction
/// when it has one ("collector (leakage)").
fn method_name(meta: &serde_json::Value) -> String {
    let method = meta["method"].as_str().unwrap_or("path_tracer");
    match meta["details"]["correction"].as_str() {
        Some(c) if method == "collector" => format!("{method} ({c})"),
        _ => method.to_string(),
    }
}

/// The colour bar of [`error_image`] as a w × h tile: −50 % on the left, +50 % on the right.
fn colour_bar(w: usize, h: usize) -> Tile {
    let error = |i: usize| (i as f64 + 0.5) / w as f64 - 0.5;
    let c: Vec<f64> = (0..w * h).map(|k| 1.0 + error(k % w)).collect();
    Tile::new(error_image(&c, &vec![1.0; w * h], &vec![true; w * h]), w, h)
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

fn png(rgb: &[u8], (w, h): (usize, usize)) -> Result<Vec<u8>> {
    let mut bytes = Vec::new();
    image::ImageEncoder::write_image(
        image::codecs::png::PngEncoder::new(&mut bytes),
        rgb,
        w as u32,
        h as u32,
        image::ColorType::Rgb8,
    )?;
    Ok(bytes)
}

/// panel.png (rows: beauty, order 1, orders ≥ 2 and each group, tone-mapped with the
/// reference's exposure of that row; columns: reference, candidates) and errors.png (signed
/// relative error of order 1 and orders ≥ 2 per candidate).
fn figures(
    out: &Path,
    r: &RenderDir,
    cands: &[RenderDir],
    k_beauty: f32,
    errors: &[(usize, String, Vec<u8>)],
) -> Result<()> {
    let (w, h) = r.size;
    let n = w * h;
    let ng = GROUP_FIRST.len();
    let mut cols = vec![format!("reference ({})", r.method)];
    cols.extend(cands.iter().map(|c| c.method.clone()));
    let mut rows: Vec<(String, Vec<Option<Tile>>)> = Vec::new();
    let mut tiles = vec![Some(Tile::new(tone_map_with(&r.beauty, k_beauty), w, h))];
    tiles.extend(
        cands
            .iter()
            .map(|c| Some(Tile::new(tone_map_with(&c.beauty, k_beauty), w, h))),
    );
    rows.push(("beauty".into(), tiles));
    let mut qs = vec![Quantity::Groups(0, 1), Quantity::Groups(1, ng)];
    qs.extend((1..ng).map(|g| Quantity::Groups(g, g + 1)));
    for q in qs {
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
        let k = exposure(&ri);
        let mut tiles = vec![Some(Tile::new(tone_map_with(&ri, k), w, h))];
        for c in cands {
            let split = b - a > 1 || a == 0 || c.splits_orders();
            tiles.push(split.then(|| Tile::new(tone_map_with(&img(c), k), w, h)));
        }
        rows.push((q.name(), tiles));
    }
    image_grid(&out.join("panel.png"), &cols, &rows)?;
    let mut err_rows: Vec<(String, Vec<Option<Tile>>)> = Vec::new();
    for name in ["order 1", "orders >= 2"] {
        let tiles = (0..cands.len())
            .map(|ci| {
                errors
                    .iter()
                    .find(|(c, q, _)| *c == ci && q == name)
                    .map(|(_, _, img)| Tile::new(img.clone(), w, h))
            })
            .collect();
        err_rows.push((format!("{name}: (c−r)/⟨r⟩"), tiles));
    }
    err_rows.push(("−50 % … 0 … +50 %".into(), vec![Some(colour_bar(w, h))]));
    image_grid(&out.join("errors.png"), &cols[1..], &err_rows)
}
