//! A new user's first hour with `nephele compare` and the pictures:
//! compare refuses renders of different scenes, cameras or sizes and a reference without the
//! path tracer's noise estimate; the PNG's exposure is set by the cloud, not the sky around
//! it, and `--exposure` overrides it.
//!
//! Every render is tiny (24 × 18 pixels, a few samples, an HG phase function so that no Mie
//! table is computed): a small sphere far from the camera under a dim sky, the case where the
//! sky used to set the exposure.

mod common;

use common::cli::{files_in, refuses, succeeds};
use serde_json::Value;
use std::path::{Path, PathBuf};

/// sphere10.json seen from 1 km under a dim sky (the sphere covers about 5 % of the frame),
/// 24 × 18 pixels, 4 spp, HG g = 0.85, changed by `edit`, written as `dir/name.json`.
fn scene(dir: &Path, name: &str, edit: impl Fn(&mut Value)) -> PathBuf {
    let path = concat!(
        env!("CARGO_MANIFEST_DIR"),
        "/fit-configs/scenes/sphere10.json"
    );
    let mut s: Value = serde_json::from_str(&std::fs::read_to_string(path).unwrap()).unwrap();
    s["sky"] = serde_json::json!([0.015, 0.025, 0.045]);
    s["camera"]["position"] = serde_json::json!([0.0, -1000.0, 150.0]);
    s["camera"]["width"] = 24.into();
    s["camera"]["height"] = 18.into();
    s["spp"] = 4.into();
    s["phase"] = serde_json::json!({"kind": "hg", "g": 0.85});
    edit(&mut s);
    let file = dir.join(format!("{name}.json"));
    std::fs::write(&file, s.to_string()).unwrap();
    file
}

/// `nephele render --scene SCENE --out DIR EXTRA…`; returns DIR.
fn render(scene: &Path, dir: &Path, name: &str, extra: &[&str]) -> PathBuf {
    let out = dir.join(name);
    let mut args = vec![
        "render",
        "--scene",
        scene.to_str().unwrap(),
        "--out",
        out.to_str().unwrap(),
    ];
    args.extend_from_slice(extra);
    succeeds(&args);
    out
}

/// A fast render (order 1 only; the HG scene is not the tables', hence the mismatch flag).
const SINGLE: [&str; 3] = ["--method", "single", "--allow-table-mismatch"];

/// `nephele compare --reference R --candidate C… --out OUT EXTRA…`, its arguments.
fn compare_args(reference: &Path, candidates: &[&Path], out: &Path, extra: &[&str]) -> Vec<String> {
    let mut args = vec!["compare".to_string(), "--reference".into(), path(reference)];
    for c in candidates {
        args.extend(["--candidate".to_string(), path(c)]);
    }
    args.extend(["--out".to_string(), path(out)]);
    args.extend(extra.iter().map(|e| e.to_string()));
    args
}

fn path(p: &Path) -> String {
    p.to_str().unwrap().to_string()
}

/// Runs `nephele compare` with `args` (from [`compare_args`]); asserts that it succeeded.
fn compare_succeeds(args: &[String]) -> std::process::Output {
    succeeds(&args.iter().map(String::as_str).collect::<Vec<_>>())
}

/// `nephele compare --reference R --candidate C --out OUT`, refused with `fix`, OUT left
/// without files.
fn compare_refuses(reference: &Path, candidate: &Path, out: &Path, fix: &str) -> String {
    let args = compare_args(reference, &[candidate], out, &[]);
    refuses(
        &args.iter().map(String::as_str).collect::<Vec<_>>(),
        fix,
        Some(out),
    )
}

/// A temporary directory with the base scene and its path-traced render "ref".
fn traced() -> (tempfile::TempDir, PathBuf, PathBuf) {
    let dir = tempfile::tempdir().unwrap();
    let base = scene(dir.path(), "base", |_| {});
    let reference = render(&base, dir.path(), "ref", &[]);
    (dir, base, reference)
}

fn json(path: &Path) -> Value {
    serde_json::from_str(&std::fs::read_to_string(path).unwrap()).unwrap()
}

#[test]
fn compare_refuses_renders_of_different_scenes_and_cameras() {
    let (dir, base, reference) = traced();
    let d = dir.path();
    let wider = scene(d, "wider", |s| {
        s["medium"]["blobs"][0]["radii"][0] = 130.0.into();
    });
    let moved = scene(d, "moved", |s| s["camera"]["position"][1] = (-900.0).into());
    let out = d.join("cmp");
    let e = compare_refuses(
        &reference,
        &render(&wider, d, "wider", &SINGLE),
        &out,
        "different scenes",
    );
    assert!(
        e.contains("medium.blobs[0].radii[0]"),
        "names what differs: {e}"
    );
    let e = compare_refuses(
        &reference,
        &render(&moved, d, "moved", &[]),
        &out,
        "different cameras",
    );
    assert!(e.contains("camera.position"), "names what differs: {e}");
    // What only says how a scene was rendered (samples, seed, description) is not the scene.
    let reseeded = scene(d, "reseeded", |s| {
        s["seed"] = 7.into();
        s["description"] = "another text".into();
    });
    let same = render(&reseeded, d, "same", &["--spp", "2"]);
    let single = render(&base, d, "single", &SINGLE);
    let o = compare_succeeds(&compare_args(&reference, &[&same, &single], &out, &[]));
    let stdout = String::from_utf8_lossy(&o.stdout);
    // The table says what its numbers are; PSNR's unit and direction too.
    assert!(
        stdout
            .lines()
            .next()
            .unwrap()
            .contains("PSNR (dB, higher is closer)"),
        "{stdout}"
    );
    let report = json(&out.join("report.json"));
    assert!(report["units"]["psnr_db"].as_str().unwrap().contains("dB"));
    assert!(report["units"]["rel_rmse"]
        .as_str()
        .unwrap()
        .contains("0.01 = 1 %"));
    // A render of a few milliseconds is not printed as "0 s" or "1 s".
    let secs = json(&same.join("render.json"))["seconds"].as_f64().unwrap();
    assert!(secs < 0.5, "the tiny render took {secs} s");
    assert!(
        !stdout.contains(" 0 s a frame") && !stdout.contains(" 1 s a frame"),
        "{stdout}"
    );
    assert!(files_in(&out).contains(&"panel.png".to_string()));
    // What the single-scattering render is worth: the path tracer's time to reach its beauty
    // error, from the reference's noise and time, over its frame; printed per candidate.
    let cand = &report["candidates"][1];
    let beauty = cand["quantities"]
        .as_array()
        .unwrap()
        .iter()
        .find(|q| q["quantity"] == "beauty")
        .unwrap();
    let opaque = &beauty["regions"]["opaque"];
    let f = |v: &serde_json::Value, k: &str| v[k].as_f64().unwrap();
    let ratio = f(opaque, "reference_noise") / f(opaque, "rel_rmse_corrected");
    let path = f(&report, "reference_seconds") * ratio * ratio;
    let eq = &cand["equal_quality"];
    assert!((f(eq, "path_seconds") / path - 1.0).abs() < 1e-9, "{eq}");
    assert!((f(eq, "speedup") * f(cand, "seconds") / path - 1.0).abs() < 1e-9);
    assert!(
        stdout.contains("x its frame: the reference's method needs"),
        "{stdout}"
    );
}

#[test]
fn compare_refuses_renders_of_different_sizes() {
    let (dir, base, reference) = traced();
    let d = dir.path();
    let smaller = render(&base, d, "smaller", &["--size", "20", "15"]);
    let e = compare_refuses(&reference, &smaller, &d.join("cmp"), "--size");
    assert!(e.contains("20×15") && e.contains("24×18"), "{e}");
}

#[test]
fn compare_refuses_a_reference_without_halves() {
    let (dir, base, path_traced) = traced();
    let d = dir.path();
    let fast = render(&base, d, "fast", &SINGLE);
    assert!(!fast.join("halves.npy").exists());
    compare_refuses(
        &fast,
        &path_traced,
        &d.join("cmp"),
        "did you swap --reference and --candidate?",
    );
}

/// beauty.png's pixels (RGB, 8 bits) and opacity.npy of a render directory.
fn png_and_opacity(dir: &Path) -> (Vec<u8>, Vec<f32>) {
    let rgb = image::open(dir.join("beauty.png"))
        .unwrap()
        .to_rgb8()
        .into_raw();
    let file = std::fs::File::open(dir.join("opacity.npy")).unwrap();
    let opacity = npyz::NpyFile::new(std::io::BufReader::new(file))
        .unwrap()
        .into_vec::<f32>()
        .unwrap();
    (rgb, opacity)
}

#[test]
fn the_exposure_is_set_by_the_cloud_not_the_sky() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    let out = render(&scene(d, "base", |_| {}), d, "ref", &[]);
    let (rgb, opacity) = png_and_opacity(&out);
    let cloud: Vec<u8> = (0..opacity.len())
        .filter(|&i| opacity[i] > 0.5)
        .map(|i| *rgb[i * 3..i * 3 + 3].iter().max().unwrap())
        .collect();
    let share = cloud.len() as f64 / opacity.len() as f64;
    // The case of the issue: the sky is most of the frame and would set a frame percentile.
    assert!(share > 0.02 && share < 0.1, "the cloud covers {share}");
    let saturated = cloud.iter().filter(|&&v| v >= 250).count() as f64 / cloud.len() as f64;
    assert!(
        saturated < 0.25,
        "{saturated} of the cloud is white: {cloud:?}"
    );
    let spread = cloud.iter().max().unwrap() - cloud.iter().min().unwrap();
    assert!(spread >= 15, "the cloud is flat: {cloud:?}");
    let meta = json(&out.join("render.json"));
    assert_eq!(meta["exposure_from"], "cloud");
    assert!(meta["exposure"].as_f64().unwrap() > 0.0);
}

#[test]
fn the_exposure_flag_sets_the_pngs_exposure() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    let base = scene(d, "base", |_| {});
    let mean = |dir: &Path| {
        let (rgb, _) = png_and_opacity(dir);
        rgb.iter().map(|&v| v as f64).sum::<f64>() / rgb.len() as f64
    };
    let dim = render(&base, d, "dim", &["--exposure", "2"]);
    let bright = render(&base, d, "bright", &["--exposure", "20"]);
    assert!(
        mean(&bright) > mean(&dim) + 10.0,
        "{} {}",
        mean(&bright),
        mean(&dim)
    );
    let meta = json(&dim.join("render.json"));
    assert_eq!(meta["exposure"].as_f64(), Some(2.0));
    assert_eq!(meta["exposure_from"], "--exposure");
    // The linear outputs do not depend on it.
    let npy = |d: &Path| std::fs::read(d.join("beauty.npy")).unwrap();
    assert_eq!(npy(&dim), npy(&bright));
    // compare tone-maps with the reference's exposure, or with its own --exposure.
    let cmp = d.join("cmp");
    let compare = |extra: &[&str]| {
        compare_succeeds(&compare_args(&bright, &[&dim], &cmp, extra));
        json(&cmp.join("report.json"))["exposure"].as_f64()
    };
    assert_eq!(compare(&[]), Some(20.0));
    let pixels = |p: &Path| image::open(p).unwrap().to_rgb8().into_raw();
    assert_eq!(
        pixels(&cmp.join("reference.png")),
        pixels(&bright.join("beauty.png"))
    );
    assert_eq!(compare(&["--exposure", "3"]), Some(3.0));
    let out = d.join("refused");
    let args = [
        "render",
        "--scene",
        base.to_str().unwrap(),
        "--exposure",
        "0",
    ];
    refuses(
        &[&args[..], &["--out", out.to_str().unwrap()]].concat(),
        "positive",
        Some(&out),
    );
}
