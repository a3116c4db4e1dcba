//! The compressed tables as renderers load them: a `.ntt` container (docs/format.md) with the
//! arrays that [`nephele_runtime::transport::tables::TransportTables`] reads (table in its module
//! docs): the joint fits of the groups of orders ≥ 2 and the phase function for order 1.

use super::joint::JointFit;
use super::tables::SlabTables;
use super::LogAdditive;
use crate::io::container::{container_bytes, Array};
use anyhow::{ensure, Result};

/// Angles (degrees) at which the phase function is stored: 0.01° steps to 5° (the Mie forward
/// peak), 0.1° beyond.
pub fn phase_angles() -> Vec<f64> {
    (0..500)
        .map(|i| i as f64 * 0.01)
        .chain((0..=1750).map(|i| 5.0 + i as f64 * 0.1))
        .collect()
}

/// The container's bytes. `phase` holds p (sr⁻¹) at [`phase_angles`].
pub fn ntt_bytes(
    tab: &SlabTables,
    form: &LogAdditive,
    q: usize,
    fits: &[JointFit],
    phase: &[f64],
) -> Result<Vec<u8>> {
    let theta = phase_angles();
    ensure!(
        phase.len() == theta.len(),
        "phase: {} values for {} angles",
        phase.len(),
        theta.len()
    );
    ensure!(
        !fits.is_empty() && fits.iter().all(|f| f.q == q),
        "no joint fits, or mixed Q"
    );
    let [_, nt, nl, _, nm, _] = tab.shape;
    let f32s = |v: &mut dyn Iterator<Item = f64>| -> Vec<f32> { v.map(|x| x as f32).collect() };
    let form_v = f32s(
        &mut [
            form.legendre,
            form.harmonics,
            form.theta_nodes,
            form.pairs as usize,
            q,
        ]
        .into_iter()
        .map(|x| x as f64),
    );
    let first = f32s(&mut fits.iter().map(|f| tab.group_first[f.group]));
    let mu_l = f32s(&mut tab.mu_l.iter().copied());
    let mu_v = f32s(&mut (0..nm).map(|m| tab.mu_v(m)));
    let thickness = f32s(&mut tab.thickness.iter().copied());
    let ln_t = f32s(&mut fits.iter().flat_map(|f| [f.ln_t_range.0, f.ln_t_range.1]));
    let beta = f32s(&mut fits.iter().flat_map(|f| f.beta.iter().copied()));
    // An empty range (no fitted cell) is stored as (1, 0): nothing lies inside.
    let u_range = f32s(&mut fits.iter().flat_map(|f| {
        f.u_range.iter().flat_map(|per_t| {
            per_t
                .iter()
                .flat_map(|&(lo, hi)| if lo <= hi { [lo, hi] } else { [1.0, 0.0] })
        })
    }));
    let theta32 = f32s(&mut theta.iter().copied());
    let phase32 = f32s(&mut phase.iter().copied());
    let g = fits.len();
    let p = form.n_params(nm, nl);
    container_bytes(&[
        Array {
            name: "form",
            dims: &[5],
            values: &form_v,
        },
        Array {
            name: "group_first",
            dims: &[g],
            values: &first,
        },
        Array {
            name: "mu_l_nodes",
            dims: &[nl],
            values: &mu_l,
        },
        Array {
            name: "mu_v_nodes",
            dims: &[nm],
            values: &mu_v,
        },
        Array {
            name: "thickness",
            dims: &[nt],
            values: &thickness,
        },
        Array {
            name: "ln_t_range",
            dims: &[g, 2],
            values: &ln_t,
        },
        Array {
            name: "beta",
            dims: &[g, p, q],
            values: &beta,
        },
        Array {
            name: "u_range",
            dims: &[g, nt, nl * nm, 2],
            values: &u_range,
        },
        Array {
            name: "phase_theta",
            dims: &[theta32.len()],
            values: &theta32,
        },
        Array {
            name: "phase",
            dims: &[phase32.len()],
            values: &phase32,
        },
    ])
}
