//! NumPy `.npz` archives of float64 arrays (readable by `numpy.load`).

use anyhow::{Context, Result};
use npyz::WriterBuilder;
use std::io::{Seek, Write};
use std::path::Path;

/// The named float64 arrays of an `.npz` file, flattened (errors name the file and the array).
pub fn read_arrays(path: &Path, names: &[&str]) -> Result<Vec<Vec<f64>>> {
    let mut npz = open(path)?;
    names
        .iter()
        .map(|name| {
            let arr = npz
                .by_name(name)?
                .with_context(|| format!("'{}' has no array '{name}'", path.display()))?;
            Ok(arr.into_vec::<f64>()?)
        })
        .collect()
}

/// An `.npz` archive, refused with what it is instead when it is not one (a zip's first bytes
/// are `PK`): "invalid Zip archive" does not tell a user they passed the JSON sidecar.
fn open(path: &Path) -> Result<npyz::npz::NpzArchive<std::io::BufReader<std::fs::File>>> {
    let mut head = [0u8; 2];
    let file =
        std::fs::File::open(path).with_context(|| format!("cannot open '{}'", path.display()))?;
    let is_zip = std::io::Read::read_exact(&mut &file, &mut head).is_ok() && head == *b"PK";
    anyhow::ensure!(
        is_zip,
        "'{}' is not an .npz archive (NumPy's zip of arrays); pass the .npz, not its .json or .csv",
        path.display()
    );
    npyz::npz::NpzArchive::open(path).with_context(|| format!("cannot open '{}'", path.display()))
}

/// The named float64 array of an `.npz` file, flattened, or None where the file has no such
/// array (an optional part of a format).
pub fn read_optional(path: &Path, name: &str) -> Result<Option<Vec<f64>>> {
    let mut npz = open(path)?;
    let context = || format!("'{}': array '{name}'", path.display());
    let values = match npz.by_name(name).with_context(context)? {
        Some(arr) => Some(arr.into_vec::<f64>().with_context(context)?),
        None => None,
    };
    Ok(values)
}

/// Named float64 arrays with their shapes, written in insertion order.
#[derive(Default)]
pub struct Npz {
    arrays: Vec<(String, Vec<u64>, Vec<f64>)>,
}

impl Npz {
    /// Starts an empty archive.
    pub fn new() -> Self {
        Self::default()
    }

    /// Adds an array of the given shape (row-major; the product of `shape` = `data.len()`).
    pub fn add(&mut self, name: &str, shape: &[usize], data: &[f64]) -> &mut Self {
        assert_eq!(
            shape.iter().product::<usize>(),
            data.len(),
            "shape of array '{name}'"
        );
        self.arrays.push((
            name.into(),
            shape.iter().map(|&s| s as u64).collect(),
            data.to_vec(),
        ));
        self
    }

    /// Writes the archive (uncompressed, like `numpy.savez`).
    pub fn write_to<W: Write + Seek>(&self, w: W) -> Result<()> {
        let mut npz = npyz::npz::NpzWriter::new(w);
        // A fixed time stamp (1980-01-01, zip's epoch): the same arrays give the same bytes.
        let opts = zip::write::FileOptions::default()
            .compression_method(zip::CompressionMethod::Stored)
            .last_modified_time(zip::DateTime::default());
        for (name, shape, data) in &self.arrays {
            let mut arr = npz
                .array::<f64>(name, opts)?
                .default_dtype()
                .shape(shape)
                .begin_nd()?;
            arr.extend(data.iter().copied())?;
            arr.finish()?;
        }
        npz.zip_writer().finish()?;
        Ok(())
    }
}
