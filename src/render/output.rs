//! What `nephele render` writes: the beauty image as OpenEXR (linear, f32 RGB), PNG
//! (tone-mapped, sRGB-encoded) and .npy (linear), the per-order-group radiance, the unscattered sky, the transmittance and the
//! opacity as .npy (float32, row 0 at the top), and a JSON sidecar — all atomically.

use super::image::{Rendered, GROUP_FIRST};
use super::scene::Scene;
use crate::io::AtomicFiles;
use anyhow::{Context, Result};
use npyz::WriterBuilder;
use std::io::Write;
use std::path::Path;

/// A .npy of `shape` (float32, or uint8 for the regions).
fn npy_bytes<T: npyz::AutoSerialize + Copy>(shape: &[u64], data: &[T]) -> Result<Vec<u8>> {
    let mut bytes = Vec::new();
    {
        let mut w = npyz::WriteOptions::<T>::new()
            .default_dtype()
            .shape(shape)
            .writer(&mut bytes)
            .begin_nd()?;
        w.extend(data.iter().copied())?;
        w.finish()?;
    }
    Ok(bytes)
}

/// Linear radiance to 8-bit sRGB: exposure so that the 90th percentile of the luminance maps to
/// 0.75 before the curve 1 − e^{−x} (soft highlights; rare bright samples of a noisy image do
/// not set the exposure), then the sRGB transfer function.
pub fn tone_map(beauty: &[f32]) -> Vec<u8> {
    tone_map_with(beauty, exposure(beauty))
}

/// The exposure k of [`tone_map`]: 1 − e^{−k p90} = 0.75, p90 the 90th percentile of the
/// luminance.
pub fn exposure(beauty: &[f32]) -> f32 {
    let mut lum: Vec<f32> = beauty
        .chunks_exact(3)
        .map(|p| 0.2126 * p[0] + 0.7152 * p[1] + 0.0722 * p[2])
        .collect();
    lum.sort_by(f32::total_cmp);
    let p90 = lum
        .get(lum.len() * 9 / 10)
        .copied()
        .unwrap_or(1.0)
        .max(1e-12);
    (4.0f32).ln() / p90
}

/// Linear radiance to 8-bit sRGB with exposure `k`: 1 − e^{−k x}, then the sRGB curve.
pub fn tone_map_with(beauty: &[f32], k: f32) -> Vec<u8> {
    beauty
        .iter()
        .map(|&v| {
            let x = 1.0 - (-k * v.max(0.0)).exp();
            let s = if x <= 0.003_130_8 {
                12.92 * x
            } else {
                1.055 * x.powf(1.0 / 2.4) - 0.055
            };
            (s * 255.0 + 0.5).clamp(0.0, 255.0) as u8
        })
        .collect()
}

/// Writes every output of `r` into `out`.
pub fn write_outputs(out: &Path, scene: &Scene, r: &Rendered) -> Result<()> {
    std::fs::create_dir_all(out).with_context(|| format!("cannot create '{}'", out.display()))?;
    let (w, h) = (r.width as u64, r.height as u64);
    let ng = GROUP_FIRST.len() as u64;
    let mut files = AtomicFiles::new();
    for (name, shape, data) in [
        ("beauty.npy", vec![h, w, 3], &r.beauty),
        ("groups.npy", vec![ng, h, w, 3], &r.groups),
        ("unscattered.npy", vec![h, w, 3], &r.unscattered),
        ("transmittance.npy", vec![h, w], &r.transmittance),
    ] {
        files.write_bytes(&out.join(name), &npy_bytes(&shape, data)?)?;
    }
    let opacity: Vec<f32> = r.transmittance.iter().map(|t| 1.0 - t).collect();
    files.write_bytes(&out.join("opacity.npy"), &npy_bytes(&[h, w], &opacity)?)?;
    if !r.halves.is_empty() {
        let shape = [2, ng, h, w, 3];
        files.write_bytes(&out.join("halves.npy"), &npy_bytes(&shape, &r.halves)?)?;
    }
    if !r.regions.is_empty() {
        files.write_bytes(&out.join("regions.npy"), &npy_bytes(&[h, w], &r.regions)?)?;
    }
    let mut png = Vec::new();
    image::ImageEncoder::write_image(
        image::codecs::png::PngEncoder::new(&mut png),
        &tone_map(&r.beauty),
        w as u32,
        h as u32,
        image::ColorType::Rgb8,
    )?;
    files.write_bytes(&out.join("beauty.png"), &png)?;
    files.write_via_path(&out.join("beauty.exr"), |p| {
        let px = |x: usize, y: usize| {
            let i = (y * r.width + x) * 3;
            (r.beauty[i], r.beauty[i + 1], r.beauty[i + 2])
        };
        // Blocks compressed in parallel are written in the order they finish: one thread
        // keeps the file the same bits from run to run.
        let channels = exr::prelude::SpecificChannels::rgb(|exr::prelude::Vec2(x, y)| px(x, y));
        use exr::prelude::WritableImage;
        exr::prelude::Image::from_channels((r.width, r.height), channels)
            .write()
            .non_parallel()
            .to_file(p)
            .map_err(|e| anyhow::anyhow!("OpenEXR: {e}"))
    })?;
    let mut files_doc = serde_json::json!({
            "beauty.npy": "[H, W, 3] the sum of groups.npy over groups and unscattered.npy",
            "groups.npy": "[group, H, W, 3] radiance scattered n times, n in the group (first orders in group_first_orders; sun and sky)",
            "unscattered.npy": "[H, W, 3] the sky seen through the medium",
            "transmittance.npy": "[H, W] transmittance of the camera ray through the medium",
            "opacity.npy": "[H, W] 1 - transmittance",
            "beauty.exr": "[H, W] RGB f32, linear (OpenEXR)",
            "beauty.png": "tone-mapped (90th percentile of luminance at 0.75 of 1 - exp(-x)), sRGB",
    });
    if !r.halves.is_empty() {
        files_doc["halves.npy"] = "[2, group, H, W, 3] groups.npy from the even and from the odd samples of each pixel: (A - B)^2 / 4 estimates the variance of a pixel's mean".into();
    }
    if !r.regions.is_empty() {
        files_doc["regions.npy"] = "[H, W] uint8: 0 opacity <= 0.5, 1 lit face (sun optical depth < 2 at the visible surface point), 2 shadowed face, 3 silhouette (0.5 < opacity < 0.99)".into();
    }
    let sidecar = serde_json::json!({
        "method": r.method,
        "details": r.details,
        "scene": scene,
        "width": w,
        "height": h,
        "spp": r.spp,
        "paths": r.paths,
        "seconds": r.seconds,
        "paths_per_second": r.paths as f64 / r.seconds.max(1e-9),
        "threads": rayon::current_num_threads(),
        "group_first_orders": GROUP_FIRST,
        "units": "linear radiance, the sun's irradiance and the sky's radiance as given in the scene (RGB); row 0 at the top",
        "files": files_doc,
        "version": crate::VERSION,
        "git_commit": option_env!("NEPHELE_GIT_COMMIT"),
    });
    let mut json = serde_json::to_vec_pretty(&sidecar)?;
    json.write_all(b"\n")?;
    files.write_bytes(&out.join("render.json"), &json)?;
    files.commit()
}
