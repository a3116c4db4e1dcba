//! Rendering a scene: a pinhole camera, rows of pixels in parallel, each pixel's samples drawn
//! from its own random stream (xoshiro256++ seeded by a hash of the scene's seed and the pixel),
//! so the image is the same bits for any thread count; and the outputs.

use super::integrator::{trace, Rgb, Volume, MAX_GROUPS};
use super::medium::{cross, normalize};
use super::scene::Scene;
use crate::slab::tables::PhaseModel;
use anyhow::Result;
use rand::{Rng, SeedableRng};
use rand_xoshiro::Xoshiro256PlusPlus;
use rayon::prelude::*;
use std::time::Instant;

/// The slab tables' order groups: first orders 1, 2, 3, 5, 7, 9, 13, 19, 31.
pub const GROUP_FIRST: [u32; 9] = [1, 2, 3, 5, 7, 9, 13, 19, 31];

/// A rendered image and its arrays (linear radiance, W m⁻² sr⁻¹; row 0 at the top).
pub struct Rendered {
    /// Width and height (pixels).
    pub width: usize,
    /// See `width`.
    pub height: usize,
    /// Radiance per order group, [group, row, column, RGB].
    pub groups: Vec<f32>,
    /// The sky seen through the medium without scattering, [row, column, RGB].
    pub unscattered: Vec<f32>,
    /// Transmittance of the camera ray through the medium, [row, column].
    pub transmittance: Vec<f32>,
    /// The sum of the groups and the unscattered part, [row, column, RGB].
    pub beauty: Vec<f32>,
    /// Wall-clock seconds.
    pub seconds: f64,
    /// Camera paths traced.
    pub paths: u64,
}

/// SplitMix64: the seed of pixel `i`'s stream.
fn pixel_seed(seed: u64, i: u64) -> u64 {
    let mut z = seed ^ i.wrapping_mul(0x9E37_79B9_7F4A_7C15);
    z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
    z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
    z ^ (z >> 31)
}

/// Renders `scene`; `progress(rows done)` after each row.
pub fn render(scene: &Scene, progress: &(dyn Fn(usize) + Sync)) -> Result<Rendered> {
    let medium = scene.build_medium()?;
    let models = PhaseModel::build_channels(&scene.phase)?;
    let cam = &scene.camera;
    let (w, h) = (cam.width as usize, cam.height as usize);
    let fwd = normalize(std::array::from_fn(|k| cam.look_at[k] - cam.position[k]));
    let right = normalize(cross(fwd, cam.up));
    let up = cross(right, fwd);
    let tan = (0.5 * cam.fov_deg.to_radians()).tan();
    let aspect = w as f64 / h as f64;
    let has_sky = scene.sky.iter().any(|&s| s > 0.0);
    let ng = GROUP_FIRST.len();
    let done = std::sync::atomic::AtomicUsize::new(0);
    let t0 = Instant::now();
    // Per row: [column][group] sun and sky radiance (E = 1, L_sky = 1), and transmittance.
    type Row = Vec<([Rgb; MAX_GROUPS], [Rgb; MAX_GROUPS], f64)>;
    let rows: Vec<Row> = PhaseModel::with_all(&models, |phases| {
        let volume = Volume {
            medium: medium.as_ref(),
            albedo: scene.albedo,
            phases,
            sun_dir: scene.sun.direction,
            sun_irradiance: 1.0,
            sky: if has_sky { 1.0 } else { 0.0 },
            group_first: &GROUP_FIRST,
        };
        (0..h)
            .into_par_iter()
            .map(|j| {
                let row = (0..w)
                    .map(|i| {
                        let mut rng = Xoshiro256PlusPlus::seed_from_u64(pixel_seed(
                            scene.seed,
                            (j * w + i) as u64,
                        ));
                        let mut acc = ([[0.0; 3]; MAX_GROUPS], [[0.0; 3]; MAX_GROUPS], 0.0);
                        for _ in 0..scene.spp {
                            let x = (2.0 * (i as f64 + rng.random::<f64>()) / w as f64 - 1.0)
                                * tan
                                * aspect;
                            let y = (1.0 - 2.0 * (j as f64 + rng.random::<f64>()) / h as f64) * tan;
                            let dir = normalize(std::array::from_fn(|k| {
                                fwd[k] + x * right[k] + y * up[k]
                            }));
                            let p = trace(&volume, cam.position, dir, &mut rng);
                            for g in 0..MAX_GROUPS {
                                for c in 0..3 {
                                    acc.0[g][c] += p.groups[g][c];
                                    acc.1[g][c] += p.sky_groups[g][c];
                                }
                            }
                            acc.2 += p.transmittance;
                        }
                        acc
                    })
                    .collect();
                progress(done.fetch_add(1, std::sync::atomic::Ordering::Relaxed) + 1);
                row
            })
            .collect()
    });
    let seconds = t0.elapsed().as_secs_f64();
    let n = scene.spp as f64;
    let (sun, sky) = (scene.sun.irradiance, scene.sky);
    let mut out = Rendered {
        width: w,
        height: h,
        groups: vec![0.0; ng * h * w * 3],
        unscattered: vec![0.0; h * w * 3],
        transmittance: vec![0.0; h * w],
        beauty: vec![0.0; h * w * 3],
        seconds,
        paths: (w * h) as u64 * scene.spp as u64,
    };
    for (j, row) in rows.iter().enumerate() {
        for (i, (g_sun, g_sky, tr)) in row.iter().enumerate() {
            let px = j * w + i;
            out.transmittance[px] = (tr / n) as f32;
            for c in 0..3 {
                let mut total = tr / n * sky[c];
                out.unscattered[px * 3 + c] = total as f32;
                for g in 0..ng {
                    let v = (g_sun[g][c] * sun[c] + g_sky[g][c] * sky[c]) / n;
                    out.groups[(g * h * w + px) * 3 + c] = v as f32;
                    total += v;
                }
                out.beauty[px * 3 + c] = total as f32;
            }
        }
    }
    Ok(out)
}
