//! The path tracer's estimator: camera paths through a participating medium by delta (Woodcock)
//! tracking, next-event estimation toward the sun with ratio tracking (or the closed form where
//! the medium is homogeneous along the shadow ray), phase-function importance sampling from
//! nephele-runtime, Russian roulette only on weights already below 10⁻³ (unbiased). Radiance
//! is split by the number of scatterings, in the slab tables' order groups.
//!
//! Adjoint walk: a camera ray leaves the eye along w (opposite to the light it receives). At a
//! real collision x after n − 1 earlier ones, light from the sun arrives travelling along −s
//! (s the unit vector toward the sun) and scatters into −w, at cos Θ = s · w:
//!
//!   L_n += β ϖ p(s · w) T_r(x → sun) E_sun,
//!
//! β the path throughput (ϖ^{n−1} without roulette); the path continues along a direction
//! sampled from p around w (p is symmetric, so this is p(w′ · w) exactly), and an escaping path
//! adds β L_sky to the order of its last scattering (the constant sky, if any).

use super::medium::{dot, normalize, Medium, Vec3};
use nephele_runtime::PhaseFunction;
use rand::Rng;

/// Most order groups.
pub const MAX_GROUPS: usize = 16;

/// What lights the medium and how it scatters.
pub struct Volume<'a> {
    /// The medium.
    pub medium: &'a dyn Medium,
    /// Single-scattering albedo ϖ.
    pub albedo: f64,
    /// Phase function.
    pub phase: &'a (dyn PhaseFunction<f64> + Sync),
    /// Unit vector toward the sun.
    pub sun_dir: Vec3,
    /// Sun irradiance on a surface facing it (W/m², or 1 for T = L/E⊥).
    pub sun_irradiance: f64,
    /// Constant sky radiance (0: none).
    pub sky: f64,
    /// First scattering order of each group, increasing from 1.
    pub group_first: &'a [u32],
}

/// One camera path's radiance, split by scattering order, and the camera ray's transmittance.
#[derive(Clone, Copy, Debug, Default)]
pub struct PathSample {
    /// Sunlight per order group (the first `group_first.len()` entries).
    pub groups: [f64; MAX_GROUPS],
    /// Skylight per order group (scattered at least once).
    pub sky_groups: [f64; MAX_GROUPS],
    /// Radiance seen without scattering (the sky through the medium).
    pub unscattered: f64,
    /// Transmittance of the camera ray through the whole medium (1 − opacity).
    pub transmittance: f64,
}

impl PathSample {
    /// The total radiance: the groups and the unscattered part.
    pub fn total(&self) -> f64 {
        self.unscattered + self.groups.iter().sum::<f64>() + self.sky_groups.iter().sum::<f64>()
    }
}

fn at(o: Vec3, w: Vec3, t: f64) -> Vec3 {
    [o[0] + t * w[0], o[1] + t * w[1], o[2] + t * w[2]]
}

fn exp_step<R: Rng>(rng: &mut R, majorant: f64) -> f64 {
    -(1.0 - rng.random::<f64>()).ln() / majorant
}

/// The next real collision along o + t w by delta tracking, or None if the ray leaves.
pub fn collide<R: Rng>(m: &dyn Medium, o: Vec3, w: Vec3, rng: &mut R) -> Option<Vec3> {
    let (t0, t1) = m.clip(o, w)?;
    let majorant = m.majorant(o, w, t0, t1);
    if !(majorant > 0.0) {
        return None;
    }
    let mut t = t0;
    loop {
        t += exp_step(rng, majorant);
        if t >= t1 {
            return None;
        }
        let p = at(o, w, t);
        if rng.random::<f64>() * majorant < m.sigma_t(p) {
            return Some(p);
        }
    }
}

/// Transmittance along o + t w to the medium's end: closed form where the medium gives its
/// optical depth, else ratio tracking (unbiased, never 0 by a single event).
pub fn transmittance<R: Rng>(m: &dyn Medium, o: Vec3, w: Vec3, rng: &mut R) -> f64 {
    let Some((t0, t1)) = m.clip(o, w) else {
        return 1.0;
    };
    if let Some(tau) = m.optical_depth(o, w, t0, t1) {
        return (-tau).exp();
    }
    let majorant = m.majorant(o, w, t0, t1);
    if !(majorant > 0.0) {
        return 1.0;
    }
    let (mut t, mut tr) = (t0, 1.0);
    loop {
        t += exp_step(rng, majorant);
        if t >= t1 || tr < 1e-12 {
            return tr;
        }
        tr *= 1.0 - m.sigma_t(at(o, w, t)) / majorant;
    }
}

/// Group index of scattering order n ≥ 1.
fn group_of(first: &[u32], n: u32) -> usize {
    first.partition_point(|&f| f <= n).saturating_sub(1)
}

/// One camera path from `o` along the unit vector `w`.
pub fn trace<R: Rng>(v: &Volume, o: Vec3, w: Vec3, rng: &mut R) -> PathSample {
    let mut out = PathSample {
        transmittance: transmittance(v.medium, o, w, rng),
        ..PathSample::default()
    };
    out.unscattered = out.transmittance * v.sky;
    let (mut o, mut w) = (o, w);
    let mut beta = 1.0;
    let mut order = 0u32;
    while let Some(x) = collide(v.medium, o, w, rng) {
        order += 1;
        let g = group_of(v.group_first, order).min(MAX_GROUPS - 1);
        let cos = dot(v.sun_dir, w);
        let tr = transmittance(v.medium, x, v.sun_dir, rng);
        out.groups[g] += beta * v.albedo * v.phase.eval(cos) * tr * v.sun_irradiance;
        beta *= v.albedo;
        if beta < 1e-3 {
            // Roulette on light paths only: survive with probability 0.1 at 10× the weight.
            if rng.random::<f64>() >= 0.1 {
                return out;
            }
            beta *= 10.0;
        }
        let (w_new, _) = v.phase.sample(rng.random(), rng.random(), w);
        (o, w) = (x, normalize(w_new));
    }
    if order > 0 && v.sky > 0.0 {
        out.sky_groups[group_of(v.group_first, order).min(MAX_GROUPS - 1)] += beta * v.sky;
    }
    out
}
