//! A voxel grid's .npy: its header read first (the memory it needs is refused before anything
//! is allocated), then its densities, float32 or float64, and a one-pass summary of what the
//! grid means optically (its thickest column) for the scene's warnings.

use crate::io::text::{bytes, short};
use anyhow::{bail, ensure, Context, Result};
use std::path::Path;
use std::sync::Arc;

/// Bytes a grid takes per voxel once loaded: its f32 densities, plus the majorant grid (one
/// cell of two f64 per 4³ voxels).
const BYTES_PER_VOXEL: f64 = 4.0 + 16.0 / 64.0;

/// The densities of a voxel grid and its shape [nx, ny, nz].
#[derive(Clone)]
pub struct Grid {
    /// [nz, ny, nx], x fastest; shared by the scene and the media built from it.
    pub data: Arc<Vec<f32>>,
    /// Voxels along x, y, z.
    pub n: [usize; 3],
    /// [`column_sums`](Self::column_sums), taken once when the grid is made: the scene's
    /// warnings ask for them at every render and every view.
    pub thickest: [f64; 3],
}

/// Reads a rank-3 [nz, ny, nx] .npy of finite, non-negative densities, after checking that it
/// fits in `available` bytes (None: unknown, not checked).
pub fn read_grid(path: &Path, available: Option<f64>) -> Result<Grid> {
    let what = || format!("voxel grid '{}'", path.display());
    let file = std::fs::File::open(path).with_context(what)?;
    let npy = npyz::NpyFile::new(std::io::BufReader::new(file)).with_context(what)?;
    let shape = npy.shape().to_vec();
    ensure!(
        shape.len() == 3 && shape.iter().all(|&d| d > 0),
        "{}: shape {shape:?}, expected [nz, ny, nx]",
        what()
    );
    ensure!(
        !npy.order().eq(&npyz::Order::Fortran),
        "{}: Fortran order; save a C-order array",
        what()
    );
    let voxels = shape.iter().product::<u64>() as f64;
    let dtype = npy.dtype().descr().trim_matches('\'').to_string();
    let (f64_file, source) = match dtype.as_str() {
        "<f4" => (false, 0.0),
        "<f8" => (true, 8.0),
        other => bail!("{}: dtype {other}, expected float32 or float64", what()),
    };
    let need = voxels * (BYTES_PER_VOXEL + source);
    if let Some(available) = available {
        ensure!(
            need <= available,
            "{}: its {} voxels ({shape:?}) need about {} of memory, more than the {} available; \
             downsample the grid (numpy: grid[::2, ::2, ::2]) or free memory",
            what(),
            short(voxels),
            bytes(need),
            bytes(available)
        );
    }
    let data: Vec<f32> = if f64_file {
        let wide = npy.into_vec::<f64>().with_context(what)?;
        ensure!(
            wide.iter()
                .all(|v| v.abs() <= f32::MAX as f64 || !v.is_finite()),
            "{}: densities beyond float32's range",
            what()
        );
        wide.into_iter().map(|v| v as f32).collect()
    } else {
        npy.into_vec::<f32>().with_context(what)?
    };
    ensure!(
        data.iter().all(|v| v.is_finite() && *v >= 0.0),
        "{}: densities must be finite and non-negative",
        what()
    );
    let n = [shape[2] as usize, shape[1] as usize, shape[0] as usize];
    Ok(Grid::new(data, n))
}

impl std::fmt::Debug for Grid {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(f, "Grid({:?} voxels)", self.n)
    }
}

impl Grid {
    /// The grid of `data` ([nz, ny, nx], x fastest) with `n` voxels along x, y, z.
    pub fn new(data: Vec<f32>, n: [usize; 3]) -> Self {
        let mut grid = Self {
            data: Arc::new(data),
            n,
            thickest: [0.0; 3],
        };
        grid.thickest = grid.column_sums();
        grid
    }

    /// The largest density summed along a line of voxels, for each axis x, y, z: multiplied by
    /// a voxel's length (m) and σ_t (1/m), the optical depth of the grid's thickest column.
    pub fn column_sums(&self) -> [f64; 3] {
        let [nx, ny, _] = self.n;
        let (mut along_z, mut along_y) = (vec![0.0f64; nx * ny], vec![0.0f64; nx]);
        let mut best = [0.0f64; 3];
        for slice in self.data.chunks(nx * ny) {
            along_y.iter_mut().for_each(|s| *s = 0.0);
            for (y, row) in slice.chunks(nx).enumerate() {
                let mut along_x = 0.0f64;
                for (x, &v) in row.iter().enumerate() {
                    along_x += v as f64;
                    along_y[x] += v as f64;
                    along_z[y * nx + x] += v as f64;
                }
                best[0] = best[0].max(along_x);
            }
            best[1] = along_y.iter().copied().fold(best[1], f64::max);
        }
        best[2] = along_z.iter().copied().fold(0.0, f64::max);
        best
    }
}

/// The warnings a voxel grid earns, given its voxels' lengths (m) along x, y, z and σ_t (1/m):
/// a thickest column past `max_tau` mean free paths (densities far above 1, or σ_t per km
/// written per metre), and voxels so stretched that the axes were likely saved in the wrong
/// order ([x, y, z] instead of [z, y, x]).
pub fn grid_warnings(grid: &Grid, voxel_m: [f64; 3], sigma_t: f64, max_tau: f64) -> Vec<String> {
    let mut w = Vec::new();
    let sums = grid.thickest;
    let tau = (0..3)
        .map(|i| sums[i] * voxel_m[i] * sigma_t)
        .fold(0.0, f64::max);
    if tau > max_tau {
        w.push(format!(
            "the voxel grid's thickest column is {} mean free paths (densities × sigma_t = {} /m \
             × the voxels' length; real clouds: up to a few hundred): densities far above 1, or \
             sigma_t per km written per metre? The render will be slow and nearly black inside",
            short(tau),
            sigma_t
        ));
    }
    let (lo, hi) = voxel_m
        .iter()
        .fold((f64::MAX, 0.0f64), |(lo, hi), &v| (lo.min(v), hi.max(v)));
    if hi > STRETCH * lo {
        let [nx, ny, nz] = grid.n;
        w.push(format!(
            "the voxels are {} × {} × {} m (x × y × z) from the grid's shape [nz, ny, nx] = \
             [{nz}, {ny}, {nx}]: a grid saved as [x, y, z] gives such stretched voxels; numpy's \
             grid.transpose(2, 1, 0) reorders it",
            short(voxel_m[0]),
            short(voxel_m[1]),
            short(voxel_m[2])
        ));
    }
    w
}

/// Voxels longer than this many times their shortest side draw the axis-order warning.
const STRETCH: f64 = 3.0;

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn column_sums_follow_each_axis() {
        // [nz, ny, nx] = [2, 3, 4], value = 100 z + 10 y + x.
        let n = [4, 3, 2];
        let data = (0..24)
            .map(|i| (100 * (i / 12) + 10 * (i / 4 % 3) + i % 4) as f32)
            .collect();
        let s = Grid::new(data, n).thickest;
        // Along x: the row z = 1, y = 2 is 4 × 120 + 0 + 1 + 2 + 3.
        assert_eq!(s[0], 486.0);
        // Along y: z = 1, x = 3 is 3 × 103 + 0 + 10 + 20.
        assert_eq!(s[1], 339.0);
        // Along z: y = 2, x = 3 is 23 + 123.
        assert_eq!(s[2], 146.0);
    }

    fn saved(dir: &Path, name: &str, bytes: Vec<u8>) -> std::path::PathBuf {
        let p = dir.join(name);
        std::fs::write(&p, bytes).unwrap();
        p
    }

    #[test]
    fn float64_grids_read_as_float32_and_memory_is_checked_before_reading() {
        let dir = tempfile::tempdir().unwrap();
        let values: Vec<f64> = (0..24).map(|i| i as f64 / 7.0).collect();
        let narrow: Vec<f32> = values.iter().map(|&v| v as f32).collect();
        use crate::io::npy::npy_bytes as npy;
        let wide = saved(dir.path(), "wide.npy", npy(&[2, 3, 4], &values).unwrap());
        let f32s = saved(dir.path(), "narrow.npy", npy(&[2, 3, 4], &narrow).unwrap());
        let (a, b) = (
            read_grid(&wide, None).unwrap(),
            read_grid(&f32s, None).unwrap(),
        );
        assert_eq!((a.n, &*a.data), ([4, 3, 2], &narrow));
        assert_eq!((b.n, &*b.data), ([4, 3, 2], &narrow));
        // 24 voxels of a float64 file take 24 × 12.25 bytes while read.
        assert!(read_grid(&wide, Some(294.0)).is_ok());
        let err = read_grid(&wide, Some(293.0)).unwrap_err().to_string();
        assert!(
            err.contains("wide.npy") && err.contains("downsample"),
            "{err}"
        );
        let ints = saved(
            dir.path(),
            "ints.npy",
            npy(&[2, 3, 4], &[1i32; 24]).unwrap(),
        );
        let err = read_grid(&ints, None).unwrap_err().to_string();
        assert!(err.contains("expected float32 or float64"), "{err}");
    }

    #[test]
    fn thick_columns_and_stretched_voxels_are_warned() {
        let grid = Grid::new(vec![1.0; 4 * 4 * 4], [4, 4, 4]);
        // 4 voxels of 10 m at σ_t 0.05 /m: 2 mfp; of 10 km: 2000.
        assert!(grid_warnings(&grid, [10.0; 3], 0.05, 2000.0).is_empty());
        let w = grid_warnings(&grid, [1e4, 10.0, 10.0], 0.05, 1999.0);
        assert_eq!(w.len(), 2, "{w:?}");
        assert!(w[0].contains("2000 mean free paths"), "{}", w[0]);
        assert!(w[1].contains("transpose(2, 1, 0)"), "{}", w[1]);
        assert!(grid_warnings(&grid, [30.0, 10.0, 10.0], 0.05, 2000.0).is_empty());
    }
}
