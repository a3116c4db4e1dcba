//! The path tracer against independent references: the slab Monte Carlo (crossing tallies of
//! forward photon walks, validated against DISORT) — a camera inside a homogeneous slab sees, per
//! order group, the radiance of the slab tables' bins, L/E⊥ = T, within their combined standard
//! errors — and a white furnace, where every medium must pass the sky radiance on unchanged.

use nephele::render::integrator::{trace, Volume};
use nephele::render::medium::Slab;
use nephele::slab::{run_slice, SlabGrid, Slice, StopRule};
use nephele_runtime::phase::HenyeyGreenstein;
use rand::{Rng, SeedableRng};
use rand_xoshiro::Xoshiro256PlusPlus;
use std::f64::consts::PI;

const GROUPS: [u32; 9] = [1, 2, 3, 5, 7, 9, 13, 19, 31];

#[test]
fn slab_pixels_match_the_slab_tables_per_order_group() {
    let (t, mu_l, depth) = (2.0, 0.6, 1.0);
    let hg = HenyeyGreenstein::new(0.7);
    let groups: Vec<(u32, u32)> = GROUPS
        .iter()
        .enumerate()
        .map(|(i, &f)| (f, GROUPS.get(i + 1).map_or(u32::MAX, |n| n - 1)))
        .collect();
    let mu_edges: Vec<f64> = (0..=8).map(|i| -1.0 + 0.25 * i as f64).collect();
    let psi_edges: Vec<f64> = (0..=4).map(|i| PI * i as f64 / 4.0).collect();
    let grid = SlabGrid::new(
        vec![0.0, depth, t],
        mu_edges.clone(),
        psi_edges.clone(),
        groups,
    )
    .unwrap();
    let slice = Slice {
        grid: &grid,
        mu_l,
        albedo: 1.0,
        phase: &hg,
    };
    let rule = StopRule {
        max_photons: 2_000_000,
        target_rel_se: 0.0,
        ..StopRule::default()
    };
    let tables = run_slice(&slice, 3, 0, &rule, &|_, _| {}).tables;
    let s_l = (1.0 - mu_l * mu_l).sqrt();
    let slab = Slab { h: t, sigma_t: 1.0 };
    let volume = Volume {
        medium: &slab,
        albedo: 1.0,
        phase: &hg,
        // The sun's light travels along +y and down: (0, s_L, −μ_L).
        sun_dir: [0.0, -s_l, mu_l],
        sun_irradiance: 1.0,
        sky: 0.0,
        group_first: &GROUPS,
    };
    let mut rng = Xoshiro256PlusPlus::seed_from_u64(11);
    let (mut z2, mut count, mut worst) = (0.0, 0, 0.0f64);
    // Views going up and down, toward and away from the sun, off the horizon.
    for (m, k) in [(6, 0), (7, 2), (1, 3), (2, 1), (5, 3)] {
        let n = 100_000;
        let mut sum = [0.0; 9];
        let mut sum2 = [0.0; 9];
        for _ in 0..n {
            // The light's direction, uniform in the bin's solid angle (μ and ψ uniform).
            let mu = mu_edges[m] + (mu_edges[m + 1] - mu_edges[m]) * rng.random::<f64>();
            let psi = psi_edges[k] + (psi_edges[k + 1] - psi_edges[k]) * rng.random::<f64>();
            let s = (1.0 - mu * mu).sqrt();
            let light = [s * psi.sin(), s * psi.cos(), mu];
            let eye = [0.0, 0.0, t - depth];
            let p = trace(&volume, eye, [-light[0], -light[1], -light[2]], &mut rng);
            for g in 0..9 {
                sum[g] += p.groups[g];
                sum2[g] += p.groups[g] * p.groups[g];
            }
        }
        for g in 0..9 {
            let mean = sum[g] / n as f64;
            let se = ((sum2[g] / n as f64 - mean * mean) / (n - 1) as f64).sqrt();
            let c = grid.cell(g, 1, m, k);
            let (tab, tab_se) = (tables.t[c], tables.t_se[c]);
            if !(tab > 0.0 && tab_se < 0.1 * tab) {
                continue;
            }
            let z = (mean - tab) / (se * se + tab_se * tab_se).sqrt();
            println!(
                "bin μ {m} ψ {k} group {g}: render {mean:.5} ± {se:.5}, tables {tab:.5} ± {tab_se:.5}, z {z:+.2}"
            );
            z2 += z * z;
            count += 1;
            worst = worst.max(z.abs());
        }
    }
    let mean_z2 = z2 / count as f64;
    println!("{count} comparisons, mean z² {mean_z2:.2}, worst |z| {worst:.2}");
    assert!(count >= 30, "only {count} comparisons");
    assert!(worst < 4.5, "worst |z| {worst}");
    assert!(mean_z2 < 2.0, "mean z² {mean_z2}");
}

/// A heterogeneous blob, σ_t = σ₀ (1 − r²/R²) inside a sphere: for delta and ratio tracking
/// against a majorant that is not the extinction.
struct Blob {
    sigma0: f64,
    r: f64,
}

impl nephele::render::medium::Medium for Blob {
    fn sigma_t(&self, p: [f64; 3]) -> f64 {
        let r2 = (p[0] * p[0] + p[1] * p[1] + p[2] * p[2]) / (self.r * self.r);
        if r2 < 1.0 {
            self.sigma0 * (1.0 - r2)
        } else {
            0.0
        }
    }

    fn clip(&self, o: [f64; 3], w: [f64; 3]) -> Option<(f64, f64)> {
        // |o + t w|² = R²: t² + 2 b t + c = 0.
        let b = o[0] * w[0] + o[1] * w[1] + o[2] * w[2];
        let c = o[0] * o[0] + o[1] * o[1] + o[2] * o[2] - self.r * self.r;
        let disc = b * b - c;
        if disc <= 0.0 {
            return None;
        }
        let (t0, t1) = (-b - disc.sqrt(), -b + disc.sqrt());
        (t1 > 0.0).then_some((t0.max(0.0), t1))
    }

    fn majorant(&self, _: [f64; 3], _: [f64; 3], _: f64, _: f64) -> f64 {
        self.sigma0
    }
}

/// White furnace around a heterogeneous blob.
#[test]
fn a_white_furnace_sees_the_sky_through_any_medium() {
    let blob = Blob {
        sigma0: 1.5,
        r: 1.0,
    };
    // Rays from outside through the blob at offsets up to 0.9 R, and from its centre.
    furnace(&blob, 200_000, 5, |i, rng| {
        if i % 2 == 0 {
            let (z, phi) = (
                2.0 * rng.random::<f64>() - 1.0,
                2.0 * PI * rng.random::<f64>(),
            );
            let s = (1.0 - z * z).sqrt();
            ([0.0; 3], [s * phi.cos(), s * phi.sin(), z])
        } else {
            ([0.9 * rng.random::<f64>(), -3.0, 0.0], [0.0, 1.0, 0.0])
        }
    });
}

/// The white furnace: albedo 1, no sun, sky radiance 1 around `medium`, `n` camera rays from
/// `ray(i, rng)`. Every ray must see radiance 1 on average (what the medium scatters away it
/// scatters in): transmittance by ratio tracking plus the scattered paths that escape. Also
/// checks that the medium matters (mean transmittance in 0.1…0.9).
fn furnace(
    medium: &dyn nephele::render::medium::Medium,
    n: usize,
    seed: u64,
    mut ray: impl FnMut(usize, &mut Xoshiro256PlusPlus) -> ([f64; 3], [f64; 3]),
) -> (f64, f64) {
    let hg = HenyeyGreenstein::new(0.7);
    let volume = Volume {
        medium,
        albedo: 1.0,
        phase: &hg,
        sun_dir: [0.0, 0.0, 1.0],
        sun_irradiance: 0.0,
        sky: 1.0,
        group_first: &GROUPS,
    };
    let mut rng = Xoshiro256PlusPlus::seed_from_u64(seed);
    let (mut sum, mut sum2, mut t_sum) = (0.0, 0.0, 0.0);
    for i in 0..n {
        let (o, w) = ray(i, &mut rng);
        let p = trace(&volume, o, w, &mut rng);
        let v = p.total();
        sum += v;
        sum2 += v * v;
        t_sum += p.transmittance;
    }
    let mean = sum / n as f64;
    let se = ((sum2 / n as f64 - mean * mean) / (n - 1) as f64).sqrt();
    let t_mean = t_sum / n as f64;
    println!("furnace: {mean:.5} ± {se:.5}; mean transmittance {t_mean:.3}");
    assert!((0.1..0.9).contains(&t_mean), "transmittance {t_mean}");
    assert!((mean - 1.0).abs() < 4.0 * se && se < 0.01, "{mean} ± {se}");
    (mean, se)
}

fn small_cloud() -> nephele::render::scene::Scene {
    let text = std::fs::read_to_string(concat!(
        env!("CARGO_MANIFEST_DIR"),
        "/fit-configs/scenes/cloud.json"
    ))
    .unwrap();
    let mut scene = nephele::render::scene::Scene::parse(&text).unwrap();
    scene.camera.width = 24;
    scene.camera.height = 16;
    scene.spp = 2;
    scene.phase = nephele::slab::PhaseSpec::Hg { g: 0.85 };
    scene
}

/// Same scene and seed, 1 or 2 threads: the same bits; and the order groups and the unscattered
/// sky add up to the beauty image.
#[test]
fn renders_are_bit_identical_for_any_thread_count_and_aovs_add_up() {
    use nephele::render::run::render;
    let scene = small_cloud();
    let with = |threads: usize| {
        rayon::ThreadPoolBuilder::new()
            .num_threads(threads)
            .build()
            .unwrap()
            .install(|| render(&scene, &|_| {}).unwrap())
    };
    let (a, b) = (with(1), with(2));
    assert!(a.beauty == b.beauty && a.groups == b.groups && a.transmittance == b.transmittance);
    let (w, h) = (a.width, a.height);
    let ng = a.groups.len() / (w * h * 3);
    let mut lit = 0;
    for px in 0..w * h * 3 {
        let sum: f64 = (0..ng)
            .map(|g| a.groups[g * w * h * 3 + px] as f64)
            .sum::<f64>()
            + a.unscattered[px] as f64;
        let beauty = a.beauty[px] as f64;
        assert!(
            (sum - beauty).abs() <= 1e-5 * beauty.max(1e-3),
            "{sum} vs {beauty}"
        );
        lit += usize::from(sum > a.unscattered[px] as f64);
    }
    assert!(lit > 0, "the cloud must be in the picture");
}

/// The voxel grid reads its values at the voxel centres, interpolates linearly between them,
/// holds the border values out to the box's faces and is empty outside.
#[test]
fn voxel_densities_are_trilinear_between_centres() {
    use nephele::render::medium::Voxels;
    // 3 × 2 × 2 voxels (x fastest) over a 3 × 2 × 2 m box: centres at x = 0.5, 1.5, 2.5, …
    let data: Vec<f32> = (0..12).map(|i| i as f32).collect();
    let v = Voxels::new(data, [3, 2, 2], [0.0; 3], [3.0, 2.0, 2.0], 1.0);
    let at = |x: f64, y: f64, z: f64| v.density([x, y, z]);
    assert_eq!(at(0.5, 0.5, 0.5), 0.0);
    assert_eq!(at(2.5, 0.5, 0.5), 2.0);
    assert_eq!(at(0.5, 1.5, 0.5), 3.0);
    assert_eq!(at(0.5, 0.5, 1.5), 6.0);
    assert!((at(1.0, 0.5, 0.5) - 0.5).abs() < 1e-12);
    assert!((at(1.5, 1.0, 1.0) - (1.0 + 1.5 + 3.0)).abs() < 1e-12);
    assert_eq!(at(0.1, 0.5, 0.5), 0.0, "clamped at the border");
    assert_eq!(at(2.9, 1.9, 1.9), 11.0, "clamped at the far corner");
    assert_eq!(at(-0.1, 0.5, 0.5), 0.0, "outside");
    assert_eq!(at(1.0, 2.1, 0.5), 0.0, "outside");
}

/// The white furnace through a random voxel grid (a majorant far above most voxels).
#[test]
fn a_white_furnace_sees_the_sky_through_a_voxel_grid() {
    use nephele::render::medium::Voxels;
    let mut rng = Xoshiro256PlusPlus::seed_from_u64(9);
    let data: Vec<f32> = (0..8 * 8 * 8)
        .map(|_| rng.random::<f32>().powi(3))
        .collect();
    let grid = Voxels::new(data, [8, 8, 8], [-1.0; 3], [2.0; 3], 3.0);
    furnace(&grid, 100_000, 9, |_, rng| {
        let o = [
            2.0 * rng.random::<f64>() - 1.0,
            -3.0,
            2.0 * rng.random::<f64>() - 1.0,
        ];
        (o, [0.0, 1.0, 0.0])
    });
}
