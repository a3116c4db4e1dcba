//! A rendered image and its AOVs, as every method fills them and `output` writes them: the
//! radiance per order group, the unscattered sky, the camera ray's transmittance, the beauty
//! image, and per method the path tracer's split-sample halves or the fast renderers' regions.

/// The order groups an image is split into (their first orders, order 1 first): the slab
/// tables' default groups, as the runtime defines them.
pub const GROUP_FIRST: [u32; 9] = nephele_runtime::fitting::DEFAULT_GROUP_FIRST;

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
    /// Samples per pixel (the scene's times the passes a time budget allowed).
    pub spp: u32,
    /// The method's name (render.json).
    pub method: String,
    /// The path tracer's split-sample halves: the groups' radiance from the even and from the
    /// odd samples of each pixel, [half, group, row, column, RGB] (empty for other methods):
    /// (A − B)²/4 estimates the variance of a pixel's mean.
    pub halves: Vec<f32>,
    /// The fast renderers' region of each pixel (`regions`), [row, column] (empty for the
    /// path tracer).
    pub regions: Vec<u8>,
    /// Method-specific facts for render.json.
    pub details: serde_json::Value,
}

/// Bytes a w × h frame takes while it renders and is written, an upper estimate: the path
/// tracer's per-pixel f64 sums of both halves (2 × 74 × 8 B), its halves, groups and AOVs in
/// f32, and their encoded copies; the fast renderers' groups, AOVs, regions and copies.
pub fn frame_bytes(w: usize, h: usize, path_tracer: bool) -> f64 {
    let per_pixel = if path_tracer { 1800.0 } else { 400.0 };
    (w * h) as f64 * per_pixel
}

impl Rendered {
    /// A black, empty image of w × h pixels.
    pub fn empty(w: usize, h: usize) -> Self {
        let ng = GROUP_FIRST.len();
        Self {
            width: w,
            height: h,
            groups: vec![0.0; ng * h * w * 3],
            unscattered: vec![0.0; h * w * 3],
            transmittance: vec![0.0; h * w],
            beauty: vec![0.0; h * w * 3],
            seconds: 0.0,
            paths: 0,
            spp: 0,
            method: String::new(),
            halves: Vec::new(),
            regions: Vec::new(),
            details: serde_json::Value::Null,
        }
    }
}
