//! The fast renderers' checks of the transport tables against the scene: the tables are for one
//! phase function and ϖ = 1, so a scene with another phase function (or other droplets) is
//! refused (or rendered with a warning), and so is another albedo but for the collector, whose
//! finite-cloud correction weighs each group by what absorption leaves (docs/collector.md); and
//! the mean cosine g of the scene's phase function, which the octave baseline scales.

use super::{FastOptions, Method};
use crate::phase::Phase;
use crate::render::scene::Scene;
use anyhow::{bail, Result};
use nephele_runtime::transport::TransportTables;

/// The tables are for one phase function and ϖ = 1: the scene's must match (p within
/// [`PHASE_TOLERANCE`] at every degree, the forward peak included; ϖ = 1 but for the
/// collector, which weighs in the absorption) unless the caller allows a mismatch. `phases`
/// come with their mean cosine g.
pub(super) fn check_tables(
    scene: &Scene,
    tables: &TransportTables,
    (phases, g): (&[Phase], f64),
    opts: &FastOptions,
    warnings: &mut Vec<String>,
) -> Result<()> {
    // Without a sky, only the collector reads the tables.
    if opts.method != Method::Collector && !scene.sky.iter().any(|&s| s > 0.0) {
        return Ok(());
    }
    let mut problems = Vec::new();
    if (scene.albedo - 1.0).abs() > 1e-9 && opts.method != Method::Collector {
        problems.push(format!(
            "the tables are for albedo 1, the scene's is {}",
            scene.albedo
        ));
    }
    let mut worst = (0.0f64, 0.0f64);
    for deg in 0..=180 {
        let mu = (deg as f64).to_radians().cos();
        let p = channel_mean(phases, mu);
        let q = tables.phase(mu as f32) as f64;
        let rel = (p - q).abs() / q.max(1e-30);
        if rel > worst.0 {
            worst = (rel, deg as f64);
        }
    }
    let scene_phase = describe_phase(&scene.phase, g);
    let tables_phase = match opts.tables_diameter_um {
        Some(d) => format!("mie, d = {d} µm, g = {:.4}", tables.mean_cosine()),
        None => format!("g = {:.4}", tables.mean_cosine()),
    };
    if worst.0 > PHASE_TOLERANCE {
        let remedy = match &scene.phase {
            crate::phase::PhaseSpec::Mie { diameter_um, .. } => format!(
                "make tables for it with `nephele tables --diameter {diameter_um} --out DIR` and \
                 pass --tables DIR"
            ),
            _ => "make tables for it with `nephele slab` and `nephele compress`, and pass \
                  --tables DIR"
                .to_string(),
        };
        problems.push(format!(
            "the scene's phase function ({scene_phase}) differs from the tables' ({tables_phase}) \
             by {:.0} % at {}°, beyond the {:.0} % at every angle the tables accept: {remedy}",
            100.0 * worst.0,
            worst.1,
            100.0 * PHASE_TOLERANCE
        ));
    } else if worst.0 > PHASE_NOTICE {
        let w = format!(
            "the scene's phase function ({scene_phase}) differs from the tables' ({tables_phase}) \
             by {:.1} % at {}°, within the {:.0} % the tables accept",
            100.0 * worst.0,
            worst.1,
            100.0 * PHASE_TOLERANCE
        );
        warnings.push(w);
    }
    if problems.is_empty() {
        return Ok(());
    }
    if opts.allow_mismatch {
        // Said once, with the render's other warnings (render.json and stderr).
        warnings.extend(problems);
        return Ok(());
    }
    bail!(
        "the scene does not match the transport tables: {} (--allow-table-mismatch renders \
         anyway)",
        problems.join("; ")
    )
}

/// Refuses, before the scene's Mie table is computed (seconds to minutes), a scene of Mie
/// droplets whose diameter lies more than [`DIAMETER_APART`] from the one the tables were made
/// for (`opts.tables_diameter_um`, when known): such phase functions differ far beyond
/// [`PHASE_TOLERANCE`]. Nearer diameters are left to [`check_tables`].
pub(super) fn check_droplets(scene: &Scene, opts: &FastOptions) -> Result<()> {
    let reads_tables = opts.method == Method::Collector || scene.sky.iter().any(|&s| s > 0.0);
    let (Some(made_for), crate::phase::PhaseSpec::Mie { diameter_um: d, .. }) =
        (opts.tables_diameter_um, &scene.phase)
    else {
        return Ok(());
    };
    if !reads_tables || opts.allow_mismatch || (d / made_for - 1.0).abs() <= DIAMETER_APART {
        return Ok(());
    }
    bail!(
        "the scene does not match the transport tables: the scene's droplets are {d} µm across, \
        the tables' {made_for} µm, so their phase functions differ far beyond the {:.0} % at \
        every angle the tables accept (10 % in diameter is already 21 % at 0°): make tables \
        for it with `nephele tables --diameter {d} --out DIR` and pass --tables DIR \
        (--allow-table-mismatch renders anyway)",
        100.0 * PHASE_TOLERANCE
    )
}

/// The relative difference of droplet diameters past which [`check_droplets`] refuses at
/// once: 10 %, where Mie 10 µm against 11 and 9 µm differ by 21 % and 25 % (against 10.5 µm,
/// 10 %), four times the tolerance.
const DIAMETER_APART: f64 = 0.1;

/// The largest relative difference of the scene's phase function from the tables' (at any
/// whole degree) the tables accept.
const PHASE_TOLERANCE: f64 = 0.05;

/// A difference below the tolerance still worth a warning.
const PHASE_NOTICE: f64 = 0.005;

/// "mie, d = 30 µm, g = 0.8712".
fn describe_phase(spec: &crate::phase::PhaseSpec, g: f64) -> String {
    use crate::phase::PhaseSpec::*;
    match spec {
        Mie { diameter_um, .. } => format!("mie, d = {diameter_um} µm, g = {g:.4}"),
        HgDraine { diameter_um, .. } => format!("hg_draine, d = {diameter_um} µm, g = {g:.4}"),
        _ => format!("g = {g:.4}"),
    }
}

/// The mean of the channels' phase functions at cosine `mu`.
fn channel_mean(phases: &[Phase], mu: f64) -> f64 {
    phases.iter().map(|p| p.with(|f| f.eval(mu))).sum::<f64>() / phases.len() as f64
}

/// g = ∫ μ p dΩ of the channels' mean, by the midpoint rule on 20 000 angles.
pub(super) fn mean_cosine(phases: &[Phase]) -> f64 {
    let n = 20_000;
    let h = std::f64::consts::PI / n as f64;
    (0..n)
        .map(|k| {
            let th = (k as f64 + 0.5) * h;
            let mu = th.cos();
            2.0 * std::f64::consts::PI * mu * channel_mean(phases, mu) * th.sin() * h
        })
        .sum()
}
