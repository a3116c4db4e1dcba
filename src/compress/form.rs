//! The compressed form is the runtime's ([`nephele_runtime::fitting::log_additive`], module
//! docs there have the equation): the toolchain fits it with the very features renderers
//! evaluate. This module adapts it to the fitter's sparse rows.

pub use nephele_runtime::fitting::{
    ln_boundary, Cell as RuntimeCell, Lerp as RuntimeLerp, LogAdditive,
};

/// A cell of the tables as the form sees it (f64).
pub type Cell = RuntimeCell<f64>;
/// A position between parameter nodes (f64).
pub type Lerp = RuntimeLerp<f64>;

/// The features of `c` as (column, value) pairs into `row` (cleared first); false where the
/// form cannot represent the cell.
pub fn features(
    form: &LogAdditive,
    c: &Cell,
    nm: usize,
    nl: usize,
    row: &mut Vec<(usize, f64)>,
) -> bool {
    row.clear();
    form.for_each_feature(c, nm, nl, |col, v| row.push((col, v)))
}

/// The form as JSON, for reports.
pub fn to_json(form: &LogAdditive) -> serde_json::Value {
    serde_json::json!({
        "kind": "log_additive",
        "legendre": form.legendre,
        "harmonics": form.harmonics,
        "theta_nodes": form.theta_nodes,
        "pairs": form.pairs,
        "cross": form.cross,
    })
}
