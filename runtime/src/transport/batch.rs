//! Many points at once: what a Python pipeline or a shell user evaluates (the Python module,
//! `nephele transport --points in.npy`), one row per point in and one row per point out, so
//! that nobody pays a process or a call per point. With the `parallel` feature the rows are
//! shared among rayon's threads; each row is evaluated alone, so the answers are the same bit
//! for bit whatever the thread count.

use super::{PointError, SlabPoint, Transport, TransportTables};

/// Values per point in: t (mfp), μ_L, depth d (mfp), μ_V, ψ_V (radians): a [`SlabPoint`].
pub const POINT_COLUMNS: usize = 5;

/// Which quantities a batch evaluates.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Quantities {
    /// Order 1, then T of every group: 1 + G columns.
    Transport,
    /// Order 1, then T, c_x, c_z and σ of every group: 1 + 4G columns.
    WithCollector,
}

impl Quantities {
    /// Values per point out for tables of `groups` groups.
    pub const fn columns(self, groups: usize) -> usize {
        match self {
            Quantities::Transport => 1 + groups,
            Quantities::WithCollector => 1 + 4 * groups,
        }
    }
}

/// The names of the columns [`evaluate_points`] writes for `tables`: "order1", then per group
/// "T_2", "T_3-4", …, "T_31+" (the group's orders), with [`Quantities::WithCollector`] each
/// followed by "c_x_…", "c_z_…", "sigma_…".
#[cfg(feature = "std")]
pub fn column_names(
    tables: &TransportTables,
    what: Quantities,
) -> std::vec::Vec<std::string::String> {
    use std::format;
    let mut names = std::vec!["order1".into()];
    for g in 0..tables.groups() {
        let first = tables.group_first_order(g).unwrap_or(0.0);
        let orders = match tables.group_first_order(g + 1) {
            Some(next) if next - 1.0 > first => format!("{first}-{}", next - 1.0),
            Some(_) => format!("{first}"),
            None => format!("{first}+"),
        };
        let parts: &[&str] = match what {
            Quantities::Transport => &["T"],
            Quantities::WithCollector => &["T", "c_x", "c_z", "sigma"],
        };
        names.extend(parts.iter().map(|p| format!("{p}_{orders}")));
    }
    names
}

/// Why a batch was refused.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum BatchError {
    /// A row is not a point of the slab ([`SlabPoint::check`]): the first such row.
    BadPoint { row: usize, error: PointError },
    /// The points are not whole rows of [`POINT_COLUMNS`] values: their length.
    PointsNotRows(usize),
    /// The output does not hold one row per point: its length and the length needed.
    OutputSize { got: usize, need: usize },
}

impl core::fmt::Display for BatchError {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        match self {
            BatchError::BadPoint { row, error } => write!(f, "row {row}: {error}"),
            BatchError::PointsNotRows(n) => write!(
                f,
                "{n} point values are not whole rows of {POINT_COLUMNS} (t, mu_L, depth, mu_V, psi_V)"
            ),
            BatchError::OutputSize { got, need } => {
                write!(f, "the output holds {got} values, the points need {need}")
            }
        }
    }
}

impl SlabPoint<f32> {
    /// The point of one input row (t, μ_L, d, μ_V, ψ_V).
    pub fn from_row(r: &[f32; POINT_COLUMNS]) -> Self {
        SlabPoint {
            thickness: r[0],
            mu_l: r[1],
            depth: r[2],
            mu_v: r[3],
            psi_v: r[4],
        }
    }
}

/// Evaluates `tables` at every row of `points` (row-major, [`POINT_COLUMNS`] per row) into
/// `out` (row-major, `what.columns(groups)` per row). Every row is checked first
/// ([`SlabPoint::check`]): a point outside the slab (d ∉ [0, t], t ≤ 0, μ_L ∉ (0, 1],
/// |μ_V| > 1, NaN, ±∞) refuses the batch, naming the first such row, and `out` is untouched.
/// Returns the rows.
pub fn evaluate_points(
    tables: &TransportTables,
    points: &[f32],
    what: Quantities,
    out: &mut [f32],
) -> Result<usize, BatchError> {
    if points.len() % POINT_COLUMNS != 0 {
        return Err(BatchError::PointsNotRows(points.len()));
    }
    let rows = points.len() / POINT_COLUMNS;
    let width = what.columns(tables.groups());
    if out.len() != rows * width {
        return Err(BatchError::OutputSize {
            got: out.len(),
            need: rows * width,
        });
    }
    for (row, p) in points.chunks_exact(POINT_COLUMNS).enumerate() {
        SlabPoint::from_row(&[p[0], p[1], p[2], p[3], p[4]])
            .check()
            .map_err(|error| BatchError::BadPoint { row, error })?;
    }
    let one = |p: &[f32], o: &mut [f32]| {
        let mut row = [0.0; POINT_COLUMNS];
        row.copy_from_slice(p);
        evaluate_row(tables, &SlabPoint::from_row(&row), what, o);
    };
    #[cfg(feature = "parallel")]
    {
        use rayon::prelude::*;
        points
            .par_chunks(POINT_COLUMNS)
            .zip(out.par_chunks_mut(width))
            .with_min_len(256)
            .for_each(|(p, o)| one(p, o));
    }
    #[cfg(not(feature = "parallel"))]
    points
        .chunks(POINT_COLUMNS)
        .zip(out.chunks_mut(width))
        .for_each(|(p, o)| one(p, o));
    Ok(rows)
}

/// One row out.
fn evaluate_row(tables: &TransportTables, at: &SlabPoint<f32>, what: Quantities, o: &mut [f32]) {
    const MOST: usize = crate::transport::format::MAX_GROUPS;
    o[0] = tables.order1(at);
    let groups = tables.groups().min(MOST);
    match what {
        Quantities::Transport => tables.transport_all(at, &mut o[1..1 + groups]),
        Quantities::WithCollector => {
            let mut all = [Transport::default(); MOST];
            tables.evaluate_all(at, &mut all[..groups]);
            for (v, slot) in all[..groups].iter().zip(o[1..].chunks_exact_mut(4)) {
                slot.copy_from_slice(&[v.t, v.c_x, v.c_z, v.sigma]);
            }
        }
    }
}
