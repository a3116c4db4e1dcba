//! Outputs: every file is written to a temporary name beside its target and renamed into
//! place, so a failed or interrupted run never leaves a partial file behind; and numbers as
//! messages show them (`text`).

pub mod atomic;
pub mod container;
pub mod npy;
pub mod npz;
pub mod plot;
pub mod text;

pub use atomic::{output_dir, output_file, write_atomic, AtomicFiles, FolderLock};
pub use npz::Npz;
