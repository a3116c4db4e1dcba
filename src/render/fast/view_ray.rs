//! The view ray's march (docs/collector.md, "March"): one ray of a pixel through the medium in
//! sub-steps ([`super::substeps`]), gathering its transmittance T_v, the integrals
//! I_{aⁱ} = ∫ σ T_v e^{−aⁱ τ_sun} ds of order 1 and the octaves (closed form per sub-step, τ_sun
//! linear over it), and the surface point p where it first crosses the lit surface's iso-level
//! ρ₀ (interpolated between sub-steps; where it never does, the sub-step of largest σ), with
//! what it knows of the medium beyond p and p's optical depth to the sun: what the collector
//! search takes as its viewpoint; and the ray's optical depth along its chord, for the sky term.

use super::octaves::MAX_OCTAVES;
use super::sky::CHORD_ENOUGH;
use super::sky_order1::Gather;
use super::substeps::substeps;
use super::{Frame, Method};
use crate::render::geometry::Vec3;
use nephele_runtime::transport::Viewpoint;
use std::ops::ControlFlow;

/// What one view ray gathers.
#[derive(Clone, Copy, Debug, Default)]
pub(super) struct ViewRay {
    /// T_v at the end.
    pub(super) transmittance: f64,
    /// I_{aⁱ} per octave (I₀ is order 1's integral).
    pub(super) integrals: [f64; MAX_OCTAVES],
    /// Where the ray meets the lit surface (or its densest sub-step).
    pub(super) surface: Option<Vec3>,
    /// The optical depth of the ray beyond the surface point (mfp), and whether that is all of
    /// it (the ray left the medium) or a lower bound (the march stopped where T_v < 10⁻⁴).
    behind: f64,
    behind_exact: bool,
    /// The sun's optical depth at the surface point (mfp; infinite without one).
    pub(super) sun_depth: f64,
    /// The ray's optical depth through the whole medium (mfp), marched on past the point where
    /// T_v < 10⁻⁴ stops everything else, up to [`CHORD_ENOUGH`]: the thickness of the sky
    /// term's slab.
    pub(super) chord: f64,
    /// The sky's order 1 per unit L_sky and ϖ, ∫ σ T_v V ds (with the maps toward the sky).
    pub(super) sky_order1: f64,
}

impl ViewRay {
    /// The viewpoint the collector search takes for this ray of direction `w`: its surface
    /// point, the light's travel toward the eye, and what the march knows of the medium
    /// beyond the point.
    pub(super) fn viewpoint(&self, w: Vec3) -> Option<Viewpoint> {
        let p = self.surface?;
        Some(Viewpoint {
            position: p.map(|x| x as f32),
            view: w.map(|x| -x as f32),
            behind_min: self.behind as f32,
            behind_max: if self.behind_exact {
                self.behind as f32
            } else {
                f32::INFINITY
            },
            sun_depth: self.sun_depth as f32,
        })
    }
}

impl Frame<'_> {
    /// Marches the view ray o + t w.
    pub(super) fn march(&self, o: Vec3, w: Vec3) -> ViewRay {
        let mut v = ViewRay {
            transmittance: 1.0,
            ..Default::default()
        };
        let Some(range) = self.medium.clip(o, w) else {
            return v;
        };
        let n_oct = if self.opts.method == Method::Octaves {
            self.opts.octaves.n
        } else {
            1
        };
        let factors = self.opts.octaves.extinction_factors();
        let at = |t: f64| -> Vec3 { std::array::from_fn(|k| o[k] + t * w[k]) };
        let mut tau_a: Option<(f64, f64)> = None;
        let (mut prev, mut densest) = (None::<(f64, f64)>, (0.0f64, 0.0f64));
        // The view ray's optical depth so far, and where the surface point was found.
        let (mut tau_v, mut tau_at_p, mut stopped) = (0.0f64, None::<f64>, false);
        let mut tau_at_densest = 0.0;
        let mut end = range.1;
        let mut sky = self.sky_order1.as_ref().map(|s| Gather::new(s, w));
        let _: Option<()> = substeps(
            self.medium.as_ref(),
            o,
            w,
            range,
            self.step,
            |a, b, sigma| {
                let h = b - a;
                if sigma == 0.0 {
                    // Where the noise has cleared the sub-step (most of a noisy boundary's
                    // sub-steps, 62 % on the default cloud), nothing scatters or attenuates:
                    // every sum below would add exactly 0, so the sun's depths are not looked
                    // up (the same bits).
                    prev = Some((0.5 * (a + b), sigma));
                    return ControlFlow::Continue(());
                }
                let ta = match tau_a {
                    Some((s, t)) if s == a => t,
                    _ => self.side.optical_depth(at(a)),
                };
                let tb = self.side.optical_depth(at(b));
                tau_a = Some((b, tb));
                let k = (tb - ta) / h;
                for (i, integral) in v.integrals.iter_mut().enumerate().take(n_oct) {
                    let ai = factors[i];
                    let rate = sigma + ai * k;
                    let e = if rate.abs() * h < 1e-9 {
                        h
                    } else {
                        -(-rate * h).exp_m1() / rate
                    };
                    *integral += sigma * v.transmittance * (-ai * ta).exp() * e;
                }
                let mid = 0.5 * (a + b);
                if let Some(sky) = &mut sky {
                    sky.add(v.transmittance, sigma, h, at(mid));
                }
                if v.surface.is_none() {
                    if sigma >= self.threshold {
                        let s = match prev {
                            Some((pm, ps)) if ps < self.threshold && sigma > ps => {
                                pm + (mid - pm) * (self.threshold - ps) / (sigma - ps)
                            }
                            _ => a,
                        };
                        v.surface = Some(at(s));
                        tau_at_p = Some(tau_v + sigma * (s - a).max(0.0));
                    } else if sigma > densest.1 {
                        densest = (mid, sigma);
                        tau_at_densest = tau_v + 0.5 * sigma * h;
                    }
                }
                prev = Some((mid, sigma));
                tau_v += sigma * h;
                v.transmittance *= (-sigma * h).exp();
                if v.transmittance < 1e-4 {
                    (stopped, end) = (true, b);
                    ControlFlow::Break(())
                } else {
                    ControlFlow::Continue(())
                }
            },
        );
        if v.surface.is_none() && densest.1 > 0.0 {
            v.surface = Some(at(densest.0));
            tau_at_p = Some(tau_at_densest);
        }
        v.chord = tau_v;
        if stopped {
            v.chord += self.chord_beyond(o, w, (end, range.1), CHORD_ENOUGH - tau_v);
        }
        if let Some(sky) = sky {
            v.sky_order1 = sky.finish(v.transmittance, v.chord);
        }
        v.behind = (tau_v - tau_at_p.unwrap_or(tau_v)).max(0.0);
        v.behind_exact = !stopped;
        v.sun_depth = v
            .surface
            .map_or(f64::INFINITY, |p| self.side.optical_depth(p));
        v
    }

    /// The optical depth (mfp) of o + t w over `segment`, up to `enough`: the rest of a view
    /// ray's chord past the march's stop, for the sky term's slab. Sub-steps of 8 march steps
    /// (4 mfp at the default step: the sky's table is read in ln t between nodes 0.79 apart, so
    /// τ within ~10 % is enough; 4 steps gave the same sky to 2 digits and a frame ~4 % slower),
    /// empty space and homogeneous cells skipped by the majorant grid as in the march.
    fn chord_beyond(&self, o: Vec3, w: Vec3, segment: (f64, f64), enough: f64) -> f64 {
        let mut tau = 0.0;
        let _: Option<()> = substeps(
            self.medium.as_ref(),
            o,
            w,
            segment,
            8.0 * self.step,
            |a, b, sigma| {
                tau += sigma * (b - a);
                if tau < enough {
                    ControlFlow::Continue(())
                } else {
                    ControlFlow::Break(())
                }
            },
        );
        tau
    }
}
