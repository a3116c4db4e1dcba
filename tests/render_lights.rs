//! Point and spot lights in the path tracer (docs/render.md, "Lights"): single scattering of a
//! light in a homogeneous slab of fog, seen along one camera ray, against the integral along
//! that ray computed here by quadrature — independently of the renderer's code:
//!
//!   L₁ = ∫ σ_s e^{−σ t} p(ω · w) e^{−σ r} I(−ω) / r² dt,
//!
//! t along the camera ray w, ω the unit vector toward the light at distance r.

use nephele::render::path::{render, Settings};
use nephele::render::scene::Scene;
use nephele::stats::adaptive_simpson;
use std::f64::consts::PI;

const SIGMA: f64 = 0.01;
const G: f64 = 0.5;
const CAMERA: [f64; 3] = [0.0, -300.0, 50.0];
const LIGHT: [f64; 3] = [0.0, -150.0, 45.0];

fn scene(light: &str) -> Scene {
    parse(light).expect("a valid scene")
}

/// The test's fog scene with `lights` (the JSON inside the list).
fn parse(lights: &str) -> anyhow::Result<Scene> {
    Scene::parse(&format!(
        r#"{{
        "medium": {{"kind": "slab", "thickness": 100}},
        "sigma_t": {SIGMA}, "albedo": 1, "phase": {{"kind": "hg", "g": {G}}},
        "sun": {{"direction": [0, 0, 1], "irradiance": [0, 0, 0]}},
        "lights": [{lights}],
        "camera": {{"position": {CAMERA:?}, "look_at": [0, 0, 0], "fov_deg": 0.01,
                    "width": 8, "height": 8}}
    }}"#
    ))
}

/// L₁ along the camera ray (the image's centre; its 8 × 8 pixels span 0.01°, a few mm where
/// the ray passes the light, so they all see it) from a light whose intensity toward x is
/// `intensity(x)`.
fn single_scattering(intensity: &dyn Fn([f64; 3]) -> f64) -> f64 {
    let d: Vec<f64> = (0..3).map(|k| -CAMERA[k]).collect();
    let len = (d[0] * d[0] + d[1] * d[1] + d[2] * d[2]).sqrt();
    let w: Vec<f64> = d.iter().map(|v| v / len).collect();
    let exit = -CAMERA[2] / w[2]; // the slab's floor, z = 0
    let hg = |mu: f64| (1.0 - G * G) / (4.0 * PI * (1.0 + G * G - 2.0 * G * mu).powf(1.5));
    let f = |t: f64| {
        let x = [
            CAMERA[0] + t * w[0],
            CAMERA[1] + t * w[1],
            CAMERA[2] + t * w[2],
        ];
        let to: Vec<f64> = (0..3).map(|k| LIGHT[k] - x[k]).collect();
        let r = (to[0] * to[0] + to[1] * to[1] + to[2] * to[2]).sqrt();
        let mu = (to[0] * w[0] + to[1] * w[1] + to[2] * w[2]) / r;
        SIGMA * (-SIGMA * t).exp() * hg(mu) * (-SIGMA * r).exp() * intensity(x) / (r * r)
    };
    adaptive_simpson(&f, 0.0, exit, 1e-12)
}

/// Order 1 (channel 0) over the 64 pixels, and its standard error from their spread (the
/// pixels are independent estimates of one ray's light).
fn rendered_order1(s: &Scene) -> (f64, f64) {
    let settings = Settings {
        spp: 4000,
        seed: 7,
        sun_lobe_steps: 0,
        ..Settings::default()
    };
    let r = render(s, &settings, &|_| {}).expect("render");
    let n = 64;
    let v: Vec<f64> = (0..n).map(|px| r.groups[px * 3] as f64).collect();
    let mean = v.iter().sum::<f64>() / n as f64;
    let var = v.iter().map(|x| (x - mean).powi(2)).sum::<f64>() / (n - 1) as f64;
    (mean, (var / n as f64).sqrt())
}

#[test]
fn a_point_light_scatters_once_as_the_integral_along_the_ray_says() {
    let s =
        scene(r#"{"kind": "point", "position": [0, -150, 45], "intensity": [1000, 1000, 1000]}"#);
    let (got, se) = rendered_order1(&s);
    let want = single_scattering(&|_| 1000.0);
    eprintln!("point light: order 1 {got:.6e} ± {se:.1e}, quadrature {want:.6e}");
    assert!(
        want > 0.0 && se < 0.02 * want,
        "too noisy: {se} against {want}"
    );
    assert!(
        (got - want).abs() < 4.0 * se + 1e-3 * want,
        "{got} vs {want} ± {se}"
    );
}

#[test]
fn a_spot_light_lights_only_its_cone_with_mitsubas_falloff() {
    // Pointing down from 5 m above the ray's closest point: the cone (30°, full to 10°)
    // covers only the part of the ray beneath it.
    let s = scene(
        r#"{"kind": "spot", "position": [0, -150, 45], "direction": [0, 0, -2],
            "intensity": [1000, 1000, 1000], "cutoff_deg": 30, "beam_width_deg": 10}"#,
    );
    let (got, se) = rendered_order1(&s);
    let falloff = |x: [f64; 3]| {
        let d = [x[0] - LIGHT[0], x[1] - LIGHT[1], x[2] - LIGHT[2]];
        let theta = (-d[2] / (d[0] * d[0] + d[1] * d[1] + d[2] * d[2]).sqrt()).acos();
        let (cut, beam) = (30f64.to_radians(), 10f64.to_radians());
        1000.0 * ((cut - theta) / (cut - beam)).clamp(0.0, 1.0)
    };
    let want = single_scattering(&falloff);
    let point = single_scattering(&|_| 1000.0);
    eprintln!(
        "spot light: order 1 {got:.6e} ± {se:.1e}, quadrature {want:.6e} (point {point:.3e})"
    );
    assert!(
        want < 0.8 * point,
        "the cone should cut the ray: {want} vs {point}"
    );
    assert!(
        (got - want).abs() < 4.0 * se + 1e-3 * want,
        "{got} vs {want} ± {se}"
    );
}

#[test]
fn a_bad_light_is_refused_with_its_name() {
    let e = parse(
        r#"{"kind": "point", "position": [0, 0, 1], "intensity": [1, 1, 1]},
           {"kind": "spot", "position": [0, 0, 1], "direction": [0, 0, -1],
            "intensity": [1, 1, 1], "cutoff_deg": 20, "beam_width_deg": 25}"#,
    )
    .unwrap_err();
    assert!(
        format!("{e:#}").contains("lights[1].beam_width_deg"),
        "{e:#}"
    );
    let e = parse(r#"{"kind": "point", "position": [0, 0, 1], "power": [1, 1, 1]}"#).unwrap_err();
    assert!(format!("{e:#}").contains("power"), "{e:#}");
}
