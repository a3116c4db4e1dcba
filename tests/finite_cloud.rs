//! The collector renderer on finite clouds against the path tracer run here (docs/collector.md,
//! "Finite clouds"): on a sphere of optical diameter 40 and on the default cumulus lit from the
//! front, the orders ≥ 2 summed over the opaque pixels must be within 25 % of the path
//! tracer's with the finite-cloud correction (measured at 160 × 120: −10 % and −1 %), where the
//! method as published is +70 % and +100 % (and this test checks it still is: the bound can
//! fail). And an absorbing slab (ϖ = 0.9, 0.99): the collector's absorption term against the
//! path tracer per order group summed, within 5 % + 3 SE. Under a sky alone: the furnace, and
//! how the light splits between orders on sphere40.

use nephele::render::fast::{render_fast, FastOptions, Finite};
use nephele::render::image::{Rendered, GROUP_FIRST};
use nephele::render::path::{render, Settings};
use nephele::render::scene::Scene;

/// A shipped scene at `width` × `height`, and its path tracer's settings at `spp`.
fn scene(name: &str, width: u32, height: u32, spp: u32) -> (Scene, Settings) {
    let path = format!(
        "{}/fit-configs/scenes/{name}.json",
        env!("CARGO_MANIFEST_DIR")
    );
    let path = std::path::Path::new(&path);
    let mut s = Scene::load(path).unwrap();
    s.camera.width = width;
    s.camera.height = height;
    let settings = Settings {
        spp,
        time_budget_s: None,
        ..Settings::load(path).unwrap()
    };
    (s, settings)
}

/// Σ over the pixels the reference sees as opaque (transmittance < 0.5) of orders ≥ 2 (channel
/// 0), and its standard error from the reference's split-sample halves (0 for a fast render).
fn scattered(r: &Rendered, mask: &[bool]) -> (f64, f64) {
    let n = r.width * r.height;
    let ng = GROUP_FIRST.len();
    let (mut sum, mut var) = (0.0, 0.0);
    for px in (0..n).filter(|&px| mask[px]) {
        let at = |a: &[f32], half: usize, g: usize| a[((half * ng + g) * n + px) * 3] as f64;
        sum += (1..ng)
            .map(|g| r.groups[(g * n + px) * 3] as f64)
            .sum::<f64>();
        if !r.halves.is_empty() {
            let d: f64 = (1..ng)
                .map(|g| at(&r.halves, 0, g) - at(&r.halves, 1, g))
                .sum();
            var += 0.25 * d * d;
        }
    }
    (sum, var.sqrt())
}

/// The relative bias of orders ≥ 2 of the collector with `finite` against the path tracer,
/// and the reference's relative standard error.
fn bias(reference: &Rendered, s: &Scene, finite: Finite) -> (f64, f64) {
    let opts = FastOptions {
        finite,
        map_resolution: 128,
        ..FastOptions::default()
    };
    let tables = nephele_runtime::embedded::mie_10um();
    let fast = render_fast(s, &tables, &opts, &|_| {}).unwrap();
    let mask: Vec<bool> = reference.transmittance.iter().map(|&t| t < 0.5).collect();
    assert!(
        mask.iter().filter(|&&m| m).count() > 50,
        "too few opaque pixels"
    );
    let (r, se) = scattered(reference, &mask);
    let (c, _) = scattered(&fast, &mask);
    (c / r - 1.0, se / r)
}

#[test]
fn the_finite_cloud_correction_brings_orders_above_one_near_the_path_tracer() {
    for (name, published_at_least) in [("sphere40", 0.4), ("cloud_front", 0.5)] {
        let (s, pt) = scene(name, 40, 30, 96);
        let reference = render(&s, &pt, &|_| {}).unwrap();
        let (corrected, se) = bias(&reference, &s, Finite::default());
        let (published, _) = bias(&reference, &s, Finite::PUBLISHED);
        eprintln!(
            "{name}: orders ≥ 2 corrected {:+.1} %, published {:+.1} % (reference SE {:.1} %)",
            100.0 * corrected,
            100.0 * published,
            100.0 * se
        );
        assert!(se < 0.03, "{name}: the reference is too noisy ({se})");
        assert!(corrected.abs() < 0.25 + 3.0 * se, "{name}: {corrected}");
        assert!(
            published > published_at_least,
            "{name}: published {published}"
        );
    }
}

#[test]
fn an_absorbing_slab_keeps_what_the_path_tracer_keeps() {
    for albedo in [0.9, 0.99] {
        let (mut s, pt) = scene("slab", 12, 8, 256);
        s.albedo = albedo;
        let reference = render(&s, &pt, &|_| {}).unwrap();
        let (b, se) = bias(&reference, &s, Finite::default());
        eprintln!(
            "ϖ = {albedo}: orders ≥ 2 {:+.2} % ± {:.2} %",
            100.0 * b,
            100.0 * se
        );
        assert!(b.abs() < 0.05 + 3.0 * se, "ϖ = {albedo}: {b} ± {se}");
    }
}

/// A conservative cloud under a uniform sky and no sun is a white furnace: every pixel's
/// beauty is the sky's radiance, whatever the cloud's shape (the exact reference, no path
/// tracer needed). The sky term in the view ray's slab keeps it to the tables' own sum error
/// and the sky grid's (measured at 40 × 30: mean +2.0 %, RMSE 2.9 % over the
/// cloud's pixels with the slab across the whole chord; +5.9 %, 5.9 % when the chord was cut at
/// the march's stop, 9.2 mfp); read in the sun's slab, as before, it was +15 % with a 44 % RMSE
/// at 160 × 120. The sides' share moves light between orders only, so it cannot move this.
#[test]
fn under_a_uniform_sky_alone_the_cloud_glows_at_the_skys_radiance() {
    let (s, _) = scene("cloud_sky", 40, 30, 1);
    assert_eq!(s.sun.irradiance, [0.0; 3]);
    let opts = FastOptions {
        map_resolution: 128,
        ..FastOptions::default()
    };
    let tables = nephele_runtime::embedded::mie_10um();
    let r = render_fast(&s, &tables, &opts, &|_| {}).unwrap();
    let (mut n, mut sum, mut sq) = (0usize, 0.0f64, 0.0f64);
    for (px, &t) in r.transmittance.iter().enumerate() {
        if t >= 0.5 {
            continue;
        }
        for c in 0..3 {
            let e = r.beauty[px * 3 + c] as f64 / s.sky[c] - 1.0;
            (n, sum, sq) = (n + 1, sum + e, sq + e * e);
        }
    }
    assert!(n > 300, "{n} cloud samples");
    let (mean, rmse) = (sum / n as f64, (sq / n as f64).sqrt());
    println!("beauty / sky − 1 over the cloud: mean {mean:+.4}, RMSE {rmse:.4}");
    assert!(mean.abs() < 0.08 && rmse < 0.12, "mean {mean}, RMSE {rmse}");
}

/// Under a white sky alone, how a cloud's light splits between orders (docs/collector.md, "The
/// sky term's slab"), against the path tracer run here on sphere40 at 40 × 30 (128 spp): per
/// group of orders ≥ 2 over the opaque pixels, channel 0. Read in a slab cut at the march's
/// stop (9.2 mfp) the split was the thin slab's: 31+ −39 %, the mean |bias| of the eight groups
/// 31 % (measured at 40 × 30 with 256 spp); the whole chord with the cloud's sides gives 31+
/// +8 % and 22 %. The bounds sit between the two (20 % and 26.5 %), each with 3 standard errors
/// of the reference (of the mean: the groups' errors combined).
#[test]
fn under_a_white_sky_the_orders_split_near_the_path_tracer() {
    let (s, pt) = scene("sphere40_sky", 40, 30, 128);
    let reference = render(&s, &pt, &|_| {}).unwrap();
    let opts = FastOptions {
        map_resolution: 128,
        ..FastOptions::default()
    };
    let tables = nephele_runtime::embedded::mie_10um();
    let fast = render_fast(&s, &tables, &opts, &|_| {}).unwrap();
    let n = reference.width * reference.height;
    let mask: Vec<bool> = reference.transmittance.iter().map(|&t| t < 0.5).collect();
    assert!(
        mask.iter().filter(|&&m| m).count() > 300,
        "too few opaque pixels"
    );
    let ng = GROUP_FIRST.len();
    let sum = |a: &[f32], g: usize| -> f64 {
        (0..n)
            .filter(|&px| mask[px])
            .map(|px| a[(g * n + px) * 3] as f64)
            .sum()
    };
    let se = |g: usize| -> f64 {
        let half = |h: usize, px: usize| reference.halves[((h * ng + g) * n + px) * 3] as f64;
        let var: f64 = (0..n)
            .filter(|&px| mask[px])
            .map(|px| 0.25 * (half(0, px) - half(1, px)).powi(2))
            .sum();
        var.sqrt()
    };
    // Order 1, marched through the maps toward the sky: read in the view ray's face-on slab
    // it was −50 % (80 × 60, 431 spp); marched, +6 %.
    let (truth, rel_se) = (sum(&reference.groups, 0), se(0) / sum(&reference.groups, 0));
    let order1 = sum(&fast.groups, 0) / truth - 1.0;
    println!("order 1: bias {order1:+.3} ± {rel_se:.3}");
    assert!(
        order1.abs() < 0.15 + 3.0 * rel_se,
        "order 1: {order1:+.3} ± {rel_se:.3}"
    );
    let (mut mean_abs, mut mean_var) = (0.0, 0.0);
    let mut last = (0.0, 0.0);
    for g in 1..ng {
        let truth = sum(&reference.groups, g);
        let b = sum(&fast.groups, g) / truth - 1.0;
        let rel_se = se(g) / truth;
        println!("orders from {}: bias {b:+.3} ± {rel_se:.3}", GROUP_FIRST[g]);
        mean_abs += b.abs() / (ng - 1) as f64;
        mean_var += (rel_se / (ng - 1) as f64).powi(2);
        last = (b, rel_se);
    }
    println!("mean |bias| {mean_abs:.3}");
    assert!(
        last.0.abs() < 0.2 + 3.0 * last.1,
        "31+: {:+.3} ± {:.3}",
        last.0,
        last.1
    );
    let mean_se = mean_var.sqrt();
    assert!(
        mean_abs < 0.265 + 3.0 * mean_se,
        "mean |bias| {mean_abs:.3} ± {mean_se:.3}"
    );
}
