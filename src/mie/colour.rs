//! Linear-sRGB channel weights over wavelength, from the CIE 1931 2° observer.
//!
//! A channel's phase function is a weighted mean of the per-wavelength phase functions:
//!   p_c(θ) = Σ_j w_cj p_λj(θ),   w_cj ∝ q_j Σ_i M_ci S(λ_j) x̄_i(λ_j),   Σ_j w_cj = 1,
//! with q_j the quadrature weights of the wavelength grid, x̄_i the colour-matching functions, S the illuminant's spectral power and M the
//! XYZ → linear-sRGB matrix (IEC 61966-2-1, as colour-science uses it). Since every p_λ has
//! ∮ p_λ dΩ = 1, the normalisation Σ_j w_cj = 1 makes ∮ p_c dΩ = 1 exactly: dividing by the
//! illuminant's own RGB is dividing by the channel's integral.

use serde::{Deserialize, Serialize};

/// XYZ → linear sRGB (IEC 61966-2-1:1999, D65 white), rows R, G, B.
pub const XYZ_TO_SRGB: [[f64; 3]; 3] = [
    [3.2406, -1.5372, -0.4986],
    [-0.9689, 1.8758, 0.0415],
    [0.0557, -0.2040, 1.0570],
];

/// The classic three-wavelength LUT of older tools: red, green, blue, nm.
pub const RGB_WAVELENGTHS_NM: [f64; 3] = [650.0, 510.0, 440.0];

const CMF_CSV: &str = include_str!("../../data/cie1931_2deg_1nm.csv");
const D65_CSV: &str = include_str!("../../data/illuminant_d65_1nm.csv");

/// Spectral power distribution of the light the channels are white-balanced for.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum Illuminant {
    /// CIE standard illuminant D65 (daylight, sRGB's white).
    D65,
    /// Equal-energy illuminant E.
    E,
}

impl Illuminant {
    /// Every illuminant with its name (command line and JSON).
    pub const NAMES: [(Illuminant, &'static str); 2] =
        [(Illuminant::D65, "d65"), (Illuminant::E, "e")];
}

/// A 1-nm table: first wavelength and rows of values.
struct Table {
    first_nm: f64,
    rows: Vec<Vec<f64>>,
}

impl Table {
    fn parse(csv: &str) -> Self {
        let rows: Vec<Vec<f64>> = csv
            .lines()
            .skip(1)
            .filter(|l| !l.trim().is_empty())
            .map(|l| {
                l.split(',')
                    .map(|v| v.trim().parse().expect("built-in CIE table"))
                    .collect()
            })
            .collect();
        Self {
            first_nm: rows[0][0],
            rows,
        }
    }

    /// Column `col` linearly interpolated at `nm` (1-nm spacing); zero outside the table,
    /// where the colour-matching functions vanish (360–830 nm).
    fn at(&self, nm: f64, col: usize) -> f64 {
        let t = nm - self.first_nm;
        let last = (self.rows.len() - 1) as f64;
        if !(0.0..=last).contains(&t) {
            return 0.0;
        }
        let i = (t.floor() as usize).min(self.rows.len() - 2);
        let f = t - i as f64;
        self.rows[i][col] * (1.0 - f) + self.rows[i + 1][col] * f
    }
}

/// Per-channel weights w_cj (rows R, G, B; each sums to 1) over the given wavelengths, with
/// `quadrature` the weights of the wavelength integral (equal, or trapezoid).
///
/// A grid that gives a channel no positive total weight (a single green wavelength has a
/// negative red response, say) has no such channel: its weights are NaN.
pub fn srgb_weights(
    wavelengths_nm: &[f64],
    quadrature: &[f64],
    illuminant: Illuminant,
) -> [Vec<f64>; 3] {
    let cmf = Table::parse(CMF_CSV);
    let d65 = Table::parse(D65_CSV);
    let mut w: [Vec<f64>; 3] = Default::default();
    for (&nm, &q) in wavelengths_nm.iter().zip(quadrature) {
        let s = q * match illuminant {
            Illuminant::D65 => d65.at(nm, 1),
            Illuminant::E => 1.0,
        };
        let xyz = [cmf.at(nm, 1), cmf.at(nm, 2), cmf.at(nm, 3)];
        for (c, row) in XYZ_TO_SRGB.iter().enumerate() {
            w[c].push(s * (row[0] * xyz[0] + row[1] * xyz[1] + row[2] * xyz[2]));
        }
    }
    for wc in w.iter_mut() {
        let total: f64 = wc.iter().sum();
        let scale = if total > 0.0 { 1.0 / total } else { f64::NAN };
        wc.iter_mut().for_each(|v| *v *= scale);
    }
    w
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn cie_tables_have_their_known_landmarks() {
        let cmf = Table::parse(CMF_CSV);
        // ȳ peaks at 555 nm with value 1 (by definition of the photopic curve).
        assert!((cmf.at(555.0, 2) - 1.0).abs() < 1e-3);
        let d65 = Table::parse(D65_CSV);
        // D65 is normalised to 100 at 560 nm.
        assert!((d65.at(560.0, 1) - 100.0).abs() < 1e-9);
    }

    #[test]
    fn d65_white_maps_to_equal_srgb() {
        // Integrated over the full visible range, D65 is sRGB's white: R = G = B.
        let nm: Vec<f64> = (360..=830).map(f64::from).collect();
        let cmf = Table::parse(CMF_CSV);
        let d65 = Table::parse(D65_CSV);
        let mut rgb = [0.0; 3];
        for &l in &nm {
            let s = d65.at(l, 1);
            for c in 0..3 {
                rgb[c] += s
                    * (1..4)
                        .map(|i| XYZ_TO_SRGB[c][i - 1] * cmf.at(l, i))
                        .sum::<f64>();
            }
        }
        assert!((rgb[0] / rgb[1] - 1.0).abs() < 2e-3 && (rgb[2] / rgb[1] - 1.0).abs() < 2e-3);
    }

    #[test]
    fn a_grid_without_red_response_has_no_red_channel() {
        let w = srgb_weights(&[550.0], &[1.0], Illuminant::D65);
        assert!(w[0][0].is_nan() && w[1][0] == 1.0);
        let nm: Vec<f64> = (80..=140).map(|i| 5.0 * i as f64).collect();
        let w = srgb_weights(&nm, &vec![1.0 / 61.0; 61], Illuminant::E);
        assert!(w
            .iter()
            .all(|c| (c.iter().sum::<f64>() - 1.0).abs() < 1e-12));
    }
}
