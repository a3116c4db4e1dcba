//! The compressed transport tables nephele ships (feature `embed`), compiled into the binary:
//! no file to find at run time.
//!
//! `MIE_10UM`: the default slab tables of `nephele slab --config fit-configs/slab-default.json`
//! (water droplets, Mie, the paper's setup at 10 µm; t = 0.5…128 mfp, eight sun cosines, nine
//! order groups), compressed by `nephele compress` with its defaults — the file
//! `outputs/transport/mie10um/transport.ntt` of the repository, whose `manifest.json` beside it
//! gives the slab run, the compressor's version and options, the CRC-32 and the error summary.
//! ```ignore
//! let tables = nephele_runtime::embedded::mie_10um();
//! let mut out = [nephele_runtime::transport::tables::Transport::default(); 8];
//! tables.evaluate_all(2.0, 8.0, -0.6, 0.35, 0.5, &mut out);
//! ```

use crate::transport::tables::TransportTables;

/// The bytes of the shipped Mie 10 µm tables (a `.ntt` container).
pub const MIE_10UM: &[u8] = include_bytes!(concat!(
    env!("CARGO_MANIFEST_DIR"),
    "/../outputs/transport/mie10um/transport.ntt"
));

/// The shipped Mie 10 µm tables, loaded (checked once; a test loads them, so this cannot fail
/// for a build of this repository).
pub fn mie_10um() -> TransportTables<'static> {
    match TransportTables::from_bytes(MIE_10UM) {
        Ok(t) => t,
        Err(e) => panic!("the embedded tables do not load: {e}"),
    }
}
