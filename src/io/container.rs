//! Writes the binary container of the transport tables (`.ntt`), the format that
//! [`nephele_runtime::container`] reads (layout there and in docs/format.md).

use anyhow::{bail, Result};
use nephele_runtime::container::FORMAT_VERSION;
use nephele_runtime::fitting::{crc32, ENTRY_BYTES, HEADER_BYTES, MAGIC, MAX_ARRAYS, NAME_BYTES};
use std::path::Path;

/// One array to store: a name (1–16 ASCII bytes, no NUL), its dimensions (1 to 4, none 0) and
/// its values in row-major order.
pub struct Array<'a> {
    /// Name, unique in the container.
    pub name: &'a str,
    /// Dimensions.
    pub dims: &'a [usize],
    /// Π dims values, row-major.
    pub values: &'a [f32],
}

/// The bytes of a container holding `arrays`, in this order.
pub fn container_bytes(arrays: &[Array]) -> Result<Vec<u8>> {
    if arrays.len() > MAX_ARRAYS {
        bail!(
            "{} arrays: a container holds at most {MAX_ARRAYS}",
            arrays.len()
        );
    }
    let mut data_at = HEADER_BYTES + arrays.len() * ENTRY_BYTES;
    let mut out = Vec::with_capacity(data_at);
    out.extend_from_slice(&MAGIC);
    out.extend_from_slice(&FORMAT_VERSION.to_le_bytes());
    out.extend_from_slice(&(arrays.len() as u32).to_le_bytes());
    for (i, a) in arrays.iter().enumerate() {
        check_array(a)?;
        if arrays[..i].iter().any(|b| b.name == a.name) {
            bail!("array name '{}' appears twice", a.name);
        }
        let mut name = [0u8; NAME_BYTES];
        name[..a.name.len()].copy_from_slice(a.name.as_bytes());
        out.extend_from_slice(&name);
        out.extend_from_slice(&(a.dims.len() as u32).to_le_bytes());
        for k in 0..4 {
            out.extend_from_slice(&(*a.dims.get(k).unwrap_or(&1) as u32).to_le_bytes());
        }
        let offset = u32::try_from(data_at).map_err(|_| anyhow::anyhow!("container over 4 GiB"))?;
        out.extend_from_slice(&offset.to_le_bytes());
        out.extend_from_slice(&[0u8; 8]);
        data_at += 4 * a.values.len();
    }
    for a in arrays {
        for v in a.values {
            out.extend_from_slice(&v.to_le_bytes());
        }
    }
    if out.len() > u32::MAX as usize {
        bail!("container over 4 GiB");
    }
    let crc = crc32(&out);
    out.extend_from_slice(&crc.to_le_bytes());
    Ok(out)
}

fn check_array(a: &Array) -> Result<()> {
    let n = a.name;
    if n.is_empty() || n.len() > NAME_BYTES || !n.is_ascii() || n.contains('\0') {
        bail!("array name '{n}': 1 to {NAME_BYTES} ASCII bytes without NUL");
    }
    if a.dims.is_empty()
        || a.dims.len() > 4
        || a.dims.iter().any(|&d| d == 0 || d > u32::MAX as usize)
    {
        bail!("array '{n}': 1 to 4 dimensions, none 0 ({:?})", a.dims);
    }
    let count: usize = a.dims.iter().product();
    if count != a.values.len() {
        bail!(
            "array '{n}': dimensions {:?} hold {count} values, got {}",
            a.dims,
            a.values.len()
        );
    }
    Ok(())
}

/// Writes a container to `path` atomically.
pub fn write_container(path: &Path, arrays: &[Array]) -> Result<()> {
    let bytes = container_bytes(arrays)?;
    super::write_atomic(path, |w| {
        std::io::Write::write_all(w, &bytes)?;
        Ok(())
    })
}
