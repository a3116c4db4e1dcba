//! The transport-table container: what the toolchain writes, the runtime reads back exactly; and
//! whatever else the runtime is given — random bytes, truncations, bit flips, foreign versions —
//! it rejects with an error, never a panic (proptest, thousands of cases).

use nephele::io::container::{container_bytes, Array};
use nephele_runtime::container::{Container, FormatError};
use proptest::prelude::*;

fn sample() -> Vec<u8> {
    let a: Vec<f32> = (0..24).map(|i| i as f32 * 0.5 - 3.0).collect();
    let b = [f32::MIN_POSITIVE, -0.0, 1e30, f32::EPSILON];
    let c: Vec<f32> = (0..2 * 3 * 4 * 5).map(|i| (i as f32).sin()).collect();
    container_bytes(&[
        Array {
            name: "grid_t",
            dims: &[24],
            values: &a,
        },
        Array {
            name: "b",
            dims: &[2, 2],
            values: &b,
        },
        Array {
            name: "sixteen_chars_xy",
            dims: &[2, 3, 4, 5],
            values: &c,
        },
    ])
    .unwrap()
}

#[test]
fn round_trip_is_exact() {
    let bytes = sample();
    let c = Container::from_bytes(&bytes).unwrap();
    assert_eq!(c.len(), 3);
    let a = c.find("grid_t").unwrap();
    assert_eq!((a.rank, a.dims, a.len()), (1, [24, 1, 1, 1], 24));
    assert!(a
        .iter()
        .enumerate()
        .all(|(i, v)| v.to_bits() == (i as f32 * 0.5 - 3.0).to_bits()));
    let b = c.find("b").unwrap();
    assert_eq!(b.get(1).unwrap().to_bits(), (-0.0f32).to_bits());
    assert_eq!(b.get(4), None);
    let d = c.find("sixteen_chars_xy").unwrap();
    assert_eq!((d.rank, d.dims), (4, [2, 3, 4, 5]));
    assert_eq!(d.get(119).unwrap().to_bits(), (119f32).sin().to_bits());
    assert!(c.find("missing").is_none() && c.array(3).is_none());
}

#[test]
fn the_writer_refuses_bad_arrays() {
    let v = [1.0f32; 4];
    for (name, dims) in [
        ("", &[4usize][..]),
        ("seventeen_chars_x", &[4]),
        ("dims", &[2, 3]),
        ("rank", &[1, 1, 1, 2, 2]),
        ("zero", &[0, 4]),
    ] {
        assert!(
            container_bytes(&[Array {
                name,
                dims,
                values: &v
            }])
            .is_err(),
            "{name}"
        );
    }
    let twice = [
        Array {
            name: "a",
            dims: &[4],
            values: &v,
        },
        Array {
            name: "a",
            dims: &[4],
            values: &v,
        },
    ];
    assert!(container_bytes(&twice).is_err());
}

#[test]
fn foreign_and_damaged_inputs_are_named() {
    let bytes = sample();
    for old in [1u8, 2, 4] {
        let mut other = bytes.clone();
        other[8] = old;
        assert_eq!(
            Container::from_bytes(&other).unwrap_err(),
            FormatError::UnsupportedVersion(old as u32)
        );
    }
    let said = FormatError::UnsupportedVersion(2).to_string();
    assert!(
        said.contains("version 2") && said.contains("nephele compress"),
        "{said}"
    );
    let mut magic = bytes.clone();
    magic[0] = b'X';
    assert_eq!(
        Container::from_bytes(&magic).unwrap_err(),
        FormatError::BadMagic
    );
    assert_eq!(
        Container::from_bytes(&bytes[..10]).unwrap_err(),
        FormatError::Truncated
    );
    let mut body = bytes.clone();
    body[100] ^= 1;
    assert_eq!(
        Container::from_bytes(&body).unwrap_err(),
        FormatError::BadChecksum
    );
    assert!(Container::from_bytes(&[]).is_err());
    // Text after the magic is a foreign file, not a version 1936287860 of the format.
    let mut text = bytes[..8].to_vec();
    text.extend_from_slice(b"this is not a tables file, but it is long enough to have a checksum");
    assert_eq!(
        Container::from_bytes(&text).unwrap_err(),
        FormatError::BadMagic
    );
    assert!(FormatError::BadMagic
        .to_string()
        .contains("not a nephele transport tables file"));
    assert!(FormatError::Truncated.to_string().starts_with("truncated"));
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(4000))]

    #[test]
    fn random_bytes_never_panic(bytes in proptest::collection::vec(any::<u8>(), 0..600)) {
        // Almost all fail the magic or the checksum; none may panic.
        let _ = Container::from_bytes(&bytes);
    }

    #[test]
    fn random_bytes_behind_a_valid_header_are_rejected(tail in proptest::collection::vec(any::<u8>(), 0..600)) {
        let mut bytes = sample()[..16].to_vec();
        bytes.extend_from_slice(&tail);
        prop_assert!(Container::from_bytes(&bytes).is_err());
    }

    #[test]
    fn every_truncation_is_an_error(cut in 0usize..10_000) {
        let bytes = sample();
        let cut = cut % bytes.len();
        // Named as what happened, not as the checksum that fails with it.
        prop_assert_eq!(Container::from_bytes(&bytes[..cut]).unwrap_err(), FormatError::Truncated);
    }

    #[test]
    fn every_bit_flip_is_an_error(bit in 0usize..100_000) {
        let mut bytes = sample();
        let bit = bit % (8 * bytes.len());
        bytes[bit / 8] ^= 1 << (bit % 8);
        prop_assert!(Container::from_bytes(&bytes).is_err());
    }

    #[test]
    fn a_checksummed_forgery_with_a_bad_directory_is_rejected(
        at in 16usize..160, value in any::<u32>()
    ) {
        // Damage inside the directory with the checksum recomputed: the entry checks must
        // catch what the CRC no longer can, without panicking; the arrays they pass must
        // lie inside the file.
        let mut bytes = sample();
        let n = bytes.len() - 4;
        bytes[at..at + 4].copy_from_slice(&value.to_le_bytes());
        let crc = nephele_runtime::fitting::crc32(&bytes[..n]);
        bytes[n..].copy_from_slice(&crc.to_le_bytes());
        if let Ok(c) = Container::from_bytes(&bytes) {
            for i in 0..c.len() {
                let a = c.array(i).unwrap();
                prop_assert!(a.len() * 4 <= bytes.len());
                let _ = a.iter().count();
            }
        }
    }
}
