//! `nephele sphere`: one sphere's efficiencies and amplitudes as JSON on stdout.

use anyhow::{bail, Result};
use clap::Args;
use nephele::mie::index::RefractiveIndex;
use nephele::mie::MieCoefficients;
use serde_json::json;

/// Options of `nephele sphere`.
#[derive(Args, Debug)]
pub struct SphereArgs {
    /// Relative refractive index: 1.333 or 1.5+0.1i (k ≥ 0 absorbs).
    #[arg(long, value_name = "M")]
    index: String,
    /// Size parameter x = π d n_medium / λ.
    #[arg(long, allow_hyphen_values = true)]
    x: f64,
    /// Scattering angles in degrees, comma-separated, or "default" for the 2251-angle grid.
    #[arg(long, value_name = "DEG,DEG,…", default_value = "0,90,180")]
    angles: String,
    /// Also print a_n, b_n.
    #[arg(long)]
    coefficients: bool,
}

/// Prints Q_ext, Q_sca, Q_back, g and S1, S2 (Bohren & Huffman convention) as JSON.
pub fn run(args: SphereArgs) -> Result<()> {
    let RefractiveIndex::Constant { n, k } = RefractiveIndex::parse(&args.index)? else {
        bail!("--index must be a number or n+ki for a single sphere");
    };
    if !(args.x.is_finite() && args.x > 0.0) {
        bail!("--x must be a positive size parameter, got {}", args.x);
    }
    let angles: Vec<f64> = if args.angles == "default" {
        nephele::mie::grid::reference_angles_deg()
    } else {
        nephele::mie::grid::angle_list(&args.angles)?
    };
    if angles.iter().any(|a| !(0.0..=180.0).contains(a)) {
        bail!("--angles must lie within 0–180°");
    }
    let coef = MieCoefficients::new(num_complex::Complex64::new(n, k), args.x);
    let e = coef.efficiencies();
    let s: Vec<_> = angles
        .iter()
        .map(|a| coef.amplitudes(a.to_radians().cos()))
        .collect();
    let mut v = json!({
        "m": [n, k], "x": args.x, "n_terms": coef.a.len(),
        "qext": e.q_ext, "qsca": e.q_sca, "qback": e.q_back, "g": e.g,
        "theta_deg": angles,
        "s1": s.iter().map(|p| [p.0.re, p.0.im]).collect::<Vec<_>>(),
        "s2": s.iter().map(|p| [p.1.re, p.1.im]).collect::<Vec<_>>(),
        "convention": "Bohren & Huffman: m = n + ik, S1/S2 dimensionless, dC/dOmega = (|S1|^2+|S2|^2)/(2k^2)"
    });
    if args.coefficients {
        v["a"] = json!(coef.a.iter().map(|c| [c.re, c.im]).collect::<Vec<_>>());
        v["b"] = json!(coef.b.iter().map(|c| [c.re, c.im]).collect::<Vec<_>>());
    }
    outln!("{}", serde_json::to_string(&v)?);
    Ok(())
}
