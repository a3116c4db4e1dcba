//! The ground-truth volumetric path tracer (docs/render.md): rows of pixels in parallel through
//! the shared pinhole camera, each pixel's samples drawn from its own random stream
//! (xoshiro256++ seeded by a hash of the scene's seed and the pixel), so the image is the same
//! bits for any thread count; passes while a time budget lasts. The estimator is
//! [`integrator`], its sun-lobe next-event estimation [`sun_lobe`].

pub mod integrator;
pub mod sun_lobe;

use super::camera::Pinhole;
use super::image::{Rendered, GROUP_FIRST};
use super::medium::Medium;
use super::scene::Scene;
use super::surface::Surfaces;
use crate::phase::Phase;
use anyhow::{ensure, Result};
use integrator::{channel_tables, trace, Volume};
use nephele_runtime::PhaseFunction;
use rand::{Rng, SeedableRng};
use rand_xoshiro::Xoshiro256PlusPlus;
use rayon::prelude::*;
use std::sync::atomic::{AtomicUsize, Ordering};
use std::sync::Mutex;
use std::time::Instant;
use sun_lobe::SunLobe;

/// The seed of pixel `i`'s stream (SplitMix64).
fn pixel_seed(seed: u64, i: u64) -> u64 {
    crate::stats::splitmix64(seed ^ i.wrapping_mul(0x9E37_79B9_7F4A_7C15))
}

/// Per-pixel sums of one half of the samples (the even or the odd ones): [sun group g
/// channel c] at g·3 + c, [sky group g channel c] after those, then the lights' [group g
/// channel c], then the camera ray's transmittance where it reaches the sky (0 where a surface
/// hides it; 0 without a sky), then its transmittance; a pixel holds the two halves one after
/// the other.
fn stride() -> usize {
    3 * GROUP_FIRST.len() * 3 + 2
}

/// The light of group g, channel c in one half's sums: the sun's and the sky's scaled by the
/// scene's irradiance and radiance, the lights' as they are.
fn light_of(part: &[f64], ng: usize, g: usize, c: usize, sun: &[f64; 3], sky: &[f64; 3]) -> f64 {
    part[g * 3 + c] * sun[c] + part[(ng + g) * 3 + c] * sky[c] + part[(2 * ng + g) * 3 + c]
}

/// What a render has done so far, for a progress display.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct Progress {
    /// Fraction done: of the rows (a fixed spp) or of the time budget.
    pub fraction: f64,
    /// Passes finished (with a time budget, passes of the scene's spp follow one another).
    pub passes: u32,
    /// Samples per pixel finished.
    pub spp: u32,
    /// The noise so far: the relative standard error of a pixel's scattered light,
    /// √⟨(A − B)²/4⟩ / ⟨(A + B)/2⟩ over every pixel and channel, A and B the means of its even
    /// and odd samples (the reference noise `nephele compare` reports); none before both
    /// halves have samples.
    pub noise: Option<f64>,
}

impl Progress {
    /// "pass 3, 24 spp, pixel noise 4.1 %".
    pub fn summary(&self) -> String {
        let noise = self.noise.map_or(String::new(), |n| {
            format!(", pixel noise {:.1} %", 100.0 * n)
        });
        format!("pass {}, {} spp{noise}", self.passes, self.spp)
    }
}

/// Renders `scene`; `progress(fraction done)` as rows finish. See [`render_reporting`].
pub fn render(scene: &Scene, progress: &(dyn Fn(f64) + Sync)) -> Result<Rendered> {
    render_reporting(scene, &|p| progress(p.fraction))
}

/// Renders `scene`; `progress` as rows finish, with the passes, spp and noise so far. With a
/// time budget, passes of `spp` samples per pixel follow one another while the next one is
/// predicted to fit (at least one): each pixel's stream continues across passes, so k passes
/// give the same bits as one render at k · spp.
pub fn render_reporting(scene: &Scene, progress: &(dyn Fn(&Progress) + Sync)) -> Result<Rendered> {
    // The path tracer's own limit: the scene knows no renderer.
    ensure!(
        scene.sun_lobe_steps <= sun_lobe::MAX_STEPS,
        "sun_lobe_steps must be 0…{} (the scene has {})",
        sun_lobe::MAX_STEPS,
        scene.sun_lobe_steps
    );
    let medium = scene.build_medium()?;
    let surfaces = Surfaces::build(&scene.surfaces)?;
    let models = Phase::build_channels(&scene.phase)?;
    let cam = Pinhole::new(&scene.camera);
    let (w, h) = (cam.width, cam.height);
    let (ng, stride) = (GROUP_FIRST.len(), stride());
    let mut sums = vec![0.0f64; w * h * 2 * stride];
    let mut rngs: Vec<Xoshiro256PlusPlus> = (0..w * h)
        .map(|px| Xoshiro256PlusPlus::seed_from_u64(pixel_seed(scene.seed, px as u64)))
        .collect();
    let rows_done = AtomicUsize::new(0);
    let t0 = Instant::now();
    let state = Mutex::new(Progress::default());
    let report = || {
        let rows = rows_done.fetch_add(1, Ordering::Relaxed) + 1;
        let mut p = state.lock().unwrap_or_else(|e| e.into_inner());
        p.fraction = match scene.time_budget_s {
            Some(budget) => (t0.elapsed().as_secs_f64() / budget).min(1.0),
            None => rows as f64 / h as f64,
        };
        progress(&p);
    };
    let mut passes = 0u32;
    Phase::with_all(&models, |phases| {
        let volume = volume(scene, medium.as_ref(), &surfaces, phases);
        loop {
            let pass_start = t0.elapsed().as_secs_f64();
            let first = passes as u64 * scene.spp as u64;
            sums.par_chunks_mut(w * 2 * stride)
                .zip(rngs.par_chunks_mut(w))
                .enumerate()
                .for_each(|(j, (row, row_rngs))| {
                    for (i, (both, rng)) in row.chunks_mut(2 * stride).zip(row_rngs).enumerate() {
                        for k in 0..scene.spp as u64 {
                            let half = ((first + k) & 1) as usize;
                            let px = &mut both[half * stride..(half + 1) * stride];
                            let dir = cam.direction(i, j, rng.random(), rng.random());
                            let p = trace(&volume, cam.position, dir, rng);
                            for g in 0..ng {
                                for c in 0..3 {
                                    px[g * 3 + c] += p.groups[g][c];
                                    px[(ng + g) * 3 + c] += p.sky_groups[g][c];
                                    px[(2 * ng + g) * 3 + c] += p.light_groups[g][c];
                                }
                            }
                            px[stride - 2] += p.unscattered;
                            px[stride - 1] += p.transmittance;
                        }
                    }
                    report();
                });
            passes += 1;
            let Some(budget) = scene.time_budget_s else {
                break;
            };
            // Cheap beside a pass (a few adds per pixel against spp paths): shown between passes.
            let spp = scene.spp * passes;
            let noise = noise_so_far(scene, &sums, spp);
            let now = t0.elapsed().as_secs_f64();
            let mut p = state.lock().unwrap_or_else(|e| e.into_inner());
            *p = Progress {
                fraction: (now / budget).min(1.0),
                passes,
                spp,
                noise,
            };
            progress(&p);
            drop(p);
            if now + (now - pass_start) > budget || passes >= max_passes(scene.spp) {
                break;
            }
        }
    });
    let spp = scene.spp * passes;
    Ok(gather(scene, &cam, &sums, spp, t0.elapsed().as_secs_f64()))
}

/// [`Progress::noise`] from the per-pixel sums of `spp` samples (two halves each); none below
/// two samples or without light.
fn noise_so_far(scene: &Scene, sums: &[f64], spp: u32) -> Option<f64> {
    if spp < 2 {
        return None;
    }
    let (ng, stride) = (GROUP_FIRST.len(), stride());
    let counts = [spp.div_ceil(2) as f64, (spp / 2) as f64];
    let (sun, sky) = (scene.sun.irradiance, scene.sky);
    let (mut var, mut mean) = (0.0, 0.0);
    for both in sums.chunks(2 * stride) {
        for c in 0..3 {
            let half = |k: usize| {
                let part = &both[k * stride..(k + 1) * stride];
                let light: f64 = (0..ng).map(|g| light_of(part, ng, g, c, &sun, &sky)).sum();
                light / counts[k]
            };
            let (a, b) = (half(0), half(1));
            var += 0.25 * (a - b) * (a - b);
            mean += 0.5 * (a + b);
        }
    }
    let n = (3 * sums.len() / (2 * stride)) as f64; // pixels × channels
    (mean > 0.0).then(|| (var / n).sqrt() / (mean / n))
}

/// The estimator's view of `scene` (medium, surfaces and phase functions built): the sun's irradiance
/// and the sky's radiance are 1 here and applied per channel when the images are gathered.
pub fn volume<'a>(
    scene: &'a Scene,
    medium: &'a dyn Medium,
    surfaces: &'a Surfaces,
    phases: &'a [&'a (dyn PhaseFunction<f64> + Sync)],
) -> Volume<'a> {
    let has_sky = scene.sky.iter().any(|&s| s > 0.0);
    Volume {
        medium,
        albedo: scene.albedo,
        phases,
        channels: channel_tables(phases),
        sun_dir: scene.sun.direction,
        sun_irradiance: 1.0,
        sky: if has_sky { 1.0 } else { 0.0 },
        group_first: &GROUP_FIRST,
        sun_lobe: SunLobe::new(scene.sun_lobe_steps, phases),
        lights: &scene.lights,
        surfaces,
    }
}

/// Most passes of a time-budgeted render: 4096, and spp · passes below 2³².
fn max_passes(spp: u32) -> u32 {
    (u32::MAX / spp.max(1)).min(4096)
}

/// The images from the per-pixel sums of `spp` samples (two halves each), scaled by the sun's
/// irradiance and the sky's radiance.
fn gather(scene: &Scene, cam: &Pinhole, sums: &[f64], spp: u32, seconds: f64) -> Rendered {
    let (w, h, ng, stride) = (cam.width, cam.height, GROUP_FIRST.len(), stride());
    let n = spp as f64;
    let counts = [spp.div_ceil(2) as f64, (spp / 2) as f64];
    let (sun, sky) = (scene.sun.irradiance, scene.sky);
    let mut out = Rendered::empty(w, h);
    out.seconds = seconds;
    out.paths = (w * h) as u64 * spp as u64;
    out.spp = spp;
    out.method = "path_tracer".into();
    out.halves = vec![0.0; 2 * ng * h * w * 3];
    for (px, both) in sums.chunks(2 * stride).enumerate() {
        let (a, b) = both.split_at(stride);
        for (half, part) in [a, b].into_iter().enumerate() {
            for g in 0..ng {
                for c in 0..3 {
                    let v = light_of(part, ng, g, c, &sun, &sky) / counts[half].max(1.0);
                    out.halves[((half * ng + g) * h * w + px) * 3 + c] = v as f32;
                }
            }
        }
        let s: Vec<f64> = (0..stride).map(|k| a[k] + b[k]).collect();
        let tr = s[stride - 1] / n;
        // The camera ray's transmittance where it reaches the sky (a surface hides it).
        let to_sky = s[stride - 2] / n;
        out.transmittance[px] = tr as f32;
        for c in 0..3 {
            let mut total = to_sky * sky[c];
            out.unscattered[px * 3 + c] = total as f32;
            for g in 0..ng {
                let v = light_of(&s, ng, g, c, &sun, &sky) / n;
                out.groups[(g * h * w + px) * 3 + c] = v as f32;
                total += v;
            }
            out.beauty[px * 3 + c] = total as f32;
        }
    }
    out
}
