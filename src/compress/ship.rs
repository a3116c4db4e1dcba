//! The compressed tables as renderers load them: a `.ntt` container (docs/format.md) with the
//! arrays that [`nephele_runtime::transport::TransportTables`] reads (table in its module
//! docs): the joint fits of the groups of orders ≥ 2 and the phase function for order 1.

use super::collector::CollectorFit;
use super::joint::JointFit;
use super::near_beam::HaloTable;
use super::LogAdditive;
use crate::io::container::{container_bytes, Array};
use crate::slab::SlabTables;
use anyhow::{ensure, Result};
use nephele_runtime::container::Container;
use nephele_runtime::fitting::{names, pack_u_range, CollectorForm, Statistic};

/// Angles (degrees) at which an analytic phase function is stored: 0.02° steps to 5° (a
/// forward peak, ~1° wide for 10 µm droplets), 0.2° beyond. A tabulated one is stored at its own
/// nodes. Between nodes the runtime interpolates as the tabulated model samples (2π p sin θ
/// linear in θ); the compressor reports the largest error this gives order 1 on the tables'
/// cells.
pub fn phase_angles() -> Vec<f64> {
    (0..250)
        .map(|i| i as f64 * 0.02)
        .chain((0..=875).map(|i| 5.0 + i as f64 * 0.2))
        .collect()
}

/// The container's bytes. `(theta, phase)`: the phase function's nodes (degrees, 0 … 180) and
/// p (sr⁻¹) there.
pub fn ntt_bytes(
    tab: &SlabTables,
    form: &LogAdditive,
    q: usize,
    fits: &[JointFit],
    collector: Option<(&CollectorForm, &[CollectorFit])>,
    (theta, phase): (&[f64], &[f64]),
) -> Result<Vec<u8>> {
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
            form.cross,
        ]
        .into_iter()
        .map(|x| x as f64),
    );
    let first = f32s(&mut fits.iter().map(|f| tab.group_first[f.group]));
    let mu_l = f32s(&mut tab.mu_l.iter().copied());
    let mu_v = f32s(&mut (0..nm).map(|m| tab.mu_v(m)));
    let thickness = f32s(&mut tab.thickness.iter().copied());
    let ln_t = f32s(&mut fits.iter().flat_map(|f| [f.ln_t_range.0, f.ln_t_range.1]));
    let g = fits.len();
    let p = form.n_params(nm, nl);
    let beta = feature_major(&fits.iter().map(|f| &f.beta[..]).collect::<Vec<_>>(), p, q)?;
    // An empty range (no fitted cell) stays empty.
    let u_range: Vec<f32> = fits
        .iter()
        .flat_map(|f| {
            f.u_range
                .iter()
                .flatten()
                .map(|&(lo, hi)| pack_u_range(lo, hi))
        })
        .collect();
    let ceiling = f32s(
        &mut fits
            .iter()
            .flat_map(|f| f.ceiling.iter().flatten().copied()),
    );
    let theta32 = f32s(&mut theta.iter().copied());
    let phase32 = f32s(&mut phase.iter().copied());
    let mut arrays: Vec<(&str, Vec<usize>, Vec<f32>)> = vec![
        (names::FORM, vec![6], form_v),
        (names::GROUP_FIRST, vec![g], first),
        (names::MU_L_NODES, vec![nl], mu_l),
        (names::MU_V_NODES, vec![nm], mu_v),
        (names::THICKNESS, vec![nt], thickness),
        (names::LN_T_RANGE, vec![g, 2], ln_t),
        (names::BETA, vec![p, g, q], beta),
        (names::U_RANGE, vec![g, nt, nl * nm], u_range),
        (names::T_CEILING, vec![g, nt, nl], ceiling),
        (names::PHASE_THETA, vec![theta32.len()], theta32),
        (names::PHASE, vec![phase32.len()], phase32),
    ];
    if let Some((cf, coll)) = collector {
        ensure!(
            coll.len() == g
                && coll.iter().zip(fits).all(|(c, f)| c.group == f.group
                    && c.q == coll[0].q
                    && c.ln_t_range == f.ln_t_range),
            "the collector fits do not match the transport fits"
        );
        let cq = coll[0].q;
        let sizes = [cf.legendre, cf.harmonics, cf.theta_nodes, cq].map(|x| x as f32);
        arrays.push((names::COLLECTOR_FORM, vec![4], sizes.to_vec()));
        for (s, (stat, name)) in Statistic::ALL.iter().zip(names::COLLECTOR_BETA).enumerate() {
            let ps = cf.n_params(*stat, nm, nl);
            let per_group: Vec<&[f64]> = coll.iter().map(|c| &c.beta[s][..]).collect();
            arrays.push((name, vec![ps, g, cq], feature_major(&per_group, ps, cq)?));
        }
    }
    let views: Vec<Array> = arrays
        .iter()
        .map(|(name, dims, values)| Array { name, dims, values })
        .collect();
    container_bytes(&views)
}

/// The tables `bytes` (without a halo) with the halo `h` appended: every array as it is, then
/// `halo_edges`, `halo_shape` and `halo` (`nephele_runtime`'s
/// `transport::halo`).
pub fn with_halo(bytes: &[u8], h: &HaloTable) -> Result<Vec<u8>> {
    let c = Container::from_bytes(bytes).map_err(|e| anyhow::anyhow!("{e}"))?;
    ensure!(
        c.find(names::HALO).is_none(),
        "these tables already hold a halo"
    );
    let len = |name| c.find(name).map_or(0, |a| a.len());
    let (nt, nl) = (len(names::THICKNESS), len(names::MU_L_NODES));
    let nb = h.edges_deg.len() - 1;
    ensure!(
        h.values.len() == h.groups * nt * nl * h.planes * nb,
        "a halo of {} values for {} groups, {nt} thicknesses, {nl} sun cosines, {} planes and {nb} annuli",
        h.values.len(),
        h.groups,
        h.planes
    );
    let mut arrays: Vec<(String, Vec<usize>, Vec<f32>)> = (0..c.len())
        .filter_map(|i| c.array(i))
        .map(|a| {
            (
                a.name.to_string(),
                a.dims[..a.rank].to_vec(),
                a.iter().collect(),
            )
        })
        .collect();
    let edges = h.edges_deg.iter().map(|&x| x as f32).collect();
    arrays.push((names::HALO_EDGES.into(), vec![nb + 1], edges));
    arrays.push((
        names::HALO_SHAPE.into(),
        vec![2],
        vec![h.groups as f32, h.planes as f32],
    ));
    arrays.push((
        names::HALO.into(),
        vec![h.groups, nt, nl, h.planes * nb],
        h.values.clone(),
    ));
    let views: Vec<Array> = arrays
        .iter()
        .map(|(name, dims, values)| Array { name, dims, values })
        .collect();
    container_bytes(&views)
}

/// The tables `bytes` without their halo (every other array as it is): the form alone, for
/// comparisons.
pub fn without_halo(bytes: &[u8]) -> Result<Vec<u8>> {
    let c = Container::from_bytes(bytes).map_err(|e| anyhow::anyhow!("{e}"))?;
    let kept: Vec<(String, Vec<usize>, Vec<f32>)> = (0..c.len())
        .filter_map(|i| c.array(i))
        .filter(|a| ![names::HALO_EDGES, names::HALO_SHAPE, names::HALO].contains(&a.name))
        .map(|a| {
            (
                a.name.to_string(),
                a.dims[..a.rank].to_vec(),
                a.iter().collect(),
            )
        })
        .collect();
    let views: Vec<Array> = kept
        .iter()
        .map(|(name, dims, values)| Array { name, dims, values })
        .collect();
    container_bytes(&views)
}

/// Per-group parameters ([P, Q] each) as one feature-major [P, G, Q] f32 array: one
/// feature's coefficients for every group together, as the runtime sums them.
fn feature_major(per_group: &[&[f64]], p: usize, q: usize) -> Result<Vec<f32>> {
    ensure!(
        per_group.iter().all(|b| b.len() == p * q),
        "parameters of {} values, expected {p} × {q}",
        per_group
            .iter()
            .map(|b| b.len())
            .find(|&n| n != p * q)
            .unwrap_or(0)
    );
    let mut out = Vec::with_capacity(p * per_group.len() * q);
    for i in 0..p {
        for b in per_group {
            out.extend(b[i * q..(i + 1) * q].iter().map(|&x| x as f32));
        }
    }
    Ok(out)
}
