//! The files around a run: an output folder that cannot be written fails before any work, a
//! render's folder holds that render's files alone, two renders do not write one folder at
//! once, and a reader that closes stdout early does not crash a command.

mod common;

use common::cli::{files_in, refuses, succeeds};
use std::path::Path;
use std::process::{Command, Stdio};

fn scene(name: &str) -> String {
    let p = Path::new(env!("CARGO_MANIFEST_DIR")).join("fit-configs/scenes");
    p.join(name).to_string_lossy().into_owned()
}

fn s(p: &Path) -> String {
    p.to_string_lossy().into_owned()
}

/// A small render of the default cloud into `out` by `method`.
fn render(out: &Path, method: &str) {
    let (scene, out) = (scene("cloud.json"), s(out));
    let mut args = vec![
        "render", "--scene", &scene, "--out", &out, "--size", "16", "12",
    ];
    args.extend(["--method", method]);
    if method == "path-tracer" {
        args.extend(["--spp", "2"]);
    }
    succeeds(&args);
}

#[test]
fn an_out_that_is_a_file_or_under_one_fails_before_any_work() {
    let dir = tempfile::tempdir().unwrap();
    let file = dir.path().join("afile");
    std::fs::write(&file, b"mine").unwrap();
    let mie = ["mie", "--diameter", "10", "--out", &s(&file)];
    let err = refuses(&mie, "is a file; give a folder", None);
    assert!(err.contains(&s(&file)), "{err}");
    let under = file.join("sub");
    let (scene, under_s) = (scene("cloud.json"), s(&under));
    let args = [
        "render", "--scene", &scene, "--out", &under_s, "--size", "16", "12",
    ];
    let err = refuses(&args, "choose another --out", None);
    assert!(err.contains(&under_s), "{err}");
    assert_eq!(std::fs::read(&file).unwrap(), b"mine");
    assert_eq!(files_in(dir.path()), ["afile"]);
}

#[test]
fn transport_points_create_the_folder_of_their_out() {
    let dir = tempfile::tempdir().unwrap();
    let points = dir.path().join("p.npy");
    let row = [8.0f32, 0.5, 2.0, -0.6, 20.0];
    let bytes = nephele::io::npy::npy_bytes(&[1, 5], &row).unwrap();
    std::fs::write(&points, bytes).unwrap();
    let out = dir.path().join("new/deeper/x.npy");
    succeeds(&["transport", "--points", &s(&points), "--out", &s(&out)]);
    assert!(out.exists());
}

#[test]
fn a_render_folder_holds_one_render_and_compare_sees_it() {
    let dir = tempfile::tempdir().unwrap();
    let mixed = dir.path().join("mixed");
    render(&mixed, "path-tracer");
    assert!(mixed.join("halves.npy").exists());
    render(&mixed, "collector");
    assert!(!mixed.join("halves.npy").exists(), "{:?}", files_in(&mixed));
    assert!(mixed.join("regions.npy").exists());
    let cmp = dir.path().join("cmp");
    let (m, c) = (s(&mixed), s(&cmp));
    let args = ["compare", "--reference", &m, "--candidate", &m, "--out", &c];
    refuses(&args, "the reference must be a path-traced render", None);
    // Back to the path tracer: the collector's regions.npy goes.
    render(&mixed, "path-tracer");
    assert!(!mixed.join("regions.npy").exists());
}

#[test]
fn a_folder_another_running_nephele_writes_is_refused_and_a_dead_claim_taken_over() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("busy");
    std::fs::create_dir(&out).unwrap();
    let lock = out.join(".nephele.lock");
    // This test's own process runs, and is not the render's.
    std::fs::write(&lock, std::process::id().to_string()).unwrap();
    let (scene, out_s) = (scene("cloud.json"), s(&out));
    let args = [
        "render", "--scene", &scene, "--out", &out_s, "--size", "16", "12",
    ];
    let err = refuses(&args, "is being written by another nephele", None);
    assert!(
        err.contains(&format!("process {}", std::process::id())),
        "{err}"
    );
    assert_eq!(files_in(&out), [".nephele.lock"]);
    // A claim whose process is gone (pid above Linux's maximum) is taken over, then released.
    std::fs::write(&lock, "4294967295").unwrap();
    render(&out, "collector");
    assert!(!lock.exists());
    assert!(out.join("render.json").exists());
}

#[test]
fn a_closed_stdout_ends_the_report_not_the_command() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("r");
    let (scene, out_s) = (scene("cloud.json"), s(&out));
    for args in [
        vec![
            "transport",
            "--t",
            "8",
            "--mu-l",
            "0.5",
            "--depth",
            "2",
            "--mu-v",
            "-0.6",
            "--psi-deg",
            "20",
        ],
        vec![
            "render", "--scene", &scene, "--out", &out_s, "--size", "16", "12", "--spp", "2",
        ],
    ] {
        let mut child = Command::new(env!("CARGO_BIN_EXE_nephele"))
            .args(&args)
            .stdout(Stdio::piped())
            .stderr(Stdio::piped())
            .spawn()
            .unwrap();
        drop(child.stdout.take()); // `| head -0`: the reader is gone before the first line
        let o = child.wait_with_output().unwrap();
        let err = String::from_utf8_lossy(&o.stderr);
        assert!(o.status.success(), "{args:?}: {:?} {err}", o.status);
        assert!(!err.contains("panicked"), "{args:?}: {err}");
    }
    assert!(out.join("render.json").exists());
}

#[test]
fn a_frame_larger_than_memory_is_refused_before_it_allocates() {
    let need = nephele::render::image::frame_bytes(16384, 16384, true);
    let available = nephele::io::available_memory().unwrap_or(0.0);
    assert!(available > 0.0, "no MemAvailable in /proc/meminfo");
    if available >= need {
        eprintln!("skipped: {available} bytes available, the frame needs {need}");
        return;
    }
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("big");
    let (scene, out_s) = (scene("cloud.json"), s(&out));
    let args = [
        "render", "--scene", &scene, "--out", &out_s, "--size", "16384", "16384",
    ];
    let err = refuses(&args, "render a smaller --size", None);
    assert!(err.contains("16384 × 16384 frame needs about"), "{err}");
    assert!(!out.exists());
}

#[test]
fn a_view_without_the_cloud_warns_and_compare_refuses_it() {
    let dir = tempfile::tempdir().unwrap();
    let path = Path::new(env!("CARGO_MANIFEST_DIR")).join("fit-configs/scenes/cloud.json");
    let mut v: serde_json::Value = serde_json::from_slice(&std::fs::read(path).unwrap()).unwrap();
    // Look from the cloud's position away from it, into a black sky.
    let eye = v["camera"]["position"].clone();
    let ahead: Vec<f64> = (0..3)
        .map(|k| 2.0 * eye[k].as_f64().unwrap() - v["camera"]["look_at"][k].as_f64().unwrap())
        .collect();
    v["camera"]["look_at"] = serde_json::json!(ahead);
    v["sky"] = serde_json::json!([0.0, 0.0, 0.0]);
    let scene = dir.path().join("away.json");
    std::fs::write(&scene, v.to_string()).unwrap();
    let out = dir.path().join("away");
    let (sc, o) = (s(&scene), s(&out));
    let args = [
        "render", "--scene", &sc, "--out", &o, "--size", "16", "12", "--spp", "2",
    ];
    let run = succeeds(&args);
    let err = String::from_utf8_lossy(&run.stderr);
    assert!(
        err.contains("warning: no pixel of the frame is opaque"),
        "{err}"
    );
    let meta: serde_json::Value =
        serde_json::from_slice(&std::fs::read(out.join("render.json")).unwrap()).unwrap();
    assert_eq!(meta["exposure"], 1.0, "{}", meta["exposure"]);
    assert_eq!(meta["exposure_from"], "black frame");
    assert!(meta["warnings"][0].as_str().unwrap().contains("no pixel"));
    let cmp = dir.path().join("cmp");
    let c = s(&cmp);
    let args = ["compare", "--reference", &o, "--candidate", &o, "--out", &c];
    refuses(&args, "its camera sees no cloud", None);
}

#[test]
fn ctrl_c_on_a_budgeted_render_writes_the_samples_finished_and_says_so() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("stopped");
    let (scene, out_s) = (scene("cloud.json"), s(&out));
    let args = [
        "render", "--scene", &scene, "--out", &out_s, "--size", "24", "18",
    ];
    let child = Command::new(env!("CARGO_BIN_EXE_nephele"))
        .args(args)
        .args(["--time-budget", "600"])
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .spawn()
        .unwrap();
    // Once the first pass has a result to write (its progress names a pass), Ctrl-C.
    std::thread::sleep(std::time::Duration::from_secs(3));
    unsafe { libc::kill(child.id() as libc::pid_t, libc::SIGINT) };
    let o = child.wait_with_output().unwrap();
    let err = String::from_utf8_lossy(&o.stderr);
    assert_eq!(o.status.code(), Some(130), "{err}");
    assert!(err.contains("interrupted (Ctrl-C) after"), "{err}");
    assert!(err.contains(&format!("written to '{out_s}'")), "{err}");
    let meta: serde_json::Value =
        serde_json::from_slice(&std::fs::read(out.join("render.json")).unwrap()).unwrap();
    assert_eq!(meta["details"]["interrupted"], true);
    assert!(meta["spp"].as_u64().unwrap() >= 2, "{}", meta["details"]);
    assert!(!out.join(".nephele.lock").exists());
}

#[test]
fn another_droplet_size_is_refused_naming_both_phase_functions_and_the_tolerance() {
    let dir = tempfile::tempdir().unwrap();
    let path = Path::new(env!("CARGO_MANIFEST_DIR")).join("fit-configs/scenes/cloud.json");
    let mut v: serde_json::Value = serde_json::from_slice(&std::fs::read(path).unwrap()).unwrap();
    v["phase"] = serde_json::json!({"kind": "hg_draine", "diameter_um": 30});
    let scene = dir.path().join("d30.json");
    std::fs::write(&scene, v.to_string()).unwrap();
    let out = dir.path().join("d30");
    let (sc, o) = (s(&scene), s(&out));
    let args = [
        "render",
        "--scene",
        &sc,
        "--out",
        &o,
        "--method",
        "collector",
    ];
    let err = refuses(
        &args,
        "beyond the 5 % at every angle the tables accept",
        None,
    );
    assert!(err.contains("hg_draine, d = 30 µm"), "{err}");
    assert!(err.contains("the tables' (mie, d = 10 µm"), "{err}");
    assert!(!out.exists(), "a folder left by a refused render");
}

/// Mie droplets 30 µm across against the 10 µm tables: refused at once, naming both diameters,
/// before the scene's own Mie table is computed (the Mie cache stays empty).
#[test]
fn mie_droplets_of_another_size_are_refused_before_mie_runs() {
    let dir = tempfile::tempdir().unwrap();
    let path = Path::new(env!("CARGO_MANIFEST_DIR")).join("fit-configs/scenes/cloud.json");
    let mut v: serde_json::Value = serde_json::from_slice(&std::fs::read(path).unwrap()).unwrap();
    v["phase"] = serde_json::json!({"kind": "mie", "diameter_um": 30});
    let scene = dir.path().join("mie30.json");
    std::fs::write(&scene, v.to_string()).unwrap();
    let cache = dir.path().join("cache");
    let o = std::process::Command::new(env!("CARGO_BIN_EXE_nephele"))
        .args(["render", "--method", "collector", "--scene"])
        .arg(&scene)
        .arg("--out")
        .arg(dir.path().join("out"))
        .env("NEPHELE_CACHE_DIR", &cache)
        .output()
        .unwrap();
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(!o.status.success(), "{err}");
    assert!(
        err.contains("droplets are 30 µm across, the tables' 10 µm")
            && err.contains("nephele tables --diameter 30"),
        "{err}"
    );
    let cached = std::fs::read_dir(&cache).map_or(0, |d| d.count());
    assert_eq!(cached, 0, "Mie ran before the refusal");
}

#[test]
fn tables_refuses_a_diameter_out_of_range_before_any_work() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("t");
    let o = s(&out);
    refuses(
        &["tables", "--diameter", "-20", "--out", &o],
        "-20 is not > 0",
        None,
    );
    let err = refuses(
        &["tables", "--diameter", "20000", "--out", &o],
        "--diameter 20000",
        None,
    );
    assert!(err.contains("must be in (0, 10000]"), "{err}");
    assert!(!out.exists());
}

/// A folder the user may not write into is refused before any work, naming it and the fix, and
/// nothing is left there. Root writes anywhere, so as root nephele runs as `nobody` (setpriv).
#[test]
fn a_read_only_output_folder_is_refused_before_any_work() {
    use std::os::unix::fs::PermissionsExt;
    let dir = tempfile::tempdir().unwrap();
    let mode = |p: &Path, m| std::fs::set_permissions(p, std::fs::Permissions::from_mode(m));
    mode(dir.path(), 0o755).unwrap();
    let path = Path::new(env!("CARGO_MANIFEST_DIR")).join("fit-configs/scenes/cloud.json");
    let mut v: serde_json::Value = serde_json::from_slice(&std::fs::read(path).unwrap()).unwrap();
    v["phase"] = serde_json::json!({"kind": "hg", "g": 0.85});
    let scene = dir.path().join("hg.json");
    std::fs::write(&scene, v.to_string()).unwrap();
    mode(&scene, 0o644).unwrap();
    let ro = dir.path().join("ro");
    std::fs::create_dir(&ro).unwrap();
    mode(&ro, 0o555).unwrap();
    let root = Command::new("id").arg("-u").output().unwrap().stdout == b"0\n";
    let nephele = || {
        let mut c = Command::new(if root {
            "setpriv"
        } else {
            env!("CARGO_BIN_EXE_nephele")
        });
        if root {
            c.args(["--reuid=65534", "--regid=65534", "--clear-groups"]);
            c.arg(env!("CARGO_BIN_EXE_nephele"));
        }
        c
    };
    for out in [ro.clone(), ro.join("out")] {
        let o = nephele()
            .args([
                "render",
                "--spp",
                "1",
                "--scene",
                &s(&scene),
                "--out",
                &s(&out),
            ])
            .env("NEPHELE_CACHE_DIR", "off")
            .output()
            .unwrap();
        let err = String::from_utf8_lossy(&o.stderr);
        assert!(!o.status.success(), "{err}");
        assert!(
            err.contains(&format!("'{}'", out.display())) && err.contains("choose another --out"),
            "{err}"
        );
    }
    assert!(files_in(&ro).is_empty(), "{:?}", files_in(&ro));
}
