//! The halo around the transmitted beam (docs/compress.md, "The halo term") against the path
//! tracer run here: a slab of 8 mean free paths under a sun at μ_L = 0.75 (a node of the
//! shipped tables), seen from below looking into the sun. Within 6° of the beam the collector's
//! orders 2, 3–4 and 5–6 must be within 20 % (+ 3 SE) of the path tracer's with the shipped
//! tables (measured at 160 × 120: −4.9 %, −6.3 %, +3.8 %), and the same tables without their
//! halo (the form alone, without the halo: −90 %, −81 %, −51 %) must be below −45 %:
//! the bound can fail.

use nephele::render::fast::{render_fast, FastOptions};
use nephele::render::image::{Rendered, GROUP_FIRST};
use nephele::render::path::{render, Settings};
use nephele::render::scene::Scene;
use nephele_runtime::embedded::{mie_10um, MIE_10UM};
use nephele_runtime::transport::TransportTables;

const FOV_DEG: f64 = 14.0;
const WITHIN_DEG: f64 = 6.0;

fn scene() -> Scene {
    let (s, c) = ((1.0f64 - 0.75 * 0.75).sqrt(), 0.75);
    Scene::parse(&format!(
        r#"{{"medium": {{"kind": "slab", "thickness": 160}}, "sigma_t": 0.05,
            "phase": {{"kind": "mie", "diameter_um": 10}},
            "sun": {{"direction": [0, {}, {c}], "irradiance": [1, 1, 1]}},
            "camera": {{"position": [0, {}, -1500], "look_at": [0, 0, 0], "fov_deg": {FOV_DEG},
                        "width": 36, "height": 36}}}}"#,
        -s,
        1500.0 * s / c
    ))
    .unwrap()
}

/// Per group (channel 0), the sum over the pixels within [`WITHIN_DEG`] of the image centre
/// (the beam), and its standard error from the split-sample halves (0 for a fast render).
fn near_beam(r: &Rendered) -> Vec<(f64, f64)> {
    let (w, h, ng) = (r.width, r.height, GROUP_FIRST.len());
    let n = w * h;
    let focal = 0.5 * h as f64 / (0.5 * FOV_DEG.to_radians()).tan();
    let within = |px: usize| {
        let (x, y) = (
            (px % w) as f64 + 0.5 - 0.5 * w as f64,
            (px / w) as f64 + 0.5 - 0.5 * h as f64,
        );
        x.hypot(y).atan2(focal) < WITHIN_DEG.to_radians()
    };
    (0..ng)
        .map(|g| {
            let (mut sum, mut var) = (0.0, 0.0);
            for px in (0..n).filter(|&px| within(px)) {
                sum += r.groups[(g * n + px) * 3] as f64;
                if !r.halves.is_empty() {
                    let d = (r.halves[(g * n + px) * 3] - r.halves[((ng + g) * n + px) * 3]) as f64;
                    var += 0.25 * d * d;
                }
            }
            (sum, var.sqrt())
        })
        .collect()
}

#[test]
fn near_the_beam_the_halo_brings_the_low_orders_to_the_path_tracer() {
    let s = scene();
    let settings = Settings {
        spp: 1024,
        seed: 3,
        ..Settings::default()
    };
    let reference = near_beam(&render(&s, &settings, &|_| {}).unwrap());
    let opts = FastOptions {
        map_resolution: 64,
        ..FastOptions::default()
    };
    let bare = nephele::compress::ship::without_halo(MIE_10UM).unwrap();
    let shipped = near_beam(&render_fast(&s, &mie_10um(), &opts, &|_| {}).unwrap());
    let alone = TransportTables::from_bytes(&bare).unwrap();
    let alone = near_beam(&render_fast(&s, &alone, &opts, &|_| {}).unwrap());
    for (g, name) in [(1, "order 2"), (2, "orders 3-4"), (3, "orders 5-6")] {
        let (r, se) = reference[g];
        let (with, without) = (shipped[g].0 / r - 1.0, alone[g].0 / r - 1.0);
        eprintln!(
            "{name} within {WITHIN_DEG}° of the beam: with the halo {:+.1} %, the form alone {:+.1} % (reference SE {:.1} %)",
            100.0 * with,
            100.0 * without,
            100.0 * se / r
        );
        assert!(
            se / r < 0.05,
            "{name}: the reference is too noisy ({})",
            se / r
        );
        assert!(
            with.abs() < 0.2 + 3.0 * se / r,
            "{name}: with the halo {with}"
        );
        assert!(without < -0.45, "{name}: the form alone {without}");
    }
}
