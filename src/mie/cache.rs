//! A disk cache of the Mie phase functions scenes ask for by diameter (`{"kind": "mie"}`): the
//! polydisperse job takes seconds, and a render would otherwise repeat it on every run.
//!
//! An entry is keyed by everything that determines its values: the job itself (serialized:
//! distribution, wavelengths, size rule, refractive indices, angles, illuminant), the crate's
//! version and [`REVISION`] (bumped whenever the Mie numerics change). The key is stored in the
//! entry and compared on reading, so a hash collision or a foreign file is a miss, never a wrong
//! phase function. Values are stored as JSON numbers, which round-trip f64 exactly: a cached
//! phase function is bit for bit the computed one. Entries are written atomically; one that
//! cannot be read is recomputed and rewritten; a cache that cannot be written is skipped.
//!
//! Where: `$NEPHELE_CACHE_DIR`, else `$XDG_CACHE_HOME/nephele`, else `$HOME/.cache/nephele`;
//! `NEPHELE_CACHE_DIR=off` turns it off.

use super::polydisperse::MieJob;
use crate::io::atomic::write_atomic;
use anyhow::{ensure, Result};
use nephele_runtime::fitting::crc32;
use serde::{Deserialize, Serialize};
use std::path::{Path, PathBuf};

/// Bumped whenever the Mie computation's values change, so that older entries miss.
pub const REVISION: u32 = 2;

/// What a cached job keeps: the angles and, per table, the mono and linear-sRGB phase functions.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct CachedPhase {
    /// Angles (degrees).
    pub theta_deg: Vec<f64>,
    /// p (sr⁻¹) at the angles.
    pub phase: Vec<f64>,
    /// Linear-sRGB channels, n_θ × 3 row-major (sr⁻¹).
    pub phase_rgb: Vec<f64>,
}

#[derive(Serialize, Deserialize)]
struct Entry {
    key: String,
    value: CachedPhase,
}

/// The cache directory from the environment (None: off, or no home to put it in).
pub fn default_dir() -> Option<PathBuf> {
    let var = |name: &str| std::env::var_os(name).filter(|v| !v.is_empty());
    match var("NEPHELE_CACHE_DIR") {
        Some(v) if v == "off" => None,
        Some(v) => Some(PathBuf::from(v)),
        None => var("XDG_CACHE_HOME")
            .map(|d| PathBuf::from(d).join("nephele"))
            .or_else(|| var("HOME").map(|h| PathBuf::from(h).join(".cache/nephele"))),
    }
}

/// The first table of `job`, from the cache in `dir` if it holds it, else computed by
/// `compute` and stored there (`dir` None: computed, nothing stored).
pub fn first_table(
    job: &MieJob,
    dir: Option<&Path>,
    compute: impl FnOnce() -> Result<CachedPhase>,
) -> Result<CachedPhase> {
    let key = format!(
        "nephele {} mie revision {REVISION} gemm {:?} {}",
        crate::VERSION,
        super::batch::Gemm::current(),
        serde_json::to_string(job)?
    );
    let Some(dir) = dir else {
        return compute();
    };
    // A file name from the key (the key itself is compared on reading).
    let path = dir.join(format!("mie-{:08x}.json", crc32(key.as_bytes())));
    if let Some(hit) = read(&path, &key) {
        return Ok(hit);
    }
    let value = compute()?;
    // A cache that cannot be written (read-only home, full disk) only costs the next run time.
    let _ = store(
        &path,
        &Entry {
            key,
            value: value.clone(),
        },
    );
    Ok(value)
}

/// The entry at `path` if it is one of `key` and well formed.
fn read(path: &Path, key: &str) -> Option<CachedPhase> {
    let text = std::fs::read_to_string(path).ok()?;
    let e: Entry = serde_json::from_str(&text).ok()?;
    let v = e.value;
    let n = v.theta_deg.len();
    let sound = e.key == key
        && n >= 2
        && v.phase.len() == n
        && v.phase_rgb.len() == 3 * n
        && v.phase.iter().chain(&v.phase_rgb).all(|p| p.is_finite());
    sound.then_some(v)
}

fn store(path: &Path, e: &Entry) -> Result<()> {
    let dir = path.parent().expect("a file in the cache directory");
    std::fs::create_dir_all(dir)?;
    write_atomic(path, |w| Ok(serde_json::to_writer(w, e)?))?;
    ensure!(
        read(path, &e.key).as_ref() == Some(&e.value),
        "the entry does not read back as written"
    );
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::mie::polydisperse::{CONVERGED_DEFAULT, DEFAULT_WAVELENGTHS};

    fn value(scale: f64) -> CachedPhase {
        CachedPhase {
            theta_deg: vec![0.0, 90.0, 180.0],
            phase: vec![0.1 * scale, 1.0 / 3.0, std::f64::consts::PI * 1e-7],
            phase_rgb: (0..9).map(|i| scale / (i as f64 + 1.0)).collect(),
        }
    }

    /// A miss computes and stores, a hit returns the very bits without computing; another
    /// job misses; a corrupt or foreign entry is recomputed and rewritten; no directory: no
    /// cache.
    #[test]
    fn hits_return_the_computed_bits_and_anything_else_recomputes() {
        let dir = tempfile::tempdir().unwrap();
        let job = MieJob::paper(10.0, CONVERGED_DEFAULT, DEFAULT_WAVELENGTHS);
        let first = first_table(&job, Some(dir.path()), || Ok(value(1.0))).unwrap();
        let again = first_table(&job, Some(dir.path()), || panic!("a hit must not compute"));
        assert_eq!(again.unwrap(), first);
        let other = MieJob::paper(12.0, CONVERGED_DEFAULT, DEFAULT_WAVELENGTHS);
        let v = first_table(&other, Some(dir.path()), || Ok(value(2.0))).unwrap();
        assert_eq!(v, value(2.0));
        let files: Vec<_> = std::fs::read_dir(dir.path()).unwrap().collect();
        assert_eq!(files.len(), 2);
        for f in files {
            std::fs::write(f.unwrap().path(), b"{\"key\": 1").unwrap();
        }
        let v = first_table(&job, Some(dir.path()), || Ok(value(3.0))).unwrap();
        assert_eq!(v, value(3.0));
        let hit = first_table(&job, Some(dir.path()), || panic!("rewritten")).unwrap();
        assert_eq!(hit, value(3.0));
        assert_eq!(
            first_table(&job, None, || Ok(value(4.0))).unwrap(),
            value(4.0)
        );
    }

    /// Every f64 a phase function can hold reads back as the bits written: 10⁵ random bit
    /// patterns of finite positive numbers from 1e-300 to 1e300 and the ends of the range (the
    /// parser of serde_json without `float_roundtrip` misses the last bit of some, e.g. in a
    /// 10 µm Mie table: a cached render was then not the computed one).
    #[test]
    fn every_value_reads_back_bit_for_bit() {
        use rand::{Rng, SeedableRng};
        let mut rng = rand_xoshiro::Xoshiro256PlusPlus::seed_from_u64(11);
        let mut phase: Vec<f64> = (0..100_000)
            .map(|_| 10f64.powf(rng.random_range(-300.0..300.0)) * rng.random_range(1.0..10.0))
            .collect();
        phase.extend([
            f64::MIN_POSITIVE,
            f64::MAX,
            5e-324,
            1.0 - f64::EPSILON,
            0.1,
            0.0,
        ]);
        let n = phase.len();
        let v = CachedPhase {
            theta_deg: (0..n).map(|i| 180.0 * i as f64 / (n - 1) as f64).collect(),
            phase_rgb: phase.iter().flat_map(|&p| [p, p * 0.7, p / 3.0]).collect(),
            phase,
        };
        let dir = tempfile::tempdir().unwrap();
        let job = MieJob::paper(10.0, CONVERGED_DEFAULT, DEFAULT_WAVELENGTHS);
        first_table(&job, Some(dir.path()), || Ok(v.clone())).unwrap();
        let hit = first_table(&job, Some(dir.path()), || panic!("a hit must not compute"));
        let bits = |x: &[f64]| x.iter().map(|v| v.to_bits()).collect::<Vec<_>>();
        let hit = hit.unwrap();
        assert!(bits(&hit.phase) == bits(&v.phase) && bits(&hit.phase_rgb) == bits(&v.phase_rgb));
        assert_eq!(bits(&hit.theta_deg), bits(&v.theta_deg));
    }
}
