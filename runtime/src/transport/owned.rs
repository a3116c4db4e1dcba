//! Transport tables that own their bytes (feature `std`): what a host-language binding keeps
//! behind a handle — the C ABI's `NepheleTables`, the Python module's `Tables` — parsed and
//! checked once, then evaluated without parsing again.

use super::tables::TransportTables;
use crate::container::FormatError;
use std::boxed::Box;

/// Transport tables with their bytes: either a copy the value owns or bytes that live for the
/// whole program (the embedded tables).
pub struct OwnedTables {
    /// The checked view of `_bytes` (declared first, so dropped before the bytes it borrows).
    tables: TransportTables<'static>,
    /// The owned copy (None for `'static` bytes).
    _bytes: Option<Box<[u8]>>,
}

impl OwnedTables {
    /// Takes `bytes`, loads and checks them ([`TransportTables::from_bytes`]).
    pub fn from_bytes(bytes: impl Into<Box<[u8]>>) -> Result<Self, FormatError> {
        let owned: Box<[u8]> = bytes.into();
        // SAFETY: the boxed bytes never move (moving the Box moves the pointer, not the bytes)
        // and are neither mutated nor dropped while `tables` lives: `tables` is dropped first
        // (field order) and is only handed out with a lifetime bounded by `&self`.
        let view: &'static [u8] = unsafe { &*(owned.as_ref() as *const [u8]) };
        Ok(Self {
            tables: TransportTables::from_bytes(view)?,
            _bytes: Some(owned),
        })
    }

    /// Loads and checks bytes that live for the whole program (no copy).
    pub fn from_static(bytes: &'static [u8]) -> Result<Self, FormatError> {
        Ok(Self {
            tables: TransportTables::from_bytes(bytes)?,
            _bytes: None,
        })
    }

    /// The tables, for as long as `self` lives.
    pub fn tables(&self) -> &TransportTables<'_> {
        &self.tables
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    const SHIPPED: &[u8] = include_bytes!(concat!(
        env!("CARGO_MANIFEST_DIR"),
        "/tables/mie10um/transport.ntt"
    ));

    /// Owned tables answer as tables borrowed from the same bytes, after the source is gone.
    #[test]
    fn owned_tables_outlive_their_source() {
        let original: std::vec::Vec<u8> = SHIPPED.to_vec();
        let owned = OwnedTables::from_bytes(original.clone()).unwrap();
        drop(original);
        let at = crate::transport::SlabPoint {
            depth: 2.0,
            thickness: 8.0,
            mu_v: 0.4,
            psi_v: 1.0,
            mu_l: 0.7,
        };
        let borrowed = TransportTables::from_bytes(SHIPPED).unwrap();
        for g in 0..borrowed.groups() {
            assert_eq!(owned.tables().transport(g, &at), borrowed.transport(g, &at));
        }
        assert!(OwnedTables::from_bytes(&SHIPPED[..100]).is_err());
    }
}
