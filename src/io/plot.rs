//! Figures (PNG) with plotters and an embedded DejaVu Sans font, so that no system font
//! library is needed.

use anyhow::{anyhow, Result};
use plotters::coord::ranged1d::ValueFormatter;
use plotters::prelude::*;
use std::path::Path;
use std::sync::Once;

static FONT: Once = Once::new();

fn register_font() {
    FONT.call_once(|| {
        let bytes: &'static [u8] = include_bytes!("../../assets/fonts/DejaVuSans.ttf");
        let _ = plotters::style::register_font("sans-serif", FontStyle::Normal, bytes);
    });
}

/// How a series is drawn.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Style {
    /// A solid line.
    Line,
    /// A dashed line.
    Dashed,
    /// Markers only.
    Points,
}

/// One named curve.
pub struct Curve<'a> {
    /// Legend label.
    pub label: String,
    /// Abscissae.
    pub x: &'a [f64],
    /// Ordinates (> 0 for a log axis).
    pub y: &'a [f64],
}

/// One named series with a style and a colour index (same index, same colour across panels).
pub struct Series<'a> {
    /// Legend label.
    pub label: String,
    /// Abscissae.
    pub x: &'a [f64],
    /// Ordinates (> 0 for a log axis; others are skipped there).
    pub y: &'a [f64],
    /// Line, dashes or markers.
    pub style: Style,
    /// Colour (index into the palette; 0 is black).
    pub colour: usize,
}

/// One chart of a figure.
pub struct Panel<'a> {
    /// Caption.
    pub title: String,
    /// x axis label.
    pub x_label: String,
    /// y axis label.
    pub y_label: String,
    /// Logarithmic y axis.
    pub log_y: bool,
    /// Logarithmic x axis (ignored unless every x > 0).
    pub log_x: bool,
    /// The series.
    pub series: Vec<Series<'a>>,
}

/// A line plot with a logarithmic y axis, written as a PNG at `path`.
pub fn log_y_plot(
    path: &Path,
    title: &str,
    x_label: &str,
    y_label: &str,
    curves: &[Curve],
) -> Result<()> {
    let series = curves
        .iter()
        .enumerate()
        .map(|(i, c)| Series {
            label: c.label.clone(),
            x: c.x,
            y: c.y,
            style: Style::Line,
            colour: i + 1,
        })
        .collect();
    let panel = Panel {
        title: title.to_string(),
        x_label: x_label.to_string(),
        y_label: y_label.to_string(),
        log_y: true,
        log_x: false,
        series,
    };
    panels_plot(path, (1200, 800), 1, &[panel])
}

fn colour_of(i: usize) -> RGBAColor {
    if i == 0 {
        BLACK.to_rgba()
    } else {
        Palette99::pick(i - 1).to_rgba()
    }
}

/// Panels on a grid of `cols` columns, written as one PNG of `size` pixels at `path`.
pub fn panels_plot(path: &Path, size: (u32, u32), cols: usize, panels: &[Panel]) -> Result<()> {
    register_font();
    let err = |e: &dyn std::fmt::Display| anyhow!("plot '{}': {e}", path.display());
    let root = BitMapBackend::new(path, size).into_drawing_area();
    root.fill(&WHITE).map_err(|e| err(&e))?;
    let rows = panels.len().div_ceil(cols.max(1));
    let areas = root.split_evenly((rows, cols.max(1)));
    for (panel, area) in panels.iter().zip(areas.iter()) {
        draw_panel(area, panel).map_err(|e| err(&e))?;
    }
    root.present().map_err(|e| err(&e))?;
    Ok(())
}

/// The data range of a panel: (x0, x1, y0, y1), positive y only on a log axis.
fn extent(panel: &Panel) -> (f64, f64, f64, f64) {
    let mut r = (
        f64::INFINITY,
        f64::NEG_INFINITY,
        f64::INFINITY,
        f64::NEG_INFINITY,
    );
    for s in &panel.series {
        for (&x, &y) in s.x.iter().zip(s.y) {
            if !(x.is_finite() && y.is_finite()) || (panel.log_y && y <= 0.0) {
                continue;
            }
            r = (r.0.min(x), r.1.max(x), r.2.min(y), r.3.max(y));
        }
    }
    if r.0 >= r.1 {
        r = (r.0 - 1.0, r.0 + 1.0, r.2, r.3);
    }
    if r.2 >= r.3 {
        r = (
            r.0,
            r.1,
            r.2 - 0.5 * r.2.abs().max(1e-3),
            r.3 + 0.5 * r.3.abs().max(1e-3),
        );
    }
    r
}

fn draw_panel<DB: DrawingBackend>(
    area: &DrawingArea<DB, plotters::coord::Shift>,
    panel: &Panel,
) -> Result<(), DrawingAreaErrorKind<DB::ErrorType>> {
    let (x0, x1, y0, y1) = extent(panel);
    let mut builder = ChartBuilder::on(area);
    builder
        .caption(&panel.title, ("sans-serif", 24))
        .margin(15)
        .margin_right(30)
        .x_label_area_size(45)
        .y_label_area_size(80);
    let pad = 0.05 * (y1 - y0);
    let (ly0, ly1) = (y0 * 0.8, y1 * 1.25);
    // plotters labels a log axis below 1 sparsely: ticks at 1-2-5 × 10^k instead.
    let lx = || (x0..x1).log_scale().with_key_points(ticks_125(x0, x1));
    match (panel.log_x && x0 > 0.0, panel.log_y) {
        (false, false) => draw_chart(
            builder.build_cartesian_2d(x0..x1, (y0 - pad)..(y1 + pad))?,
            panel,
        ),
        (false, true) => draw_chart(
            builder.build_cartesian_2d(x0..x1, (ly0..ly1).log_scale())?,
            panel,
        ),
        (true, false) => draw_chart(
            builder.build_cartesian_2d(lx(), (y0 - pad)..(y1 + pad))?,
            panel,
        ),
        (true, true) => draw_chart(
            builder.build_cartesian_2d(lx(), (ly0..ly1).log_scale())?,
            panel,
        ),
    }
}

/// 1, 2, 5 × 10^k inside [lo, hi] (none unless 0 < lo ≤ hi < ∞).
fn ticks_125(lo: f64, hi: f64) -> Vec<f64> {
    let mut out = Vec::new();
    if !(lo > 0.0 && lo <= hi && hi.is_finite()) {
        return out;
    }
    let mut decade = 10f64.powi(lo.log10().floor() as i32);
    while decade <= hi {
        out.extend(
            [1.0, 2.0, 5.0]
                .iter()
                .map(|m| m * decade)
                .filter(|v| (lo..=hi).contains(v)),
        );
        decade *= 10.0;
    }
    out
}

/// Whole numbers on a wide axis ("180", not "180.0"), otherwise at most 4 decimals without
/// trailing zeros ("0.3", not "0.30000000000000004").
fn tick(v: &f64, span: f64) -> String {
    if span >= 20.0 {
        return format!("{v:.0}");
    }
    let s = format!("{v:.4}");
    let s = s.trim_end_matches('0').trim_end_matches('.');
    if s == "-0" {
        "0".into()
    } else {
        s.into()
    }
}

fn draw_chart<'a, DB: DrawingBackend + 'a, X, Y>(
    mut chart: ChartContext<'a, DB, Cartesian2d<X, Y>>,
    panel: &Panel,
) -> Result<(), DrawingAreaErrorKind<DB::ErrorType>>
where
    X: Ranged<ValueType = f64> + ValueFormatter<f64>,
    Y: Ranged<ValueType = f64> + ValueFormatter<f64>,
{
    let (x0, x1, y0, y1) = extent(panel);
    let x_fmt = |v: &f64| tick(v, if panel.log_x { 0.0 } else { x1 - x0 });
    let y_fmt = |v: &f64| {
        if panel.log_y {
            format!("{v:.0e}")
        } else {
            tick(v, y1 - y0)
        }
    };
    chart
        .configure_mesh()
        .x_desc(&panel.x_label)
        .y_desc(&panel.y_label)
        .label_style(("sans-serif", 16))
        .x_label_formatter(&x_fmt)
        .y_label_formatter(&y_fmt)
        .draw()?;
    draw_series(&mut chart, panel, panel.log_y)
}

fn draw_series<'a, DB: DrawingBackend + 'a, X, Y>(
    chart: &mut ChartContext<'a, DB, Cartesian2d<X, Y>>,
    panel: &Panel,
    log_y: bool,
) -> Result<(), DrawingAreaErrorKind<DB::ErrorType>>
where
    X: Ranged<ValueType = f64>,
    Y: Ranged<ValueType = f64>,
{
    for s in &panel.series {
        let colour = colour_of(s.colour);
        let points: Vec<(f64, f64)> =
            s.x.iter()
                .zip(s.y)
                .filter(|(x, y)| x.is_finite() && y.is_finite() && (!log_y || **y > 0.0))
                .map(|(x, y)| (*x, *y))
                .collect();
        let anno = match s.style {
            Style::Line => chart.draw_series(LineSeries::new(points, colour.stroke_width(2)))?,
            Style::Dashed => {
                chart.draw_series(DashedLineSeries::new(points, 8, 6, colour.stroke_width(2)))?
            }
            Style::Points => chart.draw_series(
                points
                    .into_iter()
                    .map(|p| Circle::new(p, 4, colour.filled())),
            )?,
        };
        if s.label.is_empty() {
            continue; // no legend entry
        }
        let style = s.style;
        anno.label(s.label.clone())
            .legend(move |(x, y)| match style {
                Style::Points => Circle::new((x + 10, y), 4, colour.filled()).into_dyn(),
                _ => PathElement::new(vec![(x, y), (x + 20, y)], colour.stroke_width(3)).into_dyn(),
            });
    }
    chart
        .configure_series_labels()
        .label_font(("sans-serif", 16))
        .background_style(WHITE.mix(0.8))
        .border_style(BLACK)
        .draw()
}

/// One heat map: `values` over a grid of `x_labels.len()` columns and `y_labels.len()` rows,
/// row-major with row 0 at the bottom (NaN: no value, drawn grey).
pub struct HeatMap<'a> {
    /// Title.
    pub title: String,
    /// Column labels (left to right) and axis name.
    pub x_labels: Vec<String>,
    /// See `x_labels`.
    pub x_name: &'a str,
    /// Row labels (bottom to top) and axis name.
    pub y_labels: Vec<String>,
    /// See `y_labels`.
    pub y_name: &'a str,
    /// [row][column] flattened.
    pub values: Vec<f64>,
}

/// Heat maps on a grid of `cols` columns, each cell coloured from white (0) through yellow
/// (`mid`) to red (≥ `top`) and labelled with its value (`format`).
pub fn heat_maps(
    path: &Path,
    size: (u32, u32),
    cols: usize,
    (mid, top): (f64, f64),
    format: &dyn Fn(f64) -> String,
    maps: &[HeatMap],
) -> Result<()> {
    register_font();
    let err = |e: &dyn std::fmt::Display| anyhow!("plot '{}': {e}", path.display());
    let root = BitMapBackend::new(path, size).into_drawing_area();
    root.fill(&WHITE).map_err(|e| err(&e))?;
    let rows = maps.len().div_ceil(cols.max(1));
    for (map, area) in maps
        .iter()
        .zip(root.split_evenly((rows, cols.max(1))).iter())
    {
        draw_heat_map(area, map, (mid, top), format).map_err(|e| err(&e))?;
    }
    root.present().map_err(|e| err(&e))?;
    Ok(())
}

/// White → yellow at `mid` → red at `top`.
fn heat_colour(v: f64, (mid, top): (f64, f64)) -> RGBColor {
    if !v.is_finite() {
        return RGBColor(200, 200, 200);
    }
    let lerp = |a: f64, b: f64, w: f64| (a + (b - a) * w.clamp(0.0, 1.0)).round() as u8;
    if v <= mid {
        let w = v / mid;
        RGBColor(255, 255, lerp(255.0, 60.0, w))
    } else {
        let w = (v - mid) / (top - mid);
        RGBColor(
            lerp(255.0, 215.0, w),
            lerp(255.0, 40.0, w),
            lerp(60.0, 40.0, w),
        )
    }
}

fn draw_heat_map<DB: DrawingBackend>(
    area: &DrawingArea<DB, plotters::coord::Shift>,
    map: &HeatMap,
    scale: (f64, f64),
    format: &dyn Fn(f64) -> String,
) -> Result<(), DrawingAreaErrorKind<DB::ErrorType>> {
    let (nx, ny) = (map.x_labels.len(), map.y_labels.len());
    let mut chart = ChartBuilder::on(area)
        .caption(&map.title, ("sans-serif", 22))
        .margin(12)
        .x_label_area_size(40)
        .y_label_area_size(60)
        .build_cartesian_2d(0.0..nx as f64, 0.0..ny as f64)?;
    let label = |labels: &[String], v: f64| {
        let i = v.floor() as usize;
        if (v - i as f64 - 0.5).abs() < 1e-6 {
            labels.get(i).cloned().unwrap_or_default()
        } else {
            String::new()
        }
    };
    chart
        .configure_mesh()
        .disable_mesh()
        .x_labels(2 * nx + 1)
        .y_labels(2 * ny + 1)
        .x_label_formatter(&|v| label(&map.x_labels, *v))
        .y_label_formatter(&|v| label(&map.y_labels, *v))
        .x_desc(map.x_name)
        .y_desc(map.y_name)
        .label_style(("sans-serif", 16))
        .draw()?;
    for row in 0..ny {
        for col in 0..nx {
            let v = map.values.get(row * nx + col).copied().unwrap_or(f64::NAN);
            let (x, y) = (col as f64, row as f64);
            chart.draw_series(std::iter::once(Rectangle::new(
                [(x, y), (x + 1.0, y + 1.0)],
                heat_colour(v, scale).filled(),
            )))?;
            if v.is_finite() {
                chart.draw_series(std::iter::once(Text::new(
                    format(v),
                    (x + 0.2, y + 0.65),
                    ("sans-serif", 14),
                )))?;
            }
        }
    }
    Ok(())
}

/// An 8-bit RGB image for [`image_grid`].
pub struct Tile {
    rgb: Vec<u8>,
    w: usize,
    h: usize,
}

impl Tile {
    /// `rgb` of w × h pixels, row 0 at the top.
    pub fn new(rgb: Vec<u8>, w: usize, h: usize) -> Self {
        Self { rgb, w, h }
    }
}

/// A colour bar under an [`image_grid`]: the colour at each of its pixels left to right, the
/// quantity it shows, and tick labels at fractions of its width.
pub struct ColourBar {
    /// One RGB colour per pixel of the bar's width.
    pub rgb: Vec<u8>,
    /// What the colours stand for (printed on the left, as a row title).
    pub label: String,
    /// (position in [0, 1] along the bar, text).
    pub ticks: Vec<(f64, String)>,
}

/// The width (pixels) of `text` as the figures draw their titles (DejaVu Sans, 15 px),
/// estimated from above by the font's widest advance in each class of character: narrow
/// 0.42 em (i, l, r, t, space, brackets, punctuation), other lower case 0.64 em, wide 1 em
/// (m, w, M, W, %, …, + and the relations), the rest (capitals, digits) 0.8 em.
pub fn text_width(text: &str) -> usize {
    let em: f64 = text
        .chars()
        .map(|c| match c {
            'f' | 'i' | 'j' | 'l' | 'r' | 't' | ' ' | '(' | ')' | '[' | ']' | '.' | ',' | ':'
            | ';' | '-' | '\'' | '|' | '/' => 0.42,
            'm' | 'w' | 'M' | 'W' | '%' | '…' | '+' | '=' | '<' | '>' | '≥' | '≤' => 1.0,
            'a'..='z' => 0.64,
            _ => 0.8,
        })
        .sum();
    (em * 15.0).ceil() as usize
}

/// Images on a labelled grid (column titles on top, row titles on the left; a missing tile is
/// left blank), written as a PNG at `path`.
pub fn image_grid(
    path: &Path,
    columns: &[String],
    rows: &[(String, Vec<Option<Tile>>)],
) -> Result<()> {
    image_grid_with_bar(path, columns, rows, None)
}

/// Bar height, tick length and the room under the bar for its labels (pixels).
const BAR: (usize, usize, usize) = (18, 5, 24);

/// [`image_grid`] with a colour bar under the images, as wide as one tile (at most 480
/// pixels), its ticks labelled below it.
pub fn image_grid_with_bar(
    path: &Path,
    columns: &[String],
    rows: &[(String, Vec<Option<Tile>>)],
    bar: Option<&ColourBar>,
) -> Result<()> {
    register_font();
    let err = |e: &dyn std::fmt::Display| anyhow!("figure '{}': {e}", path.display());
    let (tw, th) = rows
        .iter()
        .flat_map(|(_, t)| t.iter().flatten())
        .map(|t| (t.w, t.h))
        .next()
        .unwrap_or((1, 1));
    let (left, top, gap) = (150usize, 28usize, 4usize);
    let ncols = columns
        .len()
        .max(rows.iter().map(|r| r.1.len()).max().unwrap_or(0));
    let width = left + ncols * (tw + gap);
    let grid_height = top + rows.len() * (th + gap);
    let height = grid_height + bar.map_or(0, |_| 8 + BAR.0 + BAR.1 + BAR.2);
    let root = BitMapBackend::new(path, (width as u32, height as u32)).into_drawing_area();
    root.fill(&WHITE).map_err(|e| err(&e))?;
    let style = ("sans-serif", 15).into_font().color(&BLACK);
    for (c, title) in columns.iter().enumerate() {
        let x = (left + c * (tw + gap)) as i32;
        root.draw(&Text::new(title.clone(), (x + 2, 6), style.clone()))
            .map_err(|e| err(&e))?;
    }
    for (r, (label, tiles)) in rows.iter().enumerate() {
        let y = (top + r * (th + gap)) as i32;
        root.draw(&Text::new(
            label.clone(),
            (4, y + th as i32 / 2 - 8),
            style.clone(),
        ))
        .map_err(|e| err(&e))?;
        for (c, tile) in tiles.iter().enumerate() {
            let Some(t) = tile else { continue };
            let x0 = (left + c * (tw + gap)) as i32;
            for j in 0..t.h {
                for i in 0..t.w {
                    let p = &t.rgb[(j * t.w + i) * 3..(j * t.w + i) * 3 + 3];
                    root.draw_pixel((x0 + i as i32, y + j as i32), &RGBColor(p[0], p[1], p[2]))
                        .map_err(|e| err(&e))?;
                }
            }
        }
    }
    if let Some(bar) = bar {
        draw_bar(&root, bar, (left, grid_height + 8), tw.min(480), &style).map_err(|e| err(&e))?;
    }
    root.present().map_err(|e| err(&e))?;
    Ok(())
}

/// `bar` drawn `w` pixels wide with its top-left corner at (x0, y0), its label left of it at the
/// grid's row-title margin, and its ticks below.
fn draw_bar<DB: DrawingBackend>(
    root: &DrawingArea<DB, plotters::coord::Shift>,
    bar: &ColourBar,
    (x0, y0): (usize, usize),
    w: usize,
    style: &TextStyle,
) -> std::result::Result<(), DrawingAreaErrorKind<DB::ErrorType>> {
    let n = bar.rgb.len() / 3;
    if n == 0 {
        return Ok(());
    }
    let (h, tick, _) = BAR;
    root.draw(&Text::new(
        bar.label.clone(),
        (4, (y0 + h / 2) as i32 - 8),
        style.clone(),
    ))?;
    for i in 0..w {
        let k = (i * n / w.max(1)).min(n - 1);
        let c = RGBColor(bar.rgb[3 * k], bar.rgb[3 * k + 1], bar.rgb[3 * k + 2]);
        let x = (x0 + i) as i32;
        root.draw(&PathElement::new(
            [(x, y0 as i32), (x, (y0 + h - 1) as i32)],
            c,
        ))?;
    }
    // Each label centred under its tick, kept inside the figure; on a narrow bar the inner
    // labels that would touch a kept one are left out (the ends first, then the middle).
    let y = (y0 + h) as i32;
    let right_edge = root.dim_in_pixel().0 as i32;
    let mut labels = Vec::with_capacity(bar.ticks.len());
    for (at, text) in &bar.ticks {
        let x = x0 as i32 + (at.clamp(0.0, 1.0) * (w.max(1) - 1) as f64).round() as i32;
        root.draw(&PathElement::new([(x, y), (x, y + tick as i32)], BLACK))?;
        let tw = root.estimate_text_size(text, style)?.0 as i32;
        let left = (x - tw / 2).clamp(0, (right_edge - tw).max(0));
        labels.push((left, left + tw, text));
    }
    let n = labels.len();
    let mut kept: Vec<usize> = Vec::with_capacity(n);
    // The ends first, then the middle, then the rest.
    let order = [0, n.saturating_sub(1), n / 2]
        .into_iter()
        .chain(1..n.saturating_sub(1));
    for i in order.filter(|&i| i < n) {
        let (l, r, _) = labels[i];
        let clear = kept
            .iter()
            .all(|&k| r + 6 <= labels[k].0 || labels[k].1 + 6 <= l);
        if !kept.contains(&i) && clear {
            kept.push(i);
        }
    }
    for i in kept {
        let (left, _, text) = labels[i];
        root.draw(&Text::new(
            text.clone(),
            (left, y + tick as i32 + 4),
            style.clone(),
        ))?;
    }
    Ok(())
}
