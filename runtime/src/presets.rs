//! Droplet diameter → HG + Draine parameters: the fits of Jendersie & d'Eon (SIGGRAPH 2023
//! Talks), for water droplets (n = 1.333, log-normal σ = 0.25, 400–700 nm mean). L = ln d,
//! d in µm.
//!
//! | d (µm) | g_HG | g_D | α | w_D |
//! |---|---|---|---|---|
//! | 5 ≤ d (eqs. 4–7) | e^{−0.0990567/(d−1.67154)} | e^{−2.20679/(d+3.91029) − 0.428934} | e^{3.62489 − 8.29288/(d+5.52825)} | e^{−0.599085/(d−0.641583) − 0.665888} |
//! | 1.5 ≤ d < 5 | 0.0604931 ln L + 0.940256 | 0.500411 − 0.081287/(−2L + tan L + 1.27551) | 7.30354 L + 6.31675 | 0.026914 (L − cos(5.68947 (ln L − 0.0292149))) + 0.376475 |
//! | 0.1 < d < 1.5 | 0.862 − 0.143 L² | 0.379685 cos c + 0.344213 | 250 | 0.146209 cos(3.38707 L + 2.11193) + 0.316072 + 0.0778917 L |
//! | d ≤ 0.1 | 13.8 d² | 1.1456 d sin(9.29044 d) | 250 | 0.252977 − 312.983 d^{4.3} |
//!
//! with c = 1.19692 cos(a/b) + 1.37932 L + 0.0625835, a = (L − 0.238604)(L + 1.00667),
//! b = 0.507522 − 0.15677 L (the paper's supplemental material). The main fit is used above
//! 50 µm too (an extrapolation). The branches do **not** join continuously (values just below
//! → just above each edge, printed by the test `preset_matches_the_paper_and_jumps_where_documented`):
//!
//! | edge | g_HG | g_D | α | w_D |
//! |---|---|---|---|---|
//! | 5 µm | 0.96904 → 0.97068 | 0.50333 → 0.50834 | 18.071 → 17.068 | 0.44200 → 0.44783 |
//! | 1.5 µm | 0.83849 → 0.88565 | 0.31262 → 0.40947 | 250 → 9.278 | 0.20999 → 0.37242 |
//! | 0.1 µm | 0.13800 → 0.10383 | 0.09177 → 0.11556 | 250 → 250 | 0.23729 → 0.25771 |
//!
//! The largest is at 1.5 µm, where α drops from 250 to 9.3. Our own refits (stage 3) will
//! replace these as the default once validated; this stays as the named preset
//! `jendersie_deon`.

use crate::phase::HgDraine;
use crate::real::Real;

/// The four parameters of the blend (1 − w_D) HG(g_HG) + w_D Draine(g_D, α).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct HgDraineParams {
    /// HG lobe asymmetry.
    pub g_hg: f64,
    /// Draine lobe g.
    pub g_d: f64,
    /// Draine lobe α.
    pub alpha: f64,
    /// Weight of the Draine lobe.
    pub w_d: f64,
}

impl HgDraineParams {
    /// The blend in the working precision.
    pub fn phase<F: Real>(&self) -> HgDraine<F> {
        HgDraine::hg_draine(
            F::of(self.g_hg),
            F::of(self.g_d),
            F::of(self.alpha),
            F::of(self.w_d),
        )
    }
}

fn cos(x: f64) -> f64 {
    Real::sin_cos(x).1
}

/// Jendersie & d'Eon's parameters at diameter `d_um` (> 0, µm).
pub fn jendersie_deon(d_um: f64) -> HgDraineParams {
    let d = d_um;
    let exp = |x: f64| Real::exp(x);
    if d >= 5.0 {
        return HgDraineParams {
            g_hg: exp(-0.0990567 / (d - 1.67154)),
            g_d: exp(-2.20679 / (d + 3.91029) - 0.428934),
            alpha: exp(3.62489 - 8.29288 / (d + 5.52825)),
            w_d: exp(-0.599085 / (d - 0.641583) - 0.665888),
        };
    }
    let l = Real::ln(d);
    if d >= 1.5 {
        let (s, c) = Real::sin_cos(l);
        let ln_l = Real::ln(l);
        return HgDraineParams {
            g_hg: 0.0604931 * ln_l + 0.940256,
            g_d: 0.500411 - 0.081287 / (-2.0 * l + s / c + 1.27551),
            alpha: 7.30354 * l + 6.31675,
            w_d: 0.026914 * (l - cos(5.68947 * (ln_l - 0.0292149))) + 0.376475,
        };
    }
    if d > 0.1 {
        let a = (l - 0.238604) * (l + 1.00667);
        let b = 0.507522 - 0.15677 * l;
        let c = 1.19692 * cos(a / b) + 1.37932 * l + 0.0625835;
        return HgDraineParams {
            g_hg: 0.862 - 0.143 * l * l,
            g_d: 0.379685 * cos(c) + 0.344213,
            alpha: 250.0,
            w_d: 0.146209 * cos(3.38707 * l + 2.11193) + 0.316072 + 0.0778917 * l,
        };
    }
    HgDraineParams {
        g_hg: 13.8 * d * d,
        g_d: 1.1456 * d * Real::sin_cos(9.29044 * d).0,
        alpha: 250.0,
        w_d: 0.252977 - 312.983 * exp(4.3 * l),
    }
}
