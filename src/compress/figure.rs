//! Figures of a compression: the form against the tables along depth for a few slices, the
//! error per thickness of every group (fitted and held-out slices), and the error per slice.

use super::report::GroupError;
use crate::io::plot::{heat_maps, panels_plot, HeatMap, Panel, Series, Style};
use crate::slab::SlabTables;
use anyhow::Result;
use std::path::Path;

/// Index of the value of `v` nearest `x`.
fn nearest(v: &[f64], x: f64) -> usize {
    (0..v.len())
        .min_by(|&a, &b| (v[a] - x).abs().total_cmp(&(v[b] - x).abs()))
        .unwrap_or(0)
}

/// fit_vs_tables.png: T along depth, tables (points) and form (lines), for groups of orders 2,
/// 5–6, 13–18 and 31+ (those that exist), at t ≈ 8 and 64, μ_L ≈ 0.5, views nearest straight
/// down and straight up, ψ_V in the first bin.
pub fn fit_vs_tables(path: &Path, tab: &SlabTables, pred: &[f64]) -> Result<()> {
    let [ng, _, _, nd, nm, _] = tab.shape;
    let il = nearest(&tab.mu_l, 0.5);
    let groups: Vec<usize> = [1, 3, 6, 8].into_iter().filter(|&g| g < ng).collect();
    let mut panels = Vec::new();
    let mut store: Vec<(String, Vec<f64>, Vec<(usize, Vec<f64>, Vec<f64>)>)> = Vec::new();
    for t_want in [8.0, 64.0] {
        let it = nearest(&tab.thickness, t_want);
        let depth = tab.depth[it * nd..(it + 1) * nd].to_vec();
        for (m, which) in [(0, "light going down"), (nm - 1, "light going up")] {
            let curves = groups
                .iter()
                .map(|&g| {
                    let col = |v: &[f64]| {
                        (0..nd)
                            .map(|j| v[tab.index(g, it, il, j, m, 0)])
                            .collect::<Vec<f64>>()
                    };
                    (g, col(&tab.t), col(pred))
                })
                .collect();
            let title = format!(
                "t = {}, μ_L = {}, μ_V = {:.3} ({which}), ψ_V bin 0",
                tab.thickness[it],
                tab.mu_l[il],
                tab.mu_v(m)
            );
            store.push((title, depth.clone(), curves));
        }
    }
    for (title, depth, curves) in &store {
        let mut series = Vec::new();
        for (i, (g, table, form)) in curves.iter().enumerate() {
            let first = tab.group_first[*g];
            series.push(Series {
                label: format!("orders from {first}: tables"),
                x: depth,
                y: table,
                style: Style::Points,
                colour: i + 1,
            });
            series.push(Series {
                label: "  form".into(),
                x: depth,
                y: form,
                style: Style::Line,
                colour: i + 1,
            });
        }
        panels.push(Panel {
            title: title.clone(),
            x_label: "depth d (mfp)".into(),
            y_label: "T = L/E⊥ (1/sr)".into(),
            log_y: true,
            log_x: false,
            series,
        });
    }
    panels_plot(path, (1600, 1200), 2, &panels)
}

/// error_by_thickness.png: the T-weighted relative RMS error per thickness of every group and
/// of their sum, on the fitted slices and on the held-out ones.
pub fn error_by_thickness(
    path: &Path,
    tab: &SlabTables,
    fitted: &[GroupError],
    held_out: Option<&[GroupError]>,
) -> Result<()> {
    let pct = |e: &GroupError| {
        e.rel_rms_by_t
            .iter()
            .map(|v| 100.0 * v)
            .collect::<Vec<f64>>()
    };
    let label = |e: &GroupError| {
        e.first_order.map_or("sum of orders ≥ 2".to_string(), |o| {
            format!("orders from {o}")
        })
    };
    let sets: Vec<(&str, &[GroupError])> = std::iter::once(("fitted slices", fitted))
        .chain(held_out.map(|h| {
            (
                "held-out slices (thicknesses and sun cosines left out of the fit)",
                h,
            )
        }))
        .collect();
    let values: Vec<Vec<Vec<f64>>> = sets
        .iter()
        .map(|(_, es)| es.iter().map(pct).collect())
        .collect();
    let panels: Vec<Panel> = sets
        .iter()
        .zip(&values)
        .map(|((title, es), vals)| Panel {
            title: format!("T-weighted relative RMS error, {title}"),
            x_label: "slab thickness t (mfp)".into(),
            y_label: "error (%)".into(),
            log_y: true,
            log_x: true,
            series: es
                .iter()
                .zip(vals)
                .enumerate()
                .map(|(i, (e, v))| Series {
                    label: label(e),
                    x: &tab.thickness,
                    y: v,
                    style: if e.group.is_none() {
                        Style::Dashed
                    } else {
                        Style::Line
                    },
                    colour: if e.group.is_none() { 0 } else { i + 1 },
                })
                .collect(),
        })
        .collect();
    panels_plot(path, (1600, 700), panels.len(), &panels)
}

/// error_map.png: E of every group and of their sum per (thickness, sun cosine) slice, in %,
/// fitted slices (each cell a slice of 16 depths × 16 μ_V × 12 ψ_V for the default tables).
pub fn error_map(path: &Path, tab: &SlabTables, errors: &[GroupError]) -> Result<()> {
    let maps: Vec<HeatMap> = errors
        .iter()
        .map(|e| HeatMap {
            title: e.first_order.map_or("sum of orders ≥ 2".to_string(), |o| {
                format!("orders from {o}")
            }),
            x_labels: tab.thickness.iter().map(|t| format!("{t}")).collect(),
            x_name: "t (mfp)",
            y_labels: tab.mu_l.iter().map(|m| format!("{m}")).collect(),
            y_name: "μ_L",
            values: {
                // [t, μ_L] → rows μ_L, columns t.
                let (nt, nl) = (tab.thickness.len(), tab.mu_l.len());
                (0..nl * nt)
                    .map(|i| 100.0 * e.rel_rms_by_slice[(i % nt) * nl + i / nt])
                    .collect()
            },
        })
        .collect();
    heat_maps(
        path,
        (1800, 1500),
        3,
        (8.0, 20.0),
        &|v| format!("{v:.1}"),
        &maps,
    )
}
