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
//! β the path throughput (ϖ^{n−1} without roulette); each light adds
//! β ϖ p(ω · w) T_r(x → light) I(−ω) / r² (ω toward it, r its distance; for an area light one
//! sampled point of it, I = L_e r²/q) at the same collision ([`crate::render::light`]); surfaces ([`crate::render::surface`]) end free flights and
//! block shadow rays, and at a diffuse surface vertex the path scores β (ρ/π) cos θ T_r E for
//! the sun and each light, then continues along a cosine-distributed direction with β ← β ρ
//! (at a mirror, along the mirror direction, with nothing scored); the path continues along a direction
//! sampled from p around w (p is symmetric, so this is p(w′ · w) exactly), and an escaping path
//! adds β L_sky to the order of its last scattering (the constant sky, if any).
//!
//! Per-channel phase functions p_R, p_G, p_B (a Mie table per sRGB channel): β and the
//! radiance are RGB; the new direction is sampled from a channel c drawn uniformly, so its
//! density is the mean p̄ = (p_R + p_G + p_B)/3 (one-sample MIS, balance heuristic), and each
//! channel's throughput takes the weight β_k ← β_k p_k(cos) / p̄(cos) — unbiased wherever p̄ > 0,
//! and never more than 3.
//!
//! Sun-lobe next-event estimation (`SunLobe`, K steps; see `sun_lobe`): every collision also
//! launches a walk whose first direction is drawn from p around the sun and which follows p
//! while it stays in the sun's forward-peak lobe (at most K steps); its collisions score NEE
//! for the next orders, and each order's estimates are combined by the balance heuristic over
//! the last K directions, one strategy per entry into the lobe — the Mie forward peak's
//! fireflies are divided out. The camera path itself continues as before (no weights compound).
//!
//! Roulette: a deterministic schedule by order, so that the strategies' densities can include
//! it: once ϖⁿ falls below 10⁻³ the path survives with probability 0.1 per decade (its weight
//! ×10) — never for ϖ = 1.

use super::sun_lobe::{mis_weight, History, Step, SunLobe, MAX_STEPS};
use crate::render::geometry::{dot, normalize, Vec3};
use crate::render::light::Light;
use crate::render::medium::Medium;
use crate::render::surface::{self, Hit, Material, Surfaces};
use nephele_runtime::phase::{Cosine, TabulatedChannels};
use nephele_runtime::PhaseFunction;
use rand::Rng;
use std::f64::consts::PI;
use std::ops::ControlFlow;

/// Shadow rays play roulette once their estimate falls below this fraction of a fresh path's
/// isotropic single scattering (`Volume::to_sun`).
pub const SHADOW_ROULETTE: f64 = 0.05;

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
    /// The three channels' tables evaluated together, when they are tables on the same angles
    /// ([`channel_tables`]; None: each evaluated on its own, with the same values).
    pub channels: Option<TabulatedChannels<'a, f64, 3>>,
    /// Unit vector toward the sun.
    pub sun_dir: Vec3,
    /// Sun irradiance on a surface facing it (W/m², or 1 for T = L/E⊥).
    pub sun_irradiance: f64,
    /// Constant sky radiance (0: none).
    pub sky: f64,
    /// First scattering order of each group, increasing from 1.
    pub group_first: &'a [u32],
    /// The sun-lobe walks launched at every collision (`SunLobe::OFF`: plain NEE).
    pub sun_lobe: SunLobe,
    /// Point, spot and area lights, each seen by next-event estimation at every collision.
    pub lights: &'a [Light],
    /// Opaque surfaces: they end free flights and block shadow rays.
    pub surfaces: &'a Surfaces,
}

/// RGB.
pub type Rgb = [f64; 3];

/// The three channels' phase functions as [`TabulatedChannels`] when they are tables on the
/// same angles (per-channel Mie): a cosine's angle is then found once for the three (the path
/// tracer evaluates the channels at every collision, and the angle is most of the cost).
pub fn channel_tables<'a>(
    phases: &'a [&'a (dyn PhaseFunction<f64> + Sync)],
) -> Option<TabulatedChannels<'a, f64, 3>> {
    let [r, g, b] = phases else {
        return None;
    };
    TabulatedChannels::new([r.as_tabulated()?, g.as_tabulated()?, b.as_tabulated()?])
}

/// One camera path's radiance, split by scattering order, and the camera ray's transmittance.
#[derive(Clone, Copy, Debug, Default)]
pub struct PathSample {
    /// Sunlight per order group (the first `group_first.len()` entries), RGB.
    pub groups: [Rgb; MAX_GROUPS],
    /// Skylight per order group (scattered at least once), RGB.
    pub sky_groups: [Rgb; MAX_GROUPS],
    /// The lights' light per order group, RGB (absolute: their intensities
    /// are applied here, not when the images are gathered).
    pub light_groups: [Rgb; MAX_GROUPS],
    /// Radiance seen without scattering (the sky through the medium).
    pub unscattered: f64,
    /// Transmittance of the camera ray through the whole medium (1 − opacity).
    pub transmittance: f64,
}

impl PathSample {
    /// The total radiance of channel c: the groups and the unscattered part.
    pub fn total(&self, c: usize) -> f64 {
        let sum = |g: &[Rgb; MAX_GROUPS]| g.iter().map(|v| v[c]).sum::<f64>();
        self.unscattered + sum(&self.groups) + sum(&self.sky_groups) + sum(&self.light_groups)
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
    collide_before(m, o, w, f64::INFINITY, rng)
}

/// `collide` within the first `reach` (m) of the ray: before a surface.
pub fn collide_before<R: Rng>(
    m: &dyn Medium,
    o: Vec3,
    w: Vec3,
    reach: f64,
    rng: &mut R,
) -> Option<Vec3> {
    let (a, b) = m.clip(o, w)?;
    if a >= reach {
        return None;
    }
    let segment = (a, b.min(reach));
    let mut flight = Flight::new(rng);
    m.tracking_majorants().walk(o, w, segment, |a, b, bounds| {
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
    transmittance_roulette(m, o, w, 0.0, rng)
}

/// `transmittance` with Russian roulette once the running value falls below `floor`: it goes on
/// as `floor` with probability tr/floor, else ends at 0 — unbiased, and it spares the density
/// lookups (noise) of the cells a deep collision's shadow ray would cross for nothing.
pub fn transmittance_roulette<R: Rng>(
    m: &dyn Medium,
    o: Vec3,
    w: Vec3,
    floor: f64,
    rng: &mut R,
) -> f64 {
    transmittance_within(m, o, w, f64::INFINITY, floor, rng)
}

/// `transmittance_roulette` over the first `distance` (m) of the ray only: toward a light.
pub fn transmittance_within<R: Rng>(
    m: &dyn Medium,
    o: Vec3,
    w: Vec3,
    distance: f64,
    floor: f64,
    rng: &mut R,
) -> f64 {
    let Some((a, b)) = m.clip(o, w) else {
        return 1.0;
    };
    if a >= distance {
        return 1.0;
    }
    let segment = (a, b.min(distance));
    let mut tr = 1.0;
    let mut flight = Flight::new(rng);
    let roulette = |tr: &mut f64, rng: &mut R| {
        if *tr < floor {
            *tr = if rng.random::<f64>() * floor < *tr {
                floor
            } else {
                0.0
            };
        }
    };
    m.tracking_majorants().walk(o, w, segment, |a, b, bounds| {
        if bounds.homogeneous() {
            tr *= (-bounds.max * (b - a)).exp();
        } else {
            roulette(&mut tr, rng);
            let mut t = a;
            while tr > 0.0 {
                let Some(event) = flight.next(rng, t, b, bounds.max) else {
                    break;
                };
                t = event;
                tr *= 1.0 - m.sigma_t(at(o, w, t)) / bounds.max;
                roulette(&mut tr, rng);
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
    let seen = v.hit(o, w);
    let reach = seen.map_or(f64::INFINITY, |h| h.t);
    let mut out = PathSample {
        transmittance: transmittance_within(v.medium, o, w, reach, 0.0, rng),
        ..PathSample::default()
    };
    // A surface in view hides the sky behind it.
    out.unscattered = if seen.is_none() {
        out.transmittance * v.sky
    } else {
        0.0
    };
    let (mut o, mut w) = (o, w);
    let mut beta = [1.0; 3];
    let mut order = 0u32;
    let mut history = History::default();
    // p̄ of the direction the path arrived along, when it was sampled at a collision.
    let mut arrival_pdf = None;
    // The order of the last surface vertex: the sun-lobe walks' MIS windows start after it
    // (a walk ends at a surface, so no walk can make a path through one).
    let mut base = 0u32;
    // The camera ray's surface hit is already known; later rays look theirs up.
    let mut next_hit = Some(seen);
    loop {
        let hit = next_hit.take().unwrap_or_else(|| v.hit(o, w));
        let reach = hit.map_or(f64::INFINITY, |h| h.t);
        let Some(x) = collide_before(v.medium, o, w, reach, rng) else {
            let Some(h) = hit else {
                break;
            };
            order += 1;
            let x = at(o, w, h.t);
            // A mirror's BRDF is a delta: no light can be sampled toward it.
            if h.material == Material::Diffuse {
                v.surface_nee(x, &h, &beta, order, &mut out, rng);
            }
            for (b, r) in beta.iter_mut().zip(h.reflectance) {
                *b *= r;
            }
            if !surface_roulette(&mut beta, rng) {
                return out;
            }
            (history, arrival_pdf, base) = (History::default(), None, order);
            let w_new = match h.material {
                Material::Diffuse => surface::sample_cosine(h.normal, rng.random(), rng.random()),
                Material::Mirror => surface::reflect(w, h.normal),
            };
            (o, w) = (x, w_new);
            continue;
        };
        order += 1;
        let p_sun = v.eval(dot(v.sun_dir, w));
        let mis = match arrival_pdf {
            Some(a) if v.sun_lobe.steps > 0 => {
                history.push(Step {
                    a,
                    b: v.mean(p_sun),
                });
                let mut window = [Step::default(); MAX_STEPS];
                let l = v.window(order - base);
                history.last(l, &mut window);
                mis_weight(&window[..l], 0, order, v.sun_lobe.threshold, |m| {
                    v.survival(m)
                })
            }
            _ => 1.0,
        };
        let tr = v.to_sun(x, &beta, v.mean(p_sun) * mis, rng);
        let g = v.group(order);
        for light in v.lights {
            v.to_light(light, x, w, &beta, &mut out.light_groups[g], rng);
        }
        for k in 0..3 {
            out.groups[g][k] += beta[k] * v.albedo * p_sun[k] * tr * v.sun_irradiance * mis;
            beta[k] *= v.albedo;
        }
        let q = v.survival(order);
        if q < 1.0 {
            if !(rng.random::<f64>() < q) {
                return out;
            }
            beta = beta.map(|b| b / q);
        }
        if v.sun_lobe.steps > 0 {
            v.sun_lobe_walk(x, w, (base, order), &beta, &history, &mut out, rng);
        }
        let (w_new, pdf) = v.scatter(w, &mut beta, rng);
        arrival_pdf = Some(pdf);
        (o, w) = (x, w_new);
    }
    if order > 0 && v.sky > 0.0 {
        let g = v.group(order);
        for k in 0..3 {
            out.sky_groups[g][k] += beta[k] * v.sky;
        }
    }
    out
}

/// Roulette at a surface vertex once the throughput's largest channel falls below 10⁻³:
/// survive with probability 0.1 (β × 10). Every strategy of a later MIS window shares this
/// vertex, so the walks' weights need not know it. False when the path ends.
fn surface_roulette<R: Rng>(beta: &mut Rgb, rng: &mut R) -> bool {
    if beta.iter().copied().fold(0.0, f64::max) >= 1e-3 {
        return true;
    }
    if rng.random::<f64>() < 0.1 {
        *beta = beta.map(|b| b * 10.0);
        true
    } else {
        false
    }
}

impl Volume<'_> {
    /// The nearest surface along o + t w.
    fn hit(&self, o: Vec3, w: Vec3) -> Option<Hit> {
        self.surfaces.nearest(o, w, f64::INFINITY)
    }

    /// Whether no surface lies on the first `distance` (m) of o + t w.
    fn unblocked(&self, o: Vec3, w: Vec3, distance: f64) -> bool {
        self.surfaces.nearest(o, w, distance).is_none()
    }

    /// Next-event estimation at the surface vertex x of order n (throughput β before its
    /// reflectance): the sun, β (ρ/π) cos θ_s T_r(x → sun) E, and each light,
    /// β (ρ/π) cos θ T_r(x → light) I / r², on the side of the normal.
    fn surface_nee<R: Rng>(
        &self,
        x: Vec3,
        h: &Hit,
        beta: &Rgb,
        n: u32,
        out: &mut PathSample,
        rng: &mut R,
    ) {
        let g = self.group(n);
        let cos = dot(h.normal, self.sun_dir);
        if cos > 0.0 && self.unblocked(x, self.sun_dir, f64::INFINITY) {
            let tr = transmittance(self.medium, x, self.sun_dir, rng);
            for k in 0..3 {
                out.groups[g][k] += beta[k] * surface::brdf(h, k) * cos * tr * self.sun_irradiance;
            }
        }
        for light in self.lights {
            let Some(i) = light.sample(x, rng) else {
                continue;
            };
            let cos = dot(h.normal, i.toward);
            if !(cos > 0.0) || !self.unblocked(x, i.toward, i.distance) {
                continue;
            }
            let tr = transmittance_within(self.medium, x, i.toward, i.distance, 0.0, rng);
            let r2 = i.distance * i.distance;
            for k in 0..3 {
                out.light_groups[g][k] +=
                    beta[k] * surface::brdf(h, k) * cos * tr * i.intensity[k] / r2;
            }
        }
    }

    /// p(cos) per channel (1/sr).
    fn eval(&self, cos: f64) -> Rgb {
        if let Some(tables) = &self.channels {
            return tables.pdf_cosine(Cosine::from_mu(cos));
        }
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
        if self.phases.len() == 1 && self.sun_lobe.steps == 0 {
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

    /// The shadow ray's transmittance from x toward the sun for a NEE of throughput β and
    /// phase function × MIS weight `p_mis` (1/sr): with roulette below the level at which the
    /// estimate would be `SHADOW_ROULETTE` of a fresh path's isotropic single scattering, so
    /// that rays whose light could not matter stop early (unbiased).
    fn to_sun<R: Rng>(&self, x: Vec3, beta: &Rgb, p_mis: f64, rng: &mut R) -> f64 {
        let importance = (beta[0] + beta[1] + beta[2]) / 3.0 * p_mis * 4.0 * PI;
        let floor = if importance > 0.0 {
            SHADOW_ROULETTE / importance
        } else {
            0.0
        };
        if !self.unblocked(x, self.sun_dir, f64::INFINITY) {
            return 0.0;
        }
        transmittance_roulette(self.medium, x, self.sun_dir, floor, rng)
    }

    /// Next-event estimation of `light` at the collision x reached along w, throughput β
    /// (before this collision's albedo): β ϖ p(ω · w) T_r(x → light) I(−ω) / r² into `out`,
    /// ω toward the light at distance r.
    fn to_light<R: Rng>(
        &self,
        light: &Light,
        x: Vec3,
        w: Vec3,
        beta: &Rgb,
        out: &mut Rgb,
        rng: &mut R,
    ) {
        let Some(i) = light.sample(x, rng) else {
            return;
        };
        if !self.unblocked(x, i.toward, i.distance) {
            return;
        }
        let p = self.eval(dot(i.toward, w));
        // No roulette: a light's scale is absolute, so the sun's relative floor does not apply.
        let tr = transmittance_within(self.medium, x, i.toward, i.distance, 0.0, rng);
        for k in 0..3 {
            out[k] +=
                beta[k] * self.albedo * p[k] * tr * i.intensity[k] / (i.distance * i.distance);
        }
    }

    /// The order group of scattering order n.
    fn group(&self, n: u32) -> usize {
        group_of(self.group_first, n).min(MAX_GROUPS - 1)
    }

    /// Directions of the MIS window for order n: the last K, never the camera's own.
    fn window(&self, n: u32) -> usize {
        self.sun_lobe.steps.min(n as usize - 1)
    }

    /// The probability of surviving roulette at the collision of order n: 0.1 per decade that
    /// ϖⁿ falls below 10⁻³ × 10^(earlier survivals), i.e. 0.1^(E(n) − E(n − 1)) with
    /// E(n) = max(0, ⌈n log₁₀(1/ϖ) − 3⌉); deterministic, so every strategy's density has it.
    fn survival(&self, n: u32) -> f64 {
        if self.albedo >= 1.0 {
            return 1.0;
        }
        if !(self.albedo > 0.0) {
            return 0.0;
        }
        let decades = -self.albedo.log10();
        let e = |n: u32| (n as f64 * decades - 3.0).ceil().max(0.0);
        0.1f64.powf(e(n) - e(n - 1))
    }

    /// The sun-lobe walk launched at the collision x of order m, reached along w (β after this
    /// collision's albedo and roulette): the first direction around the sun, the next ones
    /// around the previous while they stay in the lobe, at most K; the i-th collision scores
    /// order m + i with its MIS weight (module `sun_lobe`), over the directions since the last
    /// surface vertex (of order `base`, 0 if none). A surface ends the walk.
    #[allow(clippy::too_many_arguments)]
    fn sun_lobe_walk<R: Rng>(
        &self,
        x: Vec3,
        w: Vec3,
        (base, m): (u32, u32),
        beta: &Rgb,
        history: &History,
        out: &mut PathSample,
        rng: &mut R,
    ) {
        let mut window = [Step::default(); MAX_STEPS];
        let mut walk = [Step::default(); MAX_STEPS];
        let (mut pos, mut prev, mut throughput) = (x, w, *beta);
        for i in 1..=self.sun_lobe.steps {
            let around = if i == 1 { self.sun_dir } else { prev };
            let (d, _) = self.channel(rng).sample(rng.random(), rng.random(), around);
            let d = normalize(d);
            let (p_a, p_b) = (self.eval(dot(prev, d)), self.eval(dot(self.sun_dir, d)));
            let step = Step {
                a: self.mean(p_a),
                b: self.mean(p_b),
            };
            walk[i - 1] = step;
            let density = if i == 1 { step.b } else { step.a };
            for k in 0..3 {
                throughput[k] *= p_a[k] / density;
            }
            // A surface ends the walk: its collisions are the medium's only.
            let reach = self.hit(pos, d).map_or(f64::INFINITY, |h| h.t);
            let Some(x2) = collide_before(self.medium, pos, d, reach, rng) else {
                return;
            };
            let n = m + i as u32;
            let l = self.window(n - base);
            history.last(l - i, &mut window);
            window[l - i..l].copy_from_slice(&walk[..i]);
            let tau = self.sun_lobe.threshold;
            let mis = mis_weight(&window[..l], l - i + 1, n, tau, |o| self.survival(o));
            let tr = self.to_sun(x2, &throughput, step.b * mis, rng);
            let g = self.group(n);
            for k in 0..3 {
                out.groups[g][k] +=
                    throughput[k] * self.albedo * p_b[k] * tr * self.sun_irradiance * mis;
                throughput[k] *= self.albedo;
            }
            if step.b < tau {
                return;
            }
            (pos, prev) = (x2, d);
        }
    }
}
