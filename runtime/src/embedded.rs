//! The compressed transport tables nephele ships (feature `embed`), compiled into the binary:
//! no file to find at run time.
//!
//! `MIE_10UM`: the default slab tables of `nephele slab --config fit-configs/slab-default.json`
//! (water droplets, Mie, the paper's setup at 10 µm; t = 0.5…128 mfp, eight sun cosines, nine
//! order groups), compressed by `nephele compress` with its defaults — the file
//! `tables/mie10um/transport.ntt` of this crate, whose `manifest.json` beside it gives the slab
//! run, the compressor's version and options, the CRC-32 and the error summary.
//! ```
//! use nephele_runtime::transport::{SlabPoint, Transport};
//! let tables = nephele_runtime::embedded::mie_10um();
//! let at = SlabPoint { depth: 2.0, thickness: 8.0, mu_v: -0.6, psi_v: 0.35, mu_l: 0.5 };
//! let mut out = [Transport::default(); 8];
//! tables.evaluate_all(&at, &mut out);
//! assert!(out.iter().all(|g| g.t > 0.0));
//! ```

use crate::transport::TransportTables;

/// The bytes of the shipped Mie 10 µm tables (a `.ntt` container).
pub const MIE_10UM: &[u8] = include_bytes!(concat!(
    env!("CARGO_MANIFEST_DIR"),
    "/tables/mie10um/transport.ntt"
));

/// The shipped Mie 10 µm tables, loaded (checked once; a test loads them, so this cannot fail
/// for a build of this repository).
pub fn mie_10um() -> TransportTables<'static> {
    match TransportTables::from_bytes(MIE_10UM) {
        Ok(t) => t,
        Err(e) => panic!("the embedded tables do not load: {e}"),
    }
}
