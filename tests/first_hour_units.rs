//! A new user's slips of units and progress on long runs: each
//! slip that is out of range is refused at once with one line naming the fix and no file
//! written; each legal but implausible value renders with one `warning: ` line naming the
//! units; the progress callbacks report what the bars show.

mod common;

use common::cli::{files_in, nephele, refuses};
use nephele::mie::{MieJob, SizeRule};
use nephele::render::image::GROUP_FIRST;
use nephele::render::path::{render_reporting, Progress, Settings};
use nephele::render::scene::{Scene, SHIPPED_MAX_OPTICAL_SIZE};
use std::path::{Path, PathBuf};
use std::sync::Mutex;

/// `nephele mie ARGS --out DIR/out --no-plot` must be refused naming `fix`; returns the line.
fn mie_refuses(args: &[&str], fix: &str) -> String {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("out");
    let mut all = vec!["mie", "--out", out.to_str().unwrap(), "--no-plot"];
    all.extend(args);
    refuses(&all, fix, Some(&out))
}

#[test]
fn wavelengths_in_micrometres_are_refused_with_the_size_parameter_limit() {
    let err = mie_refuses(
        &["--wavelengths", "0.4:0.7:31", "--diameter", "15"],
        "wavelengths are in nm, not µm",
    );
    assert!(err.contains("size parameter x = 1.2e5"), "{err}");
    assert!(err.contains("limit 2e4"), "{err}");
}

#[test]
fn wavelengths_beyond_the_infrared_are_refused() {
    // x stays in range here (small droplets): the wavelength check alone must catch it.
    let err = mie_refuses(
        &["--wavelengths", "400:200000:3", "--diameter", "20"],
        "wavelengths are in nm",
    );
    assert!(err.contains("2e5 nm"), "{err}");
}

#[test]
fn diameter_in_metres_is_refused() {
    let err = mie_refuses(&["--diameter", "15e-6"], "diameters are in µm, not metres");
    assert!(err.contains("is 15 µm"), "{err}");
}

#[test]
fn diameter_in_nanometres_is_refused() {
    mie_refuses(&["--diameter", "15000"], "diameters are in µm, not nm");
}

#[test]
fn a_width_of_25_is_refused_with_its_range() {
    let err = mie_refuses(&["--sigma", "25"], "standard deviation of ln d");
    assert!(err.contains("(0, 1]"), "{err}");
}

#[test]
fn a_job_larger_than_memory_is_refused_before_it_allocates() {
    // 2.7e9 spheres: terabytes. Refused from the rule's node count, so it ends at once.
    mie_refuses(&["--diameter", "10", "--x-step", "1e-7"], "of memory");
}

#[test]
fn a_table_with_zeros_or_nan_is_never_accepted() {
    let job = MieJob::paper(5.0, SizeRule::Product { sizes: 5 }, 2);
    let (tables, _) = job.compute(&|_, _| {}).unwrap();
    tables[0].check_values().unwrap();
    let mut zeros = tables[0].clone();
    zeros.phase.iter_mut().for_each(|v| *v = 0.0);
    assert!(zeros.check_values().is_err());
    let mut nan = tables[0].clone();
    nan.phase_spectral[7] = f64::NAN;
    assert!(nan.check_values().is_err());
}

#[test]
fn mie_progress_runs_from_zero_to_the_whole_work() {
    let job = MieJob::paper(5.0, SizeRule::Product { sizes: 9 }, 2);
    let seen = Mutex::new(Vec::new());
    job.compute(&|done, total| seen.lock().unwrap().push((done, total)))
        .unwrap();
    let seen = seen.into_inner().unwrap();
    let total = seen[0].1;
    assert_eq!(seen[0].0, 0, "{seen:?}");
    assert_eq!(seen.last().unwrap().0, total, "{seen:?}");
    assert!(seen.windows(2).all(|w| w[0].0 <= w[1].0 && w[1].1 == total));
}

/// fit-configs/scenes/NAME.json with `edit` applied, written in `dir`; a Henyey–Greenstein
/// phase function keeps the render quick (no Mie table to compute).
fn scene_file(dir: &Path, name: &str, edit: impl Fn(&mut serde_json::Value)) -> PathBuf {
    let path =
        Path::new(env!("CARGO_MANIFEST_DIR")).join(format!("fit-configs/scenes/{name}.json"));
    let mut v: serde_json::Value = serde_json::from_slice(&std::fs::read(path).unwrap()).unwrap();
    v["phase"] = serde_json::json!({"kind": "hg", "g": 0.85});
    edit(&mut v);
    let file = dir.join(format!("{name}_edited.json"));
    std::fs::write(&file, v.to_string()).unwrap();
    file
}

/// Renders `scene` tiny with the path tracer; it must succeed, write its files, and print one
/// `warning: ` line that contains every one of `words`.
fn warns(scene: &Path, words: &[&str]) {
    let out = scene.with_extension("out");
    let o = nephele(&[
        "render",
        "--scene",
        scene.to_str().unwrap(),
        "--size",
        "16",
        "12",
        "--spp",
        "1",
        "--out",
        out.to_str().unwrap(),
    ]);
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(o.status.success(), "{err}");
    assert!(files_in(&out).iter().any(|f| f == "beauty.npy"));
    let lines: Vec<&str> = err.lines().filter(|l| l.starts_with("warning: ")).collect();
    assert_eq!(lines.len(), 1, "{err}");
    for w in words {
        assert!(lines[0].contains(w), "{:?} lacks {w:?}", lines[0]);
    }
}

#[test]
fn sigma_t_per_km_written_per_metre_warns_and_renders() {
    let dir = tempfile::tempdir().unwrap();
    let scene = scene_file(dir.path(), "cloud", |v| v["sigma_t"] = 50.0.into());
    warns(&scene, &["per metre", "/km", "sigma_t = 0.05"]);
}

#[test]
fn a_float64_voxel_grid_of_densities_far_above_one_warns_and_renders() {
    let dir = tempfile::tempdir().unwrap();
    let shipped = Path::new(env!("CARGO_MANIFEST_DIR")).join("fit-configs/scenes/voxel_cloud.npy");
    let shape = [48, 64, 64];
    let grid: Vec<f32> = nephele::io::npy::read_npy(&shipped, &shape).unwrap();
    let wide: Vec<f64> = grid.iter().map(|&v| v as f64 * 1000.0).collect();
    let npy = nephele::io::npy::npy_bytes(&shape, &wide).unwrap();
    std::fs::write(dir.path().join("dense.npy"), npy).unwrap();
    let scene = scene_file(dir.path(), "voxels", |v| {
        v["medium"]["npy"] = "dense.npy".into()
    });
    warns(&scene, &["thickest column", "densities far above 1"]);
    let json = std::fs::read(scene.with_extension("out").join("render.json")).unwrap();
    let meta: serde_json::Value = serde_json::from_slice(&json).unwrap();
    let said = meta["warnings"][0].as_str().unwrap_or("");
    assert!(said.contains("thickest column"), "{meta:?}");
}

#[test]
fn a_sun_below_the_horizon_warns_and_renders() {
    let dir = tempfile::tempdir().unwrap();
    let scene = scene_file(dir.path(), "cloud", |v| {
        let z = v["sun"]["direction"][2].as_f64().unwrap();
        v["sun"]["direction"][2] = (-z).into();
    });
    warns(&scene, &["below the horizon", "z is up"]);
}

#[test]
fn no_shipped_scene_warns() {
    let dir = Path::new(env!("CARGO_MANIFEST_DIR")).join("fit-configs/scenes");
    let (mut n, mut largest) = (0, 0.0f64);
    for e in std::fs::read_dir(dir).unwrap() {
        let path = e.unwrap().path();
        if path.extension().is_some_and(|x| x == "json") {
            let scene = Scene::load(&path).unwrap();
            let w = scene.warnings();
            assert!(w.is_empty(), "{}: {w:?}", path.display());
            largest = largest.max(scene.optical_size());
            n += 1;
        }
    }
    assert!(n >= 10, "only {n} scenes");
    // The warning quotes the shipped scenes' largest optical size: it must be the true one.
    assert!(
        (largest - SHIPPED_MAX_OPTICAL_SIZE).abs() < 1e-9,
        "{largest}"
    );
}

/// √⟨(A − B)²/4⟩ / ⟨(A + B)/2⟩ of the scattered light from a render's halves
/// [2, group, h, w, 3].
fn noise_of_halves(halves: &[f32], pixels: usize) -> f64 {
    let ng = GROUP_FIRST.len();
    let half = |k: usize, px: usize, c: usize| -> f64 {
        (0..ng)
            .map(|g| halves[((k * ng + g) * pixels + px) * 3 + c] as f64)
            .sum()
    };
    let (mut var, mut mean) = (0.0, 0.0);
    for px in 0..pixels {
        for c in 0..3 {
            let (a, b) = (half(0, px, c), half(1, px, c));
            var += 0.25 * (a - b) * (a - b);
            mean += 0.5 * (a + b);
        }
    }
    let n = (3 * pixels) as f64;
    (var / n).sqrt() / (mean / n)
}

#[test]
fn a_time_budget_reports_passes_spp_and_the_noise_of_the_halves() {
    let dir = tempfile::tempdir().unwrap();
    let file = scene_file(dir.path(), "cloud", |v| {
        v["camera"]["width"] = 12.into();
        v["camera"]["height"] = 9.into();
        v["spp"] = 2.into();
        v["time_budget_s"] = 0.3.into();
    });
    let (scene, settings) = (Scene::load(&file).unwrap(), Settings::load(&file).unwrap());
    let seen: Mutex<Vec<Progress>> = Mutex::new(Vec::new());
    let r = render_reporting(&scene, &settings, &|p| seen.lock().unwrap().push(*p)).unwrap();
    let last = *seen.lock().unwrap().last().unwrap();
    assert!(r.spp >= 4, "too few passes to test: {}", r.spp);
    // Passes of 2 samples (the settings' spp): the one the budget cuts leaves rows 2 apart.
    let n = &r.details["samples_per_pixel"];
    let (lo, hi) = (n["min"].as_u64().unwrap(), n["max"].as_u64().unwrap());
    assert_eq!((lo, last.spp as u64), (r.spp as u64, lo));
    assert!(hi == lo || hi == lo + 2, "{n}");
    assert_eq!(hi, 2 * last.passes as u64, "{n}");
    let expected = noise_of_halves(&r.halves, r.width * r.height);
    let noise = last.noise.expect("a noise estimate after two passes");
    assert!(
        (noise / expected - 1.0).abs() < 1e-4,
        "{noise} vs {expected}"
    );
    assert!(last.summary().contains(&format!("{} spp", r.spp)));
}
