//! transport.ntt: the runtime's file written from the fits, loaded back by the runtime and
//! compared with the fit on every cell (`NttCheck`).

use super::near_beam::{halo_table, near_beam_check, NearBeamCheck};
use super::run::{Measured, Options};
use super::ship::{ntt_bytes, phase_angles, with_halo};
use super::SlabTables;
use crate::io::write_atomic;
use crate::phase::{Phase, PhaseSpec};
use anyhow::{anyhow, Context, Result};
use nephele_runtime::phase::Cosine;
use nephele_runtime::transport::single_scattering;
use nephele_runtime::transport::{Transport, TransportTables};
use serde::Serialize;
use std::path::{Path, PathBuf};

/// The phase function the slab run sampled: the table stored in its tables.npz, or, for an
/// analytic phase function (or tables written before the table was stored), the one its
/// tables.json's config.phase names.
pub(super) fn phase_of_run(tab: &SlabTables, tables: &Path) -> Result<Phase> {
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
pub(super) fn write_ntt(
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
