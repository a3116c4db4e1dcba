//! Order 1 of the sky, marched along the view ray as the sun's is (docs/collector.md, "Sky"):
//! the light of a constant sky scattered once toward the eye at x,
//!
//!   L₁ = L_sky ϖ ∫ σ T_v(x) V(x) ds,   V(x) = ∫_{4π} p(s · w) e^{−τ(x, s)} dΩ_s,
//!
//! with τ(x, s) the optical depth from x toward the sky in direction s and w the view ray's
//! direction (the light that scatters forward toward the eye came from s = w, behind x). The
//! forward peak, Θ < [`PEAK_DEG`], holds a share P of p (the diffraction peak of cloud
//! droplets) and reads the ray's own chord behind x: σ T_v e^{−τ_behind} = σ e^{−τ_chord}
//! integrates to P τ e^{−τ} in closed form. The rest reads K = [`DIRECTIONS`] optical-depth
//! maps toward a Fibonacci set of sky directions s_k, each the sun's light map seen from s_k,
//! weighted by the wide part of p averaged over a cap of the directions' solid angle 4π/K,
//!
//!   V(x) ≈ P e^{−τ_behind} + Σ_k W_k e^{−τ_k(x)},   W_k ∝ p̄_wide(s_k · w),  Σ_k W_k = 1 − P.
//!
//! The maps depend on the cloud alone, neither on the sun nor on the camera. A slab has none:
//! there the face-on slab of the sky table is the slab itself.

use super::light_map::{LightMaps, MapOptions};
use crate::render::geometry::{dot, Vec3};
use crate::render::medium::Medium;
use nephele_runtime::PhaseFunction;
use rayon::prelude::*;

/// Sky directions with a map each (8 put order 1 10–24 % high on the five sky scenes, 32
/// were no closer than 16).
pub const DIRECTIONS: usize = 16;
/// Texels per side and depth planes of a map toward the sky, by default (128 put order 1
/// at +6.1 % on `sphere40_sky` and −5.9 % on `tower_sky` instead of +12.6 % and −10.9 %, for
/// 1 s of maps on the default cloud instead of 0.3 s).
pub const MAP_RESOLUTION: usize = 64;
/// The maps' march sub-step, in the view march's steps (1 cost as much and changed order 1
/// by less than 0.3 % on the five sky scenes).
pub const MAP_STEP: f64 = 2.0;
/// The view ray's transmittance below which V is no longer read: the rest of the ray, under 1 %
/// of its order 1, scatters with the last V.
pub const CUTOFF: f64 = 0.01;
/// Optical depth (mfp) of view ray gathered between readings of V, at the weight's centre
/// (every sub-step of 0.5 mfp or less: within 1.5 % on the five sky scenes, 1.3× the pixels'
/// time).
pub const GATHER: f64 = 0.5;
/// The forward peak's half-angle (degrees): read along the view ray's own chord.
pub const PEAK_DEG: f64 = 5.0;
/// Nodes of the cap-averaged wide phase function in cos θ over [−1, 1].
const COS_NODES: usize = 257;

/// The maps toward the sky and the phase function's weights.
pub struct SkyOrder1 {
    /// Unit vectors toward the sky, and their maps.
    dirs: Vec<Vec3>,
    maps: Vec<LightMaps>,
    /// p̄_wide (1/sr) at cos θ = −1 + 2i/(COS_NODES − 1).
    wide: Vec<f64>,
    /// P, the forward peak's share of p.
    peak: f64,
}

impl SkyOrder1 {
    /// Builds the maps of `medium` within `bounds` (as `maps`, as many planes as texels per
    /// side, without sections) and the weights of `phase` (normalised to 1 over the sphere).
    pub fn build(
        medium: &dyn Medium,
        bounds: (Vec3, Vec3),
        maps: &MapOptions,
        phase: &(dyn PhaseFunction<f64> + Sync),
    ) -> Self {
        let o = MapOptions {
            planes: maps.resolution,
            step: MAP_STEP * maps.step,
            sections: 0,
            surface_section: false,
            ..*maps
        };
        let dirs = fibonacci(DIRECTIONS);
        let maps = dirs
            .iter()
            .map(|&s| LightMaps::build(medium, bounds, s, &o))
            .collect();
        let cos_peak = PEAK_DEG.to_radians().cos();
        let peak = peak_share(phase, cos_peak);
        let cap = 1.0 - 2.0 / DIRECTIONS as f64; // cos of the cap of solid angle 4π/K
        let wide = (0..COS_NODES)
            .into_par_iter()
            .map(|i| {
                cap_mean(
                    phase,
                    -1.0 + 2.0 * i as f64 / (COS_NODES - 1) as f64,
                    cap,
                    cos_peak,
                )
            })
            .collect();
        Self {
            dirs,
            maps,
            wide,
            peak,
        }
    }

    /// The weights W_k of a view ray of direction `w` (unit, from the eye): p̄_wide(s_k · w)
    /// normalised to Σ W_k = 1 − P.
    pub fn weights(&self, w: Vec3) -> [f64; DIRECTIONS] {
        let mut out = [0.0; DIRECTIONS];
        for (o, &s) in out.iter_mut().zip(&self.dirs) {
            let x = (dot(s, w).clamp(-1.0, 1.0) + 1.0) * 0.5 * (COS_NODES - 1) as f64;
            let i = (x as usize).min(COS_NODES - 2);
            let f = x - i as f64;
            *o = (1.0 - f) * self.wide[i] + f * self.wide[i + 1];
        }
        let sum: f64 = out.iter().sum();
        if sum > 0.0 {
            let k = (1.0 - self.peak) / sum;
            out.iter_mut().for_each(|o| *o *= k);
        }
        out
    }

    /// Σ_k W_k e^{−τ_k(x)}: the wide part of V at `x`.
    pub fn wide_visibility(&self, x: Vec3, weights: &[f64; DIRECTIONS]) -> f64 {
        self.maps
            .iter()
            .zip(weights)
            .map(|(m, &w)| w * (-m.sun_optical_depth(x)).exp())
            .sum()
    }

    /// P: the forward peak's share, read along the chord.
    pub fn peak(&self) -> f64 {
        self.peak
    }
}

/// One view ray's sky order 1 as its march goes: the weight ∫ σ T_v ds gathered since V was
/// last read (with its centre and optical depth), read every [`GATHER`] mfp until T_v <
/// [`CUTOFF`], after which the rest of the ray scatters with the last V.
pub struct Gather<'a> {
    sky: &'a SkyOrder1,
    weights: [f64; DIRECTIONS],
    weight: f64,
    centre: Vec3,
    tau: f64,
    last_v: f64,
    /// T_v where the readings stopped.
    cut: Option<f64>,
    /// ∫ σ T_v V ds so far.
    sum: f64,
}

impl<'a> Gather<'a> {
    /// A ray of direction `w` (unit, from the eye).
    pub fn new(sky: &'a SkyOrder1, w: Vec3) -> Self {
        Self {
            sky,
            weights: sky.weights(w),
            weight: 0.0,
            centre: [0.0; 3],
            tau: 0.0,
            last_v: 0.0,
            cut: None,
            sum: 0.0,
        }
    }

    /// A sub-step of extinction `sigma` (1/m) and length `h` (m) entered with transmittance
    /// `t_v`, its middle at `mid`.
    pub fn add(&mut self, t_v: f64, sigma: f64, h: f64, mid: Vec3) {
        if self.cut.is_none() && t_v < CUTOFF {
            self.cut = Some(t_v);
        }
        if self.cut.is_some() {
            return;
        }
        let scattered = t_v * -(-sigma * h).exp_m1();
        self.weight += scattered;
        for (c, m) in self.centre.iter_mut().zip(mid) {
            *c += scattered * m;
        }
        self.tau += sigma * h;
        if self.tau >= GATHER {
            self.read();
        }
    }

    /// Reads V at the gathered weight's centre.
    fn read(&mut self) {
        if self.weight > 0.0 {
            let c = self.centre.map(|x| x / self.weight);
            self.last_v = self.sky.wide_visibility(c, &self.weights);
            self.sum += self.weight * self.last_v;
        }
        (self.weight, self.centre, self.tau) = (0.0, [0.0; 3], 0.0);
    }

    /// ∫ σ T_v V ds of the ray that ended with transmittance `t_end` and optical depth `chord`
    /// along its whole chord: the rest gathered, the rest after the cut, the forward peak
    /// (∫ σ T_v e^{−τ_behind} ds = τ e^{−τ}).
    pub fn finish(mut self, t_end: f64, chord: f64) -> f64 {
        // The rest after the cut takes the V of the last reading during the march.
        let after_cut = self.cut.map(|t| (t - t_end) * self.last_v);
        self.read();
        self.sum + after_cut.unwrap_or(0.0) + self.sky.peak() * chord * (-chord).exp()
    }
}

/// `n` unit vectors spread evenly over the sphere (a Fibonacci lattice).
fn fibonacci(n: usize) -> Vec<Vec3> {
    let golden = std::f64::consts::PI * (3.0 - 5f64.sqrt());
    (0..n)
        .map(|i| {
            let z = 1.0 - (2.0 * i as f64 + 1.0) / n as f64;
            let r = (1.0 - z * z).max(0.0).sqrt();
            let (s, c) = (golden * i as f64).sin_cos();
            [r * c, r * s, z]
        })
        .collect()
}

/// The mean of p over the cap {s : s · a ≥ `cap`} around an axis a at cos θ = `c` from the
/// view's forward direction, p taken as 0 inside the forward peak (cos Θ > `cos_peak`):
/// Gauss–Legendre in the cap's polar angle, midpoints in its azimuth.
fn cap_mean(phase: &(dyn PhaseFunction<f64> + Sync), c: f64, cap: f64, cos_peak: f64) -> f64 {
    const RINGS: usize = 24;
    const AZ: usize = 48;
    let s = (1.0 - c * c).max(0.0).sqrt();
    let (mut sum, mut weight) = (0.0, 0.0);
    for r in 0..RINGS {
        // Rings evenly spaced in cos (equal solid angle).
        let mu = 1.0 - (1.0 - cap) * (r as f64 + 0.5) / RINGS as f64;
        let st = (1.0 - mu * mu).max(0.0).sqrt();
        for k in 0..AZ {
            let phi = (k as f64 + 0.5) * std::f64::consts::TAU / AZ as f64;
            // The angle to the forward direction of a point of the cap around the axis.
            let cos = (c * mu + s * st * phi.cos()).clamp(-1.0, 1.0);
            if cos <= cos_peak {
                sum += phase.eval(cos);
            }
            weight += 1.0;
        }
    }
    sum / weight
}

/// ∫_{cos Θ > `cos_peak`} p dΩ: Gauss–Legendre panels in Θ narrowing toward 0.
fn peak_share(phase: &(dyn PhaseFunction<f64> + Sync), cos_peak: f64) -> f64 {
    let top = cos_peak.clamp(-1.0, 1.0).acos();
    let edges = [0.0, 0.02, 0.1, 0.3, 0.6, 1.0].map(|f| f * top);
    let mut sum = 0.0;
    for e in edges.windows(2) {
        let (a, b) = (e[0], e[1]);
        for (x, wx) in super::sky::GAUSS6 {
            let theta = 0.5 * (a + b) + 0.5 * (b - a) * x;
            sum += 0.5 * (b - a) * wx * theta.sin() * phase.eval(theta.cos());
        }
    }
    std::f64::consts::TAU * sum
}

#[cfg(test)]
mod tests {
    use super::*;
    use nephele_runtime::phase::HenyeyGreenstein;

    #[test]
    fn the_weights_and_the_peak_hold_the_whole_phase_function() {
        let hg = HenyeyGreenstein::new(0.85f64);
        let cos_peak = PEAK_DEG.to_radians().cos();
        let peak = peak_share(&hg, cos_peak);
        // HG's share within Θ: ∫ p dΩ in closed form.
        let g: f64 = 0.85;
        let within = |mu: f64| {
            (1.0 - g * g) / (2.0 * g)
                * (1.0 / (1.0 - g) - 1.0 / (1.0 + g * g - 2.0 * g * mu).sqrt())
        };
        assert!(
            (peak - within(cos_peak)).abs() < 1e-6,
            "{peak} vs {}",
            within(cos_peak)
        );
        // The caps of the K directions overlap and leave gaps: their raw sum is not the wide
        // part (1.0005 against 0.871 here; the weights are normalised to it), but the
        // direction nearest the view's forward takes the most.
        let w: Vec3 = [0.3, -0.5, 0.81];
        let n = dot(w, w).sqrt();
        let w = w.map(|x| x / n);
        let cap = 1.0 - 2.0 / DIRECTIONS as f64;
        let dirs = fibonacci(DIRECTIONS);
        let sky = SkyOrder1 {
            wide: (0..COS_NODES)
                .map(|i| {
                    cap_mean(
                        &hg,
                        -1.0 + 2.0 * i as f64 / (COS_NODES - 1) as f64,
                        cap,
                        cos_peak,
                    )
                })
                .collect(),
            dirs: dirs.clone(),
            maps: Vec::new(),
            peak,
        };
        let weights = sky.weights(w);
        let sum: f64 = weights.iter().sum();
        assert!((sum - (1.0 - peak)).abs() < 1e-9, "{sum}");
        let nearest = (0..DIRECTIONS).max_by(|&a, &b| dot(w, dirs[a]).total_cmp(&dot(w, dirs[b])));
        let largest = (0..DIRECTIONS).max_by(|&a, &b| weights[a].total_cmp(&weights[b]));
        assert_eq!(nearest, largest, "{weights:?}");
    }

    #[test]
    fn fibonacci_directions_are_unit_and_balanced() {
        let d = fibonacci(DIRECTIONS);
        let mean: Vec3 = std::array::from_fn(|k| d.iter().map(|v| v[k]).sum::<f64>());
        assert!(d.iter().all(|v| (dot(*v, *v) - 1.0).abs() < 1e-12));
        assert!(
            dot(mean, mean).sqrt() < 0.05 * DIRECTIONS as f64,
            "{mean:?}"
        );
    }
}
