//! `nephele export-gpu`: transport tables laid out for the GPU — the storage buffer and the
//! index uniform the WGSL port reads, as little-endian files, with the WGSL source bound to the
//! caller's group and bindings and a JSON of the layout — so that an engine in any language
//! (C++ with Dawn or Vulkan, JavaScript with WebGPU) can upload them.

use anyhow::{Context, Result};
use clap::Args;
use nephele::io::AtomicFiles;
use std::path::{Path, PathBuf};

/// Options of `nephele export-gpu`.
#[derive(Args, Debug)]
pub struct ExportGpuArgs {
    /// transport.ntt of `nephele compress` [default: the embedded Mie 10 µm tables].
    #[arg(long, value_name = "FILE")]
    pub tables: Option<PathBuf>,
    /// Directory to write tables.bin, index.bin, nephele_tables.wgsl and layout.json into.
    #[arg(long, value_name = "DIR")]
    pub out: PathBuf,
    /// The bind group the shader declares the two bindings in.
    #[arg(long, default_value_t = 0)]
    pub group: u32,
    /// The storage buffer's binding; the index uniform takes the next one.
    #[arg(long, default_value_t = 0)]
    pub binding: u32,
}

/// Runs `nephele export-gpu`.
pub fn run(a: ExportGpuArgs) -> Result<()> {
    nephele::io::check_output_dir(&a.out)?;
    let (bytes, name) = match &a.tables {
        Some(p) => (
            std::fs::read(p).with_context(|| format!("cannot read tables '{}'", p.display()))?,
            format!("'{}'", p.display()),
        ),
        None => (
            nephele_runtime::embedded::MIE_10UM.to_vec(),
            "(embedded)".into(),
        ),
    };
    let gpu = nephele_wgsl::ntt_for_gpu(&bytes).map_err(|e| anyhow::anyhow!("{name}: {e}"))?;
    anyhow::ensure!(
        a.binding < u32::MAX,
        "--binding {}: the index uniform takes the next binding",
        a.binding
    );
    let le = |words: &[u32]| {
        words
            .iter()
            .flat_map(|w| w.to_le_bytes())
            .collect::<Vec<u8>>()
    };
    let (storage, index) = (le(&gpu.words), le(&gpu.index));
    let layout = serde_json::json!({
        "what": "nephele's transport tables for the WGSL port (docs/integration.md, 'On the GPU: WGSL'): upload tables.bin as a read-only storage buffer and index.bin as a uniform buffer, bind them at the group and bindings below, and add nephele_tables.wgsl (the phase models and the tables, a whole module; nephele_wgsl::tables_module(group, binding)) before the shader's own code",
        "tables": name,
        "format_version": nephele_runtime::container::FORMAT_VERSION,
        "byte_order": "little-endian u32 words (the f32 bits of the tables' arrays, then u32 offsets)",
        "group": a.group,
        "bindings": [
            {
                "binding": a.binding,
                "wgsl": "var<storage, read> nephele_ntt: array<u32>",
                "file": "tables.bin",
                "bytes": storage.len(),
                "usage": "STORAGE | COPY_DST",
                "buffer_binding_type": "read-only storage",
                "min_binding_size": storage.len(),
                "visibility": "COMPUTE | FRAGMENT",
            },
            {
                "binding": a.binding + 1,
                "wgsl": "var<uniform> nephele_ntt_index: NepheleNttIndex",
                "file": "index.bin",
                "bytes": index.len(),
                "usage": "UNIFORM | COPY_DST",
                "buffer_binding_type": "uniform",
                "min_binding_size": index.len(),
                "visibility": "COMPUTE | FRAGMENT",
            },
        ],
        "shader": "nephele_tables.wgsl",
    });
    let shader = nephele_wgsl::tables_module(a.group, a.binding);
    write(
        &a.out,
        &[
            ("tables.bin", storage),
            ("index.bin", index),
            ("nephele_tables.wgsl", shader.into_bytes()),
            ("layout.json", serde_json::to_vec_pretty(&layout)?),
        ],
    )?;
    outln!(
        "wrote {}/tables.bin ({} words), index.bin ({} words), nephele_tables.wgsl and layout.json \
         (group {}, bindings {} and {})",
        a.out.display(),
        gpu.words.len(),
        gpu.index.len(),
        a.group,
        a.binding,
        a.binding + 1
    );
    Ok(())
}

/// The files into `dir` (created), all or none.
fn write(dir: &Path, files: &[(&str, Vec<u8>)]) -> Result<()> {
    std::fs::create_dir_all(dir).with_context(|| format!("cannot create '{}'", dir.display()))?;
    let mut out = AtomicFiles::new();
    for (name, bytes) in files {
        out.write_bytes(&dir.join(name), bytes)?;
    }
    out.commit()
}
