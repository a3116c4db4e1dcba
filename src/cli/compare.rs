//! `nephele compare`: candidate renders against a path-traced reference, per order group.

use anyhow::Result;
use clap::Args;
use nephele::render::compare::{compare_with, EqualQuality, Report, Stats, LEGEND};
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
    /// Exposure K of the images: 1 − e^{−K x} of the linear radiance x [default: the
    /// reference's, from its render.json]. The per-order rows of panel.png keep their own.
    #[arg(long, value_name = "K", value_parser = nephele::render::output::parse_exposure)]
    pub exposure: Option<f32>,
}

/// Runs `nephele compare`.
pub fn run(args: CompareArgs) -> Result<()> {
    nephele::io::check_output_dir(&args.out)?;
    let report = compare_with(&args.reference, &args.candidate, &args.out, args.exposure)?;
    print_table(&report);
    outln!(
        "wrote {}/report.json, panel.png, errors.png, reference.png, candidate*.png (mean FLIP: \
         scripts/compare_flip.py {})",
        args.out.display(),
        args.out.display()
    );
    Ok(())
}

/// The table on stdout: a legend, then per candidate and quantity, over the opaque pixels,
/// then the regions of orders ≥ 2.
pub fn print_table(report: &Report) {
    outln!("{LEGEND}");
    outln!(
        "reference {} ({}, {} spp, {}); images at exposure {:.3}",
        report.reference,
        report.reference_method,
        report.reference_spp,
        super::seconds(report.reference_seconds),
        report.exposure
    );
    for c in &report.candidates {
        outln!(
            "\n{} ({}): {} a frame, beauty PSNR {:.1} dB",
            c.dir,
            c.method,
            super::seconds(c.seconds),
            c.psnr_db
        );
        outln!("  {}", worth(c.equal_quality.as_ref()));
        outln!(
            "  {:<22} {:>8} {:>8} {:>9} {:>8} {:>15}",
            "opaque pixels",
            "bias",
            "(noise)",
            "rel RMSE",
            "(noise)",
            "corrected"
        );
        let row = |name: &str, s: &Stats| {
            outln!(
                "  {:<22} {:>+7.1}% {:>7.1}% {:>8.1}% {:>7.1}% {:>7.1}% ± {:.1}",
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

/// The figure of merit in one line: the path tracer's time to match the beauty error, against
/// the frame.
pub fn worth(e: Option<&EqualQuality>) -> String {
    match e {
        Some(e) => format!(
            "worth {:.0}x its frame: the reference's method needs {} to reach its beauty error",
            e.speedup,
            super::seconds(e.path_seconds)
        ),
        None => "worth: not measurable (no reference noise or time, or the beauty error is \
            within the reference's noise)"
            .into(),
    }
}
