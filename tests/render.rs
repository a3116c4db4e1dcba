//! The path tracer against independent references: the slab Monte Carlo (crossing tallies of
//! forward photon walks, validated against DISORT) — a camera inside a homogeneous slab sees, per
//! order group, the radiance of the slab tables' bins, L/E⊥ = T, within their combined standard
//! errors — and a white furnace, where every medium must pass the sky radiance on unchanged.

use nephele::render::majorant::{Bounds, Majorants};
use nephele::render::medium::{Medium, Slab};
use nephele::render::path::integrator::{channel_tables, trace, Volume};
use nephele::render::path::sun_lobe::SunLobe;
use nephele::render::surface::Surfaces;
use nephele::slab::{run_slice, SlabGrid, Slice, StopRule};
use nephele_runtime::phase::HenyeyGreenstein;
use nephele_runtime::PhaseFunction;
use rand::{Rng, SeedableRng};
use rand_xoshiro::Xoshiro256PlusPlus;
use std::f64::consts::PI;

/// Scenes without surfaces.
static NO_SURFACES: Surfaces = Surfaces::NONE;

const GROUPS: [u32; 9] = [1, 2, 3, 5, 7, 9, 13, 19, 31];

#[test]
fn slab_pixels_match_the_slab_tables_per_order_group() {
    let hg = HenyeyGreenstein::new(0.7);
    // Plain next-event estimation, two-vertex (one sun-lobe step) and sun-lobe walks of 16.
    let (z2, count, worst) =
        slab_comparison(&hg, &[0, 1, 16], &[(6, 0), (7, 2), (1, 3), (2, 1), (5, 3)]);
    let mean_z2 = z2 / count as f64;
    println!("{count} comparisons, mean z² {mean_z2:.2}, worst |z| {worst:.2}");
    assert!(count >= 60, "only {count} comparisons");
    assert!(worst < 4.5, "worst |z| {worst}");
    assert!(mean_z2 < 2.0, "mean z² {mean_z2}");
}

/// The same with 10 µm Mie droplets (p ≈ 200 sr⁻¹ in the forward peak) and the sun-lobe
/// estimator, including the bin of the sun's own direction seen through the slab (the aureole).
#[test]
fn mie_slab_pixels_match_the_slab_tables_per_order_group() {
    use nephele::phase::{Phase, PhaseSpec};
    let models = Phase::build_channels(&PhaseSpec::Mie {
        diameter_um: 10.0,
        rgb: false,
    })
    .unwrap();
    let (z2, count, worst) = Phase::with_all(&models, |phases| {
        slab_comparison(
            phases[0],
            &[16],
            &[(1, 0), (6, 0), (7, 2), (1, 3), (2, 1), (5, 3)],
        )
    });
    let mean_z2 = z2 / count as f64;
    println!("{count} comparisons, mean z² {mean_z2:.2}, worst |z| {worst:.2}");
    assert!(count >= 25, "only {count} comparisons");
    assert!(worst < 4.5, "worst |z| {worst}");
    assert!(mean_z2 < 2.0, "mean z² {mean_z2}");
}

/// A camera inside a slab (t = 2, μ_L = 0.6, depth 1) against the slab tables of the same
/// phase function, per order group, for the given (μ bin, ψ bin) views and sun-lobe steps:
/// (Σ z², comparisons, worst |z|).
fn slab_comparison(
    phase: &(dyn PhaseFunction<f64> + Sync),
    lobe_steps: &[usize],
    bins: &[(usize, usize)],
) -> (f64, usize, f64) {
    let (t, mu_l, depth) = (2.0, 0.6, 1.0);
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
        phase,
    };
    let rule = StopRule {
        max_photons: 2_000_000,
        target_rel_se: 0.0,
        ..StopRule::default()
    };
    let tables = run_slice(&slice, 3, 0, &rule, &|_, _| {}).tables;
    let s_l = (1.0 - mu_l * mu_l).sqrt();
    let slab = Slab { h: t, sigma_t: 1.0 };
    let (mut z2, mut count, mut worst) = (0.0, 0, 0.0f64);
    for &sun_lobe_steps in lobe_steps {
        let volume = Volume {
            medium: &slab,
            albedo: 1.0,
            phases: &[phase],
            channels: None,
            // The sun's light travels along +y and down: (0, s_L, −μ_L).
            sun_dir: [0.0, -s_l, mu_l],
            sun_irradiance: 1.0,
            sky: 0.0,
            group_first: &GROUPS,
            sun_lobe: SunLobe::new(sun_lobe_steps, &[phase]),
            lights: &[],
            surfaces: &NO_SURFACES,
        };
        let mut rng = Xoshiro256PlusPlus::seed_from_u64(11);
        // Views going up and down, toward and away from the sun, off the horizon.
        for &(m, k) in bins {
            let n = 300_000;
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
                    sum[g] += p.groups[g][0];
                    sum2[g] += p.groups[g][0] * p.groups[g][0];
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
                    "sun-lobe steps {sun_lobe_steps}, bin μ {m} ψ {k} group {g}: render {mean:.5} ± {se:.5}, tables {tab:.5} ± {tab_se:.5}, z {z:+.2}"
                );
                z2 += z * z;
                count += 1;
                worst = worst.max(z.abs());
            }
        }
    }
    (z2, count, worst)
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

    fn majorants(&self) -> Majorants<'_> {
        Majorants::Constant(Bounds {
            min: 0.0,
            max: self.sigma0,
        })
    }

    fn bounds(&self) -> Option<([f64; 3], [f64; 3])> {
        Some(([-self.r; 3], [self.r; 3]))
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
        phases: &[&hg],
        channels: None,
        sun_dir: [0.0, 0.0, 1.0],
        sun_irradiance: 0.0,
        sky: 1.0,
        group_first: &GROUPS,
        sun_lobe: SunLobe::OFF,
        lights: &[],
        surfaces: &NO_SURFACES,
    };
    let mut rng = Xoshiro256PlusPlus::seed_from_u64(seed);
    let (mut sum, mut sum2, mut t_sum) = (0.0, 0.0, 0.0);
    for i in 0..n {
        let (o, w) = ray(i, &mut rng);
        let p = trace(&volume, o, w, &mut rng);
        let v = p.total(0);
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
    scene.phase = nephele::phase::PhaseSpec::Hg { g: 0.85 };
    scene
}

/// Same scene and seed, 1 or 2 threads: the same bits; and the order groups and the unscattered
/// sky add up to the beauty image.
#[test]
fn renders_are_bit_identical_for_any_thread_count_and_aovs_add_up() {
    use nephele::render::path::{render, Settings};
    let scene = small_cloud();
    let two = Settings {
        spp: 2,
        ..Settings::default()
    };
    let with = |threads: usize| {
        rayon::ThreadPoolBuilder::new()
            .num_threads(threads)
            .build()
            .unwrap()
            .install(|| render(&scene, &two, &|_| {}).unwrap())
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
    // Oblique rays, so that the majorant walk crosses cell faces of all three axes.
    furnace(&grid, 100_000, 9, |_, rng| {
        let o = [
            2.0 * rng.random::<f64>() - 1.0,
            -3.0,
            2.0 * rng.random::<f64>() - 1.0,
        ];
        let w = [-0.3 * o[0], 1.0, -0.3 * o[2]];
        let n = (w[0] * w[0] + w[1] * w[1] + w[2] * w[2]).sqrt();
        (o, w.map(|x| x / n))
    });
}

/// A small implicit cloud: three overlapping ellipsoids with a noisy boundary layer (m), of
/// extinction 1.2 /m (optical radius ≈ 1).
fn implicit_cloud() -> nephele::render::medium::Cloud {
    implicit_cloud_of(1.2)
}

/// [`implicit_cloud`] of extinction `sigma_t` (1/m) at density 1.
fn implicit_cloud_of(sigma_t: f64) -> nephele::render::medium::Cloud {
    use nephele::render::medium::{Cloud, Ellipsoid};
    let blob = |center, radii| Ellipsoid { center, radii };
    let blobs = vec![
        blob([0.0, 0.0, 0.0], [1.0, 0.8, 0.7]),
        blob([0.7, 0.2, 0.3], [0.5, 0.5, 0.5]),
        blob([-0.6, -0.1, 0.2], [0.4, 0.5, 0.4]),
    ];
    Cloud::new(blobs, 0.15, (0.25, 3.0, 4), sigma_t, 3)
}

/// The white furnace through the implicit cloud: its majorant grid is empty outside the
/// ellipsoids and loose in the boundary layer.
#[test]
fn a_white_furnace_sees_the_sky_through_an_implicit_cloud() {
    let cloud = implicit_cloud();
    furnace(&cloud, 100_000, 11, |_, rng| {
        let o = [
            3.0 * rng.random::<f64>() - 1.5,
            -4.0,
            2.0 * rng.random::<f64>() - 1.0,
        ];
        let w = [0.2, 1.0, -0.1 * o[2]];
        let n = (w[0] * w[0] + w[1] * w[1] + w[2] * w[2]).sqrt();
        (o, w.map(|x| x / n))
    });
}

/// The majorant grids (the march's and tracking's) bound σ_t from above and below everywhere
/// (random points in the media's boxes); the implicit cloud's grid skips empty space and knows
/// its homogeneous interior.
#[test]
fn majorant_grids_bound_the_extinction() {
    use nephele::render::medium::Voxels;
    let mut rng = Xoshiro256PlusPlus::seed_from_u64(4);
    let data: Vec<f32> = (0..13 * 7 * 9)
        .map(|_| rng.random::<f32>().powi(4))
        .collect();
    let voxels = Voxels::new(data, [13, 7, 9], [-1.0, 0.0, 2.0], [2.6, 1.4, 1.8], 2.0);
    let cloud = implicit_cloud();
    let media: [(&dyn Medium, [f64; 3], [f64; 3]); 2] = [
        (&voxels, [-1.0, 0.0, 2.0], [1.6, 1.4, 3.8]),
        (&cloud, [-1.5, -1.2, -1.2], [1.5, 1.2, 1.2]),
    ];
    // Both the grid the march walks and the one delta and ratio tracking walk.
    let grids = media.iter().flat_map(|&(medium, lo, hi)| {
        [medium.majorants(), medium.tracking_majorants()].map(|m| (medium, m, lo, hi))
    });
    for (medium, majorants, lo, hi) in grids {
        let Majorants::Grid(grid) = majorants else {
            panic!("heterogeneous media have majorant grids");
        };
        let mut slack = 0.0;
        for _ in 0..200_000 {
            let p: [f64; 3] =
                std::array::from_fn(|k| lo[k] + (hi[k] - lo[k]) * rng.random::<f64>());
            let (s, b) = (medium.sigma_t(p), grid.at(p));
            assert!(
                b.min <= s && s <= b.max,
                "σ_t {s} outside the bounds {b:?} at {p:?}"
            );
            slack += b.max - s;
        }
        let (empty, full) = grid.fractions();
        println!(
            "{:?} cells, {:.0} % empty, {:.1} % homogeneous, mean slack {:.3} /m",
            grid.cells(),
            100.0 * empty,
            100.0 * full,
            slack / 2e5
        );
    }
    let Majorants::Grid(grid) = cloud.majorants() else {
        unreachable!()
    };
    let (empty, full) = grid.fractions();
    assert!(
        empty > 0.2 && full > 0.001,
        "{empty} empty, {full} homogeneous"
    );
}

/// Per-channel phase functions (one-sample MIS over the channels): each channel of an RGB render
/// (with two-vertex NEE) matches a monochrome render with that channel's phase function alone
/// (without), within the standard errors, for views reflected from and transmitted through a
/// slab lit by the sun and the sky.
#[test]
fn per_channel_phase_functions_match_monochrome_renders() {
    let hg = [0.3, 0.6, 0.85].map(HenyeyGreenstein::new);
    let slab = Slab {
        h: 2.0,
        sigma_t: 1.0,
    };
    let all: [&(dyn PhaseFunction<f64> + Sync); 3] = [&hg[0], &hg[1], &hg[2]];
    fn volume<'a>(slab: &'a Slab, phases: &'a [&'a (dyn PhaseFunction<f64> + Sync)]) -> Volume<'a> {
        Volume {
            medium: slab,
            albedo: 0.95,
            phases,
            channels: channel_tables(phases),
            sun_dir: [0.6, 0.0, 0.8],
            sun_irradiance: 1.0,
            sky: 0.3,
            group_first: &GROUPS,
            // Sun-lobe NEE with three phase functions; the monochrome renders go without.
            sun_lobe: if phases.len() == 3 {
                SunLobe::new(16, phases)
            } else {
                SunLobe::OFF
            },
            lights: &[],
            surfaces: &NO_SURFACES,
        }
    }
    let views = [
        ([0.0, 0.0, 3.0], [0.3, 0.1, -0.95]),
        ([0.0, 0.0, 3.0], [-0.7, 0.2, -0.7]),
        ([0.0, 0.0, -1.0], [0.5, 0.0, 0.87]),
        ([0.0, 0.0, -1.0], [-0.2, 0.3, 0.93]),
    ];
    // Mean and standard error of channel c over n paths.
    let stats = |v: &Volume, o, w: [f64; 3], c: usize, seed: u64| {
        let w = nephele::render::geometry::normalize(w);
        let mut rng = Xoshiro256PlusPlus::seed_from_u64(seed);
        let n = 400_000;
        let (mut s, mut s2) = (0.0, 0.0);
        for _ in 0..n {
            let x = trace(v, o, w, &mut rng).total(c);
            s += x;
            s2 += x * x;
        }
        let m = s / n as f64;
        (m, ((s2 / n as f64 - m * m) / (n - 1) as f64).sqrt())
    };
    let rgb = volume(&slab, &all);
    let (mut worst, mut z2, mut spread) = (0.0f64, 0.0, 0.0f64);
    for (i, &(o, w)) in views.iter().enumerate() {
        let mono: Vec<(f64, f64)> = (0..3)
            .map(|c| {
                stats(
                    &volume(&slab, std::slice::from_ref(&all[c])),
                    o,
                    w,
                    c,
                    100 + i as u64,
                )
            })
            .collect();
        for (c, &(m1, s1)) in mono.iter().enumerate() {
            let (m2, s2) = stats(&rgb, o, w, c, 300 + i as u64);
            let z = (m2 - m1) / (s1 * s1 + s2 * s2).sqrt();
            println!(
                "view {i} channel {c}: rgb {m2:.5} ± {s2:.5}, mono {m1:.5} ± {s1:.5}, z {z:+.2}"
            );
            worst = worst.max(z.abs());
            z2 += z * z / 12.0;
        }
        spread = spread.max((mono[0].0 - mono[2].0).abs() / mono[0].1.hypot(mono[2].1));
    }
    println!("worst |z| {worst:.2}, mean z² {z2:.2}, channels apart by up to {spread:.0} SE");
    assert!(
        spread > 20.0,
        "the channels must differ for the test to mean something"
    );
    assert!(worst < 4.0 && z2 < 2.5, "worst |z| {worst}, mean z² {z2}");
}

/// A time budget renders passes whose pixels continue their streams: whatever number of passes
/// it allowed, the image is the one a single render at the same total spp gives.
#[test]
fn a_time_budget_gives_the_image_of_its_total_spp() {
    use nephele::render::path::{render, Settings};
    let scene = small_cloud();
    let budget = Settings {
        spp: 1,
        time_budget_s: Some(0.3),
        ..Settings::default()
    };
    let budgeted = render(&scene, &budget, &|_| {}).unwrap();
    let n = &budgeted.details["samples_per_pixel"];
    let (lo, hi) = (
        n["min"].as_u64().unwrap() as u32,
        n["max"].as_u64().unwrap() as u32,
    );
    assert!(lo >= 2, "{lo} passes in 0.3 s");
    assert!(hi <= lo + 1, "the cut pass leaves rows one pass apart: {n}");
    // Each row is the bits of one render at its own samples per pixel: the least or the most.
    let at = |spp: u32| {
        let fixed = Settings {
            spp,
            time_budget_s: None,
            ..budget
        };
        render(&scene, &fixed, &|_| {}).unwrap()
    };
    let (fewer, more) = (at(lo), at(hi));
    let row = 3 * budgeted.width;
    let rows = |r: &nephele::render::image::Rendered| {
        r.beauty
            .chunks(row)
            .map(<[f32]>::to_vec)
            .collect::<Vec<_>>()
    };
    let (b, f, m) = (rows(&budgeted), rows(&fewer), rows(&more));
    for j in 0..b.len() {
        assert!(b[j] == f[j] || b[j] == m[j], "row {j} is neither render's");
    }
    println!("{lo}–{hi} spp");
}

/// A voxel grid placed by a to_world matrix (a quarter turn about z, scaled and moved) has the
/// densities and majorant bounds of the same values re-indexed over the box it covers.
#[test]
fn a_rotated_voxel_grid_is_the_re_indexed_grid() {
    use nephele::render::geometry::Affine;
    use nephele::render::medium::Voxels;
    let mut rng = Xoshiro256PlusPlus::seed_from_u64(21);
    let (nx, ny, nz) = (5usize, 4usize, 3usize);
    let a: Vec<f32> = (0..nx * ny * nz).map(|_| rng.random::<f32>()).collect();
    let (s, t) = ([2.0, 3.0, 1.5], [1.0, -2.0, 0.5]);
    // p = R S u + t with R: x → y, y → −x.
    let m = [[0.0, -s[1], 0.0], [s[0], 0.0, 0.0], [0.0, 0.0, s[2]]];
    let rotated = Voxels::with_transform(a.clone(), [nx, ny, nz], Affine::new(m, t).unwrap(), 1.0);
    // The same values over the box [t_x − s_y, t_x] × [t_y, t_y + s_x] × [t_z, t_z + s_z]:
    // B[z][j][i] = A[z][ny − 1 − i][j], B having ny columns and nx rows.
    let mut b = vec![0.0f32; nx * ny * nz];
    for z in 0..nz {
        for j in 0..nx {
            for i in 0..ny {
                b[(z * nx + j) * ny + i] = a[(z * ny + (ny - 1 - i)) * nx + j];
            }
        }
    }
    let boxed = Voxels::new(
        b,
        [ny, nx, nz],
        [t[0] - s[1], t[1], t[2]],
        [s[1], s[0], s[2]],
        1.0,
    );
    let (mut inside, mut worst) = (0, 0.0f64);
    for _ in 0..20_000 {
        let p = [
            t[0] - 3.5 + 4.0 * rng.random::<f64>(),
            t[1] - 0.5 + 3.0 * rng.random::<f64>(),
            t[2] - 0.5 + 2.5 * rng.random::<f64>(),
        ];
        let (d1, d2) = (rotated.density(p), boxed.density(p));
        worst = worst.max((d1 - d2).abs());
        inside += usize::from(d2 > 0.0);
        let Majorants::Grid(g) = rotated.majorants() else {
            panic!("a voxel grid has a majorant grid")
        };
        let bounds = g.at(p);
        // (Outside the grid the bounds of the nearest cell do not apply.)
        if d2 > 0.0 {
            assert!(
                bounds.min <= d1 + 1e-12 && d1 <= bounds.max + 1e-12,
                "{d1} outside {bounds:?}"
            );
        }
    }
    assert!(
        inside > 5_000 && worst < 1e-9,
        "{inside} points inside, worst difference {worst}"
    );
    // Rays: the same clipped segments.
    for _ in 0..1000 {
        let o = [t[0] - 1.5, t[1] + 1.0, t[2] + 0.7];
        let w = nephele::render::geometry::normalize([
            rng.random::<f64>() - 0.5,
            rng.random::<f64>() - 0.5,
            rng.random::<f64>() - 0.5,
        ]);
        let (c1, c2) = (rotated.clip(o, w).unwrap(), boxed.clip(o, w).unwrap());
        assert!(
            (c1.0 - c2.0).abs() < 1e-9 && (c1.1 - c2.1).abs() < 1e-9,
            "{c1:?} vs {c2:?}"
        );
    }
}

/// Per order group (channel 0), the mean of `batches` batch means of `per_batch` camera paths
/// from `eye` along `w`, and its standard error.
fn group_means(
    vol: &Volume,
    (eye, w): ([f64; 3], [f64; 3]),
    seed: u64,
    (batches, per_batch): (usize, usize),
) -> [(f64, f64); 9] {
    let mut rng = Xoshiro256PlusPlus::seed_from_u64(seed);
    let mut means = vec![[0.0; 9]; batches];
    for m in means.iter_mut() {
        for _ in 0..per_batch {
            let p = trace(vol, eye, w, &mut rng);
            for g in 0..9 {
                m[g] += p.groups[g][0] / per_batch as f64;
            }
        }
    }
    let k = batches as f64;
    std::array::from_fn(|g| {
        let mean = means.iter().map(|m| m[g]).sum::<f64>() / k;
        let var: f64 = means.iter().map(|m| (m[g] - mean).powi(2)).sum::<f64>() / (k - 1.0);
        (mean, (var / k).sqrt())
    })
}

/// Two estimates compared value by value: z = (b − a)/√(s_a² + s_b²) over the values whose
/// mean is positive and whose standard errors are below 30 % of it.
#[derive(Default)]
struct ZScores {
    z2: f64,
    count: usize,
    worst: f64,
}

impl ZScores {
    /// Adds (mean, standard error) `a` and `b` of one value, labelled `what`.
    fn add(&mut self, what: &str, (ma, sa): (f64, f64), (mb, sb): (f64, f64)) {
        if !(ma > 0.0 && sa < 0.3 * ma && sb < 0.3 * mb) {
            return;
        }
        let z = (mb - ma) / (sa * sa + sb * sb).sqrt();
        println!("{what}: {ma:.5} ± {sa:.5} vs {mb:.5} ± {sb:.5}, z {z:+.2}");
        self.z2 += z * z;
        self.count += 1;
        self.worst = self.worst.max(z.abs());
    }

    /// At least `min_count` values, none beyond 4.5 SE, mean z² below 2.
    fn check(&self, min_count: usize) {
        let (count, worst) = (self.count, self.worst);
        let mean_z2 = self.z2 / count as f64;
        println!("{count} comparisons, mean z² {mean_z2:.2}, worst |z| {worst:.2}");
        assert!(count >= min_count, "only {count} comparisons");
        assert!(worst < 4.5, "worst |z| {worst}");
        assert!(mean_z2 < 2.0, "mean z² {mean_z2}");
    }
}

/// The implicit cloud with delta and ratio tracking on its fine majorant grid rather than its
/// blocks (the path tracer's earlier walk).
struct FineTracking(nephele::render::medium::Cloud);

impl Medium for FineTracking {
    fn sigma_t(&self, p: [f64; 3]) -> f64 {
        self.0.sigma_t(p)
    }
    fn clip(&self, o: [f64; 3], w: [f64; 3]) -> Option<(f64, f64)> {
        self.0.clip(o, w)
    }
    fn majorants(&self) -> Majorants<'_> {
        self.0.majorants()
    }
    fn bounds(&self) -> Option<([f64; 3], [f64; 3])> {
        self.0.bounds()
    }
}

/// Tracking on the cloud's coarse majorant blocks gives, per order group, the image that
/// tracking on its fine cells gives (a looser bound changes the cost and the noise, never the
/// mean): an implicit cloud of optical radius ≈ 8 with a noisy boundary layer, 10 µm Mie
/// droplets and sun-lobe NEE, four views from outside, 20 batch means per estimate.
#[test]
fn tracking_on_coarse_majorant_blocks_keeps_every_order_group() {
    use nephele::phase::{Phase, PhaseSpec};
    let coarse = implicit_cloud_of(8.0);
    let fine = FineTracking(implicit_cloud_of(8.0));
    assert!(!std::ptr::eq(
        match coarse.tracking_majorants() {
            Majorants::Grid(g) => g,
            Majorants::Constant(_) => panic!("the cloud has grids"),
        },
        match coarse.majorants() {
            Majorants::Grid(g) => g,
            Majorants::Constant(_) => panic!("the cloud has grids"),
        }
    ));
    let models = Phase::build_channels(&PhaseSpec::Mie {
        diameter_um: 10.0,
        rgb: false,
    })
    .unwrap();
    let sun = nephele::render::geometry::normalize([-0.45, -0.65, 0.57]);
    let views = [
        ([0.0, -3.0, 0.2], [0.0, 1.0, 0.0]),
        ([0.3, 3.0, 0.0], [-0.1, -1.0, 0.0]),
        ([-3.0, 0.1, 0.3], [1.0, 0.0, -0.1]),
        ([0.2, 0.0, 3.0], [0.0, 0.1, -1.0]),
    ];
    let mut zs = ZScores::default();
    Phase::with_all(&models, |phases| {
        let volume = |medium| Volume {
            medium,
            albedo: 1.0,
            phases,
            channels: channel_tables(phases),
            sun_dir: sun,
            sun_irradiance: 1.0,
            sky: 0.0,
            group_first: &GROUPS,
            sun_lobe: SunLobe::new(16, phases),
            lights: &[],
            surfaces: &NO_SURFACES,
        };
        let (a_vol, b_vol) = (volume(&fine), volume(&coarse));
        for (v, (eye, w)) in views.iter().enumerate() {
            let w = nephele::render::geometry::normalize(*w);
            let a = group_means(&a_vol, (*eye, w), 300 + v as u64, (20, 4000));
            let b = group_means(&b_vol, (*eye, w), 400 + v as u64, (20, 4000));
            for g in 0..9 {
                zs.add(&format!("view {v} group {g}: fine vs blocks"), a[g], b[g]);
            }
        }
    });
    zs.check(24);
}

/// The sun-lobe estimator and plain next-event estimation agree per order group on a small Mie
/// scene, with and without roulette (ϖ = 1, 0.6, 0.2; the schedule starts at orders 14 and 5):
/// a homogeneous slab of optical thickness 3 seen from inside along four views (toward the
/// sun's side, away, up, down), each estimator's standard error from 20 batch means. The droplets are 2 µm (p(0) ≈ 10 sr⁻¹): with 10 µm ones (p(0) ≈ 200
/// sr⁻¹) the plain estimator is so heavy-tailed that 240 000 paths per view miss the rare
/// spikes that carry part of its mean, and its sample mean and standard error both come out
/// low (z up to +12, the sun-lobe estimate always the higher) — the 10 µm check is against the
/// slab tables instead (`mie_slab_pixels_match_the_slab_tables_per_order_group`).
#[test]
fn the_sun_lobe_estimator_agrees_with_plain_nee_per_order_group_on_mie() {
    use nephele::phase::{Phase, PhaseSpec};
    let models = Phase::build_channels(&PhaseSpec::Mie {
        diameter_um: 2.0,
        rgb: false,
    })
    .unwrap();
    let (t, mu_l): (f64, f64) = (3.0, 0.6);
    let s_l = (1.0 - mu_l * mu_l).sqrt();
    let slab = Slab { h: t, sigma_t: 1.0 };
    let views = [
        [0.3, -0.8, 0.52],
        [0.2, 0.9, -0.39],
        [0.1, 0.2, 0.97],
        [-0.2, 0.1, -0.97],
    ];
    let (batches, per_batch) = (20, 12_000);
    let mut zs = ZScores::default();
    Phase::with_all(&models, |phases| {
        for albedo in [1.0, 0.6, 0.2] {
            let volume = |sun_lobe| Volume {
                medium: &slab,
                albedo,
                phases,
                channels: channel_tables(phases),
                sun_dir: [0.0, -s_l, mu_l],
                sun_irradiance: 1.0,
                sky: 0.0,
                group_first: &GROUPS,
                sun_lobe,
                lights: &[],
                surfaces: &NO_SURFACES,
            };
            let (plain, lobe) = (volume(SunLobe::OFF), volume(SunLobe::new(16, phases)));
            for (v, view) in views.iter().enumerate() {
                let w = nephele::render::geometry::normalize(*view);
                let eye = [0.0, 0.0, t - 1.0];
                let estimate =
                    |vol: &Volume, seed| group_means(vol, (eye, w), seed, (batches, per_batch));
                let (a, b) = (
                    estimate(&plain, 100 + v as u64),
                    estimate(&lobe, 200 + v as u64),
                );
                for g in 0..9 {
                    let what = format!("ϖ {albedo} view {v} group {g}: plain vs sun lobe");
                    zs.add(&what, a[g], b[g]);
                }
            }
        }
    });
    zs.check(50);
}

/// The slope bound behind the implicit cloud's majorant cells holds: the directional derivatives
/// of the `noise` crate's Perlin noise at random points of three seeds stay below
/// `PERLIN_SLOPE` (finite differences over 10⁻⁵ of its input).
#[test]
fn perlin_noise_slope_is_below_the_majorant_bound() {
    use nephele::render::medium::PERLIN_SLOPE;
    use noise::{NoiseFn, Perlin};
    let mut rng = Xoshiro256PlusPlus::seed_from_u64(9);
    let h = 1e-5;
    let mut largest = 0.0f64;
    for seed in [1, 2, 7] {
        let perlin = Perlin::new(seed);
        for _ in 0..1_000_000 {
            let x: [f64; 3] = std::array::from_fn(|_| 200.0 * rng.random::<f64>() - 100.0);
            let u = nephele::render::geometry::normalize(std::array::from_fn(|_| {
                2.0 * rng.random::<f64>() - 1.0
            }));
            let y: [f64; 3] = std::array::from_fn(|k| x[k] + h * u[k]);
            largest = largest.max(((perlin.get(y) - perlin.get(x)) / h).abs());
        }
    }
    println!("largest directional derivative {largest:.3} (bound {PERLIN_SLOPE})");
    assert!(largest < PERLIN_SLOPE / 1.2, "{largest}");
}
