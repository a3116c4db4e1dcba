//! What `nephele render` writes: the beauty image as OpenEXR (linear, f32 RGB), PNG
//! (tone-mapped, sRGB-encoded) and .npy (linear), the per-order-group radiance, the unscattered sky, the transmittance and the
//! opacity as .npy (float32, row 0 at the top), and a JSON sidecar — all atomically.

use super::image::{Rendered, GROUP_FIRST};
use super::scene::Scene;
use crate::io::npy::npy_bytes;
use crate::io::AtomicFiles;
use anyhow::Result;
use std::io::Write;
use std::path::Path;

/// Pixels more opaque than this are the cloud's, for the automatic exposure (the same
/// threshold as `nephele compare`'s "opaque" pixels).
pub const CLOUD_OPACITY: f32 = 0.5;

/// The automatic exposure looks at the cloud alone when it covers at least this share of the
/// frame; a smaller cloud (a few pixels, or none) leaves it to the whole frame.
const MIN_CLOUD_SHARE: f64 = 0.01;

/// An exposure k (per unit of linear radiance: the tone curve is 1 − e^{−k x}) and how it was
/// chosen: "cloud", "frame" or "--exposure" (render.json records both).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Exposure {
    /// k (1 / radiance).
    pub k: f32,
    /// How it was chosen.
    pub from: &'static str,
}

/// The automatic exposure of `rgb` (linear, [pixel, RGB]): 1 − e^{−k p90} = 0.75 with p90 the
/// 90th percentile of the luminance over the cloud's pixels (`opacity` > [`CLOUD_OPACITY`]),
/// or over the whole frame when the cloud covers less than 1 % of it. On the cloud, because
/// a bright sky around a small cloud would otherwise set k and leave the cloud flat white; a
/// percentile, because rare bright samples of a noisy image must not set it.
pub fn exposure(rgb: &[f32], opacity: &[f32]) -> Exposure {
    let lum = |p: &[f32]| 0.2126 * p[0] + 0.7152 * p[1] + 0.0722 * p[2];
    let cloud: Vec<f32> = rgb
        .chunks_exact(3)
        .zip(opacity)
        .filter(|(_, &a)| a > CLOUD_OPACITY)
        .map(|(p, _)| lum(p))
        .collect();
    let enough = !cloud.is_empty() && cloud.len() as f64 >= MIN_CLOUD_SHARE * opacity.len() as f64;
    let (mut values, from) = if enough {
        (cloud, "cloud")
    } else {
        (rgb.chunks_exact(3).map(lum).collect(), "frame")
    };
    values.sort_by(f32::total_cmp);
    let p90 = values.get(values.len() * 9 / 10).copied().unwrap_or(0.0);
    if !(p90 > BLACK) {
        // A black frame: any k shows it black, and 1 keeps render.json's value readable.
        return Exposure {
            k: 1.0,
            from: "black frame",
        };
    }
    Exposure {
        k: (4.0f32).ln() / p90,
        from,
    }
}

/// A luminance below which a frame is black (radiance in the scene's units, where the sun's
/// irradiance and the sky are of order 1).
const BLACK: f32 = 1e-12;

/// What a frame itself says is likely wrong: no pixel of the medium in view (a camera looking
/// away from it, or densities all 0).
pub fn frame_warnings(opacity: &[f32]) -> Vec<String> {
    let largest = opacity.iter().copied().fold(0.0f32, f32::max);
    if largest > CLOUD_OPACITY {
        return Vec::new();
    }
    vec![format!(
        "no pixel of the frame is opaque (the largest opacity is {largest:.3}, the cloud's pixels \
         have > {CLOUD_OPACITY}): the camera looks away from the medium, or its densities are \
         all 0; check camera.look_at and the medium"
    )]
}

const EXPOSURE_RULE: &str = "K multiplies the linear radiance before 1 - exp(-K x) and must \
    be a positive number (render.json records the automatic one)";

fn is_exposure(k: f32) -> bool {
    k.is_finite() && k > 0.0
}

/// Parses a user's exposure K (`--exposure`): a positive, finite number.
pub fn parse_exposure(s: &str) -> std::result::Result<f32, String> {
    match s.parse::<f32>() {
        Ok(k) if is_exposure(k) => Ok(k),
        _ => Err(EXPOSURE_RULE.to_string()),
    }
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

/// An 8-bit RGB image of w × h pixels as PNG bytes.
pub fn png_bytes(rgb: &[u8], (w, h): (usize, usize)) -> Result<Vec<u8>> {
    let mut bytes = Vec::new();
    image::ImageEncoder::write_image(
        image::codecs::png::PngEncoder::new(&mut bytes),
        rgb,
        w as u32,
        h as u32,
        image::ColorType::Rgb8,
    )?;
    Ok(bytes)
}

/// Writes every output of `r` into `out`, beauty.png at the automatic exposure.
pub fn write_outputs(out: &Path, scene: &Scene, r: &Rendered) -> Result<()> {
    write_outputs_with(out, scene, r, None)
}

/// Writes every output of `r` into `out`, beauty.png at exposure `k` (1 / radiance; None:
/// the automatic [`exposure`]).
pub fn write_outputs_with(out: &Path, scene: &Scene, r: &Rendered, k: Option<f32>) -> Result<()> {
    if let Some(k) = k {
        anyhow::ensure!(is_exposure(k), "exposure {k}: {EXPOSURE_RULE}");
    }
    crate::io::output_dir(out)?;
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
    let chosen = match k {
        Some(k) => Exposure {
            k,
            from: "--exposure",
        },
        None => exposure(&r.beauty, &opacity),
    };
    let png = png_bytes(&tone_map_with(&r.beauty, chosen.k), (r.width, r.height))?;
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
            "beauty.png": "tone-mapped: 1 - exp(-k x) with k the exposure (the automatic one: the 90th percentile of the cloud's luminance, or the frame's when the cloud covers < 1 %, at 0.75), sRGB",
    });
    if !r.halves.is_empty() {
        files_doc["halves.npy"] = "[2, group, H, W, 3] groups.npy from the even and from the odd samples of each pixel: (A - B)^2 / 4 estimates the variance of a pixel's mean".into();
    }
    if !r.regions.is_empty() {
        files_doc["regions.npy"] = "[H, W] uint8: 0 opacity <= 0.5, 1 lit face (sun optical depth < 2 at the visible surface point), 2 shadowed face, 3 silhouette (0.5 < opacity < 0.99)".into();
    }
    let warnings = [scene.warnings(), frame_warnings(&opacity)].concat();
    let sidecar = serde_json::json!({
        "method": r.method,
        "details": r.details,
        "scene": scene,
        "warnings": warnings,
        "width": w,
        "height": h,
        "spp": r.spp,
        "paths": r.paths,
        "seconds": r.seconds,
        "paths_per_second": r.paths as f64 / r.seconds.max(1e-9),
        "threads": rayon::current_num_threads(),
        "exposure": chosen.k,
        "exposure_from": chosen.from,
        "group_first_orders": GROUP_FIRST,
        "units": "linear radiance, the sun's irradiance and the sky's radiance as given in the scene (RGB); row 0 at the top",
        "files": files_doc,
        "version": crate::VERSION,
        "git_commit": option_env!("NEPHELE_GIT_COMMIT"),
    });
    let mut json = serde_json::to_vec_pretty(&sidecar)?;
    json.write_all(b"\n")?;
    files.write_bytes(&out.join("render.json"), &json)?;
    // The folder holds one render: an optional file this render does not write is an
    // earlier render's, and would be read as this one's (a collector's "halves.npy").
    for name in OPTIONAL_FILES {
        if files_doc.get(name).is_none() {
            remove_stale(&out.join(name))?;
        }
    }
    files.commit()
}

/// The files only some renders write.
const OPTIONAL_FILES: [&str; 2] = ["halves.npy", "regions.npy"];

fn remove_stale(path: &Path) -> Result<()> {
    match std::fs::remove_file(path) {
        Err(e) if e.kind() != std::io::ErrorKind::NotFound => Err(anyhow::anyhow!(
            "cannot remove the earlier render's '{}': {e}",
            path.display()
        )),
        _ => Ok(()),
    }
}
