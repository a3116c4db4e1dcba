//! `nephele render --orbit N`: several views from one set of light maps. Each view is exactly
//! the frame a render of that camera alone gives (the maps depend on the cloud and the sun, not
//! the camera), the views turn about the look-at point's vertical, and views.json tells the
//! maps' seconds once and which views reused them.

mod common;
use common::cli::{refuses, succeeds};
use common::npy_f32;

#[test]
fn orbit_views_are_the_single_renders_of_their_cameras() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("orbit");
    let out_s = out.to_str().unwrap();
    let scene = "fit-configs/scenes/cloud.json";
    let common = [
        "--method",
        "collector",
        "--size",
        "40",
        "30",
        "--map-resolution",
        "64",
    ];
    let mut args = vec!["render", "--scene", scene, "--out", out_s, "--orbit", "3"];
    args.extend(common);
    succeeds(&args);
    let doc: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(out.join("views.json")).unwrap()).unwrap();
    let views = doc["views"].as_array().unwrap();
    assert_eq!(views.len(), 3);
    assert_eq!(views[0]["maps_reused"], false);
    assert_eq!(views[2]["maps_reused"], true);
    assert!(doc["seconds"]["light_maps_once"].as_f64().unwrap() > 0.0);
    // View 1 is the camera turned by 120° about the vertical through its look-at point.
    let (p0, p1) = (
        &views[0]["camera"]["position"],
        &views[1]["camera"]["position"],
    );
    let at = &views[0]["camera"]["look_at"];
    let f = |v: &serde_json::Value, i: usize| v[i].as_f64().unwrap();
    let r = |p: &serde_json::Value| (f(p, 0) - f(at, 0)).hypot(f(p, 1) - f(at, 1));
    assert!((r(p0) - r(p1)).abs() < 1e-6 * r(p0) && (f(p0, 2) - f(p1, 2)).abs() < 1e-9);
    let angle = |p: &serde_json::Value| (f(p, 1) - f(at, 1)).atan2(f(p, 0) - f(at, 0));
    let turn = (angle(p1) - angle(p0)).rem_euclid(std::f64::consts::TAU);
    assert!((turn - std::f64::consts::TAU / 3.0).abs() < 1e-9, "{turn}");
    // View 1 rendered alone, from its own maps: the same pixels, bit for bit.
    let alone = dir.path().join("alone");
    let scene_1 = dir.path().join("view1.json");
    let mut s: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(scene).unwrap()).unwrap();
    s["camera"]["position"] = p1.clone();
    std::fs::write(&scene_1, s.to_string()).unwrap();
    let mut args = vec!["render", "--scene", scene_1.to_str().unwrap()];
    args.extend(["--out", alone.to_str().unwrap()]);
    args.extend(common);
    succeeds(&args);
    let a = npy_f32(&out.join("view_001/groups.npy"));
    let b = npy_f32(&alone.join("groups.npy"));
    assert!(a == b, "view 1 differs from its camera rendered alone");
    assert!(a.iter().any(|&v| v > 0.0));
}

#[test]
fn the_path_tracer_takes_no_orbit() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("o");
    let args = [
        "render",
        "--scene",
        "fit-configs/scenes/cloud.json",
        "--orbit",
        "2",
        "--out",
        out.to_str().unwrap(),
    ];
    refuses(&args, "--orbit", Some(&out));
}
