//! Atomic file output: temp file in the target's directory, then rename.

use anyhow::{Context, Result};
use std::fs::File;
use std::io::{BufWriter, Write};
use std::path::{Path, PathBuf};

/// A set of files that appear together or not at all: each is written to a temporary name,
/// and [`AtomicFiles::commit`] renames them all into place once every write has succeeded.
/// Dropping the set without committing removes the temporaries.
#[derive(Default)]
pub struct AtomicFiles {
    pending: Vec<(PathBuf, PathBuf)>,
}

impl AtomicFiles {
    /// Starts an empty set.
    pub fn new() -> Self {
        Self::default()
    }

    /// Writes `path`'s content through `f` into a temporary file.
    pub fn write(
        &mut self,
        path: &Path,
        f: impl FnOnce(&mut BufWriter<File>) -> Result<()>,
    ) -> Result<()> {
        let tmp = self.temp_name(path)?;
        self.pending.push((tmp.clone(), path.to_path_buf()));
        let file =
            File::create(&tmp).with_context(|| format!("cannot create '{}'", tmp.display()))?;
        let mut w = BufWriter::new(file);
        f(&mut w).with_context(|| format!("while writing '{}'", path.display()))?;
        let file = w.into_inner().map_err(|e| e.into_error())?;
        file.sync_all()?;
        Ok(())
    }

    /// Lets `f` create the file itself at a temporary path (for writers that want a path).
    pub fn write_via_path(
        &mut self,
        path: &Path,
        f: impl FnOnce(&Path) -> Result<()>,
    ) -> Result<()> {
        let tmp = self.temp_name(path)?;
        self.pending.push((tmp.clone(), path.to_path_buf()));
        f(&tmp).with_context(|| format!("while writing '{}'", path.display()))
    }

    fn temp_name(&self, path: &Path) -> Result<PathBuf> {
        let name = path
            .file_name()
            .context("output path has no file name")?
            .to_string_lossy();
        // Keep the extension last: some writers pick the format from it.
        // Unique per process and per call: threads of one process may write the same target.
        static NEXT: std::sync::atomic::AtomicU64 = std::sync::atomic::AtomicU64::new(0);
        let k = NEXT.fetch_add(1, std::sync::atomic::Ordering::Relaxed);
        Ok(path.with_file_name(format!(".tmp-{}-{k}-{name}", std::process::id())))
    }

    /// Writes bytes into a temporary file (see [`AtomicFiles::write`]).
    pub fn write_bytes(&mut self, path: &Path, bytes: &[u8]) -> Result<()> {
        self.write(path, |w| Ok(w.write_all(bytes)?))
    }

    /// Renames every temporary file into place.
    pub fn commit(mut self) -> Result<()> {
        for (tmp, dst) in std::mem::take(&mut self.pending) {
            std::fs::rename(&tmp, &dst)
                .with_context(|| format!("cannot move output into '{}'", dst.display()))?;
        }
        Ok(())
    }
}

impl Drop for AtomicFiles {
    fn drop(&mut self) {
        for (tmp, _) in &self.pending {
            let _ = std::fs::remove_file(tmp);
        }
    }
}

/// Writes one file atomically.
pub fn write_atomic(path: &Path, f: impl FnOnce(&mut BufWriter<File>) -> Result<()>) -> Result<()> {
    let mut set = AtomicFiles::new();
    set.write(path, f)?;
    set.commit()
}
