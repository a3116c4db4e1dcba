//! Refractive index of liquid water (real part) in the visible.
//!
//! Two independent formulations are provided:
//!
//! * [`water_index_iapws`]: IAPWS R9-97, the international reference
//!   formulation, evaluated along the 0.101325 MPa isobar with the density
//!   from [`water_density_kell`].  [`water_index_iapws_density`] exposes the
//!   formulation itself, for an arbitrary density.
//! * [`water_index_daimon`]: the four-term Sellmeier fits of Daimon &
//!   Masumura (2007) to their measurements on distilled water.
//!
//! Units everywhere: wavelength `lambda_nm` in nanometres (vacuum
//! wavelength), temperature `temp_c` in degrees Celsius, density in kg/m³.
//! All indices are absolute (relative to vacuum); taking λ as an air
//! wavelength instead would change n by < 1.2e-5 in the visible.  Handbook
//! values such as the ICUMSA n_D(20 °C) = 1.33299 are relative to *air*; the
//! absolute value at 589.3 nm, 20 °C is 1.33335.
//!
//! The two formulations agree to better than 1e-5 over 380–780 nm and
//! 19–24 °C.  Inputs are not range-checked (apart from the temperature of
//! [`water_index_daimon`]); outside the documented ranges the functions
//! extrapolate.

// ---------------------------------------------------------------------------
// IAPWS R9-97
// ---------------------------------------------------------------------------

/// Coefficients a0..a7 of IAPWS R9-97, Eq. (1).
const IAPWS_A: [f64; 8] = [
    0.244_257_733,
    9.746_344_76e-3,
    -3.732_349_96e-3,
    2.686_784_72e-4,
    1.589_205_70e-3,
    2.459_342_59e-3,
    0.900_704_920,
    -1.666_262_19e-2,
];
/// Reduced UV and IR resonance wavelengths of IAPWS R9-97.
const IAPWS_LAMBDA_UV: f64 = 0.229_202_0;
const IAPWS_LAMBDA_IR: f64 = 5.432_937;
/// Reference values: T* = 273.15 K, ρ* = 1000 kg/m³, λ* = 0.589 µm.
const IAPWS_T_REF_K: f64 = 273.15;
const IAPWS_RHO_REF: f64 = 1000.0;
const IAPWS_LAMBDA_REF_NM: f64 = 589.0;

/// Refractive index of water from the IAPWS R9-97 formulation at an explicit
/// density.
///
/// With reduced variables ρ̄ = ρ / (1000 kg m⁻³), T̄ = T / (273.15 K) and
/// λ̄ = λ / (0.589 µm), the release gives the Lorentz–Lorenz function
///
/// ```text
/// (n² − 1) / (n² + 2) · 1/ρ̄ = a0 + a1 ρ̄ + a2 T̄ + a3 λ̄² T̄ + a4 / λ̄²
///                           + a5 / (λ̄² − λ̄_UV²) + a6 / (λ̄² − λ̄_IR²) + a7 ρ̄²
/// ```
///
/// so that, with A the right-hand side times ρ̄, n = √((1 + 2A) / (1 − A)).
/// Coefficients: a0 = 0.244257733, a1 = 9.74634476e-3, a2 = −3.73234996e-3,
/// a3 = 2.68678472e-4, a4 = 1.58920570e-3, a5 = 2.45934259e-3,
/// a6 = 0.900704920, a7 = −1.66626219e-2, λ̄_UV = 0.2292020,
/// λ̄_IR = 5.432937.
///
/// Valid (per the release) for 0.2–1.1 µm (reasonable extrapolation to
/// 1.9 µm), −12 °C (supercooled liquid) to 500 °C, 0–1060 kg/m³.
///
/// Source: IAPWS R9-97, "Release on the Refractive Index of Ordinary Water
/// Substance as a Function of Wavelength, Temperature and Pressure" (1997);
/// A. H. Harvey, J. S. Gallagher, J. M. H. Levelt Sengers, J. Phys. Chem.
/// Ref. Data 27, 761 (1998).  Not to be confused with the earlier Schiebener
/// et al. (1990) coefficients (a0 = 0.243905091, …).
pub fn water_index_iapws_density(lambda_nm: f64, temp_c: f64, rho_kg_m3: f64) -> f64 {
    let a = &IAPWS_A;
    let rho = rho_kg_m3 / IAPWS_RHO_REF;
    let t = (temp_c + IAPWS_T_REF_K) / IAPWS_T_REF_K;
    let l2 = (lambda_nm / IAPWS_LAMBDA_REF_NM).powi(2);
    let ll = a[0]
        + a[1] * rho
        + a[2] * t
        + a[3] * l2 * t
        + a[4] / l2
        + a[5] / (l2 - IAPWS_LAMBDA_UV * IAPWS_LAMBDA_UV)
        + a[6] / (l2 - IAPWS_LAMBDA_IR * IAPWS_LAMBDA_IR)
        + a[7] * rho * rho;
    let big_a = rho * ll;
    ((1.0 + 2.0 * big_a) / (1.0 - big_a)).sqrt()
}

/// Refractive index of liquid water at 0.101325 MPa from IAPWS R9-97
/// ([`water_index_iapws_density`]) with the density of
/// [`water_density_kell`].
///
/// Valid for 200–1100 nm and 0 °C to the normal boiling point (99.97 °C).
/// The density model differs from IAPWS-95 by at most 0.015 kg/m³ in that
/// range, which changes n by less than 5e-6 (380–780 nm).
///
/// Example: n(589.3 nm, 20 °C) = 1.333348 (absolute).
pub fn water_index_iapws(lambda_nm: f64, temp_c: f64) -> f64 {
    water_index_iapws_density(lambda_nm, temp_c, water_density_kell(temp_c))
}

/// Density of air-free liquid water at 0.101325 MPa, in kg/m³ (Kell 1975).
///
/// ```text
/// ρ(t) = (999.83952 + 16.945176 t − 7.9870401e−3 t² − 46.170461e−6 t³
///         + 105.56302e−9 t⁴ − 280.54253e−12 t⁵) / (1 + 16.879850e−3 t)
/// ```
///
/// with t in °C.  Kell fitted it for 0–150 °C on the IPTS-68 scale; here t
/// is taken as ITS-90.  Use for liquid water, 0 °C to 99.97 °C.  Measured
/// deviation from IAPWS-95 at 0.101325 MPa (ITS-90, scale difference
/// included): −0.004 to +0.015 kg/m³ over 0–99 °C.
///
/// Source: G. S. Kell, J. Chem. Eng. Data 20, 97–105 (1975), Eq. (16).
pub fn water_density_kell(temp_c: f64) -> f64 {
    let t = temp_c;
    let num = 999.839_52
        + t * (16.945_176
            + t * (-7.987_040_1e-3
                + t * (-46.170_461e-6 + t * (105.563_02e-9 + t * (-280.542_53e-12)))));
    num / (1.0 + 16.879_850e-3 * t)
}

// ---------------------------------------------------------------------------
// Daimon & Masumura (2007)
// ---------------------------------------------------------------------------

/// One Daimon–Masumura fit: temperature (°C), B_i, C_i (µm²).
struct DaimonFit {
    temp_c: f64,
    b: [f64; 4],
    c: [f64; 4],
}

/// Coefficient sets, ascending in temperature.
#[rustfmt::skip]
const DAIMON_FITS: [DaimonFit; 4] = [
    DaimonFit {
        temp_c: 19.0,
        b: [5.672526103e-1, 1.736581125e-1, 2.121531502e-2, 1.138493213e-1],
        c: [5.085550461e-3, 1.814938654e-2, 2.617260739e-2, 1.073888649e1],
    },
    DaimonFit {
        temp_c: 20.0,
        b: [5.684027565e-1, 1.726177391e-1, 2.086189578e-2, 1.130748688e-1],
        c: [5.101829712e-3, 1.821153936e-2, 2.620722293e-2, 1.069792721e1],
    },
    DaimonFit {
        temp_c: 21.5,
        b: [5.689093832e-1, 1.719708856e-1, 2.062501582e-2, 1.123965424e-1],
        c: [5.110301794e-3, 1.825180155e-2, 2.624158904e-2, 1.067505178e1],
    },
    DaimonFit {
        temp_c: 24.0,
        b: [5.666959820e-1, 1.731900098e-1, 2.095951857e-2, 1.125228406e-1],
        c: [5.084151894e-3, 1.818488474e-2, 2.625439472e-2, 1.073842352e1],
    },
];

/// n² − 1 = Σ B_i λ² / (λ² − C_i), λ in µm, C_i in µm².
fn daimon_sellmeier(fit: &DaimonFit, lambda_nm: f64) -> f64 {
    let l2 = (lambda_nm * 1e-3).powi(2);
    let mut n2 = 1.0;
    for (b, c) in fit.b.iter().zip(fit.c.iter()) {
        n2 += b * l2 / (l2 - c);
    }
    n2.sqrt()
}

/// Refractive index of distilled water from the four-term Sellmeier fits of
/// Daimon & Masumura (2007):
///
/// ```text
/// n² − 1 = Σ_{i=1..4} B_i λ² / (λ² − C_i),   λ in µm, C_i in µm²
/// ```
///
/// Fits exist for 19.0, 20.0, 21.5 and 24.0 °C.  At those temperatures the
/// corresponding fit is returned exactly; between them n is interpolated
/// linearly in temperature (at fixed wavelength) between the two bracketing
/// fits.  Returns `None` for temperatures outside [19, 24] °C (and for NaN).
/// Valid for 182–1129 nm.
///
/// Source: M. Daimon and A. Masumura, "Measurement of the refractive index of
/// distilled water from the near-infrared region to the ultraviolet region,"
/// Appl. Opt. 46, 3811–3820 (2007), doi:10.1364/AO.46.003811; coefficients
/// as given in the refractiveindex.info database (H2O, Daimon-*.yml).
pub fn water_index_daimon(lambda_nm: f64, temp_c: f64) -> Option<f64> {
    for w in DAIMON_FITS.windows(2) {
        let (lo, hi) = (&w[0], &w[1]);
        if temp_c >= lo.temp_c && temp_c <= hi.temp_c {
            let f = (temp_c - lo.temp_c) / (hi.temp_c - lo.temp_c);
            let n_lo = daimon_sellmeier(lo, lambda_nm);
            let n_hi = daimon_sellmeier(hi, lambda_nm);
            return Some((1.0 - f) * n_lo + f * n_hi);
        }
    }
    None
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Absolute index of dry air at 589.3 nm, 20 °C, 101.325 kPa (Edlén
    /// equation as revised by Birch & Downs, Metrologia 30, 155 (1993)),
    /// used to convert air-relative handbook values to absolute ones.
    const N_AIR_589_20C: f64 = 1.000_272_4;

    fn assert_close(what: &str, got: f64, want: f64, tol: f64) {
        assert!(
            (got - want).abs() <= tol,
            "{what}: got {got:.10}, want {want:.10} (tol {tol:e}, diff {:e})",
            got - want
        );
    }

    #[test]
    fn iapws_release_check_values() {
        // IAPWS R9-97 values for program verification, (T, ρ, λ) -> n, 8
        // decimals (T = 298.15 K / 773.15 K, λ = 0.2265 µm / 0.5893 µm), as
        // quoted by the `iapws` (J. Gómez) and `chemicals` (C. Bell) Python
        // packages.  Python reproduction: max deviation 4.0e-9.
        let cases = [
            (226.5, 25.0, 997.047435, 1.39277824),
            (589.3, 25.0, 997.047435, 1.33285819),
            (589.3, 500.0, 30.4758534, 1.00949307),
        ];
        for &(lambda, t, rho, n_ref) in &cases {
            let n = water_index_iapws_density(lambda, t, rho);
            assert_close("IAPWS R9-97 check value", n, n_ref, 5e-9);
        }
    }

    #[test]
    fn iapws_along_isobar_matches_check_value() {
        // The 25 °C check value uses the IAPWS-95 density at 0.1 MPa
        // (997.047435 kg/m³); Kell's density differs by 0.0025 kg/m³, i.e.
        // 8e-7 in n.
        assert_close(
            "n(589.3 nm, 25 °C)",
            water_index_iapws(589.3, 25.0),
            1.33285819,
            2e-6,
        );
    }

    #[test]
    fn iapws_matches_icumsa_sodium_d_line() {
        // ICUMSA: n_D(20 °C) = 1.33299 relative to air.
        let n_rel_air = water_index_iapws(589.3, 20.0) / N_AIR_589_20C;
        assert_close("n_D(20 °C) / n_air", n_rel_air, 1.33299, 1e-5);
    }

    #[test]
    fn kell_density_matches_iapws95() {
        // IAPWS-95 densities at 0.101325 MPa (iapws 1.5.5 Python package).
        let cases = [
            (0.0, 999.8431),
            (20.0, 998.2072),
            (40.0, 992.2164),
            (60.0, 983.1958),
            (80.0, 971.7904),
        ];
        for &(t, rho) in &cases {
            assert_close("Kell density", water_density_kell(t), rho, 0.01);
        }
    }

    #[test]
    fn daimon_matches_published_values() {
        // refractiveindex.info (Daimon-20.0C): n = 1.3334 at 0.5876 µm.
        let n = water_index_daimon(587.6, 20.0).unwrap();
        assert_close("Daimon n(587.6 nm, 20 °C)", n, 1.3334, 5e-5);
        // ICUMSA n_D(20 °C) = 1.33299 relative to air.
        let n_rel_air = water_index_daimon(589.3, 20.0).unwrap() / N_AIR_589_20C;
        assert_close("Daimon n_D(20 °C) / n_air", n_rel_air, 1.33299, 1e-5);
    }

    #[test]
    fn daimon_agrees_with_iapws_in_visible() {
        // Independent formulations; measured max difference 7.7e-6.
        for &t in &[19.0, 20.0, 21.5, 22.75, 24.0] {
            let mut lambda = 380.0;
            while lambda <= 780.0 {
                let d = water_index_daimon(lambda, t).unwrap();
                assert_close("Daimon vs IAPWS", d, water_index_iapws(lambda, t), 1e-5);
                lambda += 5.0;
            }
        }
    }

    #[test]
    fn daimon_temperature_handling() {
        assert!(water_index_daimon(550.0, 18.9).is_none());
        assert!(water_index_daimon(550.0, 24.1).is_none());
        assert!(water_index_daimon(550.0, f64::NAN).is_none());
        // Tabulated temperatures return the fit itself.
        for fit in &DAIMON_FITS {
            let n = water_index_daimon(550.0, fit.temp_c).unwrap();
            assert_eq!(n, daimon_sellmeier(fit, 550.0));
        }
        // n decreases with temperature across all fits.
        let n: Vec<f64> = [19.0, 20.0, 21.5, 22.0, 24.0]
            .iter()
            .map(|&t| water_index_daimon(589.3, t).unwrap())
            .collect();
        assert!(n.windows(2).all(|w| w[1] < w[0]), "{n:?}");
    }
}
