//! `nephele render --method collector --search-block N`: one collector search per block of
//! N × N pixels. The march (opacity, order 1, the sky term) is untouched, the searches fall to
//! one per block, and every pixel the per-pixel searches light is lit.

mod common;
use common::cli::{refuses, succeeds};
use common::npy_f32;
use std::path::Path;

/// `nephele render` of the default cloud by the collector at `size` into `out`, then `extra`.
fn collector_args<'a>(size: [&'a str; 2], out: &'a Path, extra: &[&'a str]) -> Vec<&'a str> {
    let mut args = vec!["render", "--scene", "fit-configs/scenes/cloud.json"];
    args.extend(["--method", "collector", "--size", size[0], size[1]]);
    args.extend(["--out", out.to_str().unwrap()]);
    args.extend(extra);
    args
}

/// Renders the default cloud at 40 × 30 with `block`, blocks sharing their search wherever
/// each of their pixels is at least `opacity` opaque; returns its directory.
fn render(dir: &Path, block: &str, opacity: &str) -> std::path::PathBuf {
    let out = dir.join(format!("block{block}-{opacity}"));
    let extra = [
        "--map-resolution",
        "64",
        "--search-block",
        block,
        "--search-block-opacity",
        opacity,
    ];
    succeeds(&collector_args(["40", "30"], &out, &extra));
    out
}

/// Orders ≥ 2 of channel k of a 40 × 30 render's groups.
fn orders_2(g: &[f32], k: usize) -> f32 {
    (1..9).map(|p| g[p * 40 * 30 * 3 + k]).sum()
}

/// Searches per group (render.json), the same for every group.
fn searches(dir: &Path) -> u64 {
    let doc: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(dir.join("render.json")).unwrap()).unwrap();
    let groups = doc["details"]["groups"].as_array().unwrap();
    let n = groups[0]["searches"].as_u64().unwrap();
    assert!(groups.iter().all(|g| g["searches"].as_u64() == Some(n)));
    n
}

#[test]
fn a_block_shares_one_search_and_leaves_the_march_alone() {
    let dir = tempfile::tempdir().unwrap();
    let (one, two) = (render(dir.path(), "1", "0"), render(dir.path(), "2", "0"));
    // The march is the same: transmittance and order 1 (the first of the groups' planes).
    for f in ["transmittance.npy", "unscattered.npy"] {
        assert!(
            npy_f32(&one.join(f)) == npy_f32(&two.join(f)),
            "{f} differs"
        );
    }
    let (g1, g2) = (
        npy_f32(&one.join("groups.npy")),
        npy_f32(&two.join("groups.npy")),
    );
    let plane = 40 * 30 * 3;
    assert!(g1[..plane] == g2[..plane], "order 1 differs");
    // One search per 2 × 2 block that holds a surface point, at most 20 × 15 of them.
    let (s1, s2) = (searches(&one), searches(&two));
    assert!(s1 > 100, "{s1} searches per pixel");
    assert!(
        s2 <= 20 * 15 && 4 * s2 >= s1 && s2 < s1,
        "{s2} block searches, {s1} per pixel"
    );
    // Every pixel lit by its own search is lit by its block's.
    let lit = (0..plane).filter(|&k| orders_2(&g1, k) > 0.0).count();
    assert!(lit > 100);
    let dark = (0..plane)
        .filter(|&k| orders_2(&g1, k) > 0.0 && orders_2(&g2, k) <= 0.0)
        .count();
    assert_eq!(
        dark, 0,
        "{dark} of {lit} channels lit per pixel are dark by blocks"
    );
}

/// With the default opacity threshold (0.99), a block that holds a pixel less opaque than it
/// (a silhouette) searches pixel by pixel: each such pixel's orders ≥ 2 are the bits of the
/// per-pixel render, and only the interior's blocks share, so the searches fall between the
/// uniform blocks' count and the per-pixel one.
#[test]
fn a_block_at_a_silhouette_searches_pixel_by_pixel() {
    let dir = tempfile::tempdir().unwrap();
    let one = render(dir.path(), "1", "0");
    let uniform = render(dir.path(), "2", "0");
    let edges = render(dir.path(), "2", "0.99");
    let (g1, ge) = (
        npy_f32(&one.join("groups.npy")),
        npy_f32(&edges.join("groups.npy")),
    );
    let t = npy_f32(&one.join("transmittance.npy"));
    let (w, h) = (40, 30);
    let mut silhouettes = 0;
    for (bj, bi) in (0..h)
        .step_by(2)
        .flat_map(|j| (0..w).step_by(2).map(move |i| (j, i)))
    {
        let block: Vec<usize> = (bj..bj + 2)
            .flat_map(|j| (bi..bi + 2).map(move |i| j * w + i))
            .collect();
        let alone = block.iter().any(|&p| t[p] < 1.0 && 1.0 - t[p] < 0.99);
        if !alone {
            continue;
        }
        for &p in &block {
            silhouettes += 1;
            for c in 0..3 {
                let k = p * 3 + c;
                assert_eq!(
                    orders_2(&g1, k).to_bits(),
                    orders_2(&ge, k).to_bits(),
                    "pixel {p}: {} per pixel, {} in a silhouette's block",
                    orders_2(&g1, k),
                    orders_2(&ge, k)
                );
            }
        }
    }
    assert!(
        silhouettes >= 40,
        "{silhouettes} pixels in silhouette blocks"
    );
    let (s1, su, se) = (searches(&one), searches(&uniform), searches(&edges));
    assert!(
        su < se && se < s1,
        "searches: per pixel {s1}, uniform {su}, edges {se}"
    );
}

#[test]
fn a_block_is_refused_beside_searches_on_every_ray_and_outside_1_to_16() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("o");
    let with = |extra: &[&'static str]| collector_args(["8", "6"], &out, extra);
    refuses(
        &with(&["--search-block", "2", "--search-every-ray"]),
        "--search-every-ray",
        Some(&out),
    );
    refuses(&with(&["--search-block", "0"]), "1…16", Some(&out));
    refuses(&with(&["--search-block", "17"]), "1…16", Some(&out));
}
