//! Fog in a box with a height falloff, and a diffuse ground plane, in the path tracer
//! (docs/render.md, "Fog" and "Surfaces"), against closed forms computed here independently
//! of the renderer:
//!
//! - the transmittance of exponential fog along a ray, σ H e^{−(z₀ − z_b)/H} (1 − e^{−t w_z/H}) / w_z
//!   in the exponent, by ratio tracking and by delta tracking's escape probability;
//! - a Lambertian ground under the sun and under a point light, (ρ/π) cos θ E, attenuated by a
//!   purely absorbing fog on both legs;
//! - a rectangle and a sphere area light on the ground, by their form factors;
//! - the sun-lobe walks stay unbiased with surfaces: fog over a white ground rendered with and
//!   without them agrees per order group within the combined standard errors.

use nephele::render::image::Rendered;
use nephele::render::medium::{Fog, Medium};
use nephele::render::path::integrator::{collide, transmittance};
use nephele::render::path::{render, Settings};
use nephele::render::scene::Scene;
use rand::SeedableRng;
use std::f64::consts::PI;

const LO: [f64; 3] = [-500.0, -500.0, 0.0];
const HI: [f64; 3] = [500.0, 500.0, 300.0];

/// exp(−τ) of the fog σ e^{−(z − z_b)/H} from o along the unit w to the box's edge at t_exit.
fn exp_fog_transmittance(sigma: f64, h: f64, o: [f64; 3], w: [f64; 3], t_exit: f64) -> f64 {
    let tau = sigma * h * (-(o[2] - LO[2]) / h).exp() * (1.0 - (-t_exit * w[2] / h).exp()) / w[2];
    (-tau).exp()
}

#[test]
fn exponential_fog_transmits_as_its_closed_form() {
    let (sigma, h) = (0.02, 40.0);
    let fog = Fog::new(LO, HI, sigma, Some(h));
    let mut rng = rand_xoshiro::Xoshiro256PlusPlus::seed_from_u64(11);
    // Up, down and nearly level rays from inside the box, each to the box's edge.
    for (o, w) in [
        ([0.0, 0.0, 5.0], [0.3, 0.0, 0.9539]),
        ([10.0, -20.0, 250.0], [0.0, 0.6, -0.8]),
        ([0.0, 0.0, 60.0], [0.9998, 0.0, 0.02]),
    ] {
        let n: f64 = w[0] * w[0] + w[1] * w[1] + w[2] * w[2];
        let w = w.map(|x: f64| x / n.sqrt());
        let (_, t_exit) = fog.clip(o, w).expect("inside the box");
        let want = exp_fog_transmittance(sigma, h, o, w, t_exit);
        let runs = 40_000;
        let (mut sum, mut sum2, mut escaped) = (0.0, 0.0, 0usize);
        for _ in 0..runs {
            let tr = transmittance(&fog, o, w, &mut rng);
            sum += tr;
            sum2 += tr * tr;
            escaped += usize::from(collide(&fog, o, w, &mut rng).is_none());
        }
        let mean = sum / runs as f64;
        let se = ((sum2 / runs as f64 - mean * mean) / runs as f64).sqrt();
        let p = escaped as f64 / runs as f64;
        let se_p = (want * (1.0 - want) / runs as f64).sqrt();
        eprintln!(
            "w {w:?}: ratio tracking {mean:.5} ± {se:.1e}, escapes {p:.5}, closed form {want:.5}"
        );
        assert!(
            (mean - want).abs() < 4.0 * se + 1e-9,
            "{mean} vs {want} ± {se}"
        );
        assert!((p - want).abs() < 4.0 * se_p, "{p} vs {want} ± {se_p}");
        assert!(want > 0.05 && want < 0.95, "a test that could fail: {want}");
    }
}

/// A scene of fog (albedo `albedo`) over the ground, seen from above at 4 × 4 pixels spanning a
/// hundredth of a degree around `look_at`.
fn ground_scene(fog_sigma: f64, albedo: f64, extra: &str, look_at: [f64; 3]) -> Scene {
    Scene::parse(&format!(
        r#"{{
        "medium": {{"kind": "fog", "min": [-5000, -5000, 0], "max": [5000, 5000, 100]}},
        "sigma_t": {fog_sigma}, "albedo": {albedo}, "phase": {{"kind": "hg", "g": 0.6}},
        "sun": {{"direction": [0.6, 0, 0.8], "irradiance": [2, 1, 0.5]}},
        "surfaces": [{{"kind": "ground", "height": 0, "reflectance": [0.8, 0.5, 0.2]}}],
        "camera": {{"position": [-30, 20, 150], "look_at": {look_at:?}, "fov_deg": 0.01,
                    "width": 4, "height": 4}} {extra}
    }}"#
    ))
    .expect("a valid scene")
}

/// The path tracer at `spp` samples per pixel from `seed`, with `sun_lobe_steps`.
fn traced(spp: u32, seed: u64, sun_lobe_steps: usize) -> Settings {
    Settings {
        spp,
        seed,
        sun_lobe_steps,
        ..Settings::default()
    }
}

/// The image mean of group `g`, channel `c`, and its standard error from each pixel's two
/// halves of samples: SE² = Σ_px (A − B)²/4 / n².
fn group_mean(r: &Rendered, g: usize, c: usize) -> (f64, f64) {
    let n = r.width * r.height;
    let ng = r.groups.len() / (n * 3);
    let at = |half: usize, px: usize| r.halves[((half * ng + g) * n + px) * 3 + c] as f64;
    let mean = (0..n)
        .map(|px| r.groups[(g * n + px) * 3 + c] as f64)
        .sum::<f64>()
        / n as f64;
    let var: f64 = (0..n)
        .map(|px| 0.25 * (at(0, px) - at(1, px)).powi(2))
        .sum();
    (mean, var.sqrt() / n as f64)
}

/// Asserts `got` (mean, SE) matches `want` within 4 SE, with an SE below 0.5 % of it.
fn assert_matches(what: &str, (got, se): (f64, f64), want: f64) {
    eprintln!("{what}: {got:.6e} ± {se:.1e}, closed form {want:.6e}");
    assert!(se < 5e-3 * want, "{what}: too noisy, {se} against {want}");
    assert!(
        (got - want).abs() < 4.0 * se,
        "{what}: {got} vs {want} ± {se}"
    );
}

#[test]
fn a_diffuse_ground_reflects_the_sun_through_absorbing_fog() {
    // Albedo 0: nothing scatters; the fog only absorbs, on the way down and on the way up.
    let sigma = 0.004;
    let s = ground_scene(sigma, 0.0, "", [0.0, 0.0, 0.0]);
    let r = render(&s, &traced(4096, 3, 16), &|_| {}).expect("render");
    let cam = [-30.0f64, 20.0, 150.0];
    let r_cam = (cam[0] * cam[0] + cam[1] * cam[1] + cam[2] * cam[2]).sqrt();
    let (mu_sun, depth) = (0.8, 100.0);
    let attenuation = (-sigma * depth / mu_sun - sigma * depth * r_cam / cam[2]).exp();
    for (c, (e, rho)) in [(2.0, 0.8), (1.0, 0.5), (0.5, 0.2)].into_iter().enumerate() {
        let want = rho / PI * mu_sun * e * attenuation;
        assert_matches(&format!("sun, channel {c}"), group_mean(&r, 0, c), want);
    }
    // The ground is the path's first interaction, and nothing scatters after it.
    let n = r.width * r.height;
    assert!(r.groups[3 * n..].iter().all(|&v| v == 0.0));
}

#[test]
fn a_point_light_lights_the_ground_with_the_inverse_square_law() {
    let light = [10.0f64, -5.0, 40.0];
    let extra = format!(
        r#", "lights": [{{"kind": "point", "position": {light:?}, "intensity": [300, 300, 300]}}]"#
    );
    let sigma = 0.004;
    let mut s = ground_scene(sigma, 0.0, &extra, [0.0, 0.0, 0.0]);
    s.sun.irradiance = [0.0; 3];
    let r = render(&s, &traced(4096, 3, 16), &|_| {}).expect("render");
    let cam = [-30.0f64, 20.0, 150.0];
    let r_cam = (cam[0] * cam[0] + cam[1] * cam[1] + cam[2] * cam[2]).sqrt();
    let d2 = light[0] * light[0] + light[1] * light[1] + light[2] * light[2];
    let cos = light[2] / d2.sqrt();
    // Inside the fog's 100 m: all of the light's leg, the camera's last 100 m of height.
    let attenuation = (-sigma * d2.sqrt() - sigma * 100.0 * r_cam / cam[2]).exp();
    let want = 0.8 / PI * cos * 300.0 / d2 * attenuation;
    assert_matches("point light", group_mean(&r, 0, 0), want);
}

/// The ground under an area light, lit by it alone: the fog is far out of the way.
fn lit_by(light: &str) -> Rendered {
    let s = Scene::parse(&format!(
        r#"{{
        "medium": {{"kind": "fog", "min": [1000, 1000, 0], "max": [1001, 1001, 1]}},
        "sigma_t": 0.1, "phase": {{"kind": "hg", "g": 0}},
        "sun": {{"direction": [0, 0, 1], "irradiance": [0, 0, 0]}},
        "lights": [{light}],
        "surfaces": [{{"kind": "ground", "height": 0, "reflectance": [0.8, 0.5, 0.2]}}],
        "camera": {{"position": [-30, 20, 150], "look_at": [0, 0, 0], "fov_deg": 0.01,
                    "width": 4, "height": 4}}
    }}"#
    ))
    .expect("a valid scene");
    render(&s, &traced(16384, 9, 0), &|_| {}).expect("render")
}

#[test]
fn a_rectangle_light_gives_the_ground_its_form_factor() {
    // A 4 m × 6 m rectangle 5 m up, centred over the point seen, facing down: under its
    // centre, E = 2L [a/√(a²+h²) atan(b/√(a²+h²)) + b/√(b²+h²) atan(a/√(b²+h²))] (four
    // corner form factors, half-sides a and b).
    let (a, b, h, l) = (2.0f64, 3.0f64, 5.0f64, 7.0);
    let light = |flip: bool| {
        let (eu, ev) = ([0.0, 2.0 * b, 0.0], [2.0 * a, 0.0, 0.0]);
        let (eu, ev) = if flip { (ev, eu) } else { (eu, ev) };
        format!(
            r#"{{"kind": "rectangle", "corner": [{}, {}, {h}], "edge_u": {eu:?},
                 "edge_v": {ev:?}, "radiance": [{l}, {l}, {l}]}}"#,
            -a, -b
        )
    };
    let (ra, rb) = ((a * a + h * h).sqrt(), (b * b + h * h).sqrt());
    let e = 2.0 * l * (a / ra * (b / ra).atan() + b / rb * (a / rb).atan());
    let r = lit_by(&light(false));
    assert_matches("rectangle light", group_mean(&r, 0, 0), 0.8 / PI * e);
    // Turned to face up, it sends the ground nothing.
    assert!(lit_by(&light(true)).beauty.iter().all(|&v| v == 0.0));
}

#[test]
fn a_sphere_light_gives_the_ground_pi_l_sin2() {
    // A sphere of radius R at height d above the point seen: E = π L R²/d².
    let (radius, d, l) = (1.5f64, 6.0f64, 4.0);
    let r = lit_by(&format!(
        r#"{{"kind": "sphere", "center": [0, 0, {d}], "radius": {radius},
             "radiance": [{l}, {l}, {l}]}}"#
    ));
    let e = PI * l * radius * radius / (d * d);
    assert_matches("sphere light", group_mean(&r, 0, 0), 0.8 / PI * e);
}

#[test]
fn the_sun_lobe_walks_stay_unbiased_over_a_ground() {
    // Scattering fog over a bright ground: paths cross the fog, bounce, and come back; the
    // walks' MIS windows restart after each surface vertex. With and without the walks, per
    // order group, within the combined standard errors of the two renders' pixel spreads.
    let render_with = |steps: usize| {
        let mut s = ground_scene(0.02, 0.9, "", [0.0, 0.0, 0.0]);
        s.camera.fov_deg = 30.0;
        s.camera.width = 16;
        s.camera.height = 16;
        render(&s, &traced(256, 5 + steps as u64, steps), &|_| {}).expect("render")
    };
    let (a, b) = (render_with(0), render_with(16));
    let mut tested = 0;
    for g in 0..9 {
        let ((ma, sa), (mb, sb)) = (group_mean(&a, g, 0), group_mean(&b, g, 0));
        let se = (sa * sa + sb * sb).sqrt();
        eprintln!(
            "group {g}: plain {ma:.9e} ± {sa:.1e}, walks {mb:.9e} ± {sb:.1e}, z {:.2}",
            (mb - ma) / se
        );
        if ma > 0.0 {
            tested += 1;
            assert!((ma - mb).abs() < 4.0 * se, "group {g}: {ma} vs {mb} ± {se}");
        }
    }
    assert!(tested >= 6, "{tested} groups with light");
}

#[test]
fn bad_fog_and_surfaces_are_refused_by_name() {
    let base = |medium: &str, surfaces: &str| {
        Scene::parse(&format!(
            r#"{{"medium": {medium}, "sigma_t": 0.1, "phase": {{"kind": "hg", "g": 0.5}},
                "sun": {{"direction": [0, 0, 1], "irradiance": [1, 1, 1]}},
                "surfaces": [{surfaces}],
                "camera": {{"position": [0, -10, 5], "look_at": [0, 0, 0], "fov_deg": 30,
                            "width": 4, "height": 4}}, "spp": 1}}"#
        ))
        .err()
        .map(|e| format!("{e:#}"))
    };
    let fog = r#"{"kind": "fog", "min": [0, 0, 0], "max": [1, 1, 1]}"#;
    let cases = [
        (
            r#"{"kind": "fog", "min": [0, 0, 0], "max": [1, 0, 1]}"#,
            "",
            "medium.min",
        ),
        (
            r#"{"kind": "fog", "min": [0, 0, 0], "max": [1, 1, 1], "scale_height": -2}"#,
            "",
            "scale_height",
        ),
        (
            fog,
            r#"{"kind": "ground", "height": 0, "reflectance": [0.5, 1.5, 0]}"#,
            "surfaces[0].reflectance",
        ),
        (fog, r#"{"kind": "ground", "heigth": 0}"#, "heigth"),
        (fog, r#"{"kind": "mirror"}"#, "mirror"),
        (
            fog,
            r#"{"kind": "ground", "height": 0, "reflectance": [1, 1, 1], "material": "glass"}"#,
            "glass",
        ),
    ];
    for (medium, surfaces, named) in cases {
        let e = base(medium, surfaces).expect("refused");
        assert!(e.contains(named), "'{named}' not in: {e}");
    }
    assert!(base(fog, "").is_none());
    // Fog in a mesh: not with a box as well, a file that must exist and be closed.
    let both = r#"{"kind": "fog", "min": [0, 0, 0], "max": [1, 1, 1], "mesh": "x.obj"}"#;
    assert!(base(both, "")
        .expect("refused")
        .contains("either min and max"));
    let medium = |obj: &std::path::Path| mesh_fog(obj, "", 0.1).err().map(|e| format!("{e:#}"));
    let missing = std::env::temp_dir().join("nephele-no-such-mesh.obj");
    assert!(medium(&missing)
        .expect("refused")
        .contains("nephele-no-such-mesh.obj"));
    let open = boxes_obj("open", &[([0.0; 3], [1.0; 3])]);
    let text = std::fs::read_to_string(&open).expect("read");
    std::fs::write(&open, text.lines().take(13).collect::<Vec<_>>().join("\n")).expect("write");
    let e = medium(&open).expect("refused");
    assert!(e.contains("not closed"), "{e}");
    assert!(medium(&boxes_obj("closed", &[([0.0; 3], [1.0; 3])])).is_none());
}

/// The error of the collector renderer on `s`.
fn fast_error(s: &Scene) -> String {
    let tables = nephele_runtime::embedded::mie_10um();
    let options = nephele::render::fast::FastOptions::default();
    nephele::render::fast::render_fast(s, &tables, &options, &|_| {})
        .err()
        .expect("refused")
        .to_string()
}

#[test]
fn the_fast_renderers_refuse_lights_and_surfaces() {
    let mut s = ground_scene(0.01, 0.9, "", [0.0, 0.0, 0.0]);
    let e = fast_error(&s);
    assert!(e.contains("surface"), "{e}");
    s.surfaces.clear();
    s.lights = Scene::parse(&serde_json::to_string(&s).expect("json").replacen(
        '{',
        r#"{"lights": [{"kind": "point", "position": [0, 0, 50], "intensity": [1, 1, 1]}],"#,
        1,
    ))
    .expect("a valid scene")
    .lights;
    let e = fast_error(&s);
    assert!(e.contains("point, spot or area light"), "{e}");
}

/// An OBJ file of axis-aligned boxes [lo, hi] (faces counter-clockwise from outside), written
/// to a fresh temporary directory; its path.
fn boxes_obj(name: &str, boxes: &[([f64; 3], [f64; 3])]) -> std::path::PathBuf {
    let dir = std::env::temp_dir().join(format!("nephele-mesh-{}-{name}", std::process::id()));
    std::fs::create_dir_all(&dir).expect("temp dir");
    let mut text = String::from("# boxes\n");
    for (b, (lo, hi)) in boxes.iter().enumerate() {
        for i in 0..8 {
            let c = |k: usize, bit: usize| if (i >> bit) & 1 == 1 { hi[k] } else { lo[k] };
            text += &format!("v {} {} {}\n", c(0, 0), c(1, 1), c(2, 2));
        }
        let base = 8 * b + 1;
        for q in [
            [0, 2, 3, 1],
            [4, 5, 7, 6],
            [0, 1, 5, 4],
            [2, 6, 7, 3],
            [0, 4, 6, 2],
            [1, 3, 7, 5],
        ] {
            text += &format!(
                "f {} {} {} {}\n",
                base + q[0],
                base + q[1],
                base + q[2],
                base + q[3]
            );
        }
    }
    let path = dir.join(format!("{name}.obj"));
    std::fs::write(&path, text).expect("write the OBJ");
    path
}

/// The medium of a scene of fog (extinction `sigma`) inside the mesh `obj`, `extra` keys
/// added to the medium.
fn mesh_fog(obj: &std::path::Path, extra: &str, sigma: f64) -> anyhow::Result<Box<dyn Medium>> {
    Scene::parse(&format!(
        r#"{{"medium": {{"kind": "fog", "mesh": {:?} {extra}}}, "sigma_t": {sigma},
            "phase": {{"kind": "hg", "g": 0.5}},
            "sun": {{"direction": [0, 0, 1], "irradiance": [1, 1, 1]}},
            "camera": {{"position": [0, -10, 5], "look_at": [0, 0, 0], "fov_deg": 30,
                        "width": 4, "height": 4}}, "spp": 1}}"#,
        obj.display().to_string()
    ))?
    .build_medium()
}

#[test]
fn fog_in_a_mesh_fills_exactly_its_inside() {
    // Two separate boxes in one OBJ (non-convex as a whole): a ray through both crosses fog
    // over the sum of its chords, and none between them; with a falloff, as the box fog.
    let a = ([0.0, 0.0, 0.0], [2.0, 2.0, 2.0]);
    let b = ([3.0, 0.5, 0.5], [4.0, 1.5, 1.5]);
    let obj = boxes_obj("two", &[a, b]);
    let sigma: f64 = 0.4;
    let scene = |extra: &str| mesh_fog(&obj, extra, sigma).expect("the mesh reads");
    let fog = scene("");
    let mut rng = rand_xoshiro::Xoshiro256PlusPlus::seed_from_u64(4);
    let o = [-1.0, 1.0, 1.0];
    let w = [1.0, 0.0, 0.0];
    let want: f64 = (-sigma * (2.0 + 1.0f64)).exp();
    let runs = 20_000;
    let (mut sum, mut escaped) = (0.0, 0usize);
    for _ in 0..runs {
        sum += transmittance(fog.as_ref(), o, w, &mut rng);
        escaped += usize::from(collide(fog.as_ref(), o, w, &mut rng).is_none());
    }
    let (mean, p) = (sum / runs as f64, escaped as f64 / runs as f64);
    let se = (want * (1.0 - want) / runs as f64).sqrt();
    eprintln!("two boxes: ratio tracking {mean:.5}, escapes {p:.5}, closed form {want:.5}");
    assert!((mean - want).abs() < 4.0 * se && (p - want).abs() < 4.0 * se);
    // Inside and outside, point by point, and the falloff from the mesh's floor.
    assert_eq!(fog.sigma_t([2.5, 1.0, 1.0]), 0.0);
    assert_eq!(fog.sigma_t([1.9, 0.1, 1.9]), sigma);
    let thinning = scene(r#", "scale_height": 0.5"#);
    let got = thinning.sigma_t([3.5, 1.0, 1.25]);
    assert!(
        (got - sigma * (-1.25f64 / 0.5).exp()).abs() < 1e-15,
        "{got}"
    );
}

#[test]
fn a_mesh_surface_is_lit_and_casts_its_shadow() {
    // A diffuse box 2 m tall on the ground under a sun 45° up: its top is (ρ/π) μ E, and the
    // ground just beyond it, away from the sun, lies in its shadow.
    let obj = boxes_obj("block", &[([-1.0, -1.0, 0.0], [1.0, 1.0, 2.0])]);
    let view = |look_at: [f64; 3]| {
        let s = Scene::parse(&format!(
            r#"{{
            "medium": {{"kind": "fog", "min": [1000, 1000, 0], "max": [1001, 1001, 1]}},
            "sigma_t": 0.1, "phase": {{"kind": "hg", "g": 0}},
            "sun": {{"direction": [0.7071067811865476, 0, 0.7071067811865476],
                     "irradiance": [1, 1, 1]}},
            "surfaces": [{{"kind": "ground", "height": 0, "reflectance": [0.5, 0.5, 0.5]}},
                         {{"kind": "mesh", "obj": {:?}, "reflectance": [0.9, 0.6, 0.3]}}],
            "camera": {{"position": [0, -0.5, 40], "look_at": {look_at:?}, "fov_deg": 0.01,
                        "width": 2, "height": 2}}
        }}"#,
            obj.display().to_string()
        ))
        .expect("a valid scene");
        render(&s, &traced(256, 2, 0), &|_| {}).expect("render")
    };
    let top = view([0.2, 0.1, 2.0]);
    let want = 0.9 / PI * std::f64::consts::FRAC_1_SQRT_2;
    let got = top.groups[0] as f64;
    eprintln!("the block's top: {got:.6e}, closed form {want:.6e}");
    assert!(
        (got / want - 1.0).abs() < 1e-6,
        "{got} vs {want} (f32 images)"
    );
    // Behind the block (x < −1, within 2 m of it): in its shadow, no direct sunlight (order
    // 1), only what the lit ground sends back by way of the block's shaded face.
    let shade = view([-2.5, 0.0, 0.0]);
    let n = shade.width * shade.height;
    assert!(shade.groups[..3 * n].iter().all(|&v| v == 0.0));
    assert!(shade.beauty.iter().any(|&v| v > 0.0));
    // Beside the sun's side of it: lit, (ρ/π) μ E.
    let lit = view([2.5, 0.0, 0.0]);
    let want = 0.5 / PI * std::f64::consts::FRAC_1_SQRT_2;
    assert!((lit.groups[0] as f64 / want - 1.0).abs() < 1e-6);
}

#[test]
fn a_ground_under_the_sky_hides_it_and_a_mirror_reflects_it() {
    // No fog in view, a constant sky L: a diffuse ground returns ρ L (the sky all around, a
    // furnace), a mirror ρ L; the sky behind the ground is not seen (it once was, added to
    // the unscattered image).
    for material in ["diffuse", "mirror"] {
        let s = Scene::parse(&format!(
            r#"{{
            "medium": {{"kind": "fog", "min": [1000, 1000, 0], "max": [1001, 1001, 1]}},
            "sigma_t": 0.1, "phase": {{"kind": "hg", "g": 0}},
            "sun": {{"direction": [0.6, 0, 0.8], "irradiance": [0, 0, 0]}},
            "sky": [0.2, 0.3, 0.5],
            "surfaces": [{{"kind": "ground", "height": 0, "reflectance": [0.8, 0.5, 0.25],
                           "material": "{material}"}}],
            "camera": {{"position": [0, -30, 20], "look_at": [0, 0, 0], "fov_deg": 20,
                        "width": 8, "height": 6}}
        }}"#
        ))
        .expect("a valid scene");
        let r = render(&s, &traced(4, 1, 0), &|_| {}).expect("render");
        for (px, v) in r.beauty.chunks(3).enumerate() {
            for (c, want) in [0.8 * 0.2, 0.5 * 0.3, 0.25 * 0.5].into_iter().enumerate() {
                let got = v[c] as f64;
                assert!(
                    (got / want - 1.0).abs() < 1e-6,
                    "{material}, pixel {px}, channel {c}: {got} vs {want}"
                );
            }
        }
        assert!(r.unscattered.iter().all(|&v| v == 0.0), "{material}");
    }
}
