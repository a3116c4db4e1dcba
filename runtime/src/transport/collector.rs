//! The collector form: where the light seen at a point of the slab entered it, per order group.
//! The slab tables give, per cell, the collector c = (c_x, c_z) (mfp, from the viewpoint's
//! horizontal position, x across and z along the sun's horizontal travel) and its spread σ
//! (docs/conventions.md draws the frame). Three forms, linear in their parameters like the transport's
//! ([`super::log_additive`]; u the stretched depth, x = 2u − 1, h_i the Θ hat functions,
//! a_j(μ_V) + b_j(μ_L) a parameter on the μ_V and μ_L nodes, s = sin of the polar angles):
//!
//!   ln σ   = Σ_i h_i(Θ)(α_i + α′_i x) + Σ_{k=0}^{K} (s_V s_L)^k cos kψ Σ_j [a_kj + b_kj] P_j(x)
//!   c_z/σ̂ = Σ_i h_i(Θ)(ζ_i + ζ′_i x) + s_L Σ_j [a_j + b_j] P_j(x) + Σ_{k=1}^{K} cos kψ Σ_j [·] P_j(x)
//!           + (ℓ/σ̂) [Σ_i h_i(Θ)(η_i + η′_i x) + s_L Σ_j [·] P_j(x)]
//!   c_x/σ̂ = sin ψ Σ_i h_i(Θ)(ξ_i + ξ′_i x) + Σ_{k=1}^{K} sin kψ Σ_j [·] P_j(x)
//!
//! σ̂ the fitted σ, ℓ = s_L λ (1 − e^{−d/(μ_L λ)}) with λ = 8 mfp the sun beam's horizontal
//! reach to depth d, saturating (μ_L held ≥ 0.05): d s_L/μ_L near the lit face, where light
//! enters along the beam, and at most λ s_L deep down, where it has forgotten the beam (ℓ = d
//! s_L/μ_L itself made held-out orders 3–4 worse; docs/compress.md).
//!
//! Why these terms: σ depends on the scattering angle much as T does (light seen close to the
//! sun's direction comes from a narrow collector; without the Θ table the order-2 σ was 78 %
//! off); c_x is odd in ψ (the tables mirror it), c_z even; at μ_L = 1 the collector turns with
//! the view (c_x = a sin ψ, c_z = a cos ψ), which is why the harmonics of c carry no s_L
//! factor; near the sun's direction c_z is the beam's own displacement ℓ (the ℓ terms are what
//! make order 2's c follow the beam there; docs/compress.md has the numbers). c is fitted in
//! units of σ̂ so that the parameters are dimensionless across thicknesses and the fit's
//! residuals are the report's error (in units of σ).

use super::geometry::SlabPoint;
use super::log_additive::{legendre, on_nodes, theta_hats, Cell, MAX_LEGENDRE, MAX_THETA_NODES};
use crate::real::Real;

/// Most azimuth harmonics of the collector form.
pub const MAX_COLLECTOR_HARMONICS: usize = 4;
/// Most Legendre terms in depth of the collector form.
pub const MAX_COLLECTOR_LEGENDRE: usize = 8;

/// The collector form's sizes.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct CollectorForm {
    /// Legendre terms in depth, J (≤ [`MAX_COLLECTOR_LEGENDRE`]).
    pub legendre: usize,
    /// Azimuth harmonics, K (≤ [`MAX_COLLECTOR_HARMONICS`]).
    pub harmonics: usize,
    /// Θ nodes (≥ 2).
    pub theta_nodes: usize,
}

impl Default for CollectorForm {
    fn default() -> Self {
        Self {
            legendre: 4,
            harmonics: 2,
            theta_nodes: 12,
        }
    }
}

/// Which collector statistic.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Statistic {
    /// ln σ.
    LnSigma,
    /// c_z / σ̂.
    Cz,
    /// c_x / σ̂.
    Cx,
}

impl Statistic {
    /// All three, in the order the tables store them.
    pub const ALL: [Statistic; 3] = [Statistic::LnSigma, Statistic::Cz, Statistic::Cx];
}

/// (sin kψ, cos kψ) for k = 0 … [`MAX_COLLECTOR_HARMONICS`] (past the form's K and 1: (0, 1)).
#[derive(Clone, Copy, Debug)]
pub struct Azimuth<F>([(F, F); MAX_COLLECTOR_HARMONICS + 1]);

/// One block of features: a multiplier times the Θ table or the depth polynomials on nodes.
#[derive(Clone, Copy)]
enum Block<F> {
    Theta(F),
    Depth(F),
}

const MAX_BLOCKS: usize = 2 * MAX_COLLECTOR_HARMONICS + 4;

impl CollectorForm {
    /// Whether the runtime can evaluate this form: the name of the first size outside its
    /// limits otherwise (the loader refuses such files, the compressor such options).
    pub fn check(&self) -> Result<(), &'static str> {
        if !(1..=MAX_COLLECTOR_LEGENDRE).contains(&self.legendre) {
            Err("collector Legendre terms in depth: 1 to MAX_COLLECTOR_LEGENDRE = 8")
        } else if self.harmonics > MAX_COLLECTOR_HARMONICS {
            Err("collector azimuth harmonics: at most MAX_COLLECTOR_HARMONICS = 4")
        } else if !(2..=MAX_THETA_NODES).contains(&self.theta_nodes) {
            Err("collector Θ nodes: 2 to MAX_THETA_NODES = 512")
        } else {
            Ok(())
        }
    }

    /// Parameters of `stat` for `nm` view-cosine and `nl` sun-cosine nodes.
    pub fn n_params(&self, stat: Statistic, nm: usize, nl: usize) -> usize {
        let mut blocks = [Block::Theta(0.0f64); MAX_BLOCKS];
        let n = self.blocks(
            stat,
            &Cell::<f64>::zero(),
            &self.azimuth(0.0),
            0.0,
            &mut blocks,
        );
        blocks[..n]
            .iter()
            .map(|b| match b {
                Block::Theta(_) => 2 * self.theta_nodes,
                Block::Depth(_) => self.legendre.min(MAX_LEGENDRE) * (nm + nl),
            })
            .sum()
    }

    /// The first column of c_z's ℓ/σ̂ terms (its last blocks): features computed with σ̂ = 1
    /// give c_z/σ̂ = Σ_{col < R} v β + (1/σ̂) Σ_{col ≥ R} v β, so that one set of features
    /// serves every group.
    pub fn cz_reach_start(&self, nm: usize, nl: usize) -> usize {
        self.n_params(Statistic::Cz, nm, nl)
            - 2 * self.theta_nodes
            - self.legendre.min(MAX_LEGENDRE) * (nm + nl)
    }

    /// The blocks of `stat` at `c` with their multipliers; `inv_sigma` = 1/σ̂ (c only).
    fn blocks<F: Real>(
        &self,
        stat: Statistic,
        c: &Cell<F>,
        Azimuth(trig): &Azimuth<F>,
        inv_sigma: F,
        out: &mut [Block<F>; MAX_BLOCKS],
    ) -> usize {
        let one = F::of(1.0);
        let SlabPoint {
            depth, mu_v, mu_l, ..
        } = c.at;
        let s_l = (one - mu_l * mu_l).clamp_to(F::of(0.0), one).sqrt();
        let s_v = (one - mu_v * mu_v).clamp_to(F::of(0.0), one).sqrt();
        let k_max = self.harmonics.min(MAX_COLLECTOR_HARMONICS);
        let mut n = 0;
        let mut push = |b: Block<F>| {
            out[n] = b;
            n += 1;
        };
        match stat {
            Statistic::LnSigma => {
                push(Block::Theta(one));
                let mut s_k = one;
                for &(_, cos_k) in &trig[..=k_max] {
                    push(Block::Depth(s_k * cos_k));
                    s_k = s_k * s_v * s_l;
                }
            }
            Statistic::Cz => {
                let mu_l = if mu_l > F::of(0.05) {
                    mu_l
                } else {
                    F::of(0.05)
                };
                let lam = F::of(8.0);
                let reach = s_l * lam * -crate::real::exp_m1(-depth / (mu_l * lam)) * inv_sigma;
                push(Block::Theta(one));
                push(Block::Depth(s_l));
                for &(_, cos_k) in &trig[1..=k_max] {
                    push(Block::Depth(cos_k));
                }
                push(Block::Theta(reach));
                push(Block::Depth(reach * s_l));
            }
            Statistic::Cx => {
                // sin ψ, as sin(1 · ψ): 1 · ψ is ψ exactly.
                push(Block::Theta(trig[1].0));
                for &(sin_k, _) in &trig[1..=k_max] {
                    push(Block::Depth(sin_k));
                }
            }
        }
        n
    }

    /// Calls `f(column, value)` for every feature of `stat` at `c` that is not zero by
    /// construction; `sigma` is σ̂ (mfp) for c_x and c_z, ignored for ln σ.
    pub fn for_each_feature<F: Real>(
        &self,
        stat: Statistic,
        c: &Cell<F>,
        sigma: F,
        nm: usize,
        nl: usize,
        mut f: impl FnMut(usize, F),
    ) {
        let p = legendre(F::of(2.0) * c.u - F::of(1.0), self.depth_terms());
        self.for_each_feature_in_depth(stat, c, sigma, nm, nl, |col, v, j| f(col, v * p[j]));
    }

    /// Legendre terms in x = 2u − 1 the features use (the J depth terms, the Θ table's slope).
    pub fn depth_terms(&self) -> usize {
        self.legendre.clamp(2, MAX_LEGENDRE)
    }

    /// As [`Self::for_each_feature`], split as `f(column, value, j)`: the feature is
    /// value · P_j(2u − 1), value independent of u.
    pub fn for_each_feature_in_depth<F: Real>(
        &self,
        stat: Statistic,
        c: &Cell<F>,
        sigma: F,
        nm: usize,
        nl: usize,
        f: impl FnMut(usize, F, usize),
    ) {
        let azimuth = self.azimuth(c.at.psi_v);
        self.for_each_feature_at(stat, c, &azimuth, sigma, (nm, nl), f);
    }

    /// sin kψ and cos kψ for the harmonics k ≤ K the statistics use: a caller that takes
    /// several statistics at one point computes them once (with the shipped K = 2, 8 calls of
    /// sin_cos per read, of which 3 distinct).
    pub fn azimuth<F: Real>(&self, psi: F) -> Azimuth<F> {
        // k = 1 always: c_x's Θ block takes sin ψ whatever K.
        let k_max = self.harmonics.clamp(1, MAX_COLLECTOR_HARMONICS);
        Azimuth(core::array::from_fn(|k| {
            if k <= k_max {
                (F::of(k as f64) * psi).sin_cos()
            } else {
                (F::of(0.0), F::of(1.0))
            }
        }))
    }

    /// [`Self::for_each_feature_in_depth`] with the point's harmonics `azimuth`
    /// ([`Self::azimuth`] of its ψ_V).
    #[inline]
    pub fn for_each_feature_at<F: Real>(
        &self,
        stat: Statistic,
        c: &Cell<F>,
        azimuth: &Azimuth<F>,
        sigma: F,
        (nm, nl): (usize, usize),
        mut f: impl FnMut(usize, F, usize),
    ) {
        let inv_sigma = if sigma > F::of(0.0) {
            F::of(1.0) / sigma
        } else {
            F::of(0.0)
        };
        let mut blocks = [Block::Theta(F::of(0.0)); MAX_BLOCKS];
        let n = self.blocks(stat, c, azimuth, inv_sigma, &mut blocks);
        let mut col = 0;
        for b in &blocks[..n] {
            match *b {
                Block::Theta(v) => {
                    theta_hats(self.theta_nodes, c, v, col, &mut f);
                    col += 2 * self.theta_nodes;
                }
                Block::Depth(v) => {
                    for j in 0..self.legendre.min(MAX_LEGENDRE) {
                        on_nodes(c, nm, col, v, &mut |col, v| f(col, v, j));
                        col += nm + nl;
                    }
                }
            }
        }
    }

    /// The value of `stat` at `c` with parameters `coef(column)`: ln σ, or c_z/σ̂ or c_x/σ̂.
    pub fn value<F: Real>(
        &self,
        stat: Statistic,
        c: &Cell<F>,
        sigma: F,
        nm: usize,
        nl: usize,
        coef: impl Fn(usize) -> F,
    ) -> F {
        let mut sum = F::of(0.0);
        self.for_each_feature(stat, c, sigma, nm, nl, |col, v| sum = sum + v * coef(col));
        sum
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::transport::log_additive::Lerp;

    fn cell(mu_l: f64, mu_v: f64, psi: f64, u: f64) -> Cell<f64> {
        let nodes = [0.25, 0.5, 0.75, 1.0];
        let vnodes = [-0.75, -0.25, 0.25, 0.75];
        Cell::new(
            SlabPoint {
                depth: 4.0 * u,
                thickness: 4.0,
                mu_v,
                psi_v: psi,
                mu_l,
            },
            Lerp::between(&nodes, mu_l),
            Lerp::between(&vnodes, mu_v),
            u,
        )
    }

    /// Columns stay below n_params, and c_x vanishes at ψ = 0 and π (mirror symmetry) whatever
    /// the parameters.
    #[test]
    fn columns_fit_and_symmetries_hold() {
        let form = CollectorForm::default();
        for stat in Statistic::ALL {
            let n = form.n_params(stat, 4, 4);
            let c = cell(0.6, -0.3, 0.7, 0.4);
            let mut count = 0;
            form.for_each_feature(stat, &c, 1.3, 4, 4, |col, _| {
                assert!(col < n, "{stat:?}: column {col} of {n}");
                count += 1;
            });
            assert!(count > 0);
        }
        let coef = |i: usize| 0.1 + 0.01 * (i % 7) as f64;
        for psi in [0.0, core::f64::consts::PI] {
            let v = form.value(Statistic::Cx, &cell(0.6, 0.4, psi, 0.5), 2.0, 4, 4, coef);
            assert!(v.abs() < 1e-12, "c_x at ψ = {psi}: {v}");
        }
    }

    #[test]
    fn f32_follows_f64() {
        let form = CollectorForm::default();
        let coef = |i: usize| 0.05 * ((i * 7919 % 103) as f64 / 103.0 - 0.5);
        for stat in Statistic::ALL {
            let c = cell(0.45, 0.55, 1.1, 0.3);
            let a = form.value(stat, &c, 1.7, 4, 4, coef);
            let c32 = Cell::new(
                SlabPoint {
                    depth: 1.2f32,
                    thickness: 4.0,
                    mu_v: 0.55,
                    psi_v: 1.1,
                    mu_l: 0.45,
                },
                Lerp {
                    lo: c.l.lo,
                    hi: c.l.hi,
                    w: c.l.w as f32,
                },
                Lerp {
                    lo: c.v.lo,
                    hi: c.v.hi,
                    w: c.v.w as f32,
                },
                0.3,
            );
            let b = form.value(stat, &c32, 1.7f32, 4, 4, |i| coef(i) as f32);
            assert!(
                (b as f64 - a).abs() < 1e-5 * (1.0 + a.abs()),
                "{stat:?}: {a} vs {b}"
            );
        }
    }
}
