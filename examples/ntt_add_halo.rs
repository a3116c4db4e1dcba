//! Adds the halo around the transmitted beam (docs/compress.md "The halo
//! term") to transport tables that have none, from a slab run that tallied the aureole: h =
//! ln(T_annulus / T̄_form) against the file's own form, every other array byte for byte. This is
//! how the shipped tables got theirs without refitting their form. Prints the near-beam check
//! (the form alone, then with the halo) as JSON.
//!
//!     cargo run --release --example ntt_add_halo -- RUN/tables.npz OLD.ntt NEW.ntt

use anyhow::{anyhow, ensure, Context, Result};
use nephele::compress::near_beam::{halo_table, near_beam_check};
use nephele::compress::ship::with_halo;
use nephele::slab::SlabTables;
use nephele_runtime::transport::TransportTables;
use std::path::Path;

fn main() -> Result<()> {
    let args: Vec<String> = std::env::args().skip(1).collect();
    ensure!(
        args.len() == 3,
        "usage: ntt_add_halo RUN/tables.npz OLD.ntt NEW.ntt"
    );
    let tab = SlabTables::load(Path::new(&args[0]))?;
    let aureole = tab.aureole.as_ref().ok_or_else(|| {
        anyhow!(
            "{}: the run tallied no aureole (config key aureole_deg)",
            args[0]
        )
    })?;
    let bytes = std::fs::read(&args[1]).with_context(|| format!("reading {}", args[1]))?;
    let form = TransportTables::from_bytes(&bytes).map_err(|e| anyhow!("{}: {e}", args[1]))?;
    ensure!(
        form.groups() + 1 == tab.shape[0],
        "the tables have {} groups of orders ≥ 2, the run {}",
        form.groups(),
        tab.shape[0] - 1
    );
    let out = with_halo(&bytes, &halo_table(&tab, aureole, &form))?;
    let halo = TransportTables::from_bytes(&out).map_err(|e| anyhow!("{e}"))?;
    let report = serde_json::json!({
        "form": near_beam_check(&tab, &form),
        "with_halo": near_beam_check(&tab, &halo),
    });
    nephele::io::atomic::write_atomic(Path::new(&args[2]), |w| {
        std::io::Write::write_all(w, &out)?;
        Ok(())
    })?;
    println!("{}", serde_json::to_string_pretty(&report)?);
    eprintln!(
        "{} → {} ({} bytes, with the halo)",
        args[1],
        args[2],
        out.len()
    );
    Ok(())
}
