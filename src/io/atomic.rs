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
        let file = File::create(&tmp).with_context(|| {
            format!(
                "cannot write '{}' (its temporary '{}')",
                path.display(),
                tmp.display()
            )
        })?;
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

/// Makes `dir` ready for a writer's outputs: creates it with its parents, and writes a probe
/// file into it, so that a read-only folder or a path under a file fails with the user's own
/// path.
pub fn output_dir(dir: &Path) -> Result<()> {
    create_missing(dir)?;
    probe(dir)
}

/// Checks, before any work is spent, that `dir` can hold a command's outputs (as
/// [`output_dir`]), leaving no folder behind: the command creates it when it writes.
pub fn check_output_dir(dir: &Path) -> Result<()> {
    let created = create_missing(dir)?;
    let probed = probe(dir);
    if let Some(top) = created {
        remove_created(dir, &top);
    }
    probed
}

/// Creates `dir` and its missing parents; the outermost folder it created, if any.
fn create_missing(dir: &Path) -> Result<Option<PathBuf>> {
    if dir.is_file() {
        anyhow::bail!(
            "--out '{}' is a file; give a folder (it is created if missing)",
            dir.display()
        );
    }
    let top = dir
        .ancestors()
        .filter(|a| !a.as_os_str().is_empty())
        .take_while(|a| !a.exists())
        .last()
        .map(Path::to_path_buf);
    std::fs::create_dir_all(dir).map_err(|e| {
        anyhow::anyhow!(
            "cannot create the output folder '{}': {e}; choose another --out",
            dir.display()
        )
    })?;
    Ok(top)
}

/// Removes the empty folders from `dir` up to `top`, which [`create_missing`] made.
fn remove_created(dir: &Path, top: &Path) {
    for a in dir.ancestors() {
        if std::fs::remove_dir(a).is_err() || a == top {
            break;
        }
    }
}

fn probe(dir: &Path) -> Result<()> {
    let probe = dir.join(format!(".tmp-{}-probe", std::process::id()));
    File::create(&probe).map_err(|e| {
        anyhow::anyhow!(
            "cannot write into the output folder '{}': {e}; choose another --out",
            dir.display()
        )
    })?;
    let _ = std::fs::remove_file(&probe);
    Ok(())
}

/// [`check_output_dir`] for the folder of an output file, refusing a file path that is a
/// folder.
pub fn check_output_file(path: &Path) -> Result<()> {
    if path.is_dir() {
        anyhow::bail!("--out '{}' is a folder; give a file path", path.display());
    }
    match path.parent() {
        Some(dir) if !dir.as_os_str().is_empty() => check_output_dir(dir),
        _ => check_output_dir(Path::new(".")),
    }
}

/// An output folder claimed by one command: a second render into the same folder while the
/// first runs would leave a mix of both renders' files. The claim is a `.nephele.lock` file
/// holding the process id; one left by a process that no longer runs is taken over. The folder
/// is created if missing, and removed again if the command leaves it empty.
pub struct FolderLock {
    path: PathBuf,
    dir: PathBuf,
    created: Option<PathBuf>,
}

impl FolderLock {
    /// Claims `dir`, or says which process holds it (or why it cannot be written).
    pub fn take(dir: &Path) -> Result<Self> {
        let created = create_missing(dir)?;
        let lock = Self::claim(dir);
        if let (Err(_), Some(top)) = (&lock, &created) {
            remove_created(dir, top);
        }
        let path = lock?;
        Ok(Self {
            path,
            dir: dir.to_path_buf(),
            created,
        })
    }

    fn claim(dir: &Path) -> Result<PathBuf> {
        let path = dir.join(".nephele.lock");
        for _ in 0..2 {
            match std::fs::OpenOptions::new()
                .write(true)
                .create_new(true)
                .open(&path)
            {
                Ok(mut f) => {
                    write!(f, "{}", std::process::id())?;
                    return Ok(path);
                }
                Err(e) if e.kind() == std::io::ErrorKind::AlreadyExists => {
                    let holder = std::fs::read_to_string(&path).ok();
                    match holder.and_then(|s| s.trim().parse::<u32>().ok()) {
                        Some(pid) if process_runs(pid) => anyhow::bail!(
                            "'{}' is being written by another nephele (process {pid}); wait for it \
                             or choose another --out",
                            dir.display()
                        ),
                        _ => {
                            let _ = std::fs::remove_file(&path);
                        }
                    }
                }
                Err(e) => anyhow::bail!(
                    "cannot write into the output folder '{}': {e}; choose another --out",
                    dir.display()
                ),
            }
        }
        anyhow::bail!("cannot claim '{}': it keeps reappearing", path.display())
    }
}

impl Drop for FolderLock {
    fn drop(&mut self) {
        let _ = std::fs::remove_file(&self.path);
        if let Some(top) = &self.created {
            remove_created(&self.dir, top);
        }
    }
}

/// Whether a process with this id runs (Linux: /proc; elsewhere a lock is never trusted).
fn process_runs(pid: u32) -> bool {
    pid != std::process::id() && Path::new(&format!("/proc/{pid}")).exists()
}

/// Writes one file atomically.
pub fn write_atomic(path: &Path, f: impl FnOnce(&mut BufWriter<File>) -> Result<()>) -> Result<()> {
    let mut set = AtomicFiles::new();
    set.write(path, f)?;
    set.commit()
}
