//! The multi-octave approximation of real-time engines (Wrenninge et al. 2013; Hillaire 2016,
//! Frostbite; Unreal's volumetric clouds), a baseline of the fast renderers:
//!
//!   L ≈ Σ_{i<N} bⁱ ϖ p(θ; cⁱ g) E_sun ∫ σ T_v e^{−aⁱ τ_sun} ds,
//!
//! octave 0 being single scattering with the true phase function, octaves i ≥ 1
//! Henyey–Greenstein at cⁱ g (g the phase function's mean cosine).

use nephele_runtime::phase::HenyeyGreenstein;
use nephele_runtime::PhaseFunction;
use serde::Serialize;

/// The multi-octave approximation's parameters: N octaves, extinction, scattering and
/// anisotropy factors a, b, c.
#[derive(Clone, Copy, Debug, PartialEq, Serialize)]
pub struct Octaves {
    /// N (1…8).
    pub n: usize,
    /// a: the sun's extinction of octave i is aⁱ σ_t.
    pub a: f64,
    /// b: octave i is weighted bⁱ.
    pub b: f64,
    /// c: octave i's anisotropy is cⁱ g.
    pub c: f64,
}

impl Default for Octaves {
    /// The engines' defaults: N = 4, a = b = c = 0.5.
    fn default() -> Self {
        Self {
            n: 4,
            a: 0.5,
            b: 0.5,
            c: 0.5,
        }
    }
}

/// Most octaves.
pub const MAX_OCTAVES: usize = 8;

impl Octaves {
    /// Σ_{1 ≤ i < N} bⁱ ϖ p_HG(θ; cⁱ g) I_{aⁱ}: the octaves after the first (octave 0 is order 1),
    /// per unit E_sun, for a phase function of mean cosine `g`, albedo ϖ, cos θ and the view
    /// ray's integrals I_{aⁱ} = ∫ σ T_v e^{−aⁱ τ_sun} ds.
    pub fn scattered(&self, g: f64, albedo: f64, cos: f64, integrals: &[f64; MAX_OCTAVES]) -> f64 {
        let mut sum = 0.0;
        for (i, integral) in integrals.iter().enumerate().take(self.n).skip(1) {
            let hg = HenyeyGreenstein::new(self.c.powi(i as i32) * g);
            sum += self.b.powi(i as i32) * albedo * hg.eval(cos) * integral;
        }
        sum
    }

    /// The factors aⁱ of the sun's extinction, octave by octave.
    pub fn extinction_factors(&self) -> [f64; MAX_OCTAVES] {
        std::array::from_fn(|i| self.a.powi(i as i32))
    }
}
