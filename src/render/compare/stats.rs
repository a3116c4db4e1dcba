//! The statistics of a candidate against the reference: the quantities (luminance of order 1,
//! of each group and of the beauty image), the regions' masks, bias and relative RMSE beside the
//! reference's split-sample noise.

use super::super::image::GROUP_FIRST;
use super::super::output::CLOUD_OPACITY;
use super::load::RenderDir;
use serde::Serialize;

pub(super) fn luminance(p: &[f32]) -> f64 {
    0.2126 * p[0] as f64 + 0.7152 * p[1] as f64 + 0.0722 * p[2] as f64
}

/// A per-pixel quantity: the luminance of a sum of groups (or the beauty image).
#[derive(Clone, Copy, Debug)]
pub(super) enum Quantity {
    Groups(usize, usize),
    Beauty,
}

impl Quantity {
    pub(super) fn name(self) -> String {
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
    pub(super) fn of(self, groups: &[f32], beauty: &[f32], n: usize) -> Vec<f64> {
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

pub(super) fn stats(c: &[f64], r: &[f64], v: Option<&[f64]>, mask: &[bool]) -> Option<Stats> {
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

/// The pixel sets the statistics are taken over: the reference's opaque pixels, and apart
/// the lit face, the shadowed face and the silhouette where a render has regions.
pub(super) fn masks(r: &RenderDir, cands: &[RenderDir]) -> Vec<(String, Vec<bool>)> {
    let opaque: Vec<bool> = r.opacity.iter().map(|&a| a > CLOUD_OPACITY).collect();
    let regions = r
        .regions
        .as_ref()
        .or_else(|| cands.iter().find_map(|c| c.regions.as_ref()));
    let mut masks = vec![("opaque".to_string(), opaque.clone())];
    if let Some(reg) = regions {
        for (name, code) in [
            ("lit", super::super::regions::LIT),
            ("shadowed", super::super::regions::SHADOWED),
            ("silhouette", super::super::regions::SILHOUETTE),
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
pub(super) fn group_quantities() -> Vec<Quantity> {
    let ng = GROUP_FIRST.len();
    let mut qs = vec![Quantity::Groups(0, 1), Quantity::Groups(1, ng)];
    qs.extend((1..ng).map(|g| Quantity::Groups(g, g + 1)));
    qs
}

/// v = (A − B)²/4 per pixel for quantity `q` from the halves [2, group, n, 3].
pub(super) fn split_variance(q: Quantity, halves: &[f32], n: usize) -> Vec<f64> {
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
