//! The shipped compressed transport tables (runtime/tables/mie10um): the file the runtime's
//! `embed` feature compiles in is the committed one, its manifest names it (size, CRC-32) and
//! records errors within the targets where they are met, and the runtime answers with
//! physically sensible values everywhere in its range.

use nephele_runtime::embedded::{mie_10um, MIE_10UM};
use nephele_runtime::fitting::crc32;
use nephele_runtime::transport::{SlabPoint, Transport};
use std::path::Path;

fn manifest() -> serde_json::Value {
    let dir = Path::new(env!("CARGO_MANIFEST_DIR")).join("runtime/tables/mie10um");
    let text = std::fs::read_to_string(dir.join("manifest.json")).unwrap();
    serde_json::from_str(&text).unwrap()
}

#[test]
fn the_embedded_tables_are_the_committed_file_its_manifest_describes() {
    let dir = Path::new(env!("CARGO_MANIFEST_DIR")).join("runtime/tables/mie10um");
    let on_disk = std::fs::read(dir.join("transport.ntt")).unwrap();
    assert!(on_disk == MIE_10UM);
    let m = manifest();
    assert_eq!(
        m["file"]["bytes"].as_u64().unwrap() as usize,
        MIE_10UM.len()
    );
    assert_eq!(
        m["file"]["crc32"].as_str().unwrap(),
        format!("{:08x}", crc32(&MIE_10UM[..MIE_10UM.len() - 4]))
    );
    // The shipped file within 512 KB.
    assert!(MIE_10UM.len() <= 512 * 1024, "{} bytes", MIE_10UM.len());
    assert_eq!(m["slab_run"]["config"]["phase"]["diameter_um"], 10.0);
    // Coverage, measured by the compressor over every cell of the slab tables with light: the
    // light the groups drop together (0, or off by more than 2×) is under 0.5 % of every
    // (t, μ_L) slice's, and the whole-domain error of the sum is within 5 %.
    let cov = &m["coverage"];
    let worst = cov["worst_slice_all_groups"]["share"].as_f64().unwrap();
    assert!(worst < 0.005, "{worst}");
    let sum_all = cov["rel_rms_all"]
        .as_array()
        .unwrap()
        .last()
        .unwrap()
        .as_f64()
        .unwrap();
    assert!(sum_all <= 0.05, "{sum_all}");
    assert_eq!(m["domain"]["thickness"][1], 128.0);
    // The collector meets its target (≤ 10 % of σ for orders ≥ 3), fitted and held out.
    for part in ["fitted", "held_out"] {
        for g in m["errors"][part]["collector"].as_array().unwrap() {
            if g["first_order"].as_f64().unwrap() >= 3.0 {
                assert!(g["c_in_sigma"].as_f64().unwrap() <= 0.10, "{part}: {g}");
                assert!(g["sigma_rel"].as_f64().unwrap() <= 0.10, "{part}: {g}");
            }
        }
    }
}

#[test]
fn the_embedded_tables_answer_sensibly_over_their_range() {
    let tab = mie_10um();
    assert_eq!(tab.groups(), 8);
    assert!(tab.has_collector());
    let mut out = [Transport::default(); 8];
    let mut resolved = 0;
    for &t in &[0.7f32, 3.0, 10.0, 50.0, 100.0] {
        for &mu_l in &[0.2f32, 0.45, 0.8, 1.0] {
            for &u in &[0.0f32, 0.3, 0.7, 1.0] {
                for &mu_v in &[-0.9f32, -0.3, 0.2, 0.8] {
                    for &psi in &[0.0f32, 1.0, 2.5] {
                        let at = SlabPoint {
                            depth: u * t,
                            thickness: t,
                            mu_v,
                            psi_v: psi,
                            mu_l,
                        };
                        tab.evaluate_all(&at, &mut out);
                        for (g, v) in out.iter().enumerate() {
                            // One group alone is the same group of all of them.
                            assert_eq!(tab.evaluate(g, &at), *v);
                            assert_eq!(tab.transport(g, &at), v.t);
                            assert!(v.t >= 0.0 && v.t.is_finite(), "{v:?}");
                            if v.t > 0.0 {
                                resolved += 1;
                                assert!(v.sigma > 0.0 && v.sigma < 10.0 * t.max(3.0), "{v:?}");
                                assert!(v.c_x.is_finite() && v.c_z.is_finite(), "{v:?}");
                            }
                        }
                        let o1 = tab.order1(&at);
                        assert!(o1 >= 0.0 && o1.is_finite());
                    }
                }
            }
        }
    }
    assert!(resolved > 1000, "{resolved} group values resolved");
}

/// μ_V = −0 is the horizon as +0 is: the same finite values for every group and order 1.
#[test]
fn minus_zero_is_the_horizon() {
    let tab = mie_10um();
    for (t, mu_l, d) in [(4.0f32, 0.8f32, 1.0f32), (16.0, 0.5, 0.3), (1.0, 1.0, 0.5)] {
        let at = |mu_v: f32| SlabPoint {
            depth: d,
            thickness: t,
            mu_v,
            psi_v: 0.3,
            mu_l,
        };
        let (plus, minus) = (at(0.0), at(-0.0));
        assert!(tab.order1(&plus).is_finite());
        assert_eq!(tab.order1(&plus).to_bits(), tab.order1(&minus).to_bits());
        let (mut a, mut b) = ([Transport::default(); 8], [Transport::default(); 8]);
        tab.evaluate_all(&plus, &mut a);
        tab.evaluate_all(&minus, &mut b);
        assert_eq!(a, b, "t {t} mu_L {mu_l} d {d}");
    }
}

/// The slab-table sample `nephele compress` drew beside the shipped file: random cells
/// [n, 8] (group, t, μ_L, d, μ_V, ψ_V, T, SE) and random points [n, 5] with the smallest and
/// largest table value per group around each ([n, groups]).
fn domain_check() -> [(Vec<u64>, Vec<f64>); 4] {
    let path =
        Path::new(env!("CARGO_MANIFEST_DIR")).join("runtime/tables/mie10um/domain_check.npz");
    let mut npz = npyz::npz::NpzArchive::open(&path).unwrap();
    ["cells", "points", "lo", "hi"].map(|name| {
        let a = npz.by_name(name).unwrap().unwrap();
        (a.shape().to_vec(), a.into_vec::<f64>().unwrap())
    })
}

fn point(at: &[f64]) -> SlabPoint<f32> {
    SlabPoint {
        thickness: at[0] as f32,
        mu_l: at[1] as f32,
        depth: at[2] as f32,
        mu_v: at[3] as f32,
        psi_v: at[4] as f32,
    }
}

/// Over the whole domain (every thickness, depth, view — the horizon and the faces included —
/// and sun cosine of the grid), against the Monte Carlo tables the file was fitted to, not
/// against the fit: at random cells of any group, and at random points between the grid's
/// nodes against the range of the 32 cells around them. The share of the light where the
/// runtime drops it (0, or off by more than 2×) stays small, and no group is 0 where every
/// cell around the point has its light.
#[test]
fn the_embedded_tables_cover_the_whole_domain() {
    let tab = mie_10um();
    let [(cs, cells), (ps, points), (_, lo), (_, hi)] = domain_check();
    let ng = tab.groups();
    // Cells: the runtime at the cell's centre against the bin's value.
    let (mut light, mut lost, mut e2) = (0.0, 0.0, 0.0);
    let mut worst = Vec::new();
    for c in cells.chunks(cs[1] as usize) {
        let (g, want) = (c[0] as usize - 1, c[6]);
        let got = tab.transport(g, &point(&c[1..6])) as f64;
        light += want;
        e2 += want * (got / want - 1.0).powi(2);
        if !(got > 0.0) || got > 2.0 * want || 2.0 * got < want {
            lost += want;
            worst.push((want, got, c.to_vec()));
        }
    }
    let (dropped, rms) = (lost / light, (e2 / light).sqrt());
    println!(
        "{} random cells: light dropped {:.3} %, T-weighted relative RMS {:.2} %",
        cs[0],
        100.0 * dropped,
        100.0 * rms
    );
    worst.sort_by(|a, b| b.0.total_cmp(&a.0));
    for (want, got, c) in worst.iter().take(5) {
        println!("  dropped: group {} t {} mu_L {} d {:.3} mu_V {:.4} psi {:.1}°: tables {want:.3e} ± {:.1e}, runtime {got:.3e}", c[0], c[1], c[2], c[3], c[4], c[5].to_degrees(), c[7]);
    }
    assert!(dropped < 0.005, "cells: {dropped}");
    // Points between the nodes: the sum of the groups against the range around it.
    let (mut light, mut lost, mut zeros) = (0.0, 0.0, 0);
    let mut out = [0.0f32; 8];
    for (i, at) in points.chunks(ps[1] as usize).enumerate() {
        let p = point(at);
        assert!(tab.domain().contains(&p), "{p:?}");
        tab.transport_all(&p, &mut out);
        let around = |v: &[f64]| v[i * ng..(i + 1) * ng].iter().sum::<f64>();
        let (a, b) = (around(&lo), around(&hi));
        let got: f64 = out.iter().map(|&v| v as f64).sum();
        light += b;
        if got < 0.5 * a || got > 2.0 * b {
            lost += b;
        }
        zeros += (0..ng)
            .filter(|&g| lo[i * ng + g] > 0.0 && out[g] == 0.0)
            .count();
    }
    let dropped = lost / light;
    println!("{} random points: light outside [lo/2, 2 hi] {:.3} %, groups 0 with light all around: {zeros}", ps[0], 100.0 * dropped);
    assert!(dropped < 0.005, "points: {dropped}");
    assert_eq!(zeros, 0);
}

/// The grid's edges and ±0: inside the domain, finite, and light wherever medium lies behind
/// the viewpoint; outside the grid (t, μ_L) the domain says so and the values stay finite.
#[test]
fn grid_edges_and_signed_zeros() {
    let tab = mie_10um();
    let dom = tab.domain();
    assert_eq!((dom.thickness, dom.mu_l), ((0.5, 128.0), (0.125, 1.0)));
    let mut out = [Transport::default(); 8];
    let pi = std::f32::consts::PI;
    for t in [dom.thickness.0, 3.0, dom.thickness.1] {
        for mu_l in [dom.mu_l.0, 0.6, 1.0] {
            for d in [0.0, 0.5 * t, t] {
                for mu_v in [-1.0f32, -0.0, 0.0, 1.0] {
                    for psi in [0.0, pi] {
                        let at = SlabPoint {
                            depth: d,
                            thickness: t,
                            mu_v,
                            psi_v: psi,
                            mu_l,
                        };
                        assert!(dom.contains(&at));
                        tab.evaluate_all(&at, &mut out);
                        let sum: f32 = out.iter().map(|v| v.t).sum();
                        assert!(sum.is_finite() && tab.order1(&at).is_finite(), "{at:?}");
                        let behind =
                            (mu_v > 0.0 && d < t) || (mu_v < 0.0 && d > 0.0) || mu_v == 0.0;
                        assert_eq!(sum > 0.0, behind, "{at:?}: {out:?}");
                        for v in out.iter().filter(|v| v.t > 0.0) {
                            assert!(
                                v.sigma > 0.0
                                    && v.sigma.is_finite()
                                    && v.c_x.is_finite()
                                    && v.c_z.is_finite(),
                                "{at:?}: {v:?}"
                            );
                        }
                    }
                }
            }
        }
    }
    for (t, mu_l) in [(0.2f32, 0.5f32), (500.0, 0.5), (8.0, 0.02)] {
        let at = SlabPoint {
            depth: 0.5 * t,
            thickness: t,
            mu_v: -0.4,
            psi_v: 1.0,
            mu_l,
        };
        assert!(!dom.contains(&at));
        tab.evaluate_all(&at, &mut out);
        assert!(
            out.iter()
                .all(|v| v.t.is_finite() && v.t >= 0.0 && v.sigma.is_finite()),
            "{at:?}: {out:?}"
        );
    }
}

/// The shipped tables answer as their form alone (the file without its halo) everywhere but
/// within the halo's reach (6.5°) of the transmitted beam looking down, where the halo changes
/// T; the file is of the one version this reader reads.
#[test]
fn the_halo_changes_the_tables_only_within_its_reach() {
    use nephele::slab::aureole::{from_beam, view_near_beam};
    use nephele_runtime::container::{Container, FORMAT_VERSION};
    use nephele_runtime::transport::TransportTables;
    assert_eq!(
        Container::from_bytes(MIE_10UM).unwrap().version(),
        FORMAT_VERSION
    );
    let bare = nephele::compress::ship::without_halo(MIE_10UM).unwrap();
    let new = TransportTables::from_bytes(&bare).unwrap();
    let shipped = mie_10um();
    let mut rng = nephele_stats::XorShift32::new(99);
    let mut next = || rng.unit_f32();
    let (mut inside, mut changed) = (0, 0);
    let reach = halo_reach();
    for i in 0..4000 {
        let t = 0.4 * 400f32.powf(next());
        let mut at = SlabPoint {
            depth: next() * t,
            thickness: t,
            mu_v: 2.0 * next() - 1.0,
            psi_v: 3.2 * next(),
            mu_l: 0.05 + 0.95 * next(),
        };
        if i % 2 == 1 {
            // Every other view within 1.3 × the halo's reach of the beam.
            let (theta, turn) = (
                (1.3 * reach * next() as f64).to_radians(),
                6.3 * next() as f64,
            );
            let (mu_v, psi_v) = view_near_beam(at.mu_l as f64, theta, turn);
            (at.mu_v, at.psi_v) = (mu_v as f32, psi_v as f32);
        }
        let (mut b, mut c) = ([Transport::default(); 8], [Transport::default(); 8]);
        new.evaluate_all(&at, &mut b);
        for g in 0..8 {
            assert_eq!(new.transport(g, &at), b[g].t, "group {g} at {at:?}");
        }
        shipped.evaluate_all(&at, &mut c);
        // The beam of the sun the tables read: the lowest sun's below it.
        let read_mu_l = at.mu_l.max(shipped.domain().mu_l.0);
        let cos = from_beam(read_mu_l as f64, at.mu_v as f64, at.psi_v as f64).mu;
        let edge = reach.to_radians().cos();
        if at.mu_v < 0.0 && cos > edge + 1e-5 {
            inside += 1;
            changed += usize::from(c.iter().zip(&b).any(|(x, y)| x.t != y.t));
        } else if (cos - edge).abs() > 1e-5 {
            assert_eq!(c, b, "outside the halo at {at:?}");
        }
    }
    // Where the halo reaches, it changes T (h = 0 nowhere in the shipped halo's inner annuli).
    println!("{changed} of {inside} points inside the halo changed");
    assert!(
        inside > 1000 && changed * 10 > inside * 9,
        "{changed} of {inside} changed"
    );
}

/// The last annulus edge of the shipped halo (degrees).
fn halo_reach() -> f64 {
    use nephele_runtime::container::Container;
    let c = Container::from_bytes(MIE_10UM).unwrap();
    let edges = c.find("halo_edges").unwrap();
    edges.get(edges.len() - 1).unwrap() as f64
}

/// Near the far face of thick slabs, looking at it (the continuation of the depth
/// profile beyond the fitted planes was 2–4× above an independent Monte Carlo there): order 1 +
/// every group against DISORT (tests/data/near-face-disort.json, scripts/near_face_disort.py).
#[test]
fn near_the_far_face_the_tables_follow_disort() {
    let text = std::fs::read_to_string(
        Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/data/near-face-disort.json"),
    )
    .unwrap();
    let doc: serde_json::Value = serde_json::from_str(&text).unwrap();
    let tab = mie_10um();
    let mut out = [Transport::default(); 8];
    let (mut rel, mut named_cells) = (Vec::new(), Vec::new());
    for p in doc["points"].as_array().unwrap() {
        let v: Vec<f64> = p
            .as_array()
            .unwrap()
            .iter()
            .map(|x| x.as_f64().unwrap())
            .collect();
        let at = point(&v);
        tab.evaluate_all(&at, &mut out);
        let got = tab.order1(&at) as f64 + out.iter().map(|g| g.t as f64).sum::<f64>();
        let ratio = got / v[5];
        let (t, f, mu_v) = (v[0], v[2] / v[0], v[3]);
        println!(
            "t {t:>5} mu_L {:.2} d/t {f:.2} mu_V {mu_v:+.2}: DISORT {:.3e}, tables {got:.3e} ({ratio:.2}×)",
            v[1], v[5]
        );
        assert!((1.0 / 3.0..=3.0).contains(&ratio), "{v:?}: {ratio}");
        rel.push((ratio - 1.0).abs());
        if (32.0..=64.0).contains(&t) && (0.97..=0.98).contains(&f) && (0.08..=0.25).contains(&mu_v)
        {
            named_cells.push(ratio);
        }
    }
    rel.sort_by(f64::total_cmp);
    let median = rel[rel.len() / 2];
    let worst = named_cells
        .iter()
        .fold(1.0f64, |w, &r| w.max(r).max(1.0 / r));
    println!(
        "{} points: median |rel| {:.1} %, worst {:.0} %; t 32–64, d/t 0.97–0.98, mu_V 0.08–0.25: worst {worst:.2}×",
        rel.len(),
        100.0 * median,
        100.0 * rel.last().unwrap()
    );
    assert!(named_cells.len() == 24, "{}", named_cells.len());
    assert!(worst <= 2.0, "{worst}");
    assert!(median <= 0.15, "{median}");
}

/// A point that is not in the slab (t, μ_L, d, μ_V or ψ_V out, NaN and ±∞ included) gives NaN
/// from every single-point evaluator of the Rust API, never a number; `SlabPoint::check` says
/// which coordinate (the batch, C, Python and the CLI refuse such points with it).
#[test]
fn points_outside_the_slab_are_not_numbers() {
    let tab = mie_10um();
    let at = |thickness, mu_l, depth, mu_v, psi_v| SlabPoint {
        depth,
        thickness,
        mu_v,
        psi_v,
        mu_l,
    };
    let (nan, inf) = (f32::NAN, f32::INFINITY);
    for p in [
        at(nan, 0.5, 1.0, 0.3, 0.1),
        at(inf, 0.5, 1.0, 0.3, 0.1),
        at(0.0, 0.5, 0.0, 0.3, 0.1),
        at(4.0, 1.5, 1.0, 0.3, 0.1),
        at(4.0, 0.0, 1.0, 0.3, 0.1),
        at(4.0, -0.2, 1.0, 0.3, 0.1),
        at(4.0, 0.5, 4.5, 0.3, 0.1),
        at(4.0, 0.5, -0.1, 0.3, 0.1),
        at(4.0, 0.5, 1.0, -1.5, 0.1),
        at(4.0, 0.5, 1.0, 0.3, -inf),
    ] {
        assert!(p.check().is_err(), "{p:?}");
        assert!(tab.order1(&p).is_nan(), "{p:?}");
        let mut all = [Transport::default(); 8];
        tab.evaluate_all(&p, &mut all);
        let mut t = [0.0f32; 8];
        tab.transport_all(&p, &mut t);
        for g in 0..8 {
            let one = tab.evaluate(g, &p);
            for v in [
                one.t,
                one.c_x,
                one.c_z,
                one.sigma,
                all[g].t,
                all[g].sigma,
                t[g],
            ] {
                assert!(v.is_nan(), "group {g} at {p:?}: {v}");
            }
            assert!(tab.transport(g, &p).is_nan());
        }
    }
    // Within the slab, at its faces and the horizon: numbers.
    for p in [at(4.0, 1.0, 0.0, -0.0, 0.0), at(4.0, 0.01, 4.0, 1.0, 3.1)] {
        assert!((0..8).all(|g| tab.transport(g, &p).is_finite()), "{p:?}");
    }
}
