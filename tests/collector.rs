//! The fast renderers against the path tracer (docs/collector.md): on a slab the collector
//! renderer reads the tables' own slab, so per order group it must match the path tracer within
//! the compression's error for that group; the frame is the same bits for any thread count;
//! scenes that do not match the tables are refused; `nephele compare` measures the
//! reference's noise right (two independent renders differ by √2 times it).

use nephele::render::compare::compare;
use nephele::render::fast::{render_fast, FastOptions, Method, RayPattern};
use nephele::render::image::{Rendered, GROUP_FIRST};
use nephele::render::output::write_outputs;
use nephele::render::path::{render, Settings};
use nephele::render::scene::Scene;
use std::process::Command;

/// The compressed form's own T error per group of orders ≥ 2 (T-weighted relative RMS over
/// the fitted cells, runtime/tables/mie10um/manifest.json).
fn compression_error() -> Vec<f64> {
    let text = std::fs::read_to_string(concat!(
        env!("CARGO_MANIFEST_DIR"),
        "/runtime/tables/mie10um/manifest.json"
    ))
    .unwrap();
    let m: serde_json::Value = serde_json::from_str(&text).unwrap();
    m["errors"]["fitted"]["T"].as_array().unwrap()[..GROUP_FIRST.len() - 1]
        .iter()
        .map(|g| g["rel_rms"].as_f64().unwrap())
        .collect()
}

fn slab_scene(camera_y: f64, camera_z: f64, look_z: f64) -> Scene {
    Scene::parse(&format!(
        r#"{{"medium": {{"kind": "slab", "thickness": 200}}, "sigma_t": 0.05,
            "phase": {{"kind": "mie", "diameter_um": 10}},
            "sun": {{"direction": [0, -0.7071, 0.7071], "irradiance": [1, 1, 1]}},
            "camera": {{"position": [0, {camera_y}, {camera_z}], "look_at": [0, 0, {look_z}],
                        "fov_deg": 30, "width": 12, "height": 8}}}}"#
    ))
    .unwrap()
}

/// The path tracer at `spp` samples per pixel, from `seed`.
fn traced(spp: u32, seed: u64) -> Settings {
    Settings {
        spp,
        seed,
        ..Settings::default()
    }
}

/// The image mean of group g (luminance-free: channel 0, the sun is white) and, from the
/// split-sample halves, its standard error (0 without halves).
fn group_mean(r: &Rendered, g: usize) -> (f64, f64) {
    let n = r.width * r.height;
    let ng = GROUP_FIRST.len();
    let at = |a: &[f32], k: usize, px: usize| a[((k * ng + g) * n + px) * 3] as f64;
    let mean = (0..n)
        .map(|px| r.groups[(g * n + px) * 3] as f64)
        .sum::<f64>()
        / n as f64;
    if r.halves.is_empty() {
        return (mean, 0.0);
    }
    let var: f64 = (0..n)
        .map(|px| 0.25 * (at(&r.halves, 0, px) - at(&r.halves, 1, px)).powi(2))
        .sum();
    (mean, var.sqrt() / n as f64)
}

/// Seen from above (reflection, d = 0, the sun behind the camera) and from below
/// (transmission, d = t, scattering angles near 97°), a 10-mfp Mie slab: order 1 within 1 % + 3 SE (exact by marching), each group of orders ≥ 2 that holds at
/// least 1 % of their light within its compression error + 3 SE (the compression error is
/// T-weighted: through 10 mfp order 2 holds 10⁻⁴ of the light and is not fitted to a few %),
/// and the whole of orders ≥ 2 within 5 %.
#[test]
fn on_a_slab_the_collector_renderer_matches_the_path_tracer_per_group() {
    let tables = nephele_runtime::embedded::mie_10um();
    let errors = compression_error();
    for (what, scene) in [
        ("above", slab_scene(-900.0, 700.0, 200.0)),
        ("below", slab_scene(900.0, -700.0, 0.0)),
    ] {
        let pt = render(&scene, &traced(384, 3), &|_| {}).unwrap();
        let fast = render_fast(&scene, &tables, &FastOptions::default(), &|_| {}).unwrap();
        let (mut sum_pt, mut sum_fast, mut var) = (0.0, 0.0, 0.0);
        let scattered: f64 = (1..GROUP_FIRST.len()).map(|g| group_mean(&pt, g).0).sum();
        for g in 0..GROUP_FIRST.len() {
            let (r, se) = group_mean(&pt, g);
            let (c, _) = group_mean(&fast, g);
            if g > 0 {
                sum_pt += r;
                sum_fast += c;
                var += se * se;
                if r < 0.01 * scattered {
                    println!(
                        "{what}: orders {}+: {:.2e} of the scattered light, not judged alone",
                        GROUP_FIRST[g],
                        r / scattered
                    );
                    continue;
                }
            }
            let tol = if g == 0 { 0.01 } else { errors[g - 1] };
            let rel = c / r - 1.0;
            println!(
                "{what}: orders {}+: collector {c:.4e} path tracer {r:.4e} ± {se:.1e}: \
                 {:+.1} % (allowed {:.1} % + 3 SE)",
                GROUP_FIRST[g],
                100.0 * rel,
                100.0 * tol
            );
            assert!(
                (c - r).abs() <= tol * r + 3.0 * se,
                "{what}, group {g}: {c} vs {r} ± {se}"
            );
        }
        assert!(
            (sum_fast - sum_pt).abs() <= 0.05 * sum_pt + 3.0 * var.sqrt(),
            "{what}: orders ≥ 2 {sum_fast} vs {sum_pt}"
        );
    }
}

/// The same frame, bit for bit, on one thread and on two, for every fast method (and the
/// patterns whose pixels share corner rays and their searches).
#[test]
fn fast_frames_are_the_same_bits_for_any_thread_count() {
    let tables = nephele_runtime::embedded::mie_10um();
    let mut scene = Scene::load(std::path::Path::new(concat!(
        env!("CARGO_MANIFEST_DIR"),
        "/fit-configs/scenes/cloud.json"
    )))
    .unwrap();
    scene.camera.width = 40;
    scene.camera.height = 30;
    for (method, pattern) in [
        (Method::Collector, RayPattern::Grid),
        (Method::Collector, RayPattern::Quincunx),
        (Method::Single, RayPattern::Quincunx),
        (Method::Octaves, RayPattern::Grid),
    ] {
        let opts = FastOptions {
            method,
            map_resolution: 64,
            planes: 64,
            pattern,
            ..FastOptions::default()
        };
        let run = |threads: usize| {
            rayon::ThreadPoolBuilder::new()
                .num_threads(threads)
                .build()
                .unwrap()
                .install(|| render_fast(&scene, &tables, &opts, &|_| {}).unwrap())
        };
        let (a, b) = (run(1), run(2));
        assert!(a
            .groups
            .iter()
            .zip(&b.groups)
            .all(|(x, y)| x.to_bits() == y.to_bits()));
        assert_eq!(a.transmittance, b.transmittance);
        assert!(
            a.groups.iter().any(|&v| v > 0.0),
            "{method:?}: a black frame"
        );
    }
}

/// A sun below the tables' lowest is said, with the share of the searches it held and how low
/// it went; a sun within the tables' range draws no such warning.
#[test]
fn a_sun_below_the_tables_is_said_in_the_render_json() {
    let tables = nephele_runtime::embedded::mie_10um();
    let opts = FastOptions::default();
    let warnings = |elevation_deg: f64| -> Vec<String> {
        let mut scene = slab_scene(-1500.0, 1500.0, 200.0);
        let e = elevation_deg.to_radians();
        scene.sun.direction = [0.0, -e.cos(), e.sin()];
        let r = render_fast(&scene, &tables, &opts, &|_| {}).unwrap();
        r.details["warnings"]
            .as_array()
            .unwrap()
            .iter()
            .map(|w| w.as_str().unwrap().to_string())
            .collect()
    };
    let low = warnings(3.0);
    assert!(
        low.iter().any(
            |w| w.starts_with("100.0 % of the collector searches held the sun")
                && w.contains("mu_L down to 0.052 (3.0 deg up)")
        ),
        "{low:?}"
    );
    assert!(warnings(45.0).iter().all(|w| !w.contains("held the sun")));
}

/// A scene whose phase function is not the tables' is refused with one clear error and no
/// file; --allow-table-mismatch renders it with a warning.
#[test]
fn scenes_that_do_not_match_the_tables_are_refused() {
    let dir = tempfile::tempdir().unwrap();
    let scene = dir.path().join("hg.json");
    std::fs::write(
        &scene,
        r#"{"medium": {"kind": "slab", "thickness": 100}, "sigma_t": 0.05,
            "phase": {"kind": "hg", "g": 0.5},
            "sun": {"direction": [0, 0, 1], "irradiance": [1, 1, 1]},
            "camera": {"position": [0, -500, 500], "look_at": [0, 0, 0], "fov_deg": 30,
                       "width": 8, "height": 6}, "spp": 4}"#,
    )
    .unwrap();
    let out = dir.path().join("out");
    let run = |extra: &[&str]| {
        Command::new(env!("CARGO_BIN_EXE_nephele"))
            .args(["render", "--method", "collector", "--scene"])
            .arg(&scene)
            .arg("--out")
            .arg(&out)
            .args(extra)
            .output()
            .unwrap()
    };
    let o = run(&[]);
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(
        !o.status.success() && err.contains("phase function"),
        "{err}"
    );
    assert!(!out.exists(), "files written for a refused scene");
    let o = run(&["--allow-table-mismatch"]);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    assert!(String::from_utf8_lossy(&o.stderr).contains("warning"));
    assert!(out.join("regions.npy").exists() && out.join("render.json").exists());
    let o = run(&["--map-resolution", "100"]);
    assert!(!o.status.success() && String::from_utf8_lossy(&o.stderr).contains("power of two"));
}

/// Path-traced renders of one scene with different seeds: compare's split-sample noise must
/// explain their difference (RMSE ≈ √2 × the reference's noise, bias within its noise), and a
/// render against itself gives zeros. The ratio of one pair of 24 × 16 renders scatters by
/// ±0.15 for order 1 (measured over ten pairs: 1.27–1.60), so its mean over four pairs is held
/// to √2 ± 0.2; a noise estimate off by a factor 1.3 either way fails.
#[test]
fn compare_measures_the_references_noise() {
    let dir = tempfile::tempdir().unwrap();
    let mut scene = slab_scene(-900.0, 700.0, 200.0);
    scene.camera.width = 24;
    scene.camera.height = 16;
    let a = dir.path().join("a");
    let b = dir.path().join("b");
    let names = ["orders >= 2", "order 1", "beauty"];
    let mut ratios = [0.0; 3];
    for pair in 1..=4u64 {
        for (dir, seed) in [(&a, pair), (&b, 100 + pair)] {
            let r = render(&scene, &traced(64, seed), &|_| {}).unwrap();
            write_outputs(dir, &scene, &r).unwrap();
        }
        let report = compare(&a, &[b.clone(), a.clone()], &dir.path().join("cmp")).unwrap();
        let q = |k: usize, name: &str| {
            report.candidates[k]
                .quantities
                .iter()
                .find(|q| q.quantity == name)
                .unwrap()
                .regions["opaque"]
                .clone()
        };
        for (i, name) in names.iter().enumerate() {
            let s = q(0, name);
            let ratio = s.rel_rmse / s.reference_noise;
            println!(
                "pair {pair} {name}: RMSE {:.4} noise {:.4} ratio {ratio:.3}",
                s.rel_rmse, s.reference_noise
            );
            ratios[i] += ratio / 4.0;
            assert!(
                s.bias.abs() < 4.0 * s.bias_noise * 2f64.sqrt(),
                "{name}: {s:?}"
            );
            let same = q(1, name);
            assert_eq!(same.rel_rmse, 0.0);
            assert_eq!(same.bias, 0.0);
        }
    }
    for (name, ratio) in names.iter().zip(ratios) {
        assert!(
            (ratio - 2f64.sqrt()).abs() < 0.2,
            "{name}: mean ratio {ratio}"
        );
    }
    assert!(
        dir.path().join("cmp/panel.png").exists() && dir.path().join("cmp/report.json").exists()
    );
}
