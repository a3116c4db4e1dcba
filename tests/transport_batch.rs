//! `nephele transport --points`: every row of a .npy answered as the runtime answers one point
//! (bit for bit, whatever the thread count), the columns named in the sidecar, bad input refused
//! with nothing written.

mod common;

use common::cli::{files_in, refuses, succeeds};
use nephele::io::npy::{npy_bytes, read_npy};
use nephele_runtime::embedded::mie_10um;
use nephele_runtime::transport::{SlabPoint, Transport};
use std::path::Path;

/// Points over the whole domain: faces, the horizon (±0), grid edges and beyond, random.
fn points() -> Vec<[f64; 5]> {
    let mut p = vec![
        [4.0, 0.5, 0.0, -0.3, 10.0],
        [4.0, 0.5, 4.0, 0.3, 170.0],
        [4.0, 0.5, 2.0, 0.0, 0.0],
        [4.0, 0.5, 2.0, -0.0, 0.0],
        [0.5, 0.125, 0.25, 1.0, 90.0],
        [128.0, 1.0, 127.0, -1.0, 180.0],
        [500.0, 0.02, 10.0, 0.5, 45.0], // thicker than the grid, the sun below it
        [0.25, 0.5, 0.1, 0.3, 0.0],     // thinner than the grid
    ];
    let mut rng = nephele_stats::XorShift64::new(0x2545F4914F6CDD1D);
    let mut r = || rng.unit_f64();
    for _ in 0..3000 {
        let t = 0.5 * 256f64.powf(r());
        p.push([
            t,
            0.125 + 0.875 * r(),
            t * r(),
            2.0 * r() - 1.0,
            360.0 * r() - 180.0,
        ]);
    }
    p
}

fn write_points(path: &Path, rows: &[[f64; 5]]) {
    let flat: Vec<f64> = rows.iter().flatten().copied().collect();
    std::fs::write(path, npy_bytes(&[rows.len() as u64, 5], &flat).unwrap()).unwrap();
}

#[test]
fn every_row_is_the_runtimes_answer_whatever_the_threads() {
    let dir = std::env::temp_dir().join(format!("nephele-batch-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let rows = points();
    let input = dir.join("in.npy");
    write_points(&input, &rows);
    let run = |threads: &str, name: &str| {
        let out = dir.join(name);
        succeeds(&[
            "transport",
            "--points",
            input.to_str().unwrap(),
            "--out",
            out.to_str().unwrap(),
            "--collector",
            "--threads",
            threads,
        ]);
        std::fs::read(&out).unwrap()
    };
    let (one, two) = (run("1", "one.npy"), run("2", "two.npy"));
    assert!(one == two, "the answers depend on the thread count");
    let tab = mie_10um();
    let width = 1 + 4 * tab.groups();
    let got: Vec<f32> = read_npy(&dir.join("one.npy"), &[rows.len() as u64, width as u64]).unwrap();
    let mut all = [Transport::default(); 8];
    for (r, row) in rows.iter().zip(got.chunks_exact(width)) {
        let at = SlabPoint {
            thickness: r[0] as f32,
            mu_l: r[1] as f32,
            depth: r[2] as f32,
            mu_v: r[3] as f32,
            psi_v: r[4].to_radians() as f32,
        };
        tab.evaluate_all(&at, &mut all);
        assert_eq!(row[0].to_bits(), tab.order1(&at).to_bits(), "{r:?}");
        for (g, v) in all.iter().enumerate() {
            let want = [v.t, v.c_x, v.c_z, v.sigma];
            for (k, w) in want.iter().enumerate() {
                assert_eq!(row[1 + 4 * g + k].to_bits(), w.to_bits(), "{r:?} group {g}");
            }
        }
    }
    // Rows 6 and 7 lie outside the grid: flagged row by row, counted with their farthest
    // values in the sidecar. The random rows (t ≤ 128, μ_L ≥ 0.125) are inside.
    let flags: Vec<u8> = read_npy(&dir.join("one.outside.npy"), &[rows.len() as u64]).unwrap();
    assert_eq!(&flags[..8], &[0, 0, 0, 0, 0, 0, 1 | 4, 2]);
    assert!(flags[8..].iter().all(|&f| f == 0));
    let side: serde_json::Value =
        serde_json::from_slice(&std::fs::read(dir.join("one.json")).unwrap()).unwrap();
    let outside = &side["outside_the_grid"];
    assert_eq!(outside["t_past_thickest"]["rows"], 1);
    assert_eq!(outside["t_past_thickest"]["largest_t"], 500.0);
    assert_eq!(outside["t_below_thinnest"]["smallest_t"], 0.25);
    assert_eq!(
        outside["sun_below_lowest"]["smallest_mu_l"]
            .as_f64()
            .unwrap() as f32,
        0.02
    );
    assert_eq!(side["columns"].as_array().unwrap().len(), width);
    assert_eq!(side["columns"][1], "T_2");
    assert_eq!(side["columns"][width - 4], "T_31+");
    // T only: order 1 and T per group, the same values.
    succeeds(&[
        "transport",
        "--points",
        input.to_str().unwrap(),
        "--out",
        dir.join("t.npy").to_str().unwrap(),
    ]);
    let t_only: Vec<f32> = read_npy(
        &dir.join("t.npy"),
        &[rows.len() as u64, 1 + tab.groups() as u64],
    )
    .unwrap();
    for (a, b) in t_only
        .chunks_exact(1 + tab.groups())
        .zip(got.chunks_exact(width))
    {
        assert_eq!(a[0].to_bits(), b[0].to_bits());
        for g in 0..tab.groups() {
            assert_eq!(a[1 + g].to_bits(), b[1 + 4 * g].to_bits());
        }
    }
    std::fs::remove_dir_all(&dir).unwrap();
}

#[test]
fn bad_points_are_refused_and_nothing_is_written() {
    let dir = std::env::temp_dir().join(format!("nephele-batch-bad-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let out_dir = dir.join("out");
    std::fs::create_dir_all(&out_dir).unwrap();
    let out = out_dir.join("a.npy");
    let refused = |input: &Path, names_fix: &str| {
        let args = [
            "transport",
            "--points",
            input.to_str().unwrap(),
            "--out",
            out.to_str().unwrap(),
        ];
        refuses(&args, names_fix, Some(&out_dir));
    };
    let wrong = dir.join("wrong.npy");
    std::fs::write(&wrong, npy_bytes(&[2, 4], &[0.0f64; 8]).unwrap()).unwrap();
    refused(&wrong, "shape [2, 4], expected (N, 5)");
    let ints = dir.join("ints.npy");
    std::fs::write(&ints, npy_bytes(&[1, 5], &[1i32; 5]).unwrap()).unwrap();
    refused(&ints, "expected float32 or float64");
    let nan = dir.join("nan.npy");
    write_points(
        &nan,
        &[[4.0, 0.5, 1.0, 0.3, 0.0], [4.0, f64::NAN, 1.0, 0.3, 0.0]],
    );
    refused(&nan, "row 1: mu_L = NaN is not a sun cosine");
    // Every kind of point outside the slab is an error naming its row and value.
    for (row, says) in [
        (
            [4.0, 0.5, 5.0, 0.3, 0.0],
            "depth = 5 mfp is outside the slab [0, t = 4]",
        ),
        (
            [4.0, 1.5, 1.0, 0.3, 0.0],
            "mu_L = 1.5 is not a sun cosine in (0, 1]",
        ),
        ([4.0, 0.0, 1.0, 0.3, 0.0], "mu_L = 0 is not a sun cosine"),
        (
            [4.0, 0.5, 1.0, 2.0, 0.0],
            "mu_V = 2 is not a cosine in [-1, 1]",
        ),
        (
            [f64::INFINITY, 0.5, 1.0, 0.3, 0.0],
            "t = inf mfp is not a thickness",
        ),
        (
            [4.0, 0.5, 1.0, 0.3, f64::NEG_INFINITY],
            "psi_V = -inf rad is not a finite angle",
        ),
    ] {
        let bad = dir.join("bad.npy");
        write_points(&bad, &[[4.0, 0.5, 1.0, 0.3, 0.0], row]);
        refused(&bad, &format!("row 1: {says}"));
    }
    refuses(
        &["transport", "--points", nan.to_str().unwrap()],
        "--out",
        None,
    );
    assert!(files_in(&out_dir).is_empty());
    std::fs::remove_dir_all(&dir).unwrap();
}
