//! The renderer's inverse-CDF table of a phase function, one convention for every model.
//!
//! `icdf_mu[i] = F⁻¹(ξᵢ)`, ξᵢ = i / (n − 1), with
//!
//!   F(μ) = 2π ∫_{−1}^{μ} p(μ′) dμ′,
//!
//! the CDF of the scattering cosine. It increases from −1 at ξ = 0 (backward) to +1 at ξ = 1
//! (forward) whatever the model, so a renderer can load any table the same way and interpolate
//! it linearly in ξ. Single-lobe models sample by exactly this inverse (their `sample_mu`), so
//! the table is their sampler. A mixture's sampler picks a lobe with ξ and is not monotone:
//! interpolating it would blend a backward and a forward sample at the lobe boundary. Its table
//! inverts the mixture's CDF instead, integrated by Gauss–Legendre in θ.

use crate::stats::gauss::{gauss_legendre, integrate};
use nephele_runtime::PhaseFunction;
use std::f64::consts::PI;

/// `n ≥ 2` values of F⁻¹ at ξ = 0, 1/(n − 1), …, 1 (increasing, −1 … +1).
pub fn inverse_cdf(model: &dyn PhaseFunction<f64>, n: usize) -> Vec<f64> {
    let xi = |i: usize| i as f64 / (n - 1) as f64;
    let mut table: Vec<f64> = if sampler_increases(model, 8 * n) {
        (0..n)
            .map(|i| model.sample_mu(xi(i)).clamp(-1.0, 1.0))
            .collect()
    } else {
        let cdf = ThetaCdf::new(model);
        (0..n).map(|i| cdf.mu_at(xi(i))).collect()
    };
    // The ends are exact by definition; samplers may round them (−1 + 1e-16).
    (table[0], table[n - 1]) = (-1.0, 1.0);
    table
}

/// Whether ξ ↦ `sample_mu(ξ)` is non-decreasing on m + 1 even steps (to rounding), i.e. the
/// sampler is the inverse CDF itself.
fn sampler_increases(model: &dyn PhaseFunction<f64>, m: usize) -> bool {
    let mu: Vec<f64> = (0..=m)
        .map(|k| model.sample_mu(k as f64 / m as f64))
        .collect();
    mu.windows(2).all(|w| w[1] >= w[0] - 1e-12)
}

/// C(θ) = 2π ∫₀^θ p(cos θ′) sin θ′ dθ′ (the share scattered within θ of forward), at nodes
/// dense near the forward peak: geometric from 10⁻⁶ to 0.02 rad, then every 0.002 rad.
struct ThetaCdf<'a> {
    model: &'a dyn PhaseFunction<f64>,
    rule: (Vec<f64>, Vec<f64>),
    theta: Vec<f64>,
    /// C at each node, divided by C(π) so that quadrature error does not move the ends.
    c: Vec<f64>,
    total: f64,
}

impl<'a> ThetaCdf<'a> {
    fn new(model: &'a dyn PhaseFunction<f64>) -> Self {
        let mut theta = vec![0.0];
        theta.extend((0..=60).map(|k| 1e-6 * (0.02f64 / 1e-6).powf(k as f64 / 60.0)));
        let steps = ((PI - 0.02) / 0.002).ceil() as usize;
        theta.extend((1..=steps).map(|k| 0.02 + (PI - 0.02) * k as f64 / steps as f64));
        let mut me = Self {
            model,
            rule: gauss_legendre(8),
            theta,
            c: vec![],
            total: 1.0,
        };
        let mut c = vec![0.0];
        for w in me.theta.windows(2) {
            c.push(c.last().unwrap() + me.partial(w[0], w[1]));
        }
        me.total = *c.last().unwrap();
        me.c = c.iter().map(|v| v / me.total).collect();
        me
    }

    /// 2π ∫_a^b p sin θ dθ, unnormalised.
    fn partial(&self, a: f64, b: f64) -> f64 {
        let f = |t: f64| 2.0 * PI * self.model.eval(t.cos()) * t.sin();
        integrate(&f, a, b, &self.rule, 1)
    }

    /// μ with F(μ) = ξ: C(θ) = 1 − ξ, bisected inside the node interval that holds it.
    fn mu_at(&self, xi: f64) -> f64 {
        if xi <= 0.0 {
            return -1.0;
        } else if xi >= 1.0 {
            return 1.0;
        }
        let target = 1.0 - xi;
        let k = self
            .c
            .partition_point(|v| *v <= target)
            .clamp(1, self.c.len() - 1)
            - 1;
        let (mut lo, mut hi) = (self.theta[k], self.theta[k + 1]);
        for _ in 0..60 {
            let mid = 0.5 * (lo + hi);
            if self.c[k] + self.partial(self.theta[k], mid) / self.total < target {
                lo = mid;
            } else {
                hi = mid;
            }
        }
        (0.5 * (lo + hi)).cos()
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use nephele_runtime::phase::{HenyeyGreenstein, TwoTermHg};

    #[test]
    fn a_single_lobe_table_is_its_sampler_and_a_mixture_table_inverts_its_cdf() {
        let hg = HenyeyGreenstein::new(0.7);
        let t = inverse_cdf(&hg, 33);
        assert_eq!(t[0], -1.0);
        assert_eq!(t[32], 1.0);
        assert_eq!(t[16], hg.sample_mu(0.5));
        // Two lobes: F(μ) = w F₁(μ) + (1 − w) F₂(μ), each HG's F from its sampler's inverse.
        let (g1, g2, w) = (0.8, -0.3, 0.9);
        let mix = TwoTermHg::two_term(g1, g2, w);
        let t = inverse_cdf(&mix, 65);
        assert!(t.windows(2).all(|p| p[1] >= p[0]));
        let hg_cdf = |g: f64, mu: f64| {
            // The HG CDF in closed form: F(μ) = (1 − g²)/(2g) [1/√(1 + g² − 2gμ) − 1/(1 + g)].
            (1.0 - g * g) / (2.0 * g)
                * (1.0 / (1.0 + g * g - 2.0 * g * mu).sqrt() - 1.0 / (1.0 + g))
        };
        for (i, mu) in t.iter().enumerate() {
            let f = w * hg_cdf(g1, *mu) + (1.0 - w) * hg_cdf(g2, *mu);
            assert!(
                (f - i as f64 / 64.0).abs() < 1e-9,
                "ξ = {}: F(μ) = {f}",
                i as f64 / 64.0
            );
        }
    }
}
