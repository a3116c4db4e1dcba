//! Convergence study of the Mie size/wavelength quadrature (docs/mie.md).
//!
//! For each median diameter, compares a candidate rule with a reference rule (finer ln-x step,
//! wider size support, more wavelengths) and prints the worst relative difference of p(θ) over
//! all angles, and where it occurs.
//!
//!     cargo run --release --example mie_convergence [-- D1,D2,… [REFINE]]

use nephele::mie::{MieJob, SizeRule};

fn worst(a: &[f64], b: &[f64], theta: &[f64]) -> (f64, f64) {
    a.iter()
        .zip(b)
        .zip(theta)
        .map(|((x, y), t)| ((x / y - 1.0).abs(), *t))
        .fold((0.0, 0.0), |m, v| if v.0 > m.0 { v } else { m })
}

fn conv(ln_step: f64, x_step: f64, z_max: f64) -> SizeRule {
    SizeRule::Converged {
        ln_step,
        x_step,
        z_max,
    }
}

fn main() {
    let mut args = std::env::args().skip(1);
    let ds: Vec<f64> = args.next().map_or(vec![5.0, 8.0, 20.0], |s| {
        s.split(',').map(|v| v.parse().unwrap()).collect()
    });
    // Reference: steps divided by `refine`, one more σ of support, 4× the wavelengths.
    let refine: f64 = args.next().map_or(4.0, |s| s.parse().unwrap());
    let reference = (conv(2.5e-4 / refine, 0.01 / refine, 6.0), 241);
    let candidates = [
        ("product 41×31", SizeRule::Product { sizes: 41 }, 31),
        ("product 161×61", SizeRule::Product { sizes: 161 }, 61),
        (
            "h=2.5e-4, Δx=∞, L=61 (ln x only)",
            conv(2.5e-4, 1e9, 5.0),
            61,
        ),
        ("h=5e-4, Δx=0.02, L=61", conv(5e-4, 0.02, 5.0), 61),
        ("h=2.5e-4, Δx=0.01, L=31", conv(2.5e-4, 0.01, 5.0), 31),
        ("h=2.5e-4, Δx=0.01, L=61, z=4", conv(2.5e-4, 0.01, 4.0), 61),
        (
            "**h=2.5e-4, Δx=0.01, L=61 (default)**",
            conv(2.5e-4, 0.01, 5.0),
            61,
        ),
        ("h=1.25e-4, Δx=0.005, L=121", conv(1.25e-4, 0.005, 5.0), 121),
    ];
    println!(
        "Reference: h = {:.3e}, Δx = {:.4}, z = 6, L = 241\n",
        2.5e-4 / refine,
        0.01 / refine
    );
    println!(
        "| d (µm) | rule | max rel. diff of p(θ) | at θ (°) | max rel. diff, θ < 30° | seconds |"
    );
    println!("|---|---|---|---|---|---|");
    for d in ds {
        let t0 = std::time::Instant::now();
        let (r, _) = MieJob::paper(d, reference.0, reference.1)
            .compute(&|_, _| {})
            .unwrap();
        eprintln!("reference d = {d}: {:.1} s", t0.elapsed().as_secs_f64());
        let theta = &r[0].theta_deg;
        for (name, rule, nl) in candidates {
            let t0 = std::time::Instant::now();
            let (c, _) = MieJob::paper(d, rule, nl).compute(&|_, _| {}).unwrap();
            let s = t0.elapsed().as_secs_f64();
            let (w, at) = worst(&c[0].phase, &r[0].phase, theta);
            let n30 = theta.iter().position(|&t| t >= 30.0).unwrap();
            let (wf, _) = worst(&c[0].phase[..n30], &r[0].phase[..n30], &theta[..n30]);
            println!("| {d} | {name} | {w:.2e} | {at:.2} | {wf:.2e} | {s:.2} |");
        }
    }
}
