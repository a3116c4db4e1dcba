//! The shipped tables past their thickest slab (t > 128 mfp), continued by diffusion theory
//! (runtime/src/transport/thick.rs), against slab walks of their own at t = 128, 256 and 512
//! (fit-configs/thick/, kept in tests/data/thick/ by scripts/export_thick_walk.py).
//!
//! Each walk's cells are compared with the runtime averaged over the cell (3 × 3 points in
//! μ_V and ψ_V), per group and per region: near the lit face (d ≤ 8 mfp), between the faces,
//! and on the far face. The t = 128 walk measures the compression's own error in each
//! region; past the grid the continuation may add little to it.
//!
//! Below the grid's lowest sun the same comparison runs against walks of t = 10 under the sun
//! 1°, 3° and 6° up (fit-configs/low-sun/, kept in tests/data/low_sun/).

use nephele_runtime::embedded::mie_10um;
use nephele_runtime::transport::{SlabPoint, Transport, TransportTables};
use std::path::Path;

const GROUPS: usize = 8;

/// The cells of one walk: T, its standard error and σ per (group, plane, μ_V bin, ψ_V bin).
struct Walk {
    t: f64,
    mu_l: f64,
    depth: Vec<f64>,
    mu_v_edges: Vec<f64>,
    psi_v_edges: Vec<f64>,
    transmitted: f64,
    t_cells: Vec<f32>,
    se: Vec<f32>,
    sigma: Vec<f32>,
}

fn array<T: npyz::Deserialize>(
    npz: &mut npyz::npz::NpzArchive<std::io::BufReader<std::fs::File>>,
    name: &str,
) -> Vec<T> {
    npz.by_name(name).unwrap().unwrap().into_vec::<T>().unwrap()
}

fn walk(t: u32) -> Walk {
    walk_file(&format!("thick/t{t}.npz"))
}

/// A walk kept in tests/data/`name`.
fn walk_file(name: &str) -> Walk {
    let path = Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("tests/data")
        .join(name);
    let mut z = npyz::npz::NpzArchive::open(&path).unwrap();
    Walk {
        t: array::<f64>(&mut z, "thickness")[0],
        mu_l: array::<f64>(&mut z, "mu_l")[0],
        depth: array(&mut z, "depth"),
        mu_v_edges: array(&mut z, "mu_v_edges"),
        psi_v_edges: array(&mut z, "psi_v_edges"),
        transmitted: array::<f64>(&mut z, "transmitted")[0],
        t_cells: array(&mut z, "T"),
        se: array(&mut z, "T_se"),
        sigma: array(&mut z, "sigma"),
    }
}

impl Walk {
    fn dims(&self) -> (usize, usize, usize) {
        (
            self.depth.len(),
            self.mu_v_edges.len() - 1,
            self.psi_v_edges.len() - 1,
        )
    }

    fn index(&self, g: usize, j: usize, m: usize, k: usize) -> usize {
        let (nd, nm, nk) = self.dims();
        ((g * nd + j) * nm + m) * nk + k
    }

    /// The runtime's T and σ of every group averaged over each cell, as the walk's arrays.
    fn predicted(&self, tables: &TransportTables) -> (Vec<f32>, Vec<f32>) {
        let (nd, nm, nk) = self.dims();
        let mut t_out = vec![0.0f32; GROUPS * nd * nm * nk];
        let mut s_out = t_out.clone();
        const S: usize = 3;
        for j in 0..nd {
            for m in 0..nm {
                for k in 0..nk {
                    let (mut sum_t, mut sum_s) = ([0.0f64; GROUPS], [0.0f64; GROUPS]);
                    for a in 0..S {
                        for b in 0..S {
                            let f = |e: &[f64], i: usize, s: usize| {
                                e[i] + (s as f64 + 0.5) / S as f64 * (e[i + 1] - e[i])
                            };
                            let at = SlabPoint {
                                thickness: self.t as f32,
                                mu_l: self.mu_l as f32,
                                depth: self.depth[j] as f32,
                                mu_v: f(&self.mu_v_edges, m, a) as f32,
                                psi_v: f(&self.psi_v_edges, k, b) as f32,
                            };
                            let mut all = [Transport::default(); GROUPS];
                            tables.evaluate_all(&at, &mut all);
                            for g in 0..GROUPS {
                                sum_t[g] += all[g].t as f64;
                                sum_s[g] += all[g].sigma as f64;
                            }
                        }
                    }
                    for g in 0..GROUPS {
                        let i = self.index(g, j, m, k);
                        t_out[i] = (sum_t[g] / (S * S) as f64) as f32;
                        s_out[i] = (sum_s[g] / (S * S) as f64) as f32;
                    }
                }
            }
        }
        (t_out, s_out)
    }
}

/// The regions of a slab, by plane depth.
#[derive(Clone, Copy, Debug, PartialEq)]
enum Region {
    LitFace,
    Between,
    FarFace,
}

fn region(d: f64, t: f64) -> Region {
    if d <= 8.0 {
        Region::LitFace
    } else if d >= t - 8.0 {
        Region::FarFace
    } else {
        Region::Between
    }
}

/// T-weighted bias and relative RMS of T, the walk's noise, and σ's T-weighted bias, over the
/// cells of group `g` in `r` that hold at least 1 % of the group's largest T, the horizon bins
/// (|μ_V| < 0.2 at the bin's centre, where the crossing estimator is noisiest) left out.
#[derive(Debug)]
struct Error {
    cells: usize,
    bias: f64,
    rel_rms: f64,
    noise: f64,
    sigma_bias: f64,
}

fn error(w: &Walk, pred: &(Vec<f32>, Vec<f32>), g: usize, r: Region) -> Error {
    let (nd, nm, nk) = w.dims();
    let top = (0..nd * nm * nk)
        .map(|i| w.t_cells[g * nd * nm * nk + i])
        .fold(0.0f32, f32::max) as f64;
    let (mut n, mut sw, mut sb, mut sr, mut sn, mut ss, mut sref) =
        (0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0);
    for j in (0..nd).filter(|&j| region(w.depth[j], w.t) == r) {
        for m in 0..nm {
            let centre = 0.5 * (w.mu_v_edges[m] + w.mu_v_edges[m + 1]);
            if centre.abs() < 0.2 {
                continue;
            }
            for k in 0..nk {
                let i = w.index(g, j, m, k);
                let (want, got) = (w.t_cells[i] as f64, pred.0[i] as f64);
                if want < 0.01 * top || want <= 0.0 {
                    continue;
                }
                n += 1;
                sw += want;
                sb += want * (got - want);
                sref += want * want;
                sr += want * (got / want - 1.0).powi(2);
                sn += want * (w.se[i] as f64 / want).powi(2);
                ss += want * (pred.1[i] as f64 - w.sigma[i] as f64) / w.sigma[i].max(1e-6) as f64;
            }
        }
    }
    Error {
        cells: n,
        bias: sb / sref.max(1e-300),
        rel_rms: (sr / sw.max(1e-300)).sqrt(),
        noise: (sn / sw.max(1e-300)).sqrt(),
        sigma_bias: ss / sw.max(1e-300),
    }
}

/// Near the lit face a thicker slab is the thickest one: orders 2 … 30 within 5 % of t = 128
/// (they never reach a face 64 mfp away), orders ≥ 31 not below it (the thicker slab lets less
/// of them through) and by at most the diffusion bound; never the collapse of an extrapolated
/// polynomial in ln t.
#[test]
fn near_the_lit_face_a_thicker_slab_is_the_thickest_one() {
    let tables = mie_10um();
    let mut checked = 0;
    for t in [160.0f32, 200.0, 300.0, 500.0, 1000.0, 1e5] {
        for mu_l in [0.2f32, 0.5, 1.0] {
            for d in [1.0f32, 2.0, 4.0, 8.0] {
                for mu_v in [-0.95f32, -0.6, -0.2, 0.2, 0.6, 0.95] {
                    for psi in [0.0f32, 0.35, 1.5, 3.0] {
                        let at = SlabPoint {
                            thickness: t,
                            mu_l,
                            depth: d,
                            mu_v,
                            psi_v: psi,
                        };
                        let (mut here, mut thickest) = (
                            [Transport::default(); GROUPS],
                            [Transport::default(); GROUPS],
                        );
                        tables.evaluate_all(&at, &mut here);
                        tables.evaluate_all(
                            &SlabPoint {
                                thickness: 128.0,
                                ..at
                            },
                            &mut thickest,
                        );
                        for g in 0..GROUPS {
                            let (a, b) = (here[g].t, thickest[g].t);
                            assert!(a.is_finite() && a >= 0.0, "{at:?} group {g}: {a}");
                            if g + 1 < GROUPS {
                                assert!(
                                    (a - b).abs() <= 0.05 * b,
                                    "{at:?} group {g}: {a} against {b}"
                                );
                            } else {
                                assert!(
                                    a >= b && a <= 1.15 * b,
                                    "{at:?} orders ≥ 31: {a} against {b}"
                                );
                            }
                            checked += 1;
                        }
                    }
                }
            }
        }
    }
    assert_eq!(checked, 6 * 3 * 4 * 6 * 4 * GROUPS);
}

/// Diffusion theory's transmission asymptote, T ∝ 1/(t + 2 z_e) with z_e = 2/(3(1 − g)),
/// holds for the walks' transmitted light within 2 %: the law the continuation scales the far
/// face by, with g of the tables' own phase function.
#[test]
fn the_walks_transmission_follows_the_diffusion_asymptote() {
    let g = mie_10um().mean_cosine() as f64;
    let two_ze = 4.0 / 3.0 / (1.0 - g);
    let base = walk(128);
    for t in [256, 384, 512] {
        let w = walk(t);
        let want = (base.t + two_ze) / (w.t + two_ze);
        let got = w.transmitted / base.transmitted;
        eprintln!(
            "t = {t}: transmitted {:.5} / {:.5} = {got:.4}; diffusion {want:.4}",
            w.transmitted, base.transmitted
        );
        assert!(
            (got / want - 1.0).abs() < 0.02,
            "t = {t}: {got} against {want}"
        );
    }
}

/// Past the grid the continued tables agree with the walk as well as the tables agree with
/// the walk at their thickest slab, region by region: T's bias within 4 points and its RMS
/// within 3 points of the compression's own at t = 128 (beside twice the two walks' noise),
/// the diffuse group's σ bias within 8 points of its own. Measured (docs/compress.md): the
/// far face's transmission exactly as at t = 128 (+20 % there, the compression's own), orders
/// ≥ 31 near the lit face −2.9 % at t = 256 and −4.5 % at 512 against +0.3 % at 128; σ of
/// orders ≥ 31 within 5.6 points of its own error at 128 (the far face at 512).
#[test]
fn past_the_grid_the_tables_agree_with_the_walk_as_well_as_at_the_thickest_slab() {
    let tables = mie_10um();
    let base = walk(128);
    let base_pred = base.predicted(&tables);
    for t in [256, 384, 512] {
        let w = walk(t);
        let pred = w.predicted(&tables);
        for r in [Region::LitFace, Region::Between, Region::FarFace] {
            for g in 0..GROUPS {
                let (own, here) = (error(&base, &base_pred, g, r), error(&w, &pred, g, r));
                eprintln!("t = {t} {r:?} group {g}: {here:?}\n    at t = 128: {own:?}");
                if here.cells < 20 || own.cells < 20 {
                    continue;
                }
                let noise = 2.0 * (here.noise.powi(2) + own.noise.powi(2)).sqrt();
                assert!(
                    (here.bias - own.bias).abs() <= 0.04 + noise,
                    "t = {t} {r:?} group {g}: bias {:.3} against {:.3} at t = 128",
                    here.bias,
                    own.bias
                );
                assert!(
                    here.rel_rms <= own.rel_rms + 0.03 + noise,
                    "t = {t} {r:?} group {g}: RMS {:.3} against {:.3} at t = 128",
                    here.rel_rms,
                    own.rel_rms
                );
                // σ of the groups below orders 31 is the thickest slab's own near the lit
                // face, and the two walks' planes lie at different depths, where the
                // compression's σ error differs: only the diffuse group's σ is continued.
                // Held at t = 128 it would be 23–29 % low at t = 256 and ~50 % at 512.
                assert!(
                    g + 1 < GROUPS || (here.sigma_bias - own.sigma_bias).abs() <= 0.08,
                    "t = {t} {r:?} group {g}: σ bias {:.3} against {:.3} at t = 128",
                    here.sigma_bias,
                    own.sigma_bias
                );
            }
        }
    }
}

/// Below the tables' lowest sun μ₀ (0.125, 7.2° up) they hold T/μ_L, the radiance per unit
/// irradiance on the lit face: against walks of t = 10 under the sun 6°, 3° and 1° up, every
/// group of orders 2 … 31+ (T summed over every cell the walk resolves to 30 %) is within
/// 10 %, 30 % and 60 %, where holding T itself is more than 20 %, 150 % and 400 % too bright.
#[test]
fn below_the_lowest_sun_the_tables_hold_t_over_mu_l() {
    let tables = mie_10um();
    let lowest = tables.domain().mu_l.0 as f64;
    for (deg, within, held_above) in [(6, 0.10, 0.20), (3, 0.30, 1.5), (1, 0.60, 4.0)] {
        let w = walk_file(&format!("low_sun/sun{deg}.npz"));
        assert!(w.mu_l < lowest, "the sun {deg} deg up lies below the grid");
        let pred = w.predicted(&tables);
        let (nd, nm, nk) = w.dims();
        for g in 0..GROUPS {
            let (mut want, mut got) = (0.0f64, 0.0f64);
            for i in g * nd * nm * nk..(g + 1) * nd * nm * nk {
                if w.t_cells[i] > 0.0 && w.se[i] < 0.3 * w.t_cells[i] {
                    want += w.t_cells[i] as f64;
                    got += pred.0[i] as f64;
                }
            }
            let bias = got / want - 1.0;
            let held = got * (lowest / w.mu_l) / want - 1.0;
            eprintln!(
                "sun {deg} deg up, group {g}: T/mu_L held {:+.1} %, T held {:+.1} %",
                100.0 * bias,
                100.0 * held
            );
            assert!(bias.abs() <= within, "sun {deg} deg, group {g}: {bias}");
            assert!(held > held_above, "sun {deg} deg, group {g}: {held}");
        }
    }
}
