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
//! The largest is at 1.5 µm, where α drops from 250 to 9.3.
//!
//! [`nephele_refit`] is nephele's own refit (`nephele fit` with fit-configs/paper.json
//! and small-droplets.json): the paper's forms on 5–50 µm, quintics (α = 250) on 0.1–1.5 µm and
//! quartics on 1.5–5 µm in ln d, each polished on the total E_AS over its branch. On our Mie
//! tables its total E_AS is 0.010 % above the per-diameter optima on 5–50 µm (the paper's curves:
//! 0.025 %), 1.3 % on 1.5–5 µm (paper: 1.5 %) and 6.7 % on 0.1–1.5 µm (paper: 7.6 %), where the
//! optima jump between lobe shapes no smooth curve follows; see docs/fit.md. Below 0.1 µm it is the paper's Rayleigh-limit branch (not refitted).

use crate::phase::HgDraine;
use crate::real::{Math, Real};

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
    Math::sin_cos(x).1
}

impl<F: Real> HgDraine<F> {
    /// Jendersie & d'Eon's blend for water droplets of diameter `d_um` (µm), by the paper's
    /// fits ([`jendersie_deon`]). Here, beside the fits, so that the phase models do not
    /// depend on the presets.
    pub fn from_diameter(d_um: f64) -> Self {
        jendersie_deon(d_um).phase()
    }
}

/// The largest diameter (µm) Jendersie & d'Eon's fits were made on (their Mie range): beyond it
/// they extrapolate with nothing to check them against, and from about 10⁶ µm the f32 g of the
/// HG lobe rounds to 1 (the lobe becomes a delta, NaN off it). The C ABI and the Python
/// module refuse larger ones.
pub const FIT_MAX_DIAMETER_UM: f64 = 50.0;

/// Jendersie & d'Eon's parameters at diameter `d_um` (> 0, µm; fitted up to
/// [`FIT_MAX_DIAMETER_UM`]).
pub fn jendersie_deon(d_um: f64) -> HgDraineParams {
    let d = d_um;
    let exp = |x: f64| Math::exp(x);
    if d >= 5.0 {
        return HgDraineParams {
            g_hg: exp(-0.0990567 / (d - 1.67154)),
            g_d: exp(-2.20679 / (d + 3.91029) - 0.428934),
            alpha: exp(3.62489 - 8.29288 / (d + 5.52825)),
            w_d: exp(-0.599085 / (d - 0.641583) - 0.665888),
        };
    }
    let l = Math::ln(d);
    if d >= 1.5 {
        let (s, c) = Math::sin_cos(l);
        let ln_l = Math::ln(l);
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
        g_d: 1.1456 * d * Math::sin_cos(9.29044 * d).0,
        alpha: 250.0,
        w_d: 0.252977 - 312.983 * exp(4.3 * l),
    }
}

/// One curve θ(d) of the refit (d in µm).
#[derive(Clone, Copy, Debug)]
enum Curve {
    /// exp(a − b/(d + c)).
    ExpRational { a: f64, b: f64, c: f64 },
    /// Σₖ cₖ (ln d − l0)ᵏ.
    PolyLnD { l0: f64, c: &'static [f64] },
}

impl Curve {
    fn at(self, d: f64) -> f64 {
        match self {
            Curve::ExpRational { a, b, c } => Math::exp(a - b / (d + c)),
            // Horner in x = ln d − l0.
            Curve::PolyLnD { l0, c } => {
                let x = Math::ln(d) - l0;
                c.iter().rev().fold(0.0, |acc, ck| acc * x + ck)
            }
        }
    }
}

/// A diameter branch of the refit: used from `d_min` (µm) up to the next branch.
#[derive(Clone, Copy, Debug)]
struct Branch {
    d_min: f64,
    g_hg: Curve,
    g_d: Curve,
    alpha: Curve,
    w_d: Curve,
}

// Generated by scripts/refit_preset.py from `nephele fit` runs of fit-configs/paper.json and
// fit-configs/small-droplets.json (nephele 0.1).
const REFIT: [Branch; 3] = [
    // 0.1–1.5 µm
    Branch {
        d_min: 0.1,
        g_hg: Curve::PolyLnD {
            l0: -0.9655645721515146,
            c: &[
                0.7441612455113218,
                0.19765078041876163,
                -0.287072343231652,
                0.22429557274380368,
                0.0836254152070245,
                -0.11084058995418647,
            ],
        },
        g_d: Curve::PolyLnD {
            l0: -0.9655645721515146,
            c: &[
                0.6788908723512087,
                0.25372335645174054,
                -0.22753931035859132,
                -0.02306245961785591,
                -0.06120038977142867,
                -0.072668911741264,
            ],
        },
        alpha: Curve::PolyLnD {
            l0: -0.9655645721515146,
            c: &[250.0],
        },
        w_d: Curve::PolyLnD {
            l0: -0.9655645721515146,
            c: &[
                0.2503732355260145,
                0.58139119928157,
                0.12278705352993458,
                -0.7846234669851359,
                -0.10277961137586449,
                0.2429415254718371,
            ],
        },
    },
    // 1.5–5.0 µm
    Branch {
        d_min: 1.5,
        g_hg: Curve::PolyLnD {
            l0: 0.9904469305625585,
            c: &[
                0.939065857372988,
                0.03312623449369524,
                0.011691690206953218,
                0.11822333213282439,
                -0.1662300564115769,
            ],
        },
        g_d: Curve::PolyLnD {
            l0: 0.9904469305625585,
            c: &[
                0.4018766626793819,
                0.10641757599339227,
                0.3292829646274292,
                -0.08238808414321706,
                -0.5720628666758055,
            ],
        },
        alpha: Curve::PolyLnD {
            l0: 0.9904469305625585,
            c: &[
                12.916631625725804,
                14.201114840679661,
                5.129618534763567,
                -20.934912217759194,
                5.412912767765561,
            ],
        },
        w_d: Curve::PolyLnD {
            l0: 0.9904469305625585,
            c: &[
                0.37479347963200044,
                -0.12022081662709955,
                0.5485920276585932,
                0.5411590777085401,
                -1.4723530999222063,
            ],
        },
    },
    // 5.0–50.0 µm
    Branch {
        d_min: 5.0,
        g_hg: Curve::ExpRational {
            a: 0.0,
            b: 0.09137833590082796,
            c: -2.0207404325357845,
        },
        g_d: Curve::ExpRational {
            a: -0.4235839586495554,
            b: 2.4719599302091826,
            c: 5.0656358968996,
        },
        alpha: Curve::ExpRational {
            a: 3.665406765465499,
            b: 9.764791365921273,
            c: 6.972522327595451,
        },
        w_d: Curve::ExpRational {
            a: -0.6647914536655356,
            b: 0.6606372601184719,
            c: 0.13469665952051013,
        },
    },
];

/// The fit's bounds: |g| ≤ 1 − 10⁻⁶, 0 ≤ α ≤ 250, 0 ≤ w_D ≤ 1 (the curves were polished with
/// these clamps applied, so the preset applies them too).
fn clamp_to_fit_bounds(p: HgDraineParams) -> HgDraineParams {
    let g_max = 1.0 - 1e-6;
    HgDraineParams {
        g_hg: p.g_hg.clamp(-g_max, g_max),
        g_d: p.g_d.clamp(-g_max, g_max),
        alpha: p.alpha.clamp(0.0, 250.0),
        w_d: p.w_d.clamp(0.0, 1.0),
    }
}

/// nephele's refitted parameters at diameter `d_um` (> 0, µm): 0.1–1.5, 1.5–5 and ≥ 5 µm
/// branches fitted by `nephele fit` (the last extrapolated above 50 µm); the paper's
/// [`jendersie_deon`] at d ≤ 0.1 µm.
pub fn nephele_refit(d_um: f64) -> HgDraineParams {
    if d_um <= REFIT[0].d_min {
        return jendersie_deon(d_um);
    }
    let b = REFIT
        .iter()
        .rev()
        .find(|b| d_um >= b.d_min)
        .unwrap_or(&REFIT[0]);
    clamp_to_fit_bounds(HgDraineParams {
        g_hg: b.g_hg.at(d_um),
        g_d: b.g_d.at(d_um),
        alpha: b.alpha.at(d_um),
        w_d: b.w_d.at(d_um),
    })
}
