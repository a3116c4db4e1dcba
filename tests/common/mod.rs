//! Shared helpers of the integration tests.
#![allow(dead_code)]

pub mod cli;

use std::path::PathBuf;

/// `tests/data/<name>` (published reference values, sources in tests/data/README.md) read as JSON.
pub fn reference(name: &str) -> serde_json::Value {
    let path = PathBuf::from(env!("CARGO_MANIFEST_DIR"))
        .join("tests/data")
        .join(name);
    let text = std::fs::read_to_string(&path)
        .unwrap_or_else(|e| panic!("reference file {}: {e}", path.display()));
    serde_json::from_str(&text).expect("reference JSON")
}

/// An f32 `.npy` file's values, in order.
pub fn npy_f32(path: &std::path::Path) -> Vec<f32> {
    let bytes = std::fs::read(path).unwrap_or_else(|e| panic!("{}: {e}", path.display()));
    let npy = npyz::NpyFile::new(&bytes[..]).expect("an .npy file");
    npy.into_vec().expect("f32 values")
}

/// Half a unit in the last decimal place printed for `v` (the digits a table gives).
pub fn half_ulp_of_print(v: f64) -> f64 {
    let s = format!("{v}");
    let decimals = s.split('.').nth(1).map_or(0, |f| f.len());
    0.5 * 10f64.powi(-(decimals as i32))
}
