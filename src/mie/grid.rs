//! Angle grids and the quadratures of a tabulated phase function over them.

use anyhow::{bail, Context, Result};
use nephele_runtime::fitting::Legendre;
use std::path::Path;

/// The reference grid: 0°–5° every 0.01°, then 5.1°–180° every 0.1° (2251 angles), exact
/// decimal values.
pub fn reference_angles_deg() -> Vec<f64> {
    let fine = (0..=500).map(|i| i as f64 / 100.0);
    let coarse = (51..=1800).map(|i| i as f64 / 10.0);
    fine.chain(coarse).collect()
}

/// `default` (the reference grid), a comma-separated list, or a file of one angle in degrees
/// per line (`#` comments allowed); strictly increasing from 0° to 180°.
pub fn angles_from_spec(spec: &str) -> Result<Vec<f64>> {
    if spec == "default" {
        return Ok(reference_angles_deg());
    }
    if spec.contains(',') && !Path::new(spec).exists() {
        let out = angle_list(spec)?;
        validate_angles(&out).with_context(|| format!("angles '{spec}'"))?;
        return Ok(out);
    }
    let text = std::fs::read_to_string(Path::new(spec))
        .with_context(|| format!("cannot read angle file '{spec}'"))?;
    let mut out = Vec::new();
    for (i, line) in text.lines().enumerate() {
        let line = line.trim();
        if line.is_empty() || line.starts_with('#') {
            continue;
        }
        let v: f64 = line.parse().with_context(|| {
            format!(
                "angle file '{spec}' line {}: '{line}' is not a number",
                i + 1
            )
        })?;
        out.push(v);
    }
    validate_angles(&out).with_context(|| format!("angle file '{spec}'"))?;
    Ok(out)
}

/// Angles in degrees from a comma-separated list ("0,90,180").
pub fn angle_list(spec: &str) -> Result<Vec<f64>> {
    spec.split(',')
        .map(|a| {
            a.trim()
                .parse::<f64>()
                .with_context(|| format!("angles: '{}' is not a number of degrees", a.trim()))
        })
        .collect()
}

/// Angles must be strictly increasing from exactly 0° to exactly 180°: the CDF, the Legendre
/// moments and the quadrature normalisation integrate over the whole grid.
pub fn validate_angles(deg: &[f64]) -> Result<()> {
    if deg.len() < 2 {
        bail!("need at least two angles, got {}", deg.len());
    }
    if deg[0] != 0.0 || deg[deg.len() - 1] != 180.0 {
        bail!("the angle grid must start at 0° and end at 180° (the CDF and moments integrate over it)");
    }
    if deg.windows(2).any(|w| w[1] <= w[0]) {
        bail!("angles must be strictly increasing");
    }
    Ok(())
}

/// Trapezoid weights in θ for ∫ f(θ) 2π sin θ dθ over the grid: Σ_i w_i f(θ_i).
pub fn solid_angle_weights(theta_deg: &[f64]) -> Vec<f64> {
    let th: Vec<f64> = theta_deg.iter().map(|d| d.to_radians()).collect();
    let mut w = vec![0.0; th.len()];
    for i in 0..th.len() - 1 {
        let h = 0.5 * (th[i + 1] - th[i]) * std::f64::consts::TAU;
        w[i] += h * th[i].sin();
        w[i + 1] += h * th[i + 1].sin();
    }
    w
}

/// Cumulative distribution in θ: cdf_i = ∫_0^{θ_i} p 2π sin θ dθ by the trapezoid rule,
/// divided by its last value so that it ends at exactly 1 (the table's own normalisation).
pub fn cdf(theta_deg: &[f64], phase: &[f64]) -> Vec<f64> {
    let th: Vec<f64> = theta_deg.iter().map(|d| d.to_radians()).collect();
    let mut c = vec![0.0; th.len()];
    for i in 1..th.len() {
        let f0 = phase[i - 1] * th[i - 1].sin();
        let f1 = phase[i] * th[i].sin();
        c[i] = c[i - 1] + 0.5 * (th[i] - th[i - 1]) * std::f64::consts::TAU * (f0 + f1);
    }
    let total = c[c.len() - 1];
    c.iter().map(|v| v / total).collect()
}

/// Legendre moments χ_l = 2π ∫ p(μ) P_l(μ) dμ, l = 0..=k_max, by the trapezoid rule in θ.
/// χ_0 is the quadrature's normalisation (≈ 1), χ_1 = g, and
/// p(μ) = Σ_l (2l + 1) χ_l P_l(μ) / (4π) — the moments DISORT-type solvers take.
pub fn legendre_moments(theta_deg: &[f64], phase: &[f64], k_max: usize) -> Vec<f64> {
    let w = solid_angle_weights(theta_deg);
    let mut chi = vec![0.0; k_max + 1];
    for (i, &deg) in theta_deg.iter().enumerate() {
        let mu = deg.to_radians().cos();
        let f = w[i] * phase[i];
        for (c, p) in chi.iter_mut().zip(Legendre::new(mu)) {
            *c += f * p;
        }
    }
    chi
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn reference_grid_has_2251_exact_angles() {
        let g = reference_angles_deg();
        assert_eq!(g.len(), 2251);
        assert_eq!(g[500], 5.0);
        assert_eq!(g[501], 5.1);
        assert_eq!(g[2250], 180.0);
        validate_angles(&g).unwrap();
        assert!(validate_angles(&[0.0, 90.0]).is_err());
        assert!(validate_angles(&[0.0, 90.0, 90.0, 180.0]).is_err());
        assert!(validate_angles(&[0.0, 1.0, 180.0]).is_ok());
    }

    #[test]
    fn quadratures_of_an_isotropic_and_a_linear_phase_function() {
        let g = reference_angles_deg();
        let iso = vec![1.0 / (4.0 * std::f64::consts::PI); g.len()];
        let chi = legendre_moments(&g, &iso, 3);
        assert!((chi[0] - 1.0).abs() < 1e-5 && chi[1].abs() < 1e-5 && chi[2].abs() < 1e-5);
        // p = (1 + 3 g μ)/(4π) has χ_1 = g.
        let lin: Vec<f64> = g
            .iter()
            .map(|d| (1.0 + 3.0 * 0.4 * d.to_radians().cos()) / (4.0 * std::f64::consts::PI))
            .collect();
        let chi = legendre_moments(&g, &lin, 2);
        assert!((chi[1] - 0.4).abs() < 1e-5, "{}", chi[1]);
        let c = cdf(&g, &iso);
        // Isotropic: cdf(90°) = 1/2.
        let i90 = g.iter().position(|&d| d == 90.0).unwrap();
        assert!((c[i90] - 0.5).abs() < 1e-6);
    }
}
