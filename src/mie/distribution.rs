//! Droplet size distributions and their quadratures in ln d.
//!
//! Every distribution is handled through its number density per unit ln d, f(ln d) (for a
//! density n(d) per unit diameter, f = d · n(d)), on a finite support [ln d_lo, ln d_hi].

use crate::io::text::short;
use anyhow::{bail, Result};
use serde::{Deserialize, Serialize};

/// A number-size distribution of droplet diameters.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
#[serde(tag = "kind", rename_all = "snake_case", deny_unknown_fields)]
pub enum SizeDistribution {
    /// All droplets have diameter `d_um` (µm).
    Mono {
        /// Diameter, µm.
        d_um: f64,
    },
    /// Log-normal: n(d) ∝ (1/d) exp(−(ln d − ln d_med)² / (2σ²)).
    LogNormal {
        /// Median diameter d_med, µm.
        d_median_um: f64,
        /// Standard deviation σ of ln d.
        sigma: f64,
    },
    /// Modified gamma (Deirmendjian; MiePlot's fog option) written with the mode diameter:
    /// n(d) ∝ d^α exp(−(α/γ)(d/d_mode)^γ).
    ModifiedGamma {
        /// Mode diameter (peak of n(d)), µm.
        d_mode_um: f64,
        /// Power α > 0.
        alpha: f64,
        /// Shape γ > 0.
        gamma: f64,
    },
}

/// Quadrature nodes in diameter with normalised number weights (Σ w = 1).
#[derive(Clone, Debug)]
pub struct SizeNodes {
    /// Diameters, µm.
    pub d_um: Vec<f64>,
    /// Number weights, summing to 1.
    pub weight: Vec<f64>,
}

/// Smallest diameter a distribution may name, µm: below it the number was almost certainly
/// meant in metres or mm (docs/mie.md, "Limits").
pub const D_MIN_UM: f64 = 0.01;

/// Largest log-normal σ (of ln d): the ±5σ sizes then span a factor e^10 ≈ 22 000 already;
/// cloud droplets have σ ≈ 0.1–0.5, aerosols up to ≈ 0.9 (docs/mie.md, "Limits").
pub const SIGMA_MAX: f64 = 1.0;

/// Half-width of the explicit product rule in units of σ: z ∈ [−4, 4] (docs/mie.md).
pub const PRODUCT_RULE_Z: f64 = 4.0;

impl SizeDistribution {
    /// Checks the parameters; the error names the bad one.
    pub fn validate(&self) -> Result<()> {
        let positive = |name: &str, v: f64| -> Result<()> {
            if !(v.is_finite() && v > 0.0) {
                bail!("{name} must be a positive finite number, got {v}");
            }
            Ok(())
        };
        let diameter = |name: &str, d: f64| positive(name, d).and_then(|_| diameter_floor(d));
        match *self {
            Self::Mono { d_um } => diameter("diameter (µm)", d_um),
            Self::LogNormal { d_median_um, sigma } => {
                diameter("median diameter (µm)", d_median_um)?;
                positive("sigma (σ of ln d)", sigma)?;
                sigma_range(sigma)
            }
            Self::ModifiedGamma {
                d_mode_um,
                alpha,
                gamma,
            } => {
                diameter("mode diameter (µm)", d_mode_um)?;
                positive("gamma-distribution alpha", alpha)?;
                positive("gamma-distribution gamma", gamma)
            }
        }
    }

    /// The diameter that names the distribution (median, mode or the single size), µm.
    pub fn nominal_diameter_um(&self) -> f64 {
        match *self {
            Self::Mono { d_um } => d_um,
            Self::LogNormal { d_median_um, .. } => d_median_um,
            Self::ModifiedGamma { d_mode_um, .. } => d_mode_um,
        }
    }

    /// Unnormalised number density per unit ln d at `ln_d` (d in µm); zero for `Mono`.
    pub fn density_ln_d(&self, ln_d: f64) -> f64 {
        match *self {
            Self::Mono { .. } => 0.0,
            Self::LogNormal { d_median_um, sigma } => {
                let z = (ln_d - d_median_um.ln()) / sigma;
                (-0.5 * z * z).exp()
            }
            Self::ModifiedGamma {
                d_mode_um,
                alpha,
                gamma,
            } => {
                // ln f = (α + 1) ln(d/d_mode) − (α/γ)((d/d_mode)^γ − 1), so f(d_mode) = 1.
                let u = ln_d - d_mode_um.ln();
                ((alpha + 1.0) * u - alpha / gamma * ((gamma * u).exp() - 1.0)).exp()
            }
        }
    }

    /// Support [ln d_lo, ln d_hi] outside which the density is negligible: ±`z_max` σ for the
    /// log-normal, where f falls below exp(−z_max²/2) of its peak for the gamma distribution.
    pub fn support_ln_d(&self, z_max: f64) -> (f64, f64) {
        match *self {
            Self::Mono { d_um } => (d_um.ln(), d_um.ln()),
            Self::LogNormal { d_median_um, sigma } => (
                d_median_um.ln() - z_max * sigma,
                d_median_um.ln() + z_max * sigma,
            ),
            Self::ModifiedGamma { .. } => {
                let floor = (-0.5 * z_max * z_max).exp();
                let peak_ln = self.gamma_peak_ln_d();
                let peak = self.density_ln_d(peak_ln);
                let edge = |dir: f64| {
                    let mut u = peak_ln;
                    while self.density_ln_d(u) > floor * peak {
                        u += dir * 1e-3;
                    }
                    u
                };
                (edge(-1.0), edge(1.0))
            }
        }
    }

    /// Peak of the gamma density per ln d: (d/d_mode)^γ = (α + 1)/α.
    fn gamma_peak_ln_d(&self) -> f64 {
        match *self {
            Self::ModifiedGamma {
                d_mode_um,
                alpha,
                gamma,
            } => d_mode_um.ln() + ((alpha + 1.0) / alpha).ln() / gamma,
            _ => unreachable!("only for the modified gamma distribution"),
        }
    }

    /// The explicit product rule (docs/mie.md) with `n` sizes: for the log-normal, z uniform in
    /// [−4, 4] inclusive, d_i = d_med e^{σ z_i}, w_i ∝ e^{−z_i²/2}; for the gamma distribution
    /// n points uniform in ln d over its ±4σ-equivalent support, w_i ∝ f(ln d_i).
    pub fn product_rule(&self, n: usize) -> SizeNodes {
        if let Self::Mono { d_um } = *self {
            return SizeNodes {
                d_um: vec![d_um],
                weight: vec![1.0],
            };
        }
        let (lo, hi) = self.support_ln_d(PRODUCT_RULE_Z);
        let ln_d: Vec<f64> = if n == 1 {
            vec![0.5 * (lo + hi)]
        } else {
            (0..n)
                .map(|i| lo + (hi - lo) * i as f64 / (n - 1) as f64)
                .collect()
        };
        let w: Vec<f64> = ln_d.iter().map(|&u| self.density_ln_d(u)).collect();
        let total: f64 = w.iter().sum();
        SizeNodes {
            d_um: ln_d.iter().map(|u| u.exp()).collect(),
            weight: w.iter().map(|v| v / total).collect(),
        }
    }
}

/// Refuses a diameter below [`D_MIN_UM`], naming the likely slip (metres for µm).
fn diameter_floor(d_um: f64) -> Result<()> {
    if d_um >= D_MIN_UM {
        return Ok(());
    }
    let as_m = d_um * 1e6;
    let hint = if (D_MIN_UM..=1e4).contains(&as_m) {
        format!(" ({} m is {} µm)", short(d_um), short(as_m))
    } else {
        String::new()
    };
    bail!(
        "diameter {} µm is below {D_MIN_UM} µm: diameters are in µm, not metres{hint}",
        short(d_um)
    )
}

/// Refuses a log-normal σ above [`SIGMA_MAX`]: σ is the width of ln d, and the work grows
/// with the span e^{10σ} of the sizes.
fn sigma_range(sigma: f64) -> Result<()> {
    if sigma <= SIGMA_MAX {
        return Ok(());
    }
    bail!(
        "sigma = {} is outside (0, {SIGMA_MAX}]: it is the standard deviation of ln d (0.25 for a \
         25 % spread), not a width in µm or per cent; the ±5σ sizes would span a factor {}",
        short(sigma),
        short((10.0 * sigma).exp())
    )
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn product_rule_matches_spec_nodes() {
        let dist = SizeDistribution::LogNormal {
            d_median_um: 10.0,
            sigma: 0.25,
        };
        let nodes = dist.product_rule(41);
        assert_eq!(nodes.d_um.len(), 41);
        assert!((nodes.d_um[0] - 10.0 * (-1.0f64).exp()).abs() < 1e-12);
        assert!((nodes.d_um[20] - 10.0).abs() < 1e-12);
        assert!((nodes.d_um[40] - 10.0 * 1.0f64.exp()).abs() < 1e-12);
        let z0: f64 = -4.0;
        let ratio = nodes.weight[0] / nodes.weight[20];
        assert!((ratio - (-0.5 * z0 * z0).exp()).abs() < 1e-15);
        assert!((nodes.weight.iter().sum::<f64>() - 1.0).abs() < 1e-14);
    }

    #[test]
    fn gamma_peak_is_where_density_is_largest() {
        let dist = SizeDistribution::ModifiedGamma {
            d_mode_um: 8.0,
            alpha: 6.0,
            gamma: 1.0,
        };
        let p = dist.gamma_peak_ln_d();
        let f = |u| dist.density_ln_d(u);
        assert!(f(p) > f(p + 1e-3) && f(p) > f(p - 1e-3));
        let (lo, hi) = dist.support_ln_d(5.0);
        assert!(lo < p && p < hi);
        assert!(f(lo) < 1e-5 * f(p) && f(hi) < 1e-5 * f(p));
    }

    #[test]
    fn invalid_parameters_are_rejected() {
        for bad in [f64::NAN, -1.0, 0.0, f64::INFINITY] {
            assert!(SizeDistribution::LogNormal {
                d_median_um: bad,
                sigma: 0.25
            }
            .validate()
            .is_err());
            assert!(SizeDistribution::LogNormal {
                d_median_um: 5.0,
                sigma: bad
            }
            .validate()
            .is_err());
        }
    }
}
