//! A fit run's artefacts: fits.json (config, loss, Mie summary, the paper's curves, every
//! optimum and curve), fits.npz (diameters, each model's loss and parameters, the curves') and
//! the figures. `nephele fit` and the main job write them; scripts/check_fit.py and
//! scripts/refit_preset.py read them.

use super::figures;
use super::model::Fitting;
use super::model::FITTED;
use super::run::FitReport;
use super::{FitConfig, Loss};
use crate::io::{AtomicFiles, Npz};
use crate::mie::PhaseTable;
use anyhow::{Context, Result};
use serde_json::json;
use std::path::Path;

fn loss_info(loss: Loss) -> serde_json::Value {
    let (name, weight) = match loss {
        Loss::Eas => ("E_AS", "|cos θ| sin θ"),
        Loss::LogL2 => ("log L2", "sin θ"),
    };
    json!({
        "name": name,
        "definition": format!("∫₀^π {weight} (ln p(θ) − ln p_Mie(θ))² dθ"),
        "grid": "the Mie tables' angles (default: 2251-angle reference grid, 0.01° to 5°, 0.1° beyond), trapezoid weights in θ (radians)",
    })
}

/// The paper's main-branch curves in our notation (see src/fit/curves.rs), for fits.json.
fn paper_curves() -> serde_json::Value {
    json!({
        "name": "jendersie_deon (nephele_runtime::presets)",
        "source": "Jendersie & d'Eon 2023, eqs. 4–7 (5–50 µm); supplement branches below 5 µm",
        "range_um": [5.0, 50.0],
        "g_hg": {"expression": "exp(-0.0990567/(d - 1.67154))", "form": "exp_rational_no_offset", "coefficients": {"B": 0.0990567, "C": -1.67154}},
        "g_d": {"expression": "exp(-2.20679/(d + 3.91029) - 0.428934)", "form": "exp_rational", "coefficients": {"A": -0.428934, "B": 2.20679, "C": 3.91029}},
        "alpha": {"expression": "exp(3.62489 - 8.29288/(d + 5.52825))", "form": "exp_rational", "coefficients": {"A": 3.62489, "B": 8.29288, "C": 5.52825}},
        "w_d": {"expression": "exp(-0.599085/(d - 0.641583) - 0.665888)", "form": "exp_rational", "coefficients": {"A": -0.665888, "B": 0.599085, "C": -0.641583}},
    })
}

/// Writes fits.json (the config echoed as `config`, the loss, timings, the Mie tables' g and
/// C_sca, the paper's curves and the whole report), fits.npz and, if `plot`, the figures into
/// `out`, atomically.
pub fn write_fits(
    config: &serde_json::Value,
    fit: &FitConfig,
    tables: &[PhaseTable],
    report: &FitReport,
    timings: serde_json::Value,
    out: &Path,
    plot: bool,
) -> Result<()> {
    std::fs::create_dir_all(out).with_context(|| format!("cannot create '{}'", out.display()))?;
    let mut set = AtomicFiles::new();
    let mie: Vec<serde_json::Value> = tables
        .iter()
        .map(|t| json!({"d_um": t.distribution.nominal_diameter_um(), "g": t.g, "c_sca_um2": t.c_sca_um2}))
        .collect();
    let doc = json!({
        "version": crate::VERSION,
        "git_commit": option_env!("NEPHELE_GIT_COMMIT"),
        "config": config,
        "loss": loss_info(fit.loss),
        "timings": timings,
        "mie": mie,
        "paper": paper_curves(),
        "result": report,
    });
    set.write(&out.join("fits.json"), |w| {
        serde_json::to_writer_pretty(&mut *w, &doc)?;
        Ok(())
    })?;
    set.write(&out.join("fits.npz"), |w| npz(report).write_to(w))?;
    if plot {
        let fig = |name: &str| out.join(name);
        let loss_name = if fit.loss == Loss::Eas {
            "E_AS"
        } else {
            "log L2"
        };
        set.write_via_path(&fig("phase_fits.png"), |p| {
            figures::phase_figure(p, report, tables, &fit.figure_diameters_um)
        })?;
        set.write_via_path(&fig("loss_vs_diameter.png"), |p| {
            figures::loss_figure(p, report, loss_name)
        })?;
        if report.fits[0].models.contains_key("hg_draine") {
            set.write_via_path(&fig("hg_draine_params.png"), |p| {
                figures::params_figure(p, report)
            })?;
        }
    }
    set.commit()
}

/// NumPy arrays: diameters, each model's loss and parameters, the paper's and our curves'.
fn npz(report: &FitReport) -> Npz {
    let n = report.diameters_um.len();
    let mut z = Npz::new();
    z.add("diameters_um", &[n], &report.diameters_um);
    for m in FITTED {
        if !report.fits[0].models.contains_key(&m.json_name()) {
            continue;
        }
        let k = m.param_names().len();
        let loss: Vec<f64> = report
            .fits
            .iter()
            .map(|f| f.models[&m.json_name()].optimum.loss)
            .collect();
        let params: Vec<f64> = report
            .fits
            .iter()
            .flat_map(|f| f.models[&m.json_name()].optimum.params.clone())
            .collect();
        z.add(&format!("loss_{}", m.json_name()), &[n], &loss);
        z.add(&format!("params_{}", m.json_name()), &[n, k], &params);
    }
    let paper: Vec<f64> = report.fits.iter().map(|f| f.paper.loss).collect();
    z.add("loss_paper", &[n], &paper);
    let mut curve = vec![f64::NAN; n];
    let mut curve_params = vec![f64::NAN; 4 * n];
    for b in &report.branches {
        for p in &b.points {
            if let Some(i) = report.diameters_um.iter().position(|d| *d == p.d_um) {
                curve[i] = p.loss_curve;
                for (k, name) in super::run::HG_DRAINE_PARAMS.iter().enumerate() {
                    curve_params[4 * i + k] = p.params_curve[*name];
                }
            }
        }
    }
    z.add("loss_curve", &[n], &curve);
    z.add("params_curve", &[n, 4], &curve_params);
    z
}
