//! The view ray's march (docs/collector.md, "March"): one ray of a pixel through the medium in
//! sub-steps ([`super::march`]), gathering its transmittance T_v, the integrals
//! I_{aⁱ} = ∫ σ T_v e^{−aⁱ τ_sun} ds of order 1 and the octaves (closed form per sub-step, τ_sun
//! linear over it), and the surface point p where it first crosses the lit surface's iso-level
//! ρ₀ (interpolated between sub-steps; where it never does, the sub-step of largest σ), with
//! what it knows of the medium beyond p and p's optical depth to the sun: what the collector
//! search takes as its viewpoint.

use super::march::substeps;
use super::octaves::MAX_OCTAVES;
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
                    stopped = true;
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
        v.behind = (tau_v - tau_at_p.unwrap_or(tau_v)).max(0.0);
        v.behind_exact = !stopped;
        v.sun_depth = v
            .surface
            .map_or(f64::INFINITY, |p| self.side.optical_depth(p));
        v
    }
}
