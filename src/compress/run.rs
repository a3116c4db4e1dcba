//! The compression stage end to end: fit the form to a slab run's tables, measure it on every
//! cell and on held-out slices, and write report.json, manifest.json, compressed.npz, the
//! figures and transport.ntt (loaded back by the runtime and compared with the fit).

use super::collector::{fit_collector, predict_collector, CollectorFit};
use super::coverage::{coverage, domain_check, slices_of_all, worst_slice, Coverage, SliceShare};
use super::figure;
use super::fit::{fit_all, held_out_l, predict, predict_held_out, GroupFit};
use super::form::Lerp;
use super::joint::{fit_all_joint, fit_joint_groups, spanned, JointFit};
use super::near_beam::{halo_table, near_beam_check, NearBeamCheck};
use super::report::{collector_error_on, group_error, group_error_on, CollectorError, GroupError};
use super::ship::{ntt_bytes, phase_angles, with_halo};
use super::{LogAdditive, SlabTables};
use crate::io::{write_atomic, AtomicFiles, Npz};
use crate::phase::{Phase, PhaseSpec};
use anyhow::{anyhow, ensure, Context, Result};
use nephele_runtime::fitting::{CollectorForm, Statistic};
use nephele_runtime::phase::Cosine;
use nephele_runtime::transport::single_scattering;
use nephele_runtime::transport::{Transport, TransportTables};
use rayon::prelude::*;
use serde::Serialize;
use std::path::{Path, PathBuf};
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
struct Measured {
    fits: Vec<GroupFit>,
    joint: Vec<JointFit>,
    coll: Vec<CollectorFit>,
    /// The form's T and collector (σ, c_x, c_z) over the tables' layout.
    pred: Vec<f64>,
    pred_c: [Vec<f64>; 3],
    errors: Vec<GroupError>,
    reference: (Vec<GroupError>, usize),
    collector: Vec<CollectorError>,
    held_out: Option<HeldOut>,
    params: usize,
    collector_params: usize,
    fit_seconds: f64,
    coverage: CoverageReport,
}

/// The coverage of every group and of the sum ([`super::coverage`]).
#[derive(Serialize)]
struct CoverageReport {
    definition: &'static str,
    /// The largest share of one (t, μ_L) slice's light of orders ≥ 2 dropped by the groups
    /// together.
    worst_slice_all_groups: SliceShare,
    /// Every slice's share dropped by the groups together (t outer, μ_L inner).
    slices_all_groups: Vec<SliceShare>,
    groups: Vec<Coverage>,
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
struct CollectorOptions {
    legendre: usize,
    harmonics: usize,
    theta_nodes: usize,
    smooth_t: usize,
}

impl CollectorOptions {
    fn of(opt: &Options) -> Self {
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

/// The phase function the slab run sampled: the table stored in its tables.npz, or, for an
/// analytic phase function (or tables written before the table was stored), the one its
/// tables.json's config.phase names.
fn phase_of_run(tab: &SlabTables, tables: &Path) -> Result<Phase> {
    if let Some(source) = &tab.phase {
        return Phase::from_source(source.clone())
            .with_context(|| format!("'{}': the stored phase table", tables.display()));
    }
    let json = tables.with_extension("json");
    let text = std::fs::read_to_string(&json).with_context(|| {
        format!(
            "the phase function for order 1 comes from '{}'",
            json.display()
        )
    })?;
    let doc: serde_json::Value =
        serde_json::from_str(&text).with_context(|| format!("'{}' is not JSON", json.display()))?;
    let spec: PhaseSpec = serde_json::from_value(doc["config"]["phase"].clone())
        .with_context(|| format!("'{}': no config.phase", json.display()))?;
    Phase::build(&spec)
}

/// transport.ntt as written, and how closely the runtime follows the fit.
#[derive(Clone, Debug, Serialize)]
pub struct NttCheck {
    /// Where.
    pub path: PathBuf,
    /// Its size.
    pub bytes: usize,
    /// Largest |T_runtime/T_fit − 1| over the cells where both are positive and the fit's T
    /// holds ≥ 10⁻⁶ of its (t, μ_L) slice's largest (all groups), as for order 1.
    pub worst_t: f64,
    /// The same over the fainter cells in f32's normal range: where T is continued toward a
    /// face and nearly vanishes, it is the difference of nearly equal numbers, and f32 keeps
    /// fewer of its digits.
    pub worst_t_faint: f64,
    /// Largest |σ_runtime/σ_fit − 1| and |c_runtime − c_fit|/σ_fit.
    pub worst_sigma: f64,
    /// See `worst_sigma`.
    pub worst_c_in_sigma: f64,
    /// Largest |T₁/T₁_exact − 1| of order 1 from the stored phase table against the phase
    /// function itself, over the cells' centres where T₁_exact > 10⁻⁶ of its slice maximum.
    pub worst_order1: f64,
    /// Cells where exactly one of the fit and the runtime is 0 (a lost group, or f32
    /// underflow of a T f32 could hold), not counting `below_f32`.
    pub zero_mismatches: usize,
    /// Cells where the fit's T > 0 lies below f32's smallest normal number (1.2·10⁻³⁸):
    /// the runtime's f32 cannot hold it (0 or a subnormal with few digits) and they are not
    /// compared — light no renderer sees (low orders deep in thick slabs under a grazing sun).
    pub below_f32: usize,
    /// The runtime's T near the beam against the tables' tallies there.
    pub near_beam: Option<NearBeamCheck>,
    /// The same for the form alone, where the file holds a halo (what the halo corrects).
    pub near_beam_form: Option<NearBeamCheck>,
}

/// Writes transport.ntt (joint fits and the phase function) after loading it back with the
/// runtime and comparing its f32 evaluation with the fit on every cell the form represents.
fn write_ntt(
    out: &Path,
    tab: &SlabTables,
    opt: &Options,
    model: &Phase,
    m: &Measured,
) -> Result<NttCheck> {
    let (joint, coll) = (m.joint.as_slice(), m.coll.as_slice());
    let (pred, pred_c) = (&m.pred, &m.pred_c);
    // The nodes the walk's table has (or, analytic, a fine grid) and p there as it sampled it.
    let theta = model
        .source()
        .map_or_else(phase_angles, |s| s.theta_deg.clone());
    let phase: Vec<f64> = theta
        .iter()
        .map(|deg| {
            let half = (0.5 * deg.to_radians()).sin();
            model.with(|p| p.pdf_cosine(Cosine::from_one_minus_mu(2.0 * half * half)))
        })
        .collect();
    let collector = (!coll.is_empty()).then_some((&opt.collector, coll));
    let bytes = ntt_bytes(
        tab,
        &opt.form,
        opt.smooth_t,
        joint,
        collector,
        (&theta, &phase),
    )?;
    let rt = TransportTables::from_bytes(&bytes).map_err(|e| anyhow!("{e}"))?;
    // The halo (if the run tallied an aureole) against the form without it; the checks below
    // compare the form itself with the fit.
    let halo = tab.aureole.as_ref().map(|a| halo_table(tab, a, &rt));
    let written = match &halo {
        Some(h) => with_halo(&bytes, h)?,
        None => bytes.clone(),
    };
    let [_, nt, nl, nd, nm, nk] = tab.shape;
    let mut check = NttCheck {
        path: out.join("transport.ntt"),
        bytes: bytes.len(),
        worst_t: 0.0,
        worst_sigma: 0.0,
        worst_c_in_sigma: 0.0,
        worst_order1: 0.0,
        zero_mismatches: 0,
        below_f32: 0,
        worst_t_faint: 0.0,
        near_beam: None,
        near_beam_form: halo.as_ref().map(|_| near_beam_check(tab, &rt)),
    };
    let mut all = vec![Transport::default(); joint.len()];
    for it in 0..nt {
        for il in 0..nl {
            let mut order1 = Vec::new();
            let mut slice_top = 0.0f64;
            for (f, j, m, k) in joint.iter().flat_map(|f| {
                (0..nd).flat_map(move |j| {
                    (0..nm).flat_map(move |m| (0..nk).map(move |k| (f, j, m, k)))
                })
            }) {
                slice_top = slice_top.max(pred[tab.index(f.group, it, il, j, m, k)]);
            }
            for j in 0..nd {
                for m in 0..nm {
                    for k in 0..nk {
                        let at = tab.point(it, il, j, m, k);
                        let at32 = at.to_f32();
                        rt.evaluate_all(&at32, &mut all);
                        for (f, got) in joint.iter().zip(&all) {
                            let i = tab.index(f.group, it, il, j, m, k);
                            compare(
                                &mut check,
                                (pred[i], pred_c[0][i], pred_c[1][i], pred_c[2][i]),
                                got,
                                1e-6 * slice_top,
                            );
                        }
                        let exact = model.with(|p| single_scattering(p, 1.0, &at));
                        let stored = rt.order1(&at32) as f64;
                        order1.push((exact, stored));
                    }
                }
            }
            let top = order1.iter().map(|o| o.0).fold(0.0, f64::max);
            for (exact, stored) in order1 {
                if exact > 1e-6 * top {
                    check.worst_order1 = check.worst_order1.max((stored / exact - 1.0).abs());
                }
            }
        }
    }
    check.bytes = written.len();
    write_atomic(&check.path, |w| {
        std::io::Write::write_all(w, &written)?;
        Ok(())
    })?;
    Ok(check)
}

/// Folds one cell's runtime values `got` against the fit's (T, σ, c_x, c_z) into `check`.
fn compare(
    check: &mut NttCheck,
    (t, sigma, cx, cz): (f64, f64, f64, f64),
    got: &Transport,
    faint: f64,
) {
    if t > 0.0 && t < f32::MIN_POSITIVE as f64 {
        check.below_f32 += 1;
        return;
    }
    if (t > 0.0) != (got.t > 0.0) {
        check.zero_mismatches += 1;
    }
    if !(t > 0.0 && got.t > 0.0) {
        return;
    }
    let rel = (got.t as f64 / t - 1.0).abs();
    if t < faint {
        check.worst_t_faint = check.worst_t_faint.max(rel);
    } else {
        check.worst_t = check.worst_t.max(rel);
    }
    if sigma.is_finite() && sigma > 0.0 {
        check.worst_sigma = check
            .worst_sigma
            .max((got.sigma as f64 / sigma - 1.0).abs());
        let dc = (got.c_x as f64 - cx).hypot(got.c_z as f64 - cz) / sigma;
        check.worst_c_in_sigma = check.worst_c_in_sigma.max(dc);
    }
}

/// manifest.json, what shipped tables are: the slab run they come from (its config, seed,
/// photons, tool version), the compressor's version and options, the file's size and CRC-32,
/// and the error summary (per group, fitted and held out, T and the collector).
#[derive(Serialize)]
struct Manifest {
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

fn manifest(
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
