//! Polydisperse, spectrally averaged phase functions (docs/mie.md).
//!
//! For a number distribution with weights w_i at wavelength λ, the phase function is
//!   p_λ(θ) = Σ_i w_i (|S1|² + |S2|²)_i / 2 / k²  ÷  Σ_i w_i C_sca,i,
//! normalised by the analytic cross-sections (C_sca = Q_sca π x²/k², so k² cancels), and the
//! mean phase function is the equal-weight mean of p_λ over the wavelength grid.
//!
//! Two size rules:
//! - **product rule** (`SizeRule::Product`): the spec's explicit N-size rule at every
//!   wavelength, for digit-level comparisons with other codes;
//! - **converged** (`SizeRule::Converged`): uniform in ln d with step h over ±z_max σ. With a
//!   constant index, p_λ depends on λ only through the distribution of x = π d/λ, so one table
//!   on a uniform ln-x grid (step h) serves every wavelength and every diameter whose x-range
//!   it covers; each (diameter, λ) is one row of weights over that table. A dispersive index
//!   needs its own sizes at every wavelength (same step h in ln d).

use super::batch::{weighted_intensity, Particle, WeightRow};
use super::colour::{srgb_weights, Illuminant, RGB_WAVELENGTHS_NM};
use super::distribution::SizeDistribution;
use super::grid;
use super::index::RefractiveIndex;
use super::sphere::n_terms;
use anyhow::{bail, Context, Result};
use serde::{Deserialize, Serialize};
use std::f64::consts::PI;

/// How the size (and, with a constant index, wavelength) integral is discretised.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
#[serde(tag = "kind", rename_all = "snake_case", deny_unknown_fields)]
pub enum SizeRule {
    /// The explicit product rule (docs/mie.md) with `sizes` sizes.
    Product {
        /// Number of sizes N_s.
        sizes: usize,
    },
    /// A fine grid in size parameter over ±`z_max` standard deviations of the log-normal (the
    /// equivalent tail level for the gamma): uniform in u(x) = ln x / `ln_step` + x / `x_step`,
    /// i.e. a step of `ln_step` in ln x for small x and of `x_step` in x for large x, where
    /// the resonances that must be sampled have a roughly constant spacing and width in x.
    Converged {
        /// Largest step in ln x.
        ln_step: f64,
        /// Largest step in x.
        x_step: f64,
        /// Half-width of the size support in σ.
        z_max: f64,
    },
}

/// The converged default, chosen by the convergence study in docs/mie.md (and the test
/// `converged_default_is_within_5e_3_of_a_finer_rule`).
pub const CONVERGED_DEFAULT: SizeRule = SizeRule::Converged {
    ln_step: 2.5e-4,
    x_step: 0.01,
    z_max: 5.0,
};

/// Number of wavelengths of the converged default over 400–700 nm.
pub const DEFAULT_WAVELENGTHS: usize = 61;

/// Everything a Mie phase-function job needs; one table is produced per distribution.
#[derive(Clone, Debug, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct MieJob {
    /// One size distribution per output table.
    pub distributions: Vec<SizeDistribution>,
    /// Vacuum wavelengths, nm (uniform grid, inclusive ends).
    pub wavelengths_nm: Vec<f64>,
    /// Size quadrature.
    pub rule: SizeRule,
    /// Droplet refractive index.
    pub index: RefractiveIndex,
    /// Real refractive index of the medium (1 for air).
    pub medium_index: f64,
    /// Scattering angles, degrees.
    pub angles_deg: Vec<f64>,
    /// Illuminant of the sRGB channels.
    pub illuminant: Illuminant,
    /// Highest Legendre moment to write.
    pub legendre: usize,
}

/// One polydisperse phase-function table and its integral quantities.
#[derive(Clone, Debug)]
pub struct PhaseTable {
    /// The distribution it was computed for.
    pub distribution: SizeDistribution,
    /// Angles, degrees.
    pub theta_deg: Vec<f64>,
    /// cos θ.
    pub mu: Vec<f64>,
    /// Mean over wavelengths, sr⁻¹.
    pub phase: Vec<f64>,
    /// Linear-sRGB channels, n_θ × 3 row-major, sr⁻¹.
    pub phase_rgb: Vec<f64>,
    /// Monochromatic 650/510/440 nm channels, n_θ × 3 row-major, sr⁻¹.
    pub phase_rgb_3wl: Vec<f64>,
    /// Wavelengths, nm.
    pub wavelength_nm: Vec<f64>,
    /// p_λ for each wavelength, n_λ × n_θ row-major, sr⁻¹.
    pub phase_spectral: Vec<f64>,
    /// Inverse-CDF table in θ of the mean phase function (ends at 1).
    pub cdf: Vec<f64>,
    /// Legendre moments χ_0..χ_K of the mean phase function, divided by the quadrature's χ_0
    /// so that χ_0 = 1 exactly (as the CDF ends at exactly 1).
    pub legendre: Vec<f64>,
    /// Asymmetry parameter of the mean phase function (from the Mie series).
    pub g: f64,
    /// g of each sRGB channel.
    pub g_rgb: [f64; 3],
    /// g at each wavelength.
    pub g_spectral: Vec<f64>,
    /// Mean scattering cross-section per droplet ⟨C_sca⟩, µm², at each wavelength.
    pub c_sca_spectral_um2: Vec<f64>,
    /// Mean over wavelengths of ⟨C_sca⟩, µm².
    pub c_sca_um2: f64,
    /// Area-weighted scattering efficiency ⟨C_sca⟩ / ⟨π r²⟩, wavelength mean.
    pub q_sca: f64,
    /// Effective diameter 2⟨r³⟩/⟨r²⟩, µm.
    pub effective_diameter_um: f64,
    /// ∮ p dΩ of the mean phase function by the trapezoid rule on the angle grid (the analytic
    /// value is 1; this measures how well the grid resolves the table).
    pub quadrature_norm: f64,
}

impl PhaseTable {
    /// Refuses a table with a non-finite value or a phase function that is zero everywhere
    /// (an underflow: tiny droplets, far-off units), so that no such table is ever written.
    /// `phase_rgb` and `g_rgb` are left out: a wavelength grid that gives a channel no weight
    /// has no such channel, NaN by design ([`srgb_weights`]).
    pub fn check_values(&self) -> Result<()> {
        let arrays: [(&str, &[f64]); 4] = [
            ("phase", &self.phase),
            ("phase_spectral", &self.phase_spectral),
            ("phase_rgb_3wl", &self.phase_rgb_3wl),
            ("cdf", &self.cdf),
        ];
        let scalars = [self.g, self.q_sca, self.effective_diameter_um];
        let bad = arrays
            .iter()
            .find(|(_, v)| v.iter().any(|x| !x.is_finite()) || v.iter().all(|&x| x == 0.0))
            .map(|(name, _)| *name)
            .or((!self.legendre.iter().all(|x| x.is_finite())).then_some("legendre"))
            .or((!scalars.iter().all(|x| x.is_finite())).then_some("g, Q_sca or d_eff"))
            .or((!(self.c_sca_um2 > 0.0 && self.c_sca_um2.is_finite())).then_some("C_sca"));
        if let Some(name) = bad {
            bail!(
                "the Mie table of d = {} µm came out with {name} non-finite or zero: not written \
                 (diameters are in µm, wavelengths in nm)",
                self.distribution.nominal_diameter_um()
            );
        }
        Ok(())
    }
}

/// Work statistics of a job.
#[derive(Clone, Copy, Debug, Default, Serialize)]
pub struct JobStats {
    /// Spheres evaluated (size × wavelength pairs or ln-x table entries).
    pub spheres: usize,
    /// Largest number of Mie terms.
    pub max_terms: usize,
    /// Floating-point operations in the matrix products (zero padding included).
    pub flops: f64,
    /// The same without the padding of short series.
    pub useful_flops: f64,
    /// Flops done inside the GEMM calls (padding included) and the seconds spent in them,
    /// summed over threads: the GEMM part's own rate. Read from the process-wide
    /// [`super::batch::GEMM_CLOCK`], so jobs run at the same time in one process share them.
    pub gemm_flops: f64,
    /// See [`Self::gemm_flops`].
    pub gemm_seconds: f64,
}

/// One output row: a (distribution, wavelength) pair, its wavelength and its (unnormalised)
/// number weights on a contiguous run of particles.
struct Row {
    lambda_nm: f64,
    span: WeightRow,
}

impl AsRef<WeightRow> for Row {
    fn as_ref(&self) -> &WeightRow {
        &self.span
    }
}

/// Nodes x_k of the converged grid on [x_lo, x_hi], uniform in u(x) = ln x / h + x / Δx with
/// unit step, and the Jacobian d ln x / du = 1 / (1/h + x/Δx) that turns a density per ln x
/// into trapezoid weights (the end nodes' half weights are below the 5σ tail and dropped).
fn converged_nodes(x_lo: f64, x_hi: f64, h: f64, dx: f64) -> (Vec<f64>, Vec<f64>) {
    let u = |x: f64| x.ln() / h + x / dx;
    let (u_lo, u_hi) = (u(x_lo), u(x_hi));
    let n = (u_hi - u_lo).ceil() as usize + 1;
    let mut xs = Vec::with_capacity(n);
    let mut x = x_lo;
    for k in 0..n {
        let target = u_lo + k as f64;
        for _ in 0..50 {
            // Newton on u(x) = target; u is increasing and concave in ln x, so this converges.
            let step = (u(x) - target) / (1.0 / (x * h) + 1.0 / dx);
            x -= step;
            if step.abs() <= 1e-15 * x {
                break;
            }
        }
        xs.push(x);
    }
    let jac = xs.iter().map(|&x| 1.0 / (1.0 / h + x / dx)).collect();
    (xs, jac)
}

impl MieJob {
    /// The paper's setting at median diameter `d_median_um`: log-normal σ = 0.25, water
    /// n = 1.333 in air, `n_wavelengths` uniform over 400–700 nm, the 2251-angle reference
    /// grid, D65, 64 Legendre moments; `rule` as given.
    pub fn paper(d_median_um: f64, rule: SizeRule, n_wavelengths: usize) -> Self {
        let step = 300.0 / (n_wavelengths.max(2) - 1) as f64;
        Self {
            distributions: vec![SizeDistribution::LogNormal {
                d_median_um,
                sigma: 0.25,
            }],
            wavelengths_nm: (0..n_wavelengths)
                .map(|i| 400.0 + step * i as f64)
                .collect(),
            rule,
            index: RefractiveIndex::Constant { n: 1.333, k: 0.0 },
            medium_index: 1.0,
            angles_deg: grid::reference_angles_deg(),
            illuminant: Illuminant::D65,
            legendre: 64,
        }
    }

    /// Checks the job; errors name the offending input.
    pub fn validate(&self) -> Result<()> {
        if self.distributions.is_empty() {
            bail!("no diameters given");
        }
        for d in &self.distributions {
            d.validate()?;
        }
        if self.wavelengths_nm.is_empty() {
            bail!("the wavelength grid is empty");
        }
        if self
            .wavelengths_nm
            .iter()
            .any(|l| !(l.is_finite() && *l > 0.0))
        {
            bail!("wavelengths must be positive");
        }
        if !(self.medium_index.is_finite() && self.medium_index > 0.0) {
            bail!("medium index must be positive, got {}", self.medium_index);
        }
        match self.rule {
            SizeRule::Product { sizes: 0 } => bail!("--sizes must be at least 1"),
            SizeRule::Converged {
                ln_step,
                x_step,
                z_max,
            } if !(ln_step > 0.0
                && ln_step < 0.1
                && x_step > 0.0
                && z_max > 0.0
                && z_max <= 10.0) =>
            {
                bail!("converged rule needs 0 < ln_step < 0.1, x_step > 0 and 0 < z_max ≤ 10")
            }
            _ => {}
        }
        self.index.validate()?;
        for &l in &self.wavelengths_nm {
            self.index.at(l)?;
        }
        for &l in &RGB_WAVELENGTHS_NM {
            self.index
                .at(l)
                .context("the 650/510/440 nm LUT needs the index there too")?;
        }
        grid::validate_angles(&self.angles_deg)?;
        // After the basic checks: the limits need positive, finite inputs.
        self.check_limits()
    }

    /// Quadrature weights of the wavelength mean (sum 1). The product rule uses the explicit rule's
    /// equal weights, so that its tables can be compared digit for digit; the converged rule
    /// uses the trapezoid rule, whose error falls as 1/N_λ² instead of 1/N_λ (with equal
    /// weights the end points are over-weighted by half a step: 2e-3 at 61 wavelengths).
    pub fn wavelength_weights(&self) -> Vec<f64> {
        let n = self.wavelengths_nm.len();
        if n == 1 || matches!(self.rule, SizeRule::Product { .. }) {
            return vec![1.0 / n as f64; n];
        }
        let mut w = vec![1.0 / (n - 1) as f64; n];
        w[0] *= 0.5;
        w[n - 1] *= 0.5;
        w
    }

    /// All output wavelengths: the grid, then the three LUT wavelengths.
    pub(super) fn row_wavelengths(&self) -> Vec<f64> {
        self.wavelengths_nm
            .iter()
            .chain(&RGB_WAVELENGTHS_NM)
            .copied()
            .collect()
    }

    /// Builds the particle list and one row of number weights per (distribution, λ).
    fn discretise(&self) -> Result<(Vec<Particle>, Vec<Row>)> {
        if self.shares_ln_x() {
            self.discretise_shared_ln_x()
        } else {
            self.discretise_per_wavelength()
        }
    }

    /// Whether one ln-x grid serves every row: a constant index, the converged rule and no
    /// monodisperse table.
    pub(super) fn shares_ln_x(&self) -> bool {
        self.index.is_constant()
            && matches!(self.rule, SizeRule::Converged { .. })
            && self
                .distributions
                .iter()
                .all(|d| !matches!(d, SizeDistribution::Mono { .. }))
    }

    /// Constant index: one size-parameter grid shared by every row.
    fn discretise_shared_ln_x(&self) -> Result<(Vec<Particle>, Vec<Row>)> {
        let SizeRule::Converged {
            ln_step,
            x_step,
            z_max,
        } = self.rule
        else {
            unreachable!()
        };
        let m = self.index.at(self.wavelengths_nm[0])? / self.medium_index;
        let lams = self.row_wavelengths();
        let shift = |lam: f64| (PI * self.medium_index / (lam * 1e-3)).ln(); // ln x = ln d + shift
        let (mut lo, mut hi) = (f64::INFINITY, f64::NEG_INFINITY);
        for d in &self.distributions {
            let (a, b) = d.support_ln_d(z_max);
            for &l in &lams {
                (lo, hi) = (lo.min(a + shift(l)), hi.max(b + shift(l)));
            }
        }
        let (xs, jac) = converged_nodes(lo.exp(), hi.exp(), ln_step, x_step);
        let particles = xs.iter().map(|&x| Particle { x, m }).collect();
        let mut rows = Vec::new();
        for d in &self.distributions {
            let (a, b) = d.support_ln_d(z_max);
            for &l in &lams {
                let s = shift(l);
                let first = xs.partition_point(|x| x.ln() - s < a);
                let end = xs.partition_point(|x| x.ln() - s <= b);
                let weights = (first..end)
                    .map(|k| d.density_ln_d(xs[k].ln() - s) * jac[k])
                    .collect();
                rows.push(Row {
                    lambda_nm: l,
                    span: WeightRow {
                        start: first,
                        weights,
                    },
                });
            }
        }
        Ok((particles, rows))
    }

    /// Product rule, monodisperse or dispersive index: own sizes at every wavelength.
    fn discretise_per_wavelength(&self) -> Result<(Vec<Particle>, Vec<Row>)> {
        let mut particles = Vec::new();
        let mut rows = Vec::new();
        for d in &self.distributions {
            for l in self.row_wavelengths() {
                let m = self.index.at(l)? / self.medium_index;
                let k = PI * self.medium_index / (l * 1e-3); // x = k d
                let (d_um, weights) = self.size_nodes(d, k);
                let start = particles.len();
                particles.extend(d_um.iter().map(|&di| Particle { x: k * di, m }));
                rows.push(Row {
                    lambda_nm: l,
                    span: WeightRow { start, weights },
                });
            }
        }
        Ok((particles, rows))
    }

    /// Diameters (µm, ascending) and number weights of one distribution under the job's size
    /// rule, at a wavelength where x = k d.
    fn size_nodes(&self, d: &SizeDistribution, k: f64) -> (Vec<f64>, Vec<f64>) {
        match self.rule {
            SizeRule::Product { sizes } => {
                let nodes = d.product_rule(sizes);
                (nodes.d_um, nodes.weight)
            }
            SizeRule::Converged { .. } if matches!(d, SizeDistribution::Mono { .. }) => {
                (vec![d.nominal_diameter_um()], vec![1.0])
            }
            SizeRule::Converged {
                ln_step,
                x_step,
                z_max,
            } => {
                let (a, b) = d.support_ln_d(z_max);
                let (xs, jac) = converged_nodes(k * a.exp(), k * b.exp(), ln_step, x_step);
                let d_um: Vec<f64> = xs.iter().map(|x| x / k).collect();
                let w = d_um
                    .iter()
                    .zip(&jac)
                    .map(|(di, j)| d.density_ln_d(di.ln()) * j)
                    .collect();
                (d_um, w)
            }
        }
    }

    /// Runs the job; `progress(done, total)` reports the work finished, in Mie terms summed
    /// over the spheres (a sphere's cost grows with its term count, so the bar's rate and
    /// estimate hold while the spheres grow from small to large).
    pub fn compute(
        &self,
        progress: &(dyn Fn(usize, usize) + Sync),
    ) -> Result<(Vec<PhaseTable>, JobStats)> {
        self.validate()?;
        let (particles, rows) = self.discretise()?;
        let mu: Vec<f64> = self
            .angles_deg
            .iter()
            .map(|d| d.to_radians().cos())
            .collect();
        let max_terms = particles.iter().map(|p| n_terms(p.x)).max().unwrap_or(1);
        let total: usize = particles.iter().map(|p| n_terms(p.x)).sum();
        progress(0, total);
        let basis = super::angular::AngleBasis::new(&mu, max_terms);
        let gemm_before = super::batch::GEMM_CLOCK.read();
        let (mut out, eff, work) =
            weighted_intensity(&particles, &rows, &basis, &|done| progress(done, total));
        let gemm_after = super::batch::GEMM_CLOCK.read();
        let eff: Vec<(f64, f64)> = eff.iter().map(|e| (e.q_sca, e.g)).collect();
        let integrals: Vec<RowIntegrals> = rows
            .iter()
            .map(|r| RowIntegrals::new(r, &particles, &eff, self.medium_index))
            .collect();
        // Normalise each row by its analytic cross-section: Σ w π x² Q_sca (the k² cancels).
        let n_ang = mu.len();
        for (r, ints) in integrals.iter().enumerate() {
            out[r * n_ang..(r + 1) * n_ang]
                .iter_mut()
                .for_each(|v| *v /= ints.norm);
        }
        let per_dist = self.wavelengths_nm.len() + RGB_WAVELENGTHS_NM.len();
        let tables = self
            .distributions
            .iter()
            .enumerate()
            .map(|(q, d)| {
                let rs = q * per_dist..(q + 1) * per_dist;
                self.assemble(
                    *d,
                    &out[rs.start * n_ang..rs.end * n_ang],
                    &integrals[rs],
                    &mu,
                )
            })
            .collect::<Result<Vec<_>>>()?;
        for t in &tables {
            t.check_values()?;
        }
        Ok((
            tables,
            JobStats {
                spheres: work.spheres,
                max_terms,
                flops: work.flops,
                useful_flops: work.useful_flops,
                gemm_flops: gemm_after.0 - gemm_before.0,
                gemm_seconds: gemm_after.1 - gemm_before.1,
            },
        ))
    }

    /// Mean, colour channels, CDF and moments of one distribution's rows.
    fn assemble(
        &self,
        d: SizeDistribution,
        rows: &[f64],
        ints: &[RowIntegrals],
        mu: &[f64],
    ) -> Result<PhaseTable> {
        let n_ang = mu.len();
        let n_l = self.wavelengths_nm.len();
        let spectral = &rows[..n_l * n_ang];
        let row = |j: usize| &rows[j * n_ang..(j + 1) * n_ang];
        let mean_w = self.wavelength_weights();
        let combine = |w: &[f64]| -> Vec<f64> {
            (0..n_ang)
                .map(|i| {
                    w.iter()
                        .enumerate()
                        .map(|(j, wj)| wj * spectral[j * n_ang + i])
                        .sum()
                })
                .collect()
        };
        let phase = combine(&mean_w);
        let chi = grid::legendre_moments(&self.angles_deg, &phase, self.legendre);
        let rgb_w = srgb_weights(&self.wavelengths_nm, &mean_w, self.illuminant);
        let channels: Vec<Vec<f64>> = rgb_w.iter().map(|w| combine(w)).collect();
        let interleave = |c: [&[f64]; 3]| {
            (0..n_ang)
                .flat_map(|i| c.map(|ch| ch[i]))
                .collect::<Vec<f64>>()
        };
        let g_spectral: Vec<f64> = ints[..n_l].iter().map(|r| r.g).collect();
        let dot = |w: &[f64], v: &[f64]| w.iter().zip(v).map(|(a, b)| a * b).sum::<f64>();
        let c_sca: Vec<f64> = ints[..n_l].iter().map(|r| r.c_sca_um2).collect();
        Ok(PhaseTable {
            distribution: d,
            theta_deg: self.angles_deg.clone(),
            mu: mu.to_vec(),
            cdf: grid::cdf(&self.angles_deg, &phase),
            legendre: chi.iter().map(|c| c / chi[0]).collect(),
            quadrature_norm: chi[0],
            phase_rgb: interleave([&channels[0], &channels[1], &channels[2]]),
            phase_rgb_3wl: interleave([row(n_l), row(n_l + 1), row(n_l + 2)]),
            wavelength_nm: self.wavelengths_nm.clone(),
            phase_spectral: spectral.to_vec(),
            g: dot(&mean_w, &g_spectral),
            g_rgb: [0, 1, 2].map(|c| dot(&rgb_w[c], &g_spectral)),
            c_sca_um2: dot(&mean_w, &c_sca),
            q_sca: dot(
                &mean_w,
                &ints[..n_l].iter().map(|r| r.q_sca).collect::<Vec<_>>(),
            ),
            effective_diameter_um: dot(
                &mean_w,
                &ints[..n_l].iter().map(|r| r.d_eff_um).collect::<Vec<_>>(),
            ),
            c_sca_spectral_um2: c_sca,
            g_spectral,
            phase,
        })
    }
}

/// Integral quantities of one weight row, from the Mie series (no angular quadrature).
struct RowIntegrals {
    /// Σ w π x² Q_sca with the row's own (unnormalised) weights: k² C_sca of the row.
    norm: f64,
    g: f64,
    c_sca_um2: f64,
    q_sca: f64,
    d_eff_um: f64,
}

impl RowIntegrals {
    fn new(row: &Row, particles: &[Particle], eff: &[(f64, f64)], n_med: f64) -> Self {
        let total: f64 = row.span.weights.iter().sum();
        let (mut area, mut vol, mut sca, mut gsca, mut norm) = (0.0, 0.0, 0.0, 0.0, 0.0);
        let to_r_um = row.lambda_nm * 1e-3 / (2.0 * PI * n_med); // r = x λ / (2π n_med)
        for (i, &w0) in row.span.particles().zip(&row.span.weights) {
            norm += w0 * PI * particles[i].x.powi(2) * eff[i].0;
            let w = w0 / total;
            let r = particles[i].x * to_r_um;
            let (q, g) = eff[i];
            area += w * PI * r * r;
            vol += w * r * r * r;
            sca += w * q * PI * r * r;
            gsca += w * q * PI * r * r * g;
        }
        Self {
            norm,
            g: gsca / sca,
            c_sca_um2: sca,
            q_sca: sca / area,
            d_eff_um: 2.0 * vol * PI / area,
        }
    }
}
