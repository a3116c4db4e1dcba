//! Refractive index of the droplets relative to the medium, as a function of wavelength.
//!
//! Sign convention: m = n + i k with k ≥ 0 for absorption (Bohren & Huffman); a user table
//! lists k ≥ 0 in the same sense.

use super::water::water_index_iapws;
use anyhow::{bail, Context, Result};
use num_complex::Complex64;
use serde::{Deserialize, Serialize};
use std::path::Path;

/// Where the droplet index comes from.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(tag = "kind", rename_all = "snake_case", deny_unknown_fields)]
pub enum RefractiveIndex {
    /// Wavelength-independent m = n + i k (the paper: n = 1.333, k = 0).
    Constant {
        /// Real part.
        n: f64,
        /// Imaginary part, ≥ 0.
        #[serde(default)]
        k: f64,
    },
    /// Liquid water by IAPWS R9-97 at 0.101325 MPa and `temp_c` °C (k = 0 in the visible,
    /// where water's k < 1e-8).
    Water {
        /// Temperature, °C.
        temp_c: f64,
    },
    /// A user table of (λ nm, n, k), linearly interpolated, never extrapolated.
    Table {
        /// Where the table came from (for the config echo).
        source: String,
        /// Rows (λ nm, n, k) with strictly increasing λ.
        rows: Vec<[f64; 3]>,
    },
}

impl RefractiveIndex {
    /// Parses `1.333`, `1.5+0.01i`, `water`, `water:TEMP_C` or a CSV file path.
    pub fn parse(spec: &str) -> Result<Self> {
        let s = spec.trim();
        if let Some(rest) = s.strip_prefix("water") {
            let temp_c = match rest.strip_prefix(':') {
                Some(t) => t
                    .parse::<f64>()
                    .with_context(|| format!("bad water temperature '{t}'"))?,
                None if rest.is_empty() => 20.0,
                None => bail!("index '{spec}': expected water or water:TEMP_C"),
            };
            let idx = Self::Water { temp_c };
            idx.validate()?;
            return Ok(idx);
        }
        if let Some(idx) = parse_complex(s) {
            idx.validate()?;
            return Ok(idx);
        }
        if let Some((n, k)) = negative_imaginary(s) {
            bail!(
                "index '{spec}': nephele writes an absorbing index as n+ki with k ≥ 0 (Bohren & \
                 Huffman); '{n}-{k}i' is miepython's sign for the same sphere: use {n}+{k}i"
            );
        }
        Self::from_csv(Path::new(s))
    }

    /// Reads a CSV of `wavelength_nm,n[,k]` rows; a header line and `#` comments are skipped.
    pub fn from_csv(path: &Path) -> Result<Self> {
        let text = std::fs::read_to_string(path)
            .with_context(|| format!("cannot read index table '{}'", path.display()))?;
        let mut rows = Vec::new();
        for (i, line) in text.lines().enumerate() {
            let line = line.trim();
            if line.is_empty() || line.starts_with('#') {
                continue;
            }
            let fields: Vec<&str> = line.split(',').map(str::trim).collect();
            let nums: Result<Vec<f64>, _> = fields.iter().map(|f| f.parse::<f64>()).collect();
            match nums {
                Ok(v) if v.len() == 2 || v.len() == 3 => {
                    rows.push([v[0], v[1], v.get(2).copied().unwrap_or(0.0)])
                }
                Err(_) if rows.is_empty() && i == 0 => continue, // header
                _ => bail!(
                    "index table '{}' line {}: expected 'wavelength_nm,n[,k]', got '{line}'",
                    path.display(),
                    i + 1
                ),
            }
        }
        let idx = Self::Table {
            source: path.display().to_string(),
            rows,
        };
        idx.validate()?;
        Ok(idx)
    }

    /// Checks the parameters or table.
    pub fn validate(&self) -> Result<()> {
        match self {
            Self::Constant { n, k } => {
                if !(n.is_finite() && *n > 0.0 && k.is_finite() && *k >= 0.0) {
                    bail!("refractive index must have n > 0 and k ≥ 0, got n = {n}, k = {k}");
                }
            }
            Self::Water { temp_c } => {
                if !(temp_c.is_finite() && (0.0..=100.0).contains(temp_c)) {
                    bail!("water temperature must be within 0–100 °C, got {temp_c}");
                }
            }
            Self::Table { source, rows } => {
                if rows.len() < 2 {
                    bail!("index table '{source}' needs at least two rows");
                }
                for r in rows {
                    if !(r.iter().all(|v| v.is_finite()) && r[0] > 0.0 && r[1] > 0.0 && r[2] >= 0.0)
                    {
                        bail!("index table '{source}': bad row {r:?} (need λ > 0, n > 0, k ≥ 0)");
                    }
                }
                if rows.windows(2).any(|w| w[1][0] <= w[0][0]) {
                    bail!("index table '{source}': wavelengths must be strictly increasing");
                }
            }
        }
        Ok(())
    }

    /// True if m does not depend on wavelength.
    pub fn is_constant(&self) -> bool {
        matches!(self, Self::Constant { .. })
    }

    /// m at vacuum wavelength `lambda_nm`; an error outside a table's range.
    pub fn at(&self, lambda_nm: f64) -> Result<Complex64> {
        Ok(match self {
            Self::Constant { n, k } => Complex64::new(*n, *k),
            Self::Water { temp_c } => Complex64::new(water_index_iapws(lambda_nm, *temp_c), 0.0),
            Self::Table { source, rows } => {
                let (first, last) = (rows[0][0], rows[rows.len() - 1][0]);
                if !(first..=last).contains(&lambda_nm) {
                    bail!("index table '{source}' covers {first}–{last} nm, not {lambda_nm} nm");
                }
                let i = rows
                    .partition_point(|r| r[0] <= lambda_nm)
                    .clamp(1, rows.len() - 1);
                let (a, b) = (rows[i - 1], rows[i]);
                let t = (lambda_nm - a[0]) / (b[0] - a[0]);
                Complex64::new(a[1] + t * (b[1] - a[1]), a[2] + t * (b[2] - a[2]))
            }
        })
    }
}

/// `1.333` or `1.5+0.01i` (also `1.5+0.01j`).
fn parse_complex(s: &str) -> Option<RefractiveIndex> {
    if let Ok(n) = s.parse::<f64>() {
        return Some(RefractiveIndex::Constant { n, k: 0.0 });
    }
    let body = s.strip_suffix('i').or_else(|| s.strip_suffix('j'))?;
    let split = body.rfind('+')?;
    let n = body[..split].parse::<f64>().ok()?;
    let k = body[split + 1..].parse::<f64>().ok()?;
    Some(RefractiveIndex::Constant { n, k })
}

/// (n, k) of "n-ki" (the other sign convention), if `s` has that form.
fn negative_imaginary(s: &str) -> Option<(f64, f64)> {
    let body = s.strip_suffix('i').or_else(|| s.strip_suffix('j'))?;
    let split = body
        .rfind('-')
        .filter(|&i| i > 0 && !body[..i].ends_with(['e', 'E']))?;
    let n = body[..split].parse::<f64>().ok()?;
    let k = body[split + 1..].parse::<f64>().ok()?;
    Some((n, k))
}

#[cfg(test)]
mod tests {
    use super::*;

    /// miepython's n − ki gets an error that says which sign nephele uses.
    #[test]
    fn the_other_sign_convention_is_explained() {
        let e = RefractiveIndex::parse("1.5-0.1i").unwrap_err().to_string();
        assert!(e.contains("use 1.5+0.1i"), "{e}");
        assert!(RefractiveIndex::parse("1.5e-3").is_ok());
    }

    #[test]
    fn parses_the_documented_forms() {
        assert_eq!(
            RefractiveIndex::parse("1.333").unwrap(),
            RefractiveIndex::Constant { n: 1.333, k: 0.0 }
        );
        assert_eq!(
            RefractiveIndex::parse("1.5+0.1i").unwrap(),
            RefractiveIndex::Constant { n: 1.5, k: 0.1 }
        );
        assert_eq!(
            RefractiveIndex::parse("water").unwrap(),
            RefractiveIndex::Water { temp_c: 20.0 }
        );
        assert_eq!(
            RefractiveIndex::parse("water:25").unwrap(),
            RefractiveIndex::Water { temp_c: 25.0 }
        );
        assert!(RefractiveIndex::parse("-1.3").is_err());
        assert!(RefractiveIndex::parse("water:hot").is_err());
        assert!(RefractiveIndex::parse("no-such-file.csv").is_err());
    }

    #[test]
    fn table_interpolates_and_refuses_to_extrapolate() {
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("m.csv");
        std::fs::write(&path, "wavelength_nm,n,k\n400,1.34,0\n700,1.33,0.003\n").unwrap();
        let idx = RefractiveIndex::from_csv(&path).unwrap();
        let m = idx.at(550.0).unwrap();
        assert!((m.re - 1.335).abs() < 1e-12 && (m.im - 0.0015).abs() < 1e-12);
        assert!(idx.at(399.0).is_err());
        std::fs::write(&path, "400,1.34\n300,1.33\n").unwrap();
        assert!(RefractiveIndex::from_csv(&path).is_err());
        std::fs::write(&path, "400,1.34\n500,abc\n").unwrap();
        assert!(RefractiveIndex::from_csv(&path).is_err());
    }
}
