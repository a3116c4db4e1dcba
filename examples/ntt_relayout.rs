//! Rewrites transport tables in another layout version (docs/format.md): version 2, the
//! current, stores β feature-major; version 1 group-major. Older files load as they are, only
//! the all-groups evaluation is faster on version 2.
//!
//!     cargo run --release --example ntt_relayout -- OLD.ntt NEW.ntt [VERSION]

use anyhow::{Context, Result};

fn main() -> Result<()> {
    let args: Vec<String> = std::env::args().skip(1).collect();
    anyhow::ensure!(
        (2..=3).contains(&args.len()),
        "usage: ntt_relayout OLD.ntt NEW.ntt [VERSION]"
    );
    let version = match args.get(2) {
        Some(v) => v.parse().context("VERSION must be a whole number")?,
        None => nephele_runtime::container::FORMAT_VERSION,
    };
    let bytes = std::fs::read(&args[0]).with_context(|| format!("reading {}", args[0]))?;
    let out = nephele::compress::ship::relayout(&bytes, version)?;
    nephele::io::atomic::write_atomic(std::path::Path::new(&args[1]), |w| {
        std::io::Write::write_all(w, &out)?;
        Ok(())
    })?;
    println!("{} → {} (version {version})", args[0], args[1]);
    Ok(())
}
