//! The ground-truth volumetric path tracer (docs/render.md): rows of pixels in parallel through
//! the shared pinhole camera, each pixel's samples drawn from its own random stream
//! (xoshiro256++ seeded by a hash of the settings' seed and the pixel), so the image is the
//! same bits for any thread count; passes while a time budget lasts. The estimator is
//! [`integrator`], its sun-lobe next-event estimation [`sun_lobe`], its [`settings`] apart from
//! the scene.

pub mod integrator;
pub mod settings;
pub mod sun_lobe;

pub use settings::Settings;

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
use std::sync::atomic::{AtomicBool, AtomicUsize, Ordering};
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
    /// Passes finished (with a time budget, passes of the settings' spp follow one another).
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

/// Renders `scene` with `settings`; `progress(fraction done)` as rows finish. See
/// [`render_reporting`].
pub fn render(
    scene: &Scene,
    settings: &Settings,
    progress: &(dyn Fn(f64) + Sync),
) -> Result<Rendered> {
    render_reporting(scene, settings, &|p| progress(p.fraction))
}

/// Renders `scene` with `settings`; `progress` as rows finish, with the passes, spp and noise
/// so far. See [`render_until`].
pub fn render_reporting(
    scene: &Scene,
    settings: &Settings,
    progress: &(dyn Fn(&Progress) + Sync),
) -> Result<Rendered> {
    render_until(scene, settings, progress, &AtomicBool::new(false))
}

/// Renders `scene` until it is done, the settings' time budget is spent or `stop` is set
/// (Ctrl-C).
///
/// Without a budget: one pass of the settings' spp. With one, a first pass of 2 samples per
/// pixel (every pixel gets light and a noise estimate), then passes of a tenth of the budget (at
/// most the settings' spp) while it lasts; rows not started when it runs out are left out of the
/// last pass, so the budget caps the render to within one row's work. Each pixel's stream continues
/// across passes and its even and odd samples are its halves, so a render's bits depend only
/// on how many samples each row got: k whole passes give the bits of one render at k · spp.
/// `stop` ends the render the same way, after a budgeted render's first pass; without a
/// budget, before its one pass has finished, it is an error, as nothing could be written.
pub fn render_until(
    scene: &Scene,
    settings: &Settings,
    progress: &(dyn Fn(&Progress) + Sync),
    stop: &AtomicBool,
) -> Result<Rendered> {
    settings.validate()?;
    let medium = scene.build_medium()?;
    let surfaces = Surfaces::build(&scene.surfaces)?;
    let models = Phase::build_channels(&scene.phase)?;
    let cam = Pinhole::new(&scene.camera);
    let (w, h) = (cam.width, cam.height);
    let (ng, stride) = (GROUP_FIRST.len(), stride());
    let mut sums = vec![0.0f64; w * h * 2 * stride];
    let mut rngs: Vec<Xoshiro256PlusPlus> = (0..w * h)
        .map(|px| Xoshiro256PlusPlus::seed_from_u64(pixel_seed(settings.seed, px as u64)))
        .collect();
    // Samples each row's pixels have.
    let mut row_spp = vec![0u32; h];
    let rows_done = AtomicUsize::new(0);
    let t0 = Instant::now();
    let over = || {
        let spent = settings
            .time_budget_s
            .is_some_and(|b| t0.elapsed().as_secs_f64() >= b);
        spent || stop.load(Ordering::Relaxed)
    };
    let state = Mutex::new(Progress::default());
    let report = || {
        let rows = rows_done.fetch_add(1, Ordering::Relaxed) + 1;
        let mut p = state.lock().unwrap_or_else(|e| e.into_inner());
        p.fraction = match settings.time_budget_s {
            Some(budget) => (t0.elapsed().as_secs_f64() / budget).min(1.0),
            None => rows as f64 / h as f64,
        };
        progress(&p);
    };
    let mut passes = 0u32;
    let mut spp = match settings.time_budget_s {
        Some(_) => settings.spp.min(2),
        None => settings.spp,
    };
    Phase::with_all(&models, |phases| {
        let volume = volume(scene, settings, medium.as_ref(), &surfaces, phases);
        loop {
            let first_pass = passes == 0;
            let budgeted = settings.time_budget_s.is_some();
            let ran = AtomicBool::new(false);
            sums.par_chunks_mut(w * 2 * stride)
                .zip(rngs.par_chunks_mut(w))
                .zip(row_spp.par_iter_mut())
                .enumerate()
                .for_each(|(j, ((row, row_rngs), done))| {
                    // A budgeted render's first pass (2 samples) is whole, so that a budget
                    // or a Ctrl-C always leaves an image; any other pass stops at either.
                    if !(first_pass && budgeted) && over() {
                        return;
                    }
                    for (i, (both, rng)) in row.chunks_mut(2 * stride).zip(row_rngs).enumerate() {
                        for k in 0..spp as u64 {
                            let half = ((*done as u64 + k) & 1) as usize;
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
                    *done += spp;
                    ran.store(true, Ordering::Relaxed);
                    report();
                });
            // A pass the budget cut before any row started is no pass.
            if !ran.into_inner() {
                break;
            }
            passes += 1;
            let Some(budget) = settings.time_budget_s else {
                break;
            };
            // Cheap beside a pass (a few adds per pixel against spp paths): shown between passes.
            let noise = noise_so_far(scene, &sums, &row_spp, w);
            let now = t0.elapsed().as_secs_f64();
            let mut p = state.lock().unwrap_or_else(|e| e.into_inner());
            *p = Progress {
                fraction: (now / budget).min(1.0),
                passes,
                spp: row_spp.iter().copied().min().unwrap_or(0),
                noise,
            };
            progress(&p);
            drop(p);
            if over() || passes >= max_passes(spp) {
                break;
            }
            if first_pass {
                spp = budgeted_pass(settings.spp, budget, now / spp as f64);
            }
        }
    });
    let interrupted = stop.load(Ordering::Relaxed);
    ensure!(
        row_spp.iter().all(|&n| n > 0),
        "interrupted before every pixel had a sample: nothing to write"
    );
    let mut r = gather(scene, &cam, &sums, &row_spp, t0.elapsed().as_secs_f64());
    r.details = serde_json::json!({
        "passes": passes,
        "samples_per_pixel": samples_summary(&row_spp),
        "interrupted": interrupted,
        "settings": settings,
    });
    Ok(r)
}

/// The least, the most and the mean samples per pixel over the rows.
fn samples_summary(row_spp: &[u32]) -> serde_json::Value {
    let min = row_spp.iter().copied().min().unwrap_or(0);
    let max = row_spp.iter().copied().max().unwrap_or(0);
    let mean = row_spp.iter().map(|&n| n as f64).sum::<f64>() / row_spp.len().max(1) as f64;
    serde_json::json!({"min": min, "max": max, "mean": mean})
}

/// Samples in the even and in the odd half of `n` samples.
fn half_counts(n: u32) -> [f64; 2] {
    [n.div_ceil(2) as f64, (n / 2) as f64]
}

/// [`Progress::noise`] from the per-pixel sums (two halves each) of `row_spp` samples per row
/// of `w` pixels; none until both halves of every pixel have samples, or without light.
fn noise_so_far(scene: &Scene, sums: &[f64], row_spp: &[u32], w: usize) -> Option<f64> {
    if row_spp.iter().any(|&n| n < 2) {
        return None;
    }
    let (ng, stride) = (GROUP_FIRST.len(), stride());
    let (sun, sky) = (scene.sun.irradiance, scene.sky);
    let (mut var, mut mean) = (0.0, 0.0);
    for (px, both) in sums.chunks(2 * stride).enumerate() {
        let counts = half_counts(row_spp[px / w]);
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

/// The estimator's view of `scene` (medium, surfaces and phase functions built) under
/// `settings`: the sun's irradiance and the sky's radiance are 1 here and applied per channel
/// when the images are gathered.
pub fn volume<'a>(
    scene: &'a Scene,
    settings: &Settings,
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
        sun_lobe: SunLobe::new(settings.sun_lobe_steps, phases),
        lights: &scene.lights,
        surfaces,
    }
}

/// The samples per pixel of a budgeted render's passes after the first: a tenth of the
/// `budget` (s) at `per_sample` seconds a sample per pixel, so that the pass the budget cuts
/// leaves rows at most a tenth of the budget's samples apart; between 2 and the settings' spp.
fn budgeted_pass(spp: u32, budget: f64, per_sample: f64) -> u32 {
    let fit = (0.1 * budget / per_sample.max(1e-9)).floor();
    (fit.min(spp as f64) as u32).max(2.min(spp))
}

/// Most passes of a time-budgeted render: 4096, and spp · passes below 2³².
fn max_passes(spp: u32) -> u32 {
    (u32::MAX / spp.max(1)).min(4096)
}

/// The images from the per-pixel sums (two halves each) of `row_spp` samples per row, scaled
/// by the sun's irradiance and the sky's radiance.
fn gather(scene: &Scene, cam: &Pinhole, sums: &[f64], row_spp: &[u32], seconds: f64) -> Rendered {
    let (w, h, ng, stride) = (cam.width, cam.height, GROUP_FIRST.len(), stride());
    let (sun, sky) = (scene.sun.irradiance, scene.sky);
    let mut out = Rendered::empty(w, h);
    out.seconds = seconds;
    out.paths = row_spp.iter().map(|&n| w as u64 * n as u64).sum();
    out.spp = row_spp.iter().copied().min().unwrap_or(0);
    out.method = "path_tracer".into();
    out.halves = vec![0.0; 2 * ng * h * w * 3];
    for (px, both) in sums.chunks(2 * stride).enumerate() {
        let n = row_spp[px / w] as f64;
        let counts = half_counts(row_spp[px / w]);
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
