//! The comparison's figures: panel.png (reference and candidates per order group) and
//! errors.png (signed relative error maps and their colour bar).

use super::super::output::{exposure as auto_exposure, tone_map_with};
use super::load::RenderDir;
use super::stats::{group_quantities, Quantity};
use crate::io::plot::{image_grid, image_grid_with_bar, text_width, ColourBar, Tile};
use crate::io::AtomicFiles;
use anyhow::Result;
use std::path::Path;

/// The colour bar of [`error_image`]: −50 % on the left, +50 % on the right, `w` pixels wide,
/// with its ticks at −50, −25, 0, +25 and +50 %.
pub(super) fn colour_bar(w: usize) -> ColourBar {
    let error = |i: usize| (i as f64 + 0.5) / w as f64 - 0.5;
    let c: Vec<f64> = (0..w).map(|i| 1.0 + error(i)).collect();
    ColourBar {
        rgb: error_image(&c, &vec![1.0; w], &vec![true; w]),
        label: "(c − r)/⟨r⟩".into(),
        ticks: ["−50 %", "−25 %", "0", "+25 %", "+50 %"]
            .iter()
            .enumerate()
            .map(|(k, t)| (k as f64 / 4.0, t.to_string()))
            .collect(),
    }
}

/// The signed relative error (c − r)/r̄ per pixel as false colour: blue −50 %, white 0, red
/// +50 % (r̄ the reference's opaque mean; transparent pixels grey).
pub(super) fn error_image(c: &[f64], r: &[f64], opaque: &[bool]) -> Vec<u8> {
    let m = r
        .iter()
        .zip(opaque)
        .filter(|(_, &o)| o)
        .map(|(v, _)| v)
        .sum::<f64>()
        / opaque.iter().filter(|&&o| o).count().max(1) as f64;
    let mut out = Vec::with_capacity(c.len() * 3);
    for i in 0..c.len() {
        if !opaque[i] {
            out.extend_from_slice(&[90, 90, 90]);
            continue;
        }
        let e = ((c[i] - r[i]) / m.max(1e-300) / 0.5).clamp(-1.0, 1.0);
        let fade = |x: f64| (255.0 * (1.0 - x.abs())).round() as u8;
        out.extend_from_slice(&if e >= 0.0 {
            [255, fade(e), fade(e)]
        } else {
            [fade(e), fade(e), 255]
        });
    }
    out
}

/// The integer factor that tiles w pixels wide are enlarged by so that every one of `titles`
/// fits over its column: `image_grid` draws them on one line at one size, 2 pixels into a
/// column, and a 40-pixel column would print them over each other (at most 8×).
pub(super) fn tile_scale(titles: &[String], w: usize) -> usize {
    let need = titles.iter().map(|t| text_width(t)).max().unwrap_or(0) + 2;
    need.div_ceil(w.max(1)).clamp(1, 8)
}

/// `rgb` of w × h pixels enlarged s times (each pixel an s × s block), as a tile.
pub(super) fn tile(rgb: &[u8], (w, h): (usize, usize), s: usize) -> Tile {
    let mut out = Vec::with_capacity(rgb.len() * s * s);
    for y in 0..h * s {
        for x in 0..w * s {
            let i = ((y / s) * w + x / s) * 3;
            out.extend_from_slice(&rgb[i..i + 3]);
        }
    }
    Tile::new(out, w * s, h * s)
}

/// panel.png (rows: beauty at exposure `k_beauty`, then order 1, orders ≥ 2 and each group,
/// each at the automatic exposure of the reference's image of that row; columns: reference,
/// candidates) and errors.png (signed relative error of order 1 and orders ≥ 2 per
/// candidate, and the colour bar), into `files`. Tiles are enlarged so that the column titles
/// fit.
pub(super) fn figures(
    files: &mut AtomicFiles,
    out: &Path,
    r: &RenderDir,
    cands: &[RenderDir],
    k_beauty: f32,
    errors: &[(usize, String, Vec<u8>)],
) -> Result<()> {
    let n = r.pixels();
    let mut cols = vec!["reference".to_string()];
    cols.extend(cands.iter().map(|c| c.method.clone()));
    let s = tile_scale(&cols, r.size.0);
    let mut rows: Vec<(String, Vec<Option<Tile>>)> = Vec::new();
    let beauty = |d: &RenderDir| Some(tile(&tone_map_with(&d.beauty, k_beauty), r.size, s));
    rows.push((
        "beauty".into(),
        std::iter::once(r).chain(cands).map(beauty).collect(),
    ));
    for q in group_quantities() {
        let Quantity::Groups(a, b) = q else { continue };
        let img = |d: &RenderDir| -> Vec<f32> {
            let mut v = vec![0f32; n * 3];
            for g in a..b {
                for (i, x) in v.iter_mut().enumerate() {
                    *x += d.groups[g * n * 3 + i];
                }
            }
            v
        };
        let ri = img(r);
        let k = auto_exposure(&ri, &r.opacity).k;
        let mut tiles = vec![Some(tile(&tone_map_with(&ri, k), r.size, s))];
        for c in cands {
            let split = b - a > 1 || a == 0 || c.splits_orders();
            tiles.push(split.then(|| tile(&tone_map_with(&img(c), k), r.size, s)));
        }
        rows.push((q.name(), tiles));
    }
    files.write_via_path(&out.join("panel.png"), |p| image_grid(p, &cols, &rows))?;
    let err_rows = error_rows(r.size, s, cands.len(), errors);
    let bar = colour_bar(r.size.0 * s);
    files.write_via_path(&out.join("errors.png"), |p| {
        image_grid_with_bar(p, &cols[1..], &err_rows, Some(&bar))
    })
}

/// errors.png's rows: order 1 and orders ≥ 2 per candidate (tiles of `size` enlarged `s`
/// times).
pub(super) fn error_rows(
    size: (usize, usize),
    s: usize,
    candidates: usize,
    errors: &[(usize, String, Vec<u8>)],
) -> Vec<(String, Vec<Option<Tile>>)> {
    let mut rows: Vec<(String, Vec<Option<Tile>>)> = Vec::new();
    for name in ["order 1", "orders >= 2"] {
        let tiles = (0..candidates)
            .map(|ci| {
                errors
                    .iter()
                    .find(|(c, q, _)| *c == ci && q == name)
                    .map(|(_, _, img)| tile(img, size, s))
            })
            .collect();
        rows.push((format!("{}: (c−r)/⟨r⟩", name.replace(">=", "≥")), tiles));
    }
    rows
}

#[cfg(test)]
mod tests {
    use super::colour_bar;

    /// The bar runs from pure blue (−50 %) through white (0) to pure red (+50 %), one colour
    /// per pixel, its five ticks evenly spaced from end to end.
    #[test]
    fn the_colour_bar_spans_the_error_scale() {
        let bar = colour_bar(200);
        assert_eq!(bar.rgb.len(), 200 * 3);
        let px = |i: usize| &bar.rgb[3 * i..3 * i + 3];
        let (blue, red) = (px(0), px(199));
        assert!(blue[0] <= 3 && blue[1] <= 3 && blue[2] == 255, "{blue:?}");
        assert!(red[0] == 255 && red[1] <= 3 && red[2] <= 3, "{red:?}");
        assert!(px(100).iter().all(|&c| c >= 250), "{:?}", px(100));
        let at: Vec<f64> = bar.ticks.iter().map(|t| t.0).collect();
        assert_eq!(at, [0.0, 0.25, 0.5, 0.75, 1.0]);
        assert_eq!(bar.ticks[2].1, "0");
    }
}
