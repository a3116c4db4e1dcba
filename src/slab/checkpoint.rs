//! Checkpoints and shard results of a slab run, in one directory: `config.json` (the config and
//! its hash), `slice-NNNN.npz` + `slice-NNNN.json` for every finished slice (its exact sums and
//! its report), `current.npz` + `current.json` for the slice in progress (its sums after the
//! last checkpointed round). Every file is written atomically. A run resumed from it, or the
//! merge of several shards' directories, ends with the same bits as one uninterrupted run: the
//! sums are kept exactly and every batch has its own random stream.

use super::config::SlabConfig;
use super::grid::SlabGrid;
use super::run::SliceReport;
use super::tally::Accumulator;
use crate::io::{AtomicFiles, Npz};
use anyhow::{bail, Context, Result};
use std::path::{Path, PathBuf};

/// A checkpoint directory for one config.
pub struct Checkpoint {
    dir: PathBuf,
}

/// FNV-1a of the config's JSON: what a checkpoint or shard belongs to.
pub fn config_hash(cfg: &SlabConfig) -> String {
    let text = serde_json::to_string(cfg).unwrap_or_default();
    let mut h: u64 = 0xcbf2_9ce4_8422_2325;
    for b in text.bytes() {
        h = (h ^ b as u64).wrapping_mul(0x0100_0000_01b3);
    }
    format!("{h:016x}")
}

impl Checkpoint {
    /// Opens (creating) `dir` for `cfg`; refuses a directory holding another config's sums.
    pub fn open(dir: &Path, cfg: &SlabConfig) -> Result<Self> {
        std::fs::create_dir_all(dir)
            .with_context(|| format!("cannot create '{}'", dir.display()))?;
        let cp = Checkpoint {
            dir: dir.to_path_buf(),
        };
        let hash = config_hash(cfg);
        let stamp = dir.join("config.json");
        if stamp.exists() {
            let found = cp.hash_in(&stamp)?;
            if found != hash {
                bail!("'{}' holds sums of another config (hash {found}, this one {hash}): remove it or use another --out", dir.display());
            }
        } else {
            crate::io::write_atomic(&stamp, |w| {
                serde_json::to_writer_pretty(
                    &mut *w,
                    &serde_json::json!({"config_hash": hash, "config": cfg}),
                )?;
                Ok(())
            })?;
        }
        Ok(cp)
    }

    /// Opens an existing directory (a shard's) for reading, checking it belongs to `cfg`.
    pub fn existing(dir: &Path, cfg: &SlabConfig) -> Result<Self> {
        let cp = Checkpoint {
            dir: dir.to_path_buf(),
        };
        let found = cp.hash_in(&dir.join("config.json"))?;
        if found != config_hash(cfg) {
            bail!(
                "'{}' holds sums of another config (hash {found})",
                dir.display()
            );
        }
        Ok(cp)
    }

    fn hash_in(&self, stamp: &Path) -> Result<String> {
        let text = std::fs::read_to_string(stamp)
            .with_context(|| format!("cannot read '{}'", stamp.display()))?;
        let v: serde_json::Value =
            serde_json::from_str(&text).with_context(|| format!("'{}'", stamp.display()))?;
        Ok(v["config_hash"].as_str().unwrap_or_default().to_string())
    }

    fn slice_path(&self, s: usize, ext: &str) -> PathBuf {
        self.dir.join(format!("slice-{s:04}.{ext}"))
    }

    /// A finished slice, if this directory holds it.
    pub fn finished(
        &self,
        s: usize,
        grid: &SlabGrid,
    ) -> Result<Option<(SliceReport, Accumulator)>> {
        let (npz, json) = (self.slice_path(s, "npz"), self.slice_path(s, "json"));
        if !npz.exists() || !json.exists() {
            return Ok(None);
        }
        let report: SliceReport = serde_json::from_str(&std::fs::read_to_string(&json)?)
            .with_context(|| format!("'{}'", json.display()))?;
        Ok(Some((report, Accumulator::load(&npz, "", grid)?)))
    }

    /// Records a finished slice and drops the in-progress sums.
    pub fn finish(&self, s: usize, report: &SliceReport, acc: &Accumulator) -> Result<()> {
        let mut set = AtomicFiles::new();
        set.write(&self.slice_path(s, "npz"), |w| {
            let mut z = Npz::new();
            acc.save(&mut z, "");
            z.write_to(w)
        })?;
        set.write(&self.slice_path(s, "json"), |w| {
            serde_json::to_writer_pretty(&mut *w, report)?;
            Ok(())
        })?;
        set.commit()?;
        for f in ["current.npz", "current.json"] {
            let _ = std::fs::remove_file(self.dir.join(f));
        }
        Ok(())
    }

    /// The in-progress sums of slice `s` and the seconds already spent on it, if saved.
    pub fn current(&self, s: usize, grid: &SlabGrid) -> Result<Option<(Accumulator, f64)>> {
        let json = self.dir.join("current.json");
        if !json.exists() {
            return Ok(None);
        }
        let v: serde_json::Value = serde_json::from_str(&std::fs::read_to_string(&json)?)?;
        if v["slice"].as_u64() != Some(s as u64) {
            return Ok(None);
        }
        let acc = Accumulator::load(&self.dir.join("current.npz"), "", grid)?;
        Ok(Some((acc, v["seconds"].as_f64().unwrap_or(0.0))))
    }

    /// Saves the sums of slice `s` after a round.
    pub fn save_current(&self, s: usize, acc: &Accumulator, seconds: f64) -> Result<()> {
        let mut set = AtomicFiles::new();
        set.write(&self.dir.join("current.npz"), |w| {
            let mut z = Npz::new();
            acc.save(&mut z, "");
            z.write_to(w)
        })?;
        set.write(&self.dir.join("current.json"), |w| {
            serde_json::to_writer(
                &mut *w,
                &serde_json::json!({"slice": s, "batches": acc.batches, "seconds": seconds}),
            )?;
            Ok(())
        })?;
        set.commit()
    }

    /// Deletes the directory (after the tables are written).
    pub fn remove(self) -> Result<()> {
        std::fs::remove_dir_all(&self.dir)
            .with_context(|| format!("cannot remove '{}'", self.dir.display()))
    }
}
