//! The figures of a fit run: Mie vs the fitted models (the paper's Figure 2), the loss against
//! diameter (Figure 3), and each HG+Draine parameter against diameter with its curves.

use super::model::Fitting;
use super::model::{Model, FITTED};
use super::run::{paper_theta, FitReport, HG_DRAINE_PARAMS};
use crate::io::plot::{panels_plot, Panel, Series, Style};
use crate::mie::PhaseTable;
use anyhow::Result;
use std::path::Path;

/// Diameters spanning more than a decade are drawn on a log axis.
fn wide(d: &[f64]) -> bool {
    d.first()
        .zip(d.last())
        .is_some_and(|(lo, hi)| *lo > 0.0 && hi / lo > 10.0)
}

/// Index of the fitted diameter nearest to `d`.
pub fn nearest(report: &FitReport, d: f64) -> usize {
    let dist = |i: usize| (report.diameters_um[i] - d).abs();
    (0..report.diameters_um.len())
        .min_by(|&a, &b| dist(a).total_cmp(&dist(b)))
        .unwrap_or(0)
}

/// Mie vs each fitted model at the diameters nearest to `wanted` (log-scale p(θ)).
pub fn phase_figure(
    path: &Path,
    report: &FitReport,
    tables: &[PhaseTable],
    wanted: &[f64],
) -> Result<()> {
    let mut idx: Vec<usize> = wanted.iter().map(|&d| nearest(report, d)).collect();
    idx.dedup();
    let curves: Vec<(usize, Vec<(String, Vec<f64>, Style, usize)>)> = idx
        .iter()
        .map(|&i| {
            let t = &tables[i];
            let mut s = vec![("Mie".to_string(), t.phase.clone(), Style::Line, 0)];
            for (k, m) in FITTED.iter().enumerate() {
                if let Some(f) = report.fits[i].models.get(&m.json_name()) {
                    let p = m.phase(&f.optimum.params)?;
                    s.push((
                        m.label().to_string(),
                        t.mu.iter().map(|&mu| p.eval(mu)).collect(),
                        Style::Line,
                        k + 1,
                    ));
                }
            }
            let paper = Model::HgDraine.phase(&paper_theta(report.diameters_um[i]))?;
            s.push((
                "HG+Draine, paper".into(),
                t.mu.iter().map(|&mu| paper.eval(mu)).collect(),
                Style::Dashed,
                7,
            ));
            Ok((i, s))
        })
        .collect::<Result<_>>()?;
    let panels: Vec<Panel> = curves
        .iter()
        .map(|(i, s)| Panel {
            title: format!("d = {} µm", report.diameters_um[*i]),
            x_label: "scattering angle θ (degrees)".into(),
            y_label: "p(θ) (1/sr)".into(),
            log_y: true,
            log_x: false,
            series: s
                .iter()
                .map(|(label, y, style, colour)| Series {
                    label: label.clone(),
                    x: &tables[*i].theta_deg,
                    y,
                    style: *style,
                    colour: *colour,
                })
                .collect(),
        })
        .collect();
    let cols = if panels.len() > 1 { 2 } else { 1 };
    let rows = panels.len().div_ceil(cols) as u32;
    panels_plot(path, (800 * cols as u32, 600 * rows), cols, &panels)
}

/// The loss of every model's per-diameter optimum, our curve's and the paper's, against d.
pub fn loss_figure(path: &Path, report: &FitReport, loss_name: &str) -> Result<()> {
    let d = &report.diameters_um;
    let mut series_data: Vec<(String, Vec<f64>, Vec<f64>, Style, usize)> = Vec::new();
    for (k, m) in FITTED.iter().enumerate() {
        if report.fits[0].models.contains_key(&m.json_name()) {
            let y = report
                .fits
                .iter()
                .map(|f| f.models[&m.json_name()].optimum.loss)
                .collect();
            series_data.push((m.label().to_string(), d.clone(), y, Style::Line, k + 1));
        }
    }
    let paper: Vec<f64> = report.fits.iter().map(|f| f.paper.loss).collect();
    series_data.push((
        "HG+Draine, paper's curves".into(),
        d.clone(),
        paper,
        Style::Dashed,
        7,
    ));
    for b in &report.branches {
        let x = b.points.iter().map(|p| p.d_um).collect();
        let y = b.points.iter().map(|p| p.loss_curve).collect();
        series_data.push((
            format!("HG+Draine, our curves {:?} µm", b.range_um),
            x,
            y,
            Style::Points,
            5,
        ));
    }
    let panel = Panel {
        title: format!("{loss_name} of each model's best fit vs droplet diameter"),
        x_label: "median diameter d (µm)".into(),
        y_label: loss_name.into(),
        log_y: true,
        log_x: wide(d),
        series: series_data
            .iter()
            .map(|(l, x, y, s, c)| Series {
                label: l.clone(),
                x,
                y,
                style: *s,
                colour: *c,
            })
            .collect(),
    };
    panels_plot(path, (1200, 800), 1, &[panel])
}

/// Each HG+Draine parameter against d: per-diameter optima, our curves, the paper's curves.
pub fn params_figure(path: &Path, report: &FitReport) -> Result<()> {
    let d = &report.diameters_um;
    let (lo, hi) = (d[0], d[d.len() - 1]);
    let at = |t: f64| {
        if wide(d) {
            lo * (hi / lo).powf(t)
        } else {
            lo + (hi - lo) * t
        }
    };
    let dense: Vec<f64> = (0..=400).map(|i| at(i as f64 / 400.0)).collect();
    let mut data: Vec<Vec<(String, Vec<f64>, Vec<f64>, Style, usize)>> = Vec::new();
    for k in 0..HG_DRAINE_PARAMS.len() {
        let mut s = Vec::new();
        let opt: Vec<f64> = report
            .fits
            .iter()
            .map(|f| f.models["hg_draine"].optimum.params[k])
            .collect();
        s.push((
            "per-diameter optimum".to_string(),
            d.clone(),
            opt,
            Style::Points,
            0,
        ));
        let paper: Vec<f64> = dense.iter().map(|&x| paper_theta(x)[k]).collect();
        s.push((
            "paper's curve".into(),
            dense.clone(),
            paper,
            Style::Dashed,
            7,
        ));
        for (j, b) in report.branches.iter().enumerate() {
            let [a, z] = b.range_um;
            let x: Vec<f64> = dense
                .iter()
                .copied()
                .filter(|x| (a..=z).contains(x))
                .collect();
            let y = x.iter().map(|&x| b.fitted[k].at(x)).collect();
            let label = if j == 0 {
                format!(
                    "our curve{}",
                    if report.branches.len() > 1 { "s" } else { "" }
                )
            } else {
                String::new()
            };
            s.push((label, x, y, Style::Line, 1));
        }
        data.push(s);
    }
    let panels: Vec<Panel> = HG_DRAINE_PARAMS
        .iter()
        .zip(&data)
        .map(|(name, s)| Panel {
            title: format!("HG+Draine {name}(d)"),
            x_label: "median diameter d (µm)".into(),
            y_label: name.to_string(),
            log_y: false,
            log_x: wide(d),
            series: s
                .iter()
                .map(|(l, x, y, st, c)| Series {
                    label: l.clone(),
                    x,
                    y,
                    style: *st,
                    colour: *c,
                })
                .collect(),
        })
        .collect();
    panels_plot(path, (1600, 1200), 2, &panels)
}
