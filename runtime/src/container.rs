//! The binary container of nephele's transport tables (`.ntt`): named little-endian f32 arrays
//! behind a fixed header and a directory, closed by a CRC-32. Read in place from a byte slice
//! — no allocation, no copy, no alignment requirement — and checked completely before any
//! array is handed out: a truncated, corrupt or foreign input is an error, never a panic.
//!
//! Layout (all integers little-endian; docs/format.md):
//!
//! ```text
//! offset  size  field
//!      0     8  magic  "NEPHTT\r\n"
//!      8     4  u32    version (2; 1 still loads)
//!     12     4  u32    number of arrays n (≤ MAX_ARRAYS)
//!     16  48·n  directory, one entry per array:
//!                 16 B  name, ASCII, NUL-padded (at least one byte, no NUL inside)
//!                  4 B  u32 rank r (1 ≤ r ≤ 4)
//!                 16 B  u32 × 4 dimensions (unused ones 1)
//!                  4 B  u32 offset of the data from the start of the file
//!                  8 B  u64 reserved (0)
//!      …     …  data: each array's Π dims f32 values, row-major, inside the file
//!   L − 4     4  u32    CRC-32 (IEEE 802.3, as zlib) of bytes [0, L − 4)
//! ```

/// The version this crate writes and the only one it reads: the transport parameters
/// feature-major, optionally the halo around the transmitted beam. A file of another version
/// holds its parameters in another layout, or arrays this reader would ignore: it is refused,
/// and rebuilt with `nephele compress`.
pub const FORMAT_VERSION: u32 = 3;

use layout::{crc32, ENTRY_BYTES, HEADER_BYTES, MAGIC, MAX_ARRAYS, NAME_BYTES};

/// Versions above this are not versions: the bytes after the magic are something else.
const MAX_PLAUSIBLE_VERSION: u32 = 0xFFFF;

/// The largest end of an array's data the directory claims (bytes from the start), read
/// without checking the entries (which the CRC-32 guards after).
fn claimed_end(bytes: &[u8], arrays: usize) -> usize {
    (0..arrays)
        .map(|i| {
            let e = HEADER_BYTES + i * ENTRY_BYTES;
            let count = (0..4)
                .map(|k| u32_at(bytes, e + 20 + 4 * k).unwrap_or(1).max(1) as u64)
                .product::<u64>();
            let offset = u32_at(bytes, e + 36).unwrap_or(0) as u64;
            offset
                .saturating_add(count.saturating_mul(4))
                .min(usize::MAX as u64) as usize
        })
        .max()
        .unwrap_or(0)
}

/// Why a byte slice is not a valid container.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum FormatError {
    /// Shorter than its header, directory, data or checksum say.
    Truncated,
    /// Not starting with the magic bytes `NEPHTT\r\n`.
    BadMagic,
    /// A version this reader does not know.
    UnsupportedVersion(u32),
    /// The CRC-32 does not match the contents.
    BadChecksum,
    /// A directory entry that cannot be right (its index).
    BadEntry(usize),
    /// Two arrays of the same name (the second's index).
    DuplicateName(usize),
    /// An array a reader needs is not there.
    Missing(&'static str),
    /// An array has the wrong shape or impossible values for its reader.
    BadArray(&'static str),
}

impl core::fmt::Display for FormatError {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        match self {
            FormatError::Truncated => write!(
                f,
                "truncated transport tables: the file ends before the data its directory lists"
            ),
            FormatError::BadMagic => write!(
                f,
                "not a nephele transport tables file (.ntt): it does not start with the tables' header"
            ),
            FormatError::UnsupportedVersion(v) => {
                write!(
                    f,
                    "transport tables version {v}: this reader reads version {FORMAT_VERSION} only (rebuild them with `nephele compress`)"
                )
            }
            FormatError::BadChecksum => write!(f, "transport tables checksum mismatch (corrupt)"),
            FormatError::BadEntry(i) => write!(f, "transport tables: bad directory entry {i}"),
            FormatError::DuplicateName(i) => {
                write!(f, "transport tables: array {i} repeats a name")
            }
            FormatError::Missing(name) => write!(f, "transport tables: no array '{name}'"),
            FormatError::BadArray(name) => write!(f, "transport tables: bad array '{name}'"),
        }
    }
}

/// A validated container, borrowing its bytes.
#[derive(Clone, Copy, Debug)]
pub struct Container<'a> {
    bytes: &'a [u8],
    arrays: usize,
}

/// One f32 array of a container, borrowing its bytes.
#[derive(Clone, Copy, Debug)]
pub struct ArrayView<'a> {
    /// Its name.
    pub name: &'a str,
    /// Its dimensions (unused trailing ones are 1).
    pub dims: [usize; 4],
    /// Its rank.
    pub rank: usize,
    data: &'a [u8],
}

impl<'a> ArrayView<'a> {
    /// Number of values.
    pub fn len(&self) -> usize {
        self.data.len() / 4
    }

    /// Whether it holds no value (never, for a validated container).
    pub fn is_empty(&self) -> bool {
        self.data.is_empty()
    }

    /// Value `i` in row-major order (None past the end).
    #[inline]
    pub fn get(&self, i: usize) -> Option<f32> {
        let b = self.data.get(4 * i..4 * i + 4)?;
        Some(f32::from_le_bytes([b[0], b[1], b[2], b[3]]))
    }

    /// Its little-endian bytes (4 per value).
    pub fn bytes(&self) -> &'a [u8] {
        self.data
    }

    /// Every value, in row-major order.
    pub fn iter(&self) -> impl Iterator<Item = f32> + 'a {
        self.data
            .chunks_exact(4)
            .map(|b| f32::from_le_bytes([b[0], b[1], b[2], b[3]]))
    }
}

fn u32_at(b: &[u8], at: usize) -> Option<u32> {
    let s = b.get(at..at.checked_add(4)?)?;
    Some(u32::from_le_bytes([s[0], s[1], s[2], s[3]]))
}

impl<'a> Container<'a> {
    /// Validates `bytes` completely: magic, version, checksum, every directory entry (name,
    /// rank, dimensions, data inside the file, names distinct).
    pub fn from_bytes(bytes: &'a [u8]) -> Result<Self, FormatError> {
        if bytes.len() < HEADER_BYTES + 4 {
            return Err(if bytes.len() >= 8 && bytes[..8] != MAGIC {
                FormatError::BadMagic
            } else {
                FormatError::Truncated
            });
        }
        if bytes[..8] != MAGIC {
            return Err(FormatError::BadMagic);
        }
        let version = u32_at(bytes, 8).ok_or(FormatError::Truncated)?;
        // A version no writer could have written (text after the magic, say) is a foreign
        // file, not a newer one.
        if version > MAX_PLAUSIBLE_VERSION {
            return Err(FormatError::BadMagic);
        }
        if version != FORMAT_VERSION {
            return Err(FormatError::UnsupportedVersion(version));
        }
        let body = bytes.len() - 4;
        let arrays = u32_at(bytes, 12).ok_or(FormatError::Truncated)? as usize;
        let short = arrays > MAX_ARRAYS || HEADER_BYTES + arrays * ENTRY_BYTES > body;
        if u32_at(bytes, body) != Some(crc32(&bytes[..body])) {
            // A truncated file's last four bytes are data, so its checksum fails too: say
            // what happened when the directory (of a plausible size) claims data past the end.
            let cut = arrays <= MAX_ARRAYS && (short || claimed_end(bytes, arrays) > body);
            return Err(if cut {
                FormatError::Truncated
            } else {
                FormatError::BadChecksum
            });
        }
        if short {
            return Err(FormatError::Truncated);
        }
        let c = Container { bytes, arrays };
        for i in 0..arrays {
            let a = c.parse(i).ok_or(FormatError::BadEntry(i))?;
            if (0..i).any(|k| c.parse(k).is_some_and(|b| b.name == a.name)) {
                return Err(FormatError::DuplicateName(i));
            }
        }
        Ok(c)
    }

    /// Number of arrays.
    pub fn len(&self) -> usize {
        self.arrays
    }

    /// The file's version ([`FORMAT_VERSION`]).
    pub fn version(&self) -> u32 {
        u32_at(self.bytes, 8).unwrap_or(FORMAT_VERSION)
    }

    /// Whether it holds no array.
    pub fn is_empty(&self) -> bool {
        self.arrays == 0
    }

    /// Array `i` of the directory.
    pub fn array(&self, i: usize) -> Option<ArrayView<'a>> {
        if i < self.arrays {
            self.parse(i)
        } else {
            None
        }
    }

    /// The array named `name`.
    pub fn find(&self, name: &str) -> Option<ArrayView<'a>> {
        (0..self.arrays)
            .filter_map(|i| self.parse(i))
            .find(|a| a.name == name)
    }

    /// Directory entry `i`, or None if it is malformed.
    fn parse(&self, i: usize) -> Option<ArrayView<'a>> {
        let e = HEADER_BYTES + i * ENTRY_BYTES;
        let entry = self.bytes.get(e..e + ENTRY_BYTES)?;
        let raw = &entry[..NAME_BYTES];
        let len = raw.iter().position(|&b| b == 0).unwrap_or(NAME_BYTES);
        if len == 0 || raw[len..].iter().any(|&b| b != 0) || !raw[..len].is_ascii() {
            return None;
        }
        let name = core::str::from_utf8(&raw[..len]).ok()?;
        let rank = u32_at(entry, 16)? as usize;
        if !(1..=4).contains(&rank) {
            return None;
        }
        let mut dims = [1usize; 4];
        let mut count = 1usize;
        for (k, d) in dims.iter_mut().enumerate() {
            *d = u32_at(entry, 20 + 4 * k)? as usize;
            if *d == 0 || (k >= rank && *d != 1) {
                return None;
            }
            count = count.checked_mul(*d)?;
        }
        let offset = u32_at(entry, 36)? as usize;
        if entry[40..48].iter().any(|&b| b != 0)
            || offset < HEADER_BYTES + self.arrays * ENTRY_BYTES
        {
            return None;
        }
        let end = offset.checked_add(count.checked_mul(4)?)?;
        if end > self.bytes.len() - 4 {
            return None;
        }
        Some(ArrayView {
            name,
            dims,
            rank,
            data: &self.bytes[offset..end],
        })
    }
}

/// The container's byte layout (the table above) and its checksum: what a writer needs, not a
/// renderer (the toolchain reaches it through `nephele_runtime::fitting`).
pub(crate) mod layout {
    /// The first 8 bytes of every container ("\r\n" catches text-mode mangling, as PNG does).
    pub const MAGIC: [u8; 8] = *b"NEPHTT\r\n";
    /// Most arrays one container may hold.
    pub const MAX_ARRAYS: usize = 4096;
    /// Bytes of one directory entry.
    pub const ENTRY_BYTES: usize = 48;
    /// Bytes before the directory.
    pub const HEADER_BYTES: usize = 16;
    /// Longest array name.
    pub const NAME_BYTES: usize = 16;

    /// The CRC-32 table (reflected IEEE polynomial 0xEDB88320), built at compile time.
    const CRC_TABLE: [u32; 256] = {
        let mut table = [0u32; 256];
        let mut i = 0;
        while i < 256 {
            let mut c = i as u32;
            let mut k = 0;
            while k < 8 {
                c = if c & 1 != 0 {
                    0xEDB8_8320 ^ (c >> 1)
                } else {
                    c >> 1
                };
                k += 1;
            }
            table[i] = c;
            i += 1;
        }
        table
    };

    /// CRC-32 of `bytes` (IEEE 802.3, the checksum of zlib, PNG and gzip).
    pub fn crc32(bytes: &[u8]) -> u32 {
        !bytes.iter().fold(!0u32, |c, &b| {
            CRC_TABLE[((c ^ b as u32) & 0xFF) as usize] ^ (c >> 8)
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn crc32_known_values() {
        assert_eq!(crc32(b""), 0);
        assert_eq!(crc32(b"123456789"), 0xCBF4_3926);
        assert_eq!(
            crc32(b"The quick brown fox jumps over the lazy dog"),
            0x414F_A339
        );
    }
}
