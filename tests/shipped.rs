//! The shipped compressed transport tables (runtime/tables/mie10um): the file the runtime's
//! `embed` feature compiles in is the committed one, its manifest names it (size, CRC-32) and
//! records errors within the targets where they are met, and the runtime answers with
//! physically sensible values everywhere in its range.

use nephele_runtime::container::crc32;
use nephele_runtime::embedded::{mie_10um, MIE_10UM};
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
    assert!(MIE_10UM.len() <= 256 * 1000, "{} bytes", MIE_10UM.len());
    assert_eq!(m["slab_run"]["config"]["phase"]["diameter_um"], 10.0);
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
