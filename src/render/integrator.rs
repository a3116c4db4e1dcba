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
//!
//! Per-channel phase functions p_R, p_G, p_B (a Mie table per sRGB channel): β and the
//! radiance are RGB; the new direction is sampled from a channel c drawn uniformly, so its
//! density is the mean p̄ = (p_R + p_G + p_B)/3 (one-sample MIS, balance heuristic), and each
//! channel's throughput takes the weight β_k ← β_k p_k(cos) / p̄(cos) — unbiased wherever p̄ > 0,
//! and never more than 3.
//!
//! Two-vertex next-event estimation (`guided_nee`). With a forward peak (Mie: p(1) ~ 10³ sr⁻¹
//! at 10 µm) the estimate above is heavy-tailed: the rare segment w′ within a few degrees of s
//! brings p(s · w′) ≫ 1 at its next collision x′ (fireflies). So order n + 1 gets a second
//! strategy at every collision x: B samples w′ from p around s (density p_B = p(s · w′)), flies
//! to x′ and adds NEE there; the path's own next collision (strategy A, density p_A = p(w · w′))
//! is the first. Balance-heuristic MIS between the two, both giving
//!
//!   L_{n+1} += β ϖ² p_A p_B T_r(x′ → sun) E_sun / (p_A + p_B) / p_strategy,
//!
//! i.e. A's NEE at x′ takes the weight p_A/(p_A + p_B) and B's contribution is β ϖ² p_A
//! T_r E_sun · p_B/(p_A + p_B) ≤ β ϖ² p_A T_r E_sun: the peak cancels. The path itself
//! continues as before (no weights compound), orders 1 keep plain NEE. With per-channel
//! phase functions p_A, p_B in the MIS weights are the channel means (the densities sampled).

use super::geometry::{dot, normalize, Vec3};
use super::medium::Medium;
use nephele_runtime::PhaseFunction;
use rand::Rng;
use std::ops::ControlFlow;

/// Most order groups.
pub const MAX_GROUPS: usize = 16;

/// What lights the medium and how it scatters.
pub struct Volume<'a> {
    /// The medium.
    pub medium: &'a dyn Medium,
    /// Single-scattering albedo ϖ.
    pub albedo: f64,
    /// The phase function: one for all channels, or one per RGB channel.
    pub phases: &'a [&'a (dyn PhaseFunction<f64> + Sync)],
    /// Unit vector toward the sun.
    pub sun_dir: Vec3,
    /// Sun irradiance on a surface facing it (W/m², or 1 for T = L/E⊥).
    pub sun_irradiance: f64,
    /// Constant sky radiance (0: none).
    pub sky: f64,
    /// First scattering order of each group, increasing from 1.
    pub group_first: &'a [u32],
    /// Two-vertex next-event estimation (see the module's docs).
    pub guided_nee: bool,
}

/// RGB.
pub type Rgb = [f64; 3];

/// One camera path's radiance, split by scattering order, and the camera ray's transmittance.
#[derive(Clone, Copy, Debug, Default)]
pub struct PathSample {
    /// Sunlight per order group (the first `group_first.len()` entries), RGB.
    pub groups: [Rgb; MAX_GROUPS],
    /// Skylight per order group (scattered at least once), RGB.
    pub sky_groups: [Rgb; MAX_GROUPS],
    /// Radiance seen without scattering (the sky through the medium).
    pub unscattered: f64,
    /// Transmittance of the camera ray through the whole medium (1 − opacity).
    pub transmittance: f64,
}

impl PathSample {
    /// The total radiance of channel c: the groups and the unscattered part.
    pub fn total(&self, c: usize) -> f64 {
        let sum = |g: &[Rgb; MAX_GROUPS]| g.iter().map(|v| v[c]).sum::<f64>();
        self.unscattered + sum(&self.groups) + sum(&self.sky_groups)
    }
}

fn at(o: Vec3, w: Vec3, t: f64) -> Vec3 {
    [o[0] + t * w[0], o[1] + t * w[1], o[2] + t * w[2]]
}

/// A free flight: an exponential optical depth τ drawn once and spent cell by cell (σ̄ Δt per
/// cell) across majorant cells, so that cell faces cost no random numbers (free paths are
/// memoryless, so this is the Poisson process of rate σ̄(t) along the ray).
struct Flight {
    tau: f64,
}

impl Flight {
    fn new<R: Rng>(rng: &mut R) -> Self {
        Self {
            tau: -(1.0 - rng.random::<f64>()).ln(),
        }
    }

    /// The next tentative collision in [t, b] under majorant σ̄ (then a new τ is drawn), or
    /// None when the flight crosses b (having spent σ̄ (b − t) of τ).
    fn next<R: Rng>(&mut self, rng: &mut R, t: f64, b: f64, majorant: f64) -> Option<f64> {
        if !(majorant > 0.0) {
            return None;
        }
        let reach = majorant * (b - t);
        if reach <= self.tau {
            self.tau -= reach;
            return None;
        }
        let event = t + self.tau / majorant;
        *self = Self::new(rng);
        Some(event)
    }
}

/// The next real collision along o + t w by delta tracking, or None if the ray leaves.
pub fn collide<R: Rng>(m: &dyn Medium, o: Vec3, w: Vec3, rng: &mut R) -> Option<Vec3> {
    let segment = m.clip(o, w)?;
    let mut flight = Flight::new(rng);
    m.majorants().walk(o, w, segment, |a, b, bounds| {
        let mut t = a;
        while let Some(event) = flight.next(rng, t, b, bounds.max) {
            t = event;
            let p = at(o, w, t);
            // In a homogeneous cell every tentative collision is real.
            if bounds.homogeneous() || rng.random::<f64>() * bounds.max < m.sigma_t(p) {
                return ControlFlow::Break(p);
            }
        }
        ControlFlow::Continue(())
    })
}

/// Transmittance along o + t w to the medium's end: closed form exp(−σ Δt) on homogeneous
/// cells, else ratio tracking (unbiased, never 0 by a single event).
pub fn transmittance<R: Rng>(m: &dyn Medium, o: Vec3, w: Vec3, rng: &mut R) -> f64 {
    let Some(segment) = m.clip(o, w) else {
        return 1.0;
    };
    let mut tr = 1.0;
    let mut flight = Flight::new(rng);
    m.majorants().walk(o, w, segment, |a, b, bounds| {
        if bounds.homogeneous() {
            tr *= (-bounds.max * (b - a)).exp();
        } else {
            let mut t = a;
            while let Some(event) = flight.next(rng, t, b, bounds.max) {
                t = event;
                tr *= 1.0 - m.sigma_t(at(o, w, t)) / bounds.max;
            }
        }
        if tr < 1e-12 {
            ControlFlow::Break(())
        } else {
            ControlFlow::Continue(())
        }
    });
    tr
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
    let mut beta = [1.0; 3];
    let mut order = 0u32;
    // p̄ of the direction the path arrived along, when it was sampled at a collision.
    let mut arrival_pdf = None;
    while let Some(x) = collide(v.medium, o, w, rng) {
        order += 1;
        let g = group_of(v.group_first, order).min(MAX_GROUPS - 1);
        let tr = transmittance(v.medium, x, v.sun_dir, rng);
        let p_sun = v.eval(dot(v.sun_dir, w));
        // Strategy A's MIS weight against B (run at the previous collision).
        let mis = match arrival_pdf {
            Some(p_a) if v.guided_nee => p_a / (p_a + v.mean(p_sun)),
            _ => 1.0,
        };
        for k in 0..3 {
            out.groups[g][k] += beta[k] * v.albedo * p_sun[k] * tr * v.sun_irradiance * mis;
            beta[k] *= v.albedo;
        }
        if beta.iter().all(|&b| b < 1e-3) {
            // Roulette on light paths only: survive with probability 0.1 at 10× the weight.
            if rng.random::<f64>() >= 0.1 {
                return out;
            }
            beta = beta.map(|b| 10.0 * b);
        }
        if v.guided_nee {
            let g_next = group_of(v.group_first, order + 1).min(MAX_GROUPS - 1);
            let c = v.guided_contribution(x, w, &beta, rng);
            for k in 0..3 {
                out.groups[g_next][k] += c[k];
            }
        }
        let (w_new, pdf) = v.scatter(w, &mut beta, rng);
        arrival_pdf = Some(pdf);
        (o, w) = (x, w_new);
    }
    if order > 0 && v.sky > 0.0 {
        let g = group_of(v.group_first, order).min(MAX_GROUPS - 1);
        for k in 0..3 {
            out.sky_groups[g][k] += beta[k] * v.sky;
        }
    }
    out
}

impl Volume<'_> {
    /// p(cos) per channel (1/sr).
    fn eval(&self, cos: f64) -> Rgb {
        match self.phases {
            [p] => [p.eval(cos); 3],
            ps => std::array::from_fn(|k| ps[k].eval(cos)),
        }
    }

    /// The channel mean p̄ (the density of a direction sampled from a uniform channel).
    fn mean(&self, p: Rgb) -> f64 {
        if self.phases.len() == 3 {
            (p[0] + p[1] + p[2]) / 3.0
        } else {
            p[0]
        }
    }

    /// The phase function to sample: a channel's, drawn uniformly, when there are three.
    fn channel<R: Rng>(&self, rng: &mut R) -> &(dyn PhaseFunction<f64> + Sync) {
        if self.phases.len() == 3 {
            self.phases[(3.0 * rng.random::<f64>()).min(2.0) as usize]
        } else {
            self.phases[0]
        }
    }

    /// A new direction around w from the phase function, the channels' weights p_k / p̄
    /// applied to β, and p̄(w · w′), the density it was drawn with (NaN when neither the
    /// channels nor two-vertex NEE need it: one phase function's weight is 1).
    fn scatter<R: Rng>(&self, w: Vec3, beta: &mut Rgb, rng: &mut R) -> (Vec3, f64) {
        let phase = self.channel(rng);
        let (w_new, _) = phase.sample(rng.random(), rng.random(), w);
        let w_new = normalize(w_new);
        if self.phases.len() == 1 && !self.guided_nee {
            return (w_new, f64::NAN);
        }
        let p = self.eval(dot(w_new, w));
        let mean = self.mean(p);
        if self.phases.len() == 3 {
            for k in 0..3 {
                beta[k] *= p[k] / mean;
            }
        }
        (w_new, mean)
    }

    /// Strategy B at the collision x reached along w (β after this collision's albedo): the
    /// next order's sunlight through a direction sampled around the sun (module docs).
    fn guided_contribution<R: Rng>(&self, x: Vec3, w: Vec3, beta: &Rgb, rng: &mut R) -> Rgb {
        let phase = self.channel(rng);
        let (w2, _) = phase.sample(rng.random(), rng.random(), self.sun_dir);
        let w2 = normalize(w2);
        let Some(x2) = collide(self.medium, x, w2, rng) else {
            return [0.0; 3];
        };
        let tr = transmittance(self.medium, x2, self.sun_dir, rng);
        let (p_a, p_b) = (self.eval(dot(w, w2)), self.eval(dot(self.sun_dir, w2)));
        let denom = self.mean(p_a) + self.mean(p_b);
        std::array::from_fn(|k| {
            beta[k] * self.albedo * p_a[k] * p_b[k] * tr * self.sun_irradiance / denom
        })
    }
}
