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
