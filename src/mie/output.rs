//! A Mie phase-function table's artefacts, written and read here: phase.npz, phase.json and
//! optionally phase.csv (`nephele mie`, and the main job's tables).

use super::PhaseTable;
use crate::io::npz::read_arrays;
use crate::io::{AtomicFiles, Npz};
use anyhow::Result;
use serde_json::{json, Value};
use std::io::Write;
use std::path::Path;

/// The npz keys of a Mie table (docs/mie.md) plus the extra per-wavelength integrals.
pub fn table_npz(t: &PhaseTable) -> Npz {
    let n = t.theta_deg.len();
    let nl = t.wavelength_nm.len();
    let mut npz = Npz::new();
    npz.add("theta_deg", &[n], &t.theta_deg)
        .add("mu", &[n], &t.mu)
        .add("phase", &[n], &t.phase)
        .add("phase_rgb", &[n, 3], &t.phase_rgb)
        .add("phase_rgb_3wl", &[n, 3], &t.phase_rgb_3wl)
        .add("wavelength_nm", &[nl], &t.wavelength_nm)
        .add("phase_spectral", &[nl, n], &t.phase_spectral)
        .add("cdf", &[n], &t.cdf)
        .add("legendre", &[t.legendre.len()], &t.legendre)
        .add("g_spectral", &[nl], &t.g_spectral)
        .add("c_sca_spectral_um2", &[nl], &t.c_sca_spectral_um2);
    npz
}

/// The sidecar: integral quantities, then whatever the caller adds (config echo, timings).
pub fn table_json(t: &PhaseTable, extra: Value) -> Value {
    let mut v = json!({
        "tool": "nephele",
        "version": crate::VERSION,
        "git_commit": option_env!("NEPHELE_GIT_COMMIT"),
        "distribution": t.distribution,
        "g": t.g,
        "g_rgb": t.g_rgb,
        "c_sca_um2": t.c_sca_um2,
        "q_sca": t.q_sca,
        "effective_diameter_um": t.effective_diameter_um,
        "normalisation_by_quadrature": t.quadrature_norm,
        "n_angles": t.theta_deg.len(),
        "n_wavelengths": t.wavelength_nm.len(),
        "conventions": {
            "phase": "normalised: integral of p over the sphere = 1, unit 1/sr; theta between incident and scattered directions",
            "phase_rgb": "linear sRGB channels (CIE 1931 2 deg, illuminant in config), each normalised to 1",
            "phase_rgb_3wl": "monochromatic 650, 510, 440 nm",
            "cdf": "trapezoid in theta of 2 pi p sin(theta), divided by its last value",
            "legendre": "chi_l = 2 pi int p P_l dmu (trapezoid in theta) / chi_0, so chi_0 = 1; p = sum (2l+1) chi_l P_l / (4 pi)",
            "index_sign": "m = n + ik, k >= 0 absorbs"
        }
    });
    if let (Value::Object(map), Value::Object(more)) = (&mut v, extra) {
        map.extend(more);
    }
    v
}

/// Writes phase.npz, phase.json (and phase.csv if `csv`) into `set` under `dir`.
pub fn write_table(
    set: &mut AtomicFiles,
    dir: &Path,
    t: &PhaseTable,
    extra: Value,
    csv: bool,
) -> Result<()> {
    std::fs::create_dir_all(dir)?;
    set.write(&dir.join("phase.npz"), |w| table_npz(t).write_to(w))?;
    let json = serde_json::to_vec_pretty(&table_json(t, extra))?;
    set.write_bytes(&dir.join("phase.json"), &json)?;
    if csv {
        set.write(&dir.join("phase.csv"), |w| {
            writeln!(w, "theta_deg,mu,phase,phase_r,phase_g,phase_b,cdf")?;
            for i in 0..t.theta_deg.len() {
                let rgb = &t.phase_rgb[3 * i..3 * i + 3];
                writeln!(
                    w,
                    "{},{:.17e},{:.17e},{:.17e},{:.17e},{:.17e},{:.17e}",
                    t.theta_deg[i], t.mu[i], t.phase[i], rgb[0], rgb[1], rgb[2], t.cdf[i]
                )?;
            }
            Ok(())
        })?;
    }
    Ok(())
}

/// θ (degrees) and p (sr⁻¹) of a phase.npz: `phase`, or with `rgb` the three linear-sRGB
/// channels of `phase_rgb` (one column each).
pub fn read_phase(path: &Path, rgb: bool) -> Result<(Vec<f64>, Vec<Vec<f64>>)> {
    let name = if rgb { "phase_rgb" } else { "phase" };
    let mut a = read_arrays(path, &["theta_deg", name])?;
    let p = a.pop().unwrap_or_default();
    let theta = a.pop().unwrap_or_default();
    anyhow::ensure!(
        p.len() == theta.len() * if rgb { 3 } else { 1 },
        "'{}': {name} does not match theta_deg",
        path.display()
    );
    Ok((theta, if rgb { channels(&p) } else { vec![p] }))
}

/// The three columns of an interleaved [n, 3] array (the sRGB channels of `phase_rgb`).
pub fn channels(rgb: &[f64]) -> Vec<Vec<f64>> {
    (0..3)
        .map(|c| rgb.iter().skip(c).step_by(3).copied().collect())
        .collect()
}
