//! What a Mie job may ask for, checked before anything is allocated (docs/mie.md, "Limits"):
//! the documented size-parameter range, wavelengths that are plausible in nm, and the memory a
//! job will need. A slip of units (µm for nm, metres for µm) lands far outside these ranges, so
//! each refusal names the likely slip.

use super::distribution::{SizeDistribution, PRODUCT_RULE_Z};
use super::sphere::n_terms;
use super::{MieJob, SizeRule};
use crate::io::text::{bytes, short};
use anyhow::{bail, Result};
use std::f64::consts::PI;

/// Smallest size parameter x = π d n_medium / λ the Mie series is verified at (the Rayleigh
/// limit test; docs/mie.md).
pub const X_MIN: f64 = 1e-3;
/// Largest verified size parameter (the stability test at 2·10⁴; docs/mie.md).
pub const X_MAX: f64 = 2e4;
/// Plausible vacuum wavelengths, nm: far UV to far infrared. Outside, the number was almost
/// certainly meant in other units.
pub const WAVELENGTH_RANGE_NM: (f64, f64) = (100.0, 1e5);

/// Memory and work of a job, estimated from the rule alone (nothing allocated).
#[derive(Clone, Copy, Debug, Default)]
pub struct Footprint {
    /// Spheres to evaluate.
    pub spheres: f64,
    /// Largest size parameter.
    pub x_max: f64,
    /// Bytes of the largest arrays held at once.
    pub bytes: f64,
}

impl MieJob {
    /// Every size parameter within [`X_MIN`, `X_MAX`] and every wavelength plausible in nm.
    pub(super) fn check_limits(&self) -> Result<()> {
        // x falls with λ: the shortest and the longest wavelength bound every other.
        let lams = self.row_wavelengths();
        let shortest = lams.iter().copied().fold(f64::INFINITY, f64::min);
        let longest = lams.iter().copied().fold(0.0, f64::max);
        for d in &self.distributions {
            self.check_x(d, shortest)?;
            self.check_x(d, longest)?;
        }
        let (lo, hi) = WAVELENGTH_RANGE_NM;
        let (min, max) = self
            .wavelengths_nm
            .iter()
            .fold((f64::INFINITY, 0.0f64), |(a, b), &l| (a.min(l), b.max(l)));
        // The extreme one: the grid's far end shows the slip best.
        let l = if min < lo { min } else { max };
        if !(lo..=hi).contains(&l) {
            let hint = if l < lo && (lo..=hi).contains(&(l * 1e3)) {
                format!(" ({} µm is {} nm)", short(l), short(l * 1e3))
            } else {
                String::new()
            };
            bail!(
                "wavelength {} nm is outside {lo}–{hi:e} nm: wavelengths are in nm{hint}",
                short(l)
            );
        }
        Ok(())
    }

    /// x of the nominal diameter, then of the largest and smallest sizes of `dist`, at
    /// `lambda_nm` (the nominal one first: when it is out of range, that is the slip to name).
    fn check_x(&self, dist: &SizeDistribution, lambda_nm: f64) -> Result<()> {
        let k = PI * self.medium_index / (lambda_nm * 1e-3); // x = k d, d in µm
        let d0 = dist.nominal_diameter_um();
        let (lo, hi) = self.size_range_um(dist);
        for d in [d0, hi, lo] {
            let x = k * d;
            if (X_MIN..=X_MAX).contains(&x) {
                continue;
            }
            let which = if d == d0 {
                format!("d = {} µm", short(d))
            } else {
                let end = if d > d0 { "largest" } else { "smallest" };
                format!(
                    "d = {} µm, the {end} size of d = {} µm,",
                    short(d),
                    short(d0)
                )
            };
            let (rel, limit) = if x > X_MAX {
                ("exceeds", X_MAX)
            } else {
                ("is below", X_MIN)
            };
            bail!(
                "size parameter x = {} ({which} at λ = {} nm) {rel} the documented limit {limit:e}: {}",
                short(x),
                short(lambda_nm),
                slip(lambda_nm, d0, x > X_MAX)
            );
        }
        Ok(())
    }

    /// The smallest and largest diameters (µm) the job's rule evaluates for `dist`.
    fn size_range_um(&self, dist: &SizeDistribution) -> (f64, f64) {
        let z = match self.rule {
            SizeRule::Product { .. } => PRODUCT_RULE_Z,
            SizeRule::Converged { z_max, .. } => z_max,
        };
        let (a, b) = dist.support_ln_d(z);
        (a.exp(), b.exp())
    }

    /// Spheres and bytes the job will need, from the rule's node counts (docs/mie.md, "Limits").
    pub fn footprint(&self) -> Footprint {
        let lams = self.row_wavelengths();
        let k = |l: f64| PI * self.medium_index / (l * 1e-3);
        let nodes = |x_lo: f64, x_hi: f64, mono: bool| match self.rule {
            _ if mono => 1.0,
            SizeRule::Product { sizes } => sizes as f64,
            SizeRule::Converged {
                ln_step, x_step, ..
            } => {
                let u = |x: f64| x.ln() / ln_step + x / x_step;
                (u(x_hi) - u(x_lo)).ceil() + 1.0
            }
        };
        let (mut weights, mut x_lo, mut x_hi) = (0.0, f64::INFINITY, 0.0f64);
        for d in &self.distributions {
            let (lo, hi) = self.size_range_um(d);
            let mono = matches!(d, SizeDistribution::Mono { .. });
            for &l in &lams {
                weights += nodes(k(l) * lo, k(l) * hi, mono);
                (x_lo, x_hi) = (x_lo.min(k(l) * lo), x_hi.max(k(l) * hi));
            }
        }
        // A shared ln-x grid holds each sphere once; otherwise every weight is its own sphere.
        let spheres = if self.shares_ln_x() {
            nodes(x_lo, x_hi, false)
        } else {
            weights
        };
        let n_ang = self.angles_deg.len() as f64;
        let rows = (self.distributions.len() * lams.len()) as f64;
        // Per sphere: the particle, its sort index, efficiencies and their copy (80 B); the
        // angle basis U, V twice while it is built; the output rows; the tables. Measured peaks
        // (docs/mie.md, "Limits") are within 10 % of this plus the program's own 64 MB.
        let bytes = 64e6
            + 80.0 * spheres
            + 8.0 * weights
            + 32.0 * n_terms(x_hi) as f64 * n_ang
            + 16.0 * rows * n_ang
            + 8.0 * 256.0 * n_ang;
        Footprint {
            spheres,
            x_max: x_hi,
            bytes,
        }
    }

    /// Refuses a job that needs more than `available` bytes, before it allocates them.
    pub fn check_memory(&self, available: f64) -> Result<()> {
        let f = self.footprint();
        if f.bytes <= available {
            return Ok(());
        }
        let coarser = match self.rule {
            SizeRule::Product { .. } => "fewer --sizes",
            SizeRule::Converged { .. } => "a coarser --x-step / --ln-step",
        };
        bail!(
            "this job needs about {} of memory, more than the {} available ({} spheres up to \
             x = {}, {} angles, {} × {} output rows): ask for fewer diameters, wavelengths or \
             angles, or {coarser}",
            bytes(f.bytes),
            bytes(available),
            short(f.spheres),
            short(f.x_max),
            self.angles_deg.len(),
            self.distributions.len(),
            self.row_wavelengths().len()
        )
    }
}

/// The likely slip behind a size parameter out of range (`large`: above [`X_MAX`]), from the
/// wavelength `lambda_nm` and the nominal diameter `d_um`.
fn slip(lambda_nm: f64, d_um: f64, large: bool) -> String {
    let (lo, hi) = WAVELENGTH_RANGE_NM;
    if lambda_nm < lo {
        "wavelengths are in nm, not µm".into()
    } else if lambda_nm > hi {
        "wavelengths are in nm".into()
    } else if large && d_um >= 1e4 {
        "diameters are in µm, not nm".into()
    } else if large {
        format!(
            "the Mie series is verified up to x = {X_MAX:e} (docs/mie.md); use smaller droplets, \
             a narrower distribution or longer wavelengths"
        )
    } else {
        format!(
            "the Mie series is verified down to x = {X_MIN:e} (docs/mie.md); use larger \
             droplets, a narrower distribution or shorter wavelengths"
        )
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::mie::polydisperse::CONVERGED_DEFAULT;

    #[test]
    fn footprint_counts_the_spheres_of_the_shared_grid() {
        // The docs' measured count of `--diameter 20` (64 494 spheres), within a few nodes.
        let job = MieJob::paper(20.0, CONVERGED_DEFAULT, 61);
        let f = job.footprint();
        assert!((f.spheres - 64_494.0).abs() < 10.0, "{}", f.spheres);
        assert!(f.bytes < 1e9);
        assert!(job.check_memory(f.bytes * 0.5).is_err());
        assert!(job.check_memory(f.bytes * 2.0).is_ok());
    }
}
