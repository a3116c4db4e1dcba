//! `nephele compare`: candidate renders against a path-traced reference, per order group.

use anyhow::Result;
use clap::Args;
use nephele::render::compare::{compare, Report};
use std::path::PathBuf;

/// Options of `nephele compare`.
#[derive(Args, Debug)]
pub struct CompareArgs {
    /// The reference: a directory `nephele render` wrote (the path tracer's, with halves.npy
    /// for its noise).
    #[arg(long, value_name = "DIR")]
    pub reference: PathBuf,
    /// A candidate render directory (repeat for several: collector, octaves, single …).
    #[arg(long, value_name = "DIR", required = true)]
    pub candidate: Vec<PathBuf>,
    /// Output directory: report.json, reference.png, candidate<k>.png, panel.png, errors.png.
    #[arg(long, value_name = "DIR", default_value = "outputs/compare")]
    pub out: PathBuf,
}

/// Runs `nephele compare`.
pub fn run(args: CompareArgs) -> Result<()> {
    let report = compare(&args.reference, &args.candidate, &args.out)?;
    print_table(&report);
    println!(
        "wrote {}/report.json, panel.png, errors.png, reference.png, candidate*.png (mean FLIP: \
         scripts/compare_flip.py {})",
        args.out.display(),
        args.out.display()
    );
    Ok(())
}

/// The table on stdout: per candidate and quantity, over the opaque pixels, then the regions
/// of orders ≥ 2.
pub fn print_table(report: &Report) {
    println!(
        "reference {} ({}, {} spp, {:.0} s)",
        report.reference, report.reference_method, report.reference_spp, report.reference_seconds
    );
    for c in &report.candidates {
        println!(
            "\n{} ({}): {:.3} s a frame, beauty PSNR {:.1} dB",
            c.dir, c.method, c.seconds, c.psnr_db
        );
        println!(
            "  {:<14} {:>8} {:>8} {:>9} {:>8} {:>15}",
            "opaque pixels", "bias", "(noise)", "rel RMSE", "(noise)", "corrected"
        );
        let row = |name: &str, s: &nephele::render::compare::Stats| {
            println!(
                "  {:<14} {:>+7.1}% {:>7.1}% {:>8.1}% {:>7.1}% {:>7.1}% ± {:.1}",
                name,
                100.0 * s.bias,
                100.0 * s.bias_noise,
                100.0 * s.rel_rmse,
                100.0 * s.reference_noise,
                100.0 * s.rel_rmse_corrected,
                100.0 * s.rel_rmse_corrected_se
            )
        };
        for q in &c.quantities {
            if let Some(s) = q.regions.get("opaque") {
                row(&q.quantity, s);
            }
        }
        if let Some(q) = c.quantities.iter().find(|q| q.quantity == "orders >= 2") {
            for region in ["lit", "shadowed", "silhouette"] {
                if let Some(s) = q.regions.get(region) {
                    row(&format!(">=2 {region} ({})", s.pixels), s);
                }
            }
        }
    }
}
