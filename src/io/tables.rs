//! Transport tables as commands and renderers load them: a `.ntt` file, a folder holding
//! `transport.ntt` (as `nephele tables` and `nephele compress` write it), or the embedded
//! Mie 10 µm tables.

use anyhow::{Context, Result};
use nephele_runtime::transport::TransportTables;
use std::path::Path;

/// `f` on transport tables: the file's (or a folder's transport.ntt, as `nephele tables` and
/// `nephele compress` write it), or the embedded Mie 10 µm ones; a file that is not tables is
/// named in the error.
pub fn with_tables<R>(
    path: Option<&Path>,
    f: impl FnOnce(&TransportTables) -> Result<R>,
) -> Result<R> {
    let in_dir = path.filter(|p| p.is_dir()).map(|p| p.join("transport.ntt"));
    let path = in_dir.as_deref().or(path);
    let bytes: std::borrow::Cow<'static, [u8]> = match path {
        Some(p) => std::fs::read(p)
            .with_context(|| format!("cannot read tables '{}'", p.display()))?
            .into(),
        None => nephele_runtime::embedded::MIE_10UM.into(),
    };
    let tables = TransportTables::from_bytes(&bytes).map_err(|e| {
        let name = path.map_or("(embedded)".into(), |p| format!("'{}'", p.display()));
        anyhow::anyhow!("transport tables {name}: {e}")
    })?;
    f(&tables)
}

/// The Mie droplet diameter (µm) the tables at `path` were made for: 10 for the embedded ones;
/// for a file or folder, the slab phase `{"kind": "mie", "diameter_um": D}` its manifest.json
/// (beside transport.ntt, as `nephele compress` writes it) names; none when there is no
/// manifest or it names another phase function.
pub fn mie_diameter(path: Option<&Path>) -> Option<f64> {
    let Some(path) = path else {
        return Some(EMBEDDED_DIAMETER_UM);
    };
    let dir = if path.is_dir() { path } else { path.parent()? };
    let text = std::fs::read_to_string(dir.join("manifest.json")).ok()?;
    let manifest: serde_json::Value = serde_json::from_str(&text).ok()?;
    mie_phase_in(&manifest)
}

/// The embedded tables' droplet diameter (µm).
pub const EMBEDDED_DIAMETER_UM: f64 = 10.0;

/// The first `"phase": {"kind": "mie", "diameter_um": D}` anywhere in `v`: D.
fn mie_phase_in(v: &serde_json::Value) -> Option<f64> {
    match v {
        serde_json::Value::Object(m) => {
            let here = m.get("phase").filter(|p| p["kind"] == "mie");
            here.and_then(|p| p["diameter_um"].as_f64())
                .or_else(|| m.values().find_map(mie_phase_in))
        }
        serde_json::Value::Array(a) => a.iter().find_map(mie_phase_in),
        _ => None,
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The shipped tables' manifest names the droplets the embedded tables are for.
    #[test]
    fn the_shipped_manifest_names_the_embedded_diameter() {
        let shipped = concat!(
            env!("CARGO_MANIFEST_DIR"),
            "/runtime/tables/mie10um/transport.ntt"
        );
        assert_eq!(
            mie_diameter(Some(Path::new(shipped))),
            Some(EMBEDDED_DIAMETER_UM)
        );
        assert_eq!(mie_diameter(None), Some(EMBEDDED_DIAMETER_UM));
        assert_eq!(mie_diameter(Some(Path::new("/nonexistent/t.ntt"))), None);
    }
}
