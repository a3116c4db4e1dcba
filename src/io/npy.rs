//! Single arrays as NumPy .npy files: the bytes of one to write (atomically, by the caller's
//! [`super::AtomicFiles`]) and one read back with its shape checked.

use anyhow::{ensure, Context, Result};
use npyz::WriterBuilder;
use std::path::Path;

/// A C-order .npy of `shape` holding `data` (float32, float64, uint8, … by `T`).
pub fn npy_bytes<T: npyz::AutoSerialize + Copy>(shape: &[u64], data: &[T]) -> Result<Vec<u8>> {
    let mut bytes = Vec::new();
    {
        let mut w = npyz::WriteOptions::<T>::new()
            .default_dtype()
            .shape(shape)
            .writer(&mut bytes)
            .begin_nd()?;
        w.extend(data.iter().copied())?;
        w.finish()?;
    }
    Ok(bytes)
}

/// The values of a .npy of exactly `shape`, read as `T`.
pub fn read_npy<T: npyz::Deserialize>(path: &Path, shape: &[u64]) -> Result<Vec<T>> {
    let what = || format!("'{}'", path.display());
    let file = std::fs::File::open(path).with_context(|| format!("cannot read {}", what()))?;
    let npy = npyz::NpyFile::new(std::io::BufReader::new(file)).with_context(what)?;
    ensure!(
        npy.shape() == shape,
        "{}: shape {:?}, expected {:?}",
        what(),
        npy.shape(),
        shape
    );
    npy.into_vec::<T>().with_context(what)
}

/// The rows of a C-order 2-D .npy of float32 or float64 values with `columns` columns (read
/// as f64), and their count; `names` describes the columns in the error messages.
pub fn read_rows(path: &Path, columns: usize, names: &str) -> Result<(Vec<f64>, usize)> {
    let what = || format!("'{}'", path.display());
    let file = std::fs::File::open(path).with_context(|| format!("cannot read {}", what()))?;
    let npy = npyz::NpyFile::new(std::io::BufReader::new(file)).with_context(what)?;
    let shape = npy.shape().to_vec();
    ensure!(
        shape.len() == 2 && shape[1] == columns as u64,
        "{}: shape {shape:?}, expected (N, {columns}) with columns {names}",
        what()
    );
    ensure!(
        npy.order() != npyz::Order::Fortran,
        "{}: Fortran order; save a C-order array (numpy.ascontiguousarray)",
        what()
    );
    let dtype = npy.dtype();
    let values = match dtype.descr().trim_matches('\'') {
        "<f8" => npy.into_vec::<f64>()?,
        "<f4" => npy.into_vec::<f32>()?.into_iter().map(f64::from).collect(),
        other => anyhow::bail!("{}: dtype {other}, expected float32 or float64", what()),
    };
    Ok((values, shape[0] as usize))
}
