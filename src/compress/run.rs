//! The compression stage end to end: fit the form to a slab run's tables, measure it on every
//! cell and on held-out slices, and write report.json, manifest.json, compressed.npz, the
//! figures and transport.ntt (loaded back by the runtime and compared with the fit).

use super::collector::{fit_collector, predict_collector, CollectorFit};
use super::coverage::{coverage, domain_check, slices_of_all, worst_slice, Coverage, SliceShare};
use super::figure;
use super::fit::{fit_all, held_out_l, predict, predict_held_out, GroupFit};
use super::form::Lerp;
use super::joint::{fit_all_joint, fit_joint_groups, spanned, JointFit};
use super::manifest::manifest;
use super::near_beam::near_beam_check;
pub use super::ntt::NttCheck;
use super::ntt::{phase_of_run, write_ntt};
use super::report::{collector_error_on, group_error, group_error_on, CollectorError, GroupError};
use super::{LogAdditive, SlabTables};
use crate::io::{write_atomic, AtomicFiles, Npz};
use anyhow::{anyhow, ensure, Context, Result};
use nephele_runtime::fitting::{CollectorForm, Statistic};
use nephele_runtime::transport::TransportTables;
use rayon::prelude::*;
use serde::Serialize;
use std::path::Path;
use std::time::Instant;

/// What to fit.
#[derive(Clone, Copy, Debug)]
pub struct Options {
    /// The form's sizes.
    pub form: LogAdditive,
    /// Legendre terms in ln t of the joint fits; 0 fits each thickness on its own.
    pub smooth_t: usize,
    /// Whether to run the held-out study.
    pub held_out: bool,
    /// The collector form's sizes (fitted with joint fits only).
    pub collector: CollectorForm,
    /// Legendre terms in ln t of the collector's parameters.
    pub collector_q: usize,
}

impl Options {
    /// Refuses options the runtime could not load (its limits, one home in
    /// `nephele_runtime::fitting`) or the joint fits cannot use.
    pub fn check(&self) -> Result<()> {
        if let Err(limit) = self.form.check() {
            anyhow::bail!("the form is outside what the runtime loads ({limit})");
        }
        anyhow::ensure!(
            self.smooth_t <= MAX_SMOOTH_T && self.collector_q <= MAX_SMOOTH_T,
            "Legendre terms in ln t (--smooth-t, --collector-smooth-t): at most {MAX_SMOOTH_T}"
        );
        if self.collector_q > 0 {
            if let Err(limit) = self.collector.check() {
                anyhow::bail!("the collector form is outside what the runtime loads ({limit})");
            }
        }
        Ok(())
    }
}

/// Most Legendre terms in ln t of a joint fit (the runtime reads up to
/// `fitting::MAX_Q`; more than the default grid's thicknesses make the fit ill-posed).
pub const MAX_SMOOTH_T: usize = 9;

impl Default for Options {
    /// The defaults of `nephele compress` (docs/compress.md has the study behind them).
    fn default() -> Self {
        Self {
            form: LogAdditive::default(),
            smooth_t: 5,
            held_out: true,
            collector: CollectorForm::default(),
            collector_q: 4,
        }
    }
}

/// The held-out study: which slices were left out, and the errors there.
#[derive(Clone, Debug, Serialize)]
pub struct HeldOut {
    /// Thicknesses left out.
    pub thicknesses: Vec<f64>,
    /// Sun cosines left out.
    pub mu_l: Vec<f64>,
    /// Errors on the held-out slices, per group then for the sum.
    pub errors: Vec<GroupError>,
    /// Collector errors on the held-out slices, per group.
    pub collector: Vec<CollectorError>,
    /// The held-out fit's T over the tables' layout (compressed.npz `T_held_out`).
    #[serde(skip)]
    pub pred: Vec<f64>,
}

/// What a compression produced.
#[derive(Clone, Debug)]
pub struct Outcome {
    /// Errors on every slice, per group then for the sum of the groups of orders ≥ 2.
    pub errors: Vec<GroupError>,
    /// The held-out study, if run.
    pub held_out: Option<HeldOut>,
    /// The reference (Bouthors-like) form's errors on the fitted slices, per group then for the
    /// sum, and its parameter count.
    pub reference: (Vec<GroupError>, usize),
    /// Collector errors per group (joint fits only).
    pub collector: Vec<CollectorError>,
    /// Parameters of T.
    pub params: usize,
    /// Parameters of σ, c_z and c_x.
    pub collector_params: usize,
    /// Seconds spent fitting (the first fit).
    pub fit_seconds: f64,
    /// transport.ntt and the runtime's agreement with the fit (joint fits only).
    pub ntt: Option<NttCheck>,
    /// Coverage: the worst slice's share of light the groups drop together, and per group
    /// then for the sum.
    pub coverage: (SliceShare, Vec<Coverage>),
    /// What the fit cannot know from these tables: a domain of one thickness or one sun, more
    /// ln t terms than thicknesses.
    pub warnings: Vec<String>,
}

/// The warnings of a fit of `opt` to tables on this grid of thicknesses and sun cosines.
pub fn grid_warnings(thickness: &[f64], mu_l: &[f64], opt: &Options) -> Vec<String> {
    let mut w = Vec::new();
    let (nt, nl) = (thickness.len(), mu_l.len());
    if nt == 1 || nl == 1 {
        w.push(format!(
            "the tables hold {} and {}: the fit errors are measured there alone, and the \
             compressed tables answer every other thickness and sun from that grid",
            plural(nt, "thickness", "thicknesses"),
            plural(nl, "sun cosine", "sun cosines"),
        ));
    }
    for (terms, flag) in [
        (opt.smooth_t, "--smooth-t"),
        (opt.collector_q, "--collector-smooth-t"),
    ] {
        if terms > nt {
            w.push(format!(
                "{flag} {terms}: {terms} terms in ln t fitted to {} — more terms than \
                 thicknesses, so the fit is not determined by the tables between them; use \
                 {flag} {nt} or fewer, or a slab run with more thicknesses",
                plural(nt, "thickness", "thicknesses")
            ));
        }
    }
    w
}

fn plural(n: usize, one: &str, many: &str) -> String {
    format!("{n} {}", if n == 1 { one } else { many })
}

/// Fits, measures and writes everything into `out`.
pub fn compress(tables: &Path, out: &Path, opt: &Options) -> Result<Outcome> {
    compress_reporting(tables, out, opt, &|_| {})
}

/// As [`compress`], calling `stage(what)` as each stage starts (minutes on the default tables:
/// for a progress display).
pub fn compress_reporting(
    tables: &Path,
    out: &Path,
    opt: &Options,
    stage: &dyn Fn(&str),
) -> Result<Outcome> {
    opt.check()?;
    stage("reading the tables");
    let tab = SlabTables::load(tables)?;
    ensure!(tab.shape[0] >= 2, "the tables hold no group of orders ≥ 2");
    let m = measure(&tab, opt, stage)?;
    stage("writing");
    std::fs::create_dir_all(out).with_context(|| format!("cannot create '{}'", out.display()))?;
    let ntt = if m.joint.is_empty() {
        None
    } else {
        let phase = phase_of_run(&tab, tables)?;
        let mut check = write_ntt(out, &tab, opt, &phase, &m)?;
        let bytes = std::fs::read(&check.path)?;
        let rt = TransportTables::from_bytes(&bytes).map_err(|e| anyhow!("{e}"))?;
        check.near_beam = (rt.groups() + 1 == tab.shape[0]).then(|| near_beam_check(&tab, &rt));
        Some(check)
    };
    let report = Report::new(tables, opt, &m, ntt.as_ref());
    write_json(&out.join("report.json"), &report)?;
    write_arrays(out, &tab, &m)?;
    write_figures(out, &tab, &m)?;
    write_json(
        &out.join("manifest.json"),
        &manifest(tables, &tab, opt, &m, ntt.as_ref())?,
    )?;
    write_atomic(&out.join("domain_check.npz"), |w| {
        domain_check(&tab, DOMAIN_CHECK_SAMPLES).write_to(w)
    })?;
    Ok(Outcome {
        coverage: (m.coverage.worst_slice_all_groups, m.coverage.groups.clone()),
        errors: m.errors,
        reference: m.reference,
        collector: m.collector,
        held_out: m.held_out,
        params: m.params,
        collector_params: m.collector_params,
        fit_seconds: m.fit_seconds,
        ntt,
        warnings: grid_warnings(&tab.thickness, &tab.mu_l, opt),
    })
}

/// Random cells and random points in domain_check.npz.
const DOMAIN_CHECK_SAMPLES: usize = 1500;

/// Everything a compression computes before it writes anything.
pub(super) struct Measured {
    pub(super) fits: Vec<GroupFit>,
    pub(super) joint: Vec<JointFit>,
    pub(super) coll: Vec<CollectorFit>,
    /// The form's T and collector (σ, c_x, c_z) over the tables' layout.
    pub(super) pred: Vec<f64>,
    pub(super) pred_c: [Vec<f64>; 3],
    pub(super) errors: Vec<GroupError>,
    pub(super) reference: (Vec<GroupError>, usize),
    pub(super) collector: Vec<CollectorError>,
    pub(super) held_out: Option<HeldOut>,
    pub(super) params: usize,
    pub(super) collector_params: usize,
    pub(super) fit_seconds: f64,
    pub(super) coverage: CoverageReport,
}

/// The coverage of every group and of the sum ([`super::coverage`]).
#[derive(Serialize)]
pub(super) struct CoverageReport {
    pub(super) definition: &'static str,
    /// The largest share of one (t, μ_L) slice's light of orders ≥ 2 dropped by the groups
    /// together.
    pub(super) worst_slice_all_groups: SliceShare,
    /// Every slice's share dropped by the groups together (t outer, μ_L inner).
    pub(super) slices_all_groups: Vec<SliceShare>,
    pub(super) groups: Vec<Coverage>,
}

impl CoverageReport {
    fn of(tab: &SlabTables, pred: &[f64]) -> Self {
        let mut groups: Vec<_> = (1..tab.shape[0])
            .map(|g| coverage(tab, pred, Some(g)))
            .collect();
        groups.push(coverage(tab, pred, None));
        let slices = slices_of_all(tab, pred);
        Self {
            definition: "over every cell with T > 0 (horizon bins, cells next to the faces and noisy cells included): the share of the light in cells where the form is 0 (zero) or off by more than a factor 2 either way (dropped); worst_slice: the largest share of one (t, mu_L) slice's light of orders >= 2 a group drops; rel_rms_all: T-weighted relative RMS over the same cells, noise_all the tables' own, rel_rms_all_net = sqrt(max(0, E^2 - N^2))",
            worst_slice_all_groups: worst_slice(&slices),
            slices_all_groups: slices,
            groups,
        }
    }
}

/// Fits T and the collector, the reference form and the held-out study, and measures them on
/// every cell.
fn measure(tab: &SlabTables, opt: &Options, stage: &dyn Fn(&str)) -> Result<Measured> {
    let [ng, nt, nl, _, nm, _] = tab.shape;
    let t0 = Instant::now();
    stage("fitting T");
    let (fits, joint) = fit(tab, opt, &[], &[])?;
    stage("fitting the collector's c and σ");
    let coll = fit_collectors(tab, opt, &[], &[])?;
    let fit_seconds = t0.elapsed().as_secs_f64();
    let pred = predict_everywhere(tab, &opt.form, &fits);
    let per_group = |pred: &[f64]| -> Vec<GroupError> {
        let mut e: Vec<_> = (1..ng).map(|g| group_error(tab, pred, Some(g))).collect();
        e.push(group_error(tab, pred, None));
        e
    };
    let errors = per_group(&pred);
    let coverage = CoverageReport::of(tab, &pred);
    stage("the reference form");
    let reference = per_group(&super::bouthors::fit_and_predict(tab)?);
    let reference_params = super::bouthors::n_params(nm, nl) * (ng - 1) * nt;
    let pred_c = predict_collector(tab, &opt.collector, &coll, (&fits, &pred), &Lerp::at);
    let collector: Vec<_> = coll
        .iter()
        .map(|f| collector_error_on(tab, &pred_c, f.group, &|_, _| true))
        .collect();
    let collector_params = if coll.is_empty() {
        0
    } else {
        Statistic::ALL
            .iter()
            .map(|&s| opt.collector.n_params(s, nm, nl))
            .sum::<usize>()
            * (ng - 1)
            * opt.collector_q
    };
    let held_out = opt
        .held_out
        .then(|| {
            stage("the held-out study (a second fit)");
            held_out_study(tab, opt)
        })
        .transpose()?;
    let params = opt.form.n_params(nm, nl)
        * if opt.smooth_t == 0 {
            fits.len()
        } else {
            (ng - 1) * opt.smooth_t
        };
    Ok(Measured {
        fits,
        joint,
        coll,
        pred,
        pred_c,
        errors,
        reference: (reference, reference_params),
        collector,
        held_out,
        params,
        collector_params,
        fit_seconds,
        coverage,
    })
}

/// `value` as pretty JSON (keys sorted), atomically.
fn write_json(path: &Path, value: &impl Serialize) -> Result<()> {
    let value = serde_json::to_value(value)?;
    write_atomic(path, |w| {
        serde_json::to_writer_pretty(&mut *w, &value)?;
        Ok(())
    })
}

/// compressed.npz: the form's T and collector over the tables' layout, and its coefficients.
fn write_arrays(out: &Path, tab: &SlabTables, m: &Measured) -> Result<()> {
    let mut npz = Npz::new();
    npz.add("T_form", &tab.shape, &m.pred);
    if let Some(h) = &m.held_out {
        npz.add("T_held_out", &tab.shape, &h.pred);
    }
    if !m.coll.is_empty() {
        for (name, v) in ["sigma_form", "cx_form", "cz_form"].iter().zip(&m.pred_c) {
            npz.add(name, &tab.shape, v);
        }
    }
    for f in &m.fits {
        npz.add(
            &format!("coef_g{}_t{}", f.group, f.it),
            &[f.coef.len()],
            &f.coef,
        );
    }
    write_atomic(&out.join("compressed.npz"), |w| npz.write_to(w))
}

/// fit_vs_tables.png, error_by_thickness.png and error_map.png.
fn write_figures(out: &Path, tab: &SlabTables, m: &Measured) -> Result<()> {
    let mut figures = AtomicFiles::new();
    figures.write_via_path(&out.join("fit_vs_tables.png"), |p| {
        figure::fit_vs_tables(p, tab, &m.pred)
    })?;
    figures.write_via_path(&out.join("error_by_thickness.png"), |p| {
        let held_out = m.held_out.as_ref().map(|h| h.errors.as_slice());
        figure::error_by_thickness(p, tab, &m.errors, held_out)
    })?;
    figures.write_via_path(&out.join("error_map.png"), |p| {
        figure::error_map(p, tab, &m.errors)
    })?;
    figures.commit()
}

/// report.json: the form, every error, the held-out study, the reference form and the
/// runtime's agreement with the fit.
#[derive(Serialize)]
struct Report<'a> {
    tables: &'a Path,
    form: serde_json::Value,
    smooth_t: usize,
    parameters: usize,
    fit_seconds: f64,
    errors: &'a [GroupError],
    collector: CollectorReport<'a>,
    held_out: Option<&'a HeldOut>,
    reference_form: ReferenceReport<'a>,
    coverage: &'a CoverageReport,
    transport_ntt: Option<&'a NttCheck>,
    version: &'static str,
    git_commit: Option<&'static str>,
}

#[derive(Serialize)]
struct CollectorReport<'a> {
    form: CollectorOptions,
    parameters: usize,
    errors: &'a [CollectorError],
}

/// The collector form's sizes and its Q, as reports and manifests write them.
#[derive(Serialize)]
pub(super) struct CollectorOptions {
    legendre: usize,
    harmonics: usize,
    theta_nodes: usize,
    smooth_t: usize,
}

impl CollectorOptions {
    pub(super) fn of(opt: &Options) -> Self {
        Self {
            legendre: opt.collector.legendre,
            harmonics: opt.collector.harmonics,
            theta_nodes: opt.collector.theta_nodes,
            smooth_t: opt.collector_q,
        }
    }
}

#[derive(Serialize)]
struct ReferenceReport<'a> {
    kind: &'static str,
    parameters: usize,
    errors: &'a [GroupError],
}

impl<'a> Report<'a> {
    fn new(tables: &'a Path, opt: &Options, m: &'a Measured, ntt: Option<&'a NttCheck>) -> Self {
        Report {
            tables,
            form: super::form::to_json(&opt.form),
            smooth_t: opt.smooth_t,
            parameters: m.params,
            fit_seconds: m.fit_seconds,
            errors: &m.errors,
            collector: CollectorReport {
                form: CollectorOptions::of(opt),
                parameters: m.collector_params,
                errors: &m.collector,
            },
            held_out: m.held_out.as_ref(),
            reference_form: ReferenceReport {
                kind: "bouthors_like (src/compress/bouthors.rs): ln T = ln B + a(mu_V) + x(mu_L) + [b_V(mu_V) + b_L(mu_L)] x + c2 P2(x) + c3 P3(x) + P(Theta) + sum_k [e_k(mu_V) + f_k(mu_L)] (s_V s_L)^k cos k psi, per (group, thickness)",
                parameters: m.reference.1,
                errors: &m.reference.0,
            },
            coverage: &m.coverage,
            transport_ntt: ntt,
            version: crate::VERSION,
            git_commit: option_env!("NEPHELE_GIT_COMMIT"),
        }
    }
}

/// The fits (per thickness, or joint and then read at every thickness), skipping the
/// thicknesses `skip_t` and sun cosines `skip_l`.
fn fit(
    tab: &SlabTables,
    opt: &Options,
    skip_t: &[usize],
    skip_l: &[usize],
) -> Result<(Vec<GroupFit>, Vec<JointFit>)> {
    if opt.smooth_t == 0 {
        return Ok((fit_all(tab, &opt.form, skip_t, skip_l)?, Vec::new()));
    }
    let joint = fit_joint_groups(tab, &opt.form, opt.smooth_t, skip_t, skip_l)?;
    let fits = joint
        .iter()
        .flat_map(|j| (0..tab.shape[1]).map(move |it| j.at(tab, it)))
        .collect();
    Ok((fits, joint))
}

/// The collector fits of every group of orders ≥ 2 (none with per-thickness fits of T), over
/// the thicknesses T's joint fit spans.
fn fit_collectors(
    tab: &SlabTables,
    opt: &Options,
    skip_t: &[usize],
    skip_l: &[usize],
) -> Result<Vec<CollectorFit>> {
    if opt.smooth_t == 0 || opt.collector_q == 0 {
        return Ok(Vec::new());
    }
    let groups: Vec<usize> = (1..tab.shape[0]).collect();
    groups
        .par_iter()
        .map(|&g| {
            let (span, range) = spanned(tab, g, skip_t)?;
            let form = &opt.collector;
            fit_collector(tab, form, g, opt.collector_q, (&span, range), skip_l)
        })
        .collect()
}

/// The form's T over the whole table layout.
fn predict_everywhere(tab: &SlabTables, form: &LogAdditive, fits: &[GroupFit]) -> Vec<f64> {
    let [_, nt, nl, nd, nm, nk] = tab.shape;
    let slice = nl * nd * nm * nk;
    let mut pred = vec![0.0; tab.t.len()];
    for f in fits {
        let start = (f.group * nt + f.it) * slice;
        pred[start..start + slice].copy_from_slice(&predict(tab, form, f));
    }
    pred
}

/// A second fit without the inner thicknesses and sun cosines at a third and two thirds of
/// their grids, measured on those slices only.
fn held_out_study(tab: &SlabTables, opt: &Options) -> Result<HeldOut> {
    let [ng, nt, nl, ..] = tab.shape;
    let inner = |n: usize| -> Vec<usize> {
        let mut v: Vec<usize> = [n / 3, 2 * n / 3]
            .into_iter()
            .filter(|&i| i > 0 && i + 1 < n)
            .collect();
        v.dedup();
        v
    };
    let (skip_t, skip_l) = (inner(nt), inner(nl));
    let fits = if opt.smooth_t == 0 {
        fit_all(tab, &opt.form, &skip_t, &skip_l)?
    } else {
        fit_all_joint(tab, &opt.form, opt.smooth_t, &skip_t, &skip_l)?
    };
    let pred = predict_held_out(tab, &opt.form, &fits, &skip_l);
    let held = |it: usize, il: usize| skip_t.contains(&it) || skip_l.contains(&il);
    let mut errors: Vec<_> = (1..ng)
        .map(|g| group_error_on(tab, &pred, Some(g), &held))
        .collect();
    errors.push(group_error_on(tab, &pred, None, &held));
    let coll = fit_collectors(tab, opt, &skip_t, &skip_l)?;
    let l_of = held_out_l(tab, &skip_l);
    let pred_c = predict_collector(tab, &opt.collector, &coll, (&fits, &pred), &l_of);
    let collector = coll
        .iter()
        .map(|f| collector_error_on(tab, &pred_c, f.group, &held))
        .collect();
    Ok(HeldOut {
        thicknesses: skip_t.iter().map(|&i| tab.thickness[i]).collect(),
        mu_l: skip_l.iter().map(|&i| tab.mu_l[i]).collect(),
        errors,
        collector,
        pred,
    })
}

#[cfg(test)]
mod grid_tests {
    use super::*;

    #[test]
    fn a_point_domain_and_more_ln_t_terms_than_thicknesses_are_warned() {
        let opt = Options::default();
        let w = grid_warnings(&[8.0], &[0.5], &opt);
        assert!(w[0].contains("1 thickness and 1 sun cosine"), "{w:?}");
        let w = grid_warnings(&[1.0, 4.0, 16.0], &[0.5, 1.0], &opt);
        assert_eq!(w.len(), 1 + usize::from(opt.collector_q > 3), "{w:?}");
        assert!(
            w[0].contains("--smooth-t 5: 5 terms in ln t fitted to 3 thicknesses"),
            "{w:?}"
        );
        let five = [1.0, 2.0, 4.0, 8.0, 16.0];
        assert!(grid_warnings(&five, &[0.5, 1.0], &opt).is_empty());
    }
}
