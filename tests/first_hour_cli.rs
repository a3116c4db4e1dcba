//! A new user's slips on the command line: negative numbers reach their range check,
//! flags a command does not take are refused, and each refusal is one line that names the fix,
//! with no file written.

mod common;

use common::cli::{nephele, refuses, succeeds};
use std::path::Path;

fn scene(name: &str) -> String {
    Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("fit-configs/scenes")
        .join(name)
        .to_string_lossy()
        .into_owned()
}

/// `nephele render --scene cloud.json --out OUT` followed by `extra`, refused with `fix`.
fn render_refuses(extra: &[&str], fix: &str) {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("out");
    let (scene, out_s) = (scene("cloud.json"), out.to_string_lossy().into_owned());
    let mut args = vec!["render", "--scene", &scene, "--out", &out_s];
    args.extend_from_slice(extra);
    refuses(&args, fix, Some(&out));
}

#[test]
fn negative_numbers_are_parsed_then_refused_with_their_range() {
    render_refuses(&["--size", "-96", "72"], "-96 is not in 1..=16384");
    render_refuses(&["--time-budget", "-5"], "-5 is not > 0");
    render_refuses(&["--spp", "0"], "0 is not in 1..=1000000");
    render_refuses(&["--sun-lobe-steps", "40"], "40 is not in 0..=32");
    let t = [
        "transport",
        "--t",
        "4",
        "--depth",
        "1",
        "--mu-v",
        "0.5",
        "--psi-deg",
        "0",
    ];
    let mut args = t.to_vec();
    args.extend(["--mu-l", "-0.5"]);
    refuses(
        &args,
        "--mu-l: mu_L = -0.5 is not a sun cosine in (0, 1]",
        None,
    );
}

#[test]
fn flags_of_another_method_are_refused() {
    render_refuses(
        &["--method", "collector", "--spp", "64", "--time-budget", "5"],
        "--spp, --time-budget do not apply to --method collector (path-tracer only)",
    );
    render_refuses(
        &["--octaves", "4", "0.5", "0.5", "0.5"],
        "--octaves does not apply to --method path-tracer (octaves only)",
    );
    render_refuses(
        &["--map-resolution", "128"],
        "--map-resolution does not apply to --method path-tracer",
    );
    render_refuses(
        &["--method", "single", "--iterations", "4"],
        "--iterations does not apply to --method single (collector only)",
    );
    render_refuses(
        &[
            "--method",
            "collector",
            "--correction",
            "none",
            "--leakage-scale",
            "2",
        ],
        "--leakage-scale does not apply without the leakage correction",
    );
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("out");
    refuses(
        &[
            "compress",
            "--tables",
            "none.npz",
            "--out",
            out.to_str().unwrap(),
            "--collector-smooth-t",
            "0",
            "--collector-legendre",
            "4",
        ],
        "--collector-legendre does not apply with --collector-smooth-t 0",
        Some(&out),
    );
}

#[test]
fn a_parse_error_is_one_line_and_help_still_prints() {
    render_refuses(&["--sizes", "9"], "unexpected argument '--sizes'");
    let help = nephele(&["render", "--help"]);
    assert!(help.status.success());
    assert!(String::from_utf8_lossy(&help.stdout).contains("--method"));
}

#[test]
fn transport_uses_the_embedded_tables_like_render() {
    let o = succeeds(&[
        "transport",
        "--t",
        "4",
        "--mu-l",
        "0.8",
        "--depth",
        "1",
        "--mu-v",
        "0.5",
        "--psi-deg",
        "0",
    ]);
    let json: serde_json::Value = serde_json::from_slice(&o.stdout).unwrap();
    let t2 = json["groups"][0]["T"].as_f64().unwrap();
    assert!(t2 > 0.0 && t2.is_finite(), "T of orders 2: {t2}");
}

#[test]
fn a_phase_table_that_is_not_an_npz_says_so() {
    let dir = tempfile::tempdir().unwrap();
    let json = dir.path().join("phase.json");
    std::fs::write(&json, "{}").unwrap();
    let out = dir.path().join("out");
    refuses(
        &[
            "phase",
            "--model",
            "tabulated",
            "--table",
            json.to_str().unwrap(),
            "--out",
            out.to_str().unwrap(),
        ],
        "is not an .npz archive",
        Some(&out),
    );
}

#[test]
fn mie_and_phase_refuse_what_they_would_ignore() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("out");
    let o = out.to_str().unwrap();
    let mie = |extra: &[&str], fix: &str| {
        let mut args = vec!["mie", "--out", o];
        args.extend_from_slice(extra);
        refuses(&args, fix, Some(&out));
    };
    mie(
        &["--distribution", "mono", "--sigma", "0.3"],
        "--sigma (sigma) applies to the log-normal distribution only",
    );
    mie(
        &["--distribution", "gamma:6:1", "--sigma", "0.3"],
        "applies to the log-normal distribution only, not to 'gamma:6:1'",
    );
    mie(
        &["--sizes", "9", "--x-step", "0.02"],
        "--x-step sets the converged size rule, which --sizes does not use",
    );
    mie(
        &["--distribution", "mono", "--sizes", "9"],
        "which a mono distribution (one size) does not use",
    );
    refuses(
        &[
            "phase", "--model", "hg", "--g", "0.5", "--seed", "3", "--out", o,
        ],
        "--seed applies to --samples",
        Some(&out),
    );
}

#[test]
fn a_bad_blob_names_the_key_the_scene_uses() {
    let dir = tempfile::tempdir().unwrap();
    let text = std::fs::read_to_string(scene("cloud.json")).unwrap();
    let bad = text.replacen(
        "\"radii\": [500, 450, 380]",
        "\"radii\": [500, -450, 380]",
        1,
    );
    assert_ne!(bad, text, "cloud.json changed: update this test");
    let path = dir.path().join("bad.json");
    std::fs::write(&path, bad).unwrap();
    let out = dir.path().join("out");
    refuses(
        &[
            "render",
            "--scene",
            path.to_str().unwrap(),
            "--out",
            out.to_str().unwrap(),
        ],
        "medium.blobs[0].radii must be three positive numbers (m)",
        Some(&out),
    );
}
