//! Outputs: every file is written to a temporary name beside its target and renamed into
//! place, so a failed or interrupted run never leaves a partial file behind; and numbers as
//! messages show them (`text`).

pub mod atomic;
pub mod container;
pub mod npy;
pub mod npz;
pub mod plot;
pub mod tables;
pub mod text;

/// Bytes of memory available to a new allocation (Linux's MemAvailable), if known.
pub fn available_memory() -> Option<f64> {
    let info = std::fs::read_to_string("/proc/meminfo").ok()?;
    let line = info.lines().find(|l| l.starts_with("MemAvailable:"))?;
    let kb: f64 = line.split_whitespace().nth(1)?.parse().ok()?;
    Some(kb * 1024.0)
}

pub use atomic::{
    check_output_dir, check_output_file, output_dir, write_atomic, AtomicFiles, FolderLock,
};
pub use npz::Npz;
