//! The regions of an image (`regions.npy`, written by the fast renderers, read by `compare`):
//! empty sky, the lit and the shadowed face of the cloud, and its silhouette, from a pixel's
//! opacity and the sun's optical depth at its visible surface point.

/// Opacity ≤ 0.5.
pub const EMPTY: u8 = 0;
/// Opaque, the visible surface point sunlit (τ_sun < 2).
pub const LIT: u8 = 1;
/// Opaque, the visible surface point in the cloud's shadow (τ_sun ≥ 2).
pub const SHADOWED: u8 = 2;
/// 0.5 < opacity < [`OPAQUE`]: the silhouette.
pub const SILHOUETTE: u8 = 3;

/// The opacity from which a pixel is the cloud's interior (lit or shadowed face), below which
/// (down to 0.5) it is the silhouette.
pub const OPAQUE: f64 = 0.99;

/// The region code of a pixel of opacity `alpha` whose surface point has sun optical depth
/// `tau`.
pub fn region_of(alpha: f64, tau: f64) -> u8 {
    if alpha <= 0.5 {
        EMPTY
    } else if alpha < OPAQUE {
        SILHOUETTE
    } else if tau < 2.0 {
        LIT
    } else {
        SHADOWED
    }
}
