use super::*;
use std::alloc::{GlobalAlloc, Layout, System};
use std::cell::Cell;

/// The system allocator, noting the largest block this thread asked for.
struct Probe;

thread_local! {
    static LARGEST: Cell<usize> = const { Cell::new(0) };
}

#[allow(unsafe_code)]
// SAFETY: every call is the system allocator's, with the caller's own arguments.
unsafe impl GlobalAlloc for Probe {
    unsafe fn alloc(&self, layout: Layout) -> *mut u8 {
        _ = LARGEST.try_with(|l| l.set(l.get().max(layout.size())));
        unsafe { System.alloc(layout) }
    }

    unsafe fn dealloc(&self, ptr: *mut u8, layout: Layout) {
        unsafe { System.dealloc(ptr, layout) }
    }

    unsafe fn realloc(&self, ptr: *mut u8, layout: Layout, new_size: usize) -> *mut u8 {
        _ = LARGEST.try_with(|l| l.set(l.get().max(new_size)));
        unsafe { System.realloc(ptr, layout, new_size) }
    }
}

#[global_allocator]
static PROBE: Probe = Probe;

/// `f`'s result and the largest block it allocated on this thread.
fn largest_block<T>(f: impl FnOnce() -> T) -> (T, usize) {
    LARGEST.with(|l| l.set(0));
    let result = f();
    (result, LARGEST.with(Cell::get))
}

/// Most bytes one allocation of [`decode`] may take: its list of at most five parts.
const DECODE_BLOCK: usize = 5 * std::mem::size_of::<&[u8]>();

const HEADER: Header = Header {
    step: 7,
    seed: 11,
    batch: 8,
    features: 8,
    heads: 2,
    kernel: 3,
    switches: 0b11111,
    learning_rate: 1e-3,
    prior: 1,
};

/// Offset of header word `i` (the part count at [`HEADER_WORDS`]).
fn word_at(i: usize) -> usize {
    MAGIC.len() + i * WORD
}

fn part(len: usize, salt: u8) -> Vec<u8> {
    (0..len)
        .map(|i| (i as u8).wrapping_mul(31) ^ salt)
        .collect()
}

fn network() -> Vec<u8> {
    encode(&HEADER, &[part(64, 1)]).unwrap()
}

fn distilling() -> Vec<u8> {
    let parts: Vec<Vec<u8>> = (0..5).map(|i| part(9 + i, i as u8)).collect();
    encode(&HEADER, &parts).unwrap()
}

/// `bytes` with word `i` set to `value` and the CRC made to match again.
fn forged(bytes: &[u8], i: usize, value: u64) -> Vec<u8> {
    let mut out = bytes.to_vec();
    out[word_at(i)..word_at(i) + WORD].copy_from_slice(&value.to_le_bytes());
    reseal(&mut out);
    out
}

fn reseal(bytes: &mut [u8]) {
    let n = bytes.len() - CRC_LEN;
    let crc = checksum(&bytes[..n]);
    bytes[n..].copy_from_slice(&crc.to_le_bytes());
}

#[test]
fn a_file_reads_back_as_written() {
    let parts: Vec<Vec<u8>> = (0..4).map(|i| part(100 * i + 1, i as u8)).collect();
    let bytes = encode(&HEADER, &parts).unwrap();
    let (file, block) = largest_block(|| decode(&bytes));
    // The probe sees the list of parts, and nothing larger.
    assert_eq!(block, 4 * std::mem::size_of::<&[u8]>());
    let file = file.unwrap();
    assert_eq!(file.header, HEADER);
    assert_eq!(file.kind, Kind::Checkpoint);
    assert_eq!(
        file.parts,
        parts.iter().map(Vec::as_slice).collect::<Vec<_>>()
    );
    assert_eq!(file.crc.to_le_bytes(), bytes[bytes.len() - 4..]);
    assert_eq!(&bytes[..8], b"PCTEACH3");
    let net = network();
    let net = decode(&net).unwrap();
    assert_eq!((net.kind, net.parts.len()), (Kind::Network, 1));
    assert_eq!(decode(&distilling()).unwrap().kind, Kind::Distilling);
    assert_eq!(HEADER.switches_on().collect::<Vec<_>>(), SWITCHES.to_vec());
}

#[test]
fn every_single_bit_flip_is_rejected() {
    let mut flips = 0;
    for file in [network(), distilling()] {
        let mut bytes = file.clone();
        for bit in 0..bytes.len() * 8 {
            bytes[bit / 8] ^= 1 << (bit % 8);
            let (result, block) = largest_block(|| decode(&bytes));
            match result {
                Ok(_) => panic!("a flip of bit {bit} was read"),
                Err(Error::Checksum { .. }) => {}
                // The magic's: another family or version.
                Err(Error::Magic | Error::Legacy { .. } | Error::UnknownVersion { .. }) => {
                    assert!(bit < 64, "bit {bit}")
                }
                Err(e) => panic!("bit {bit}: {e}"),
            }
            assert!(block <= DECODE_BLOCK, "bit {bit}: a block of {block} bytes");
            bytes[bit / 8] ^= 1 << (bit % 8);
            flips += 1;
        }
        assert_eq!(bytes, file);
    }
    eprintln!("{flips} single-bit flips, each rejected");
}

#[test]
fn every_truncation_and_extension_is_rejected() {
    let file = distilling();
    for len in 0..file.len() {
        assert!(decode(&file[..len]).is_err(), "{len} bytes");
    }
    // One byte more, resealed: the parts no longer end at the checksum.
    let mut longer = file[..file.len() - CRC_LEN].to_vec();
    longer.push(0);
    longer.extend(checksum(&longer).to_le_bytes());
    assert_eq!(decode(&longer), Err(Error::Trailing { bytes: 1 }));
    // Unsealed, it is damage.
    let mut unsealed = file.clone();
    unsealed.push(0);
    assert!(matches!(decode(&unsealed), Err(Error::Checksum { .. })));
}

/// Each word set to 0, odd, huge and all ones, with the CRC made to match: whether the file
/// must still read.
#[test]
fn header_words_out_of_bounds_are_named_with_their_value_and_bound() {
    const VALUES: [u64; 4] = [0, 3, 1 << 40, u64::MAX];
    let accepted: [(&str, [bool; 4]); HEADER_WORDS + 1] = [
        ("step", [true, true, false, false]),
        ("seed", [true, true, true, true]),
        ("batch", [false, true, false, false]),
        ("features", [false, false, false, false]),
        // 3 does not divide the 8 features.
        ("heads", [false, false, false, false]),
        ("kernel", [false, true, false, false]),
        ("switches", [true, true, false, false]),
        // As bits: 0.0, two subnormals (positive, finite: accepted) and a NaN.
        ("learning_rate", [false, true, true, false]),
        ("prior", [true, false, false, false]),
        (PARTS_WORD, [false; 4]),
    ];
    let file = network();
    for (i, (name, accepted)) in accepted.iter().enumerate() {
        assert_eq!(*name, WORDS.get(i).copied().unwrap_or(PARTS_WORD));
        for (&value, &ok) in VALUES.iter().zip(accepted) {
            let bytes = forged(&file, i, value);
            let (result, block) = largest_block(|| decode(&bytes));
            assert!(block <= DECODE_BLOCK, "{name} = {value}: {block} bytes");
            match (result, ok) {
                (Ok(f), true) => assert_eq!(f.header.to_words()[i], value),
                (
                    Err(Error::Word {
                        word,
                        value: v,
                        bound,
                    }),
                    false,
                ) => {
                    assert_eq!((word, v), (*name, value));
                    let message = Error::Word {
                        word,
                        value: v,
                        bound,
                    }
                    .to_string();
                    assert!(message.contains(name), "{message}");
                    assert!(message.contains(&bound.to_string()), "{message}");
                }
                (other, _) => panic!("{name} = {value}: {other:?}"),
            }
        }
    }
    // The checksum comes first: the same words without a matching CRC are damage.
    let mut bytes = file.clone();
    bytes[word_at(3)..word_at(4)].copy_from_slice(&(1u64 << 40).to_le_bytes());
    assert!(matches!(decode(&bytes), Err(Error::Checksum { .. })));
}

#[test]
fn other_learning_rates_and_sizes_at_their_bounds() {
    let rate = |r: f64| forged(&network(), 7, r.to_bits());
    for r in [f64::INFINITY, f64::NEG_INFINITY, -1e-3, 2.0, -0.0] {
        assert!(
            matches!(
                decode(&rate(r)),
                Err(Error::Word {
                    word: "learning_rate",
                    ..
                })
            ),
            "{r}"
        );
    }
    assert!(decode(&rate(MAX_LEARNING_RATE)).is_ok());
    let set = |i: usize, v: u64| decode(&forged(&network(), i, v)).map(|f| f.header);
    assert!(set(3, MAX_FEATURES).is_ok() && set(3, MAX_FEATURES + 2).is_err());
    // Two features, one per head.
    assert!(set(3, MIN_FEATURES).is_ok() && set(3, 6).is_ok() && set(3, 1).is_err());
    assert!(set(4, 1).is_ok() && set(4, 8).is_ok() && set(4, 16).is_err());
    assert!(set(5, 1).is_ok() && set(5, MAX_KERNEL).is_ok() && set(5, MAX_KERNEL + 2).is_err());
    assert!(set(2, MAX_BATCH).is_ok() && set(2, MAX_BATCH + 1).is_err());
    assert!(set(0, MAX_STEP).is_ok() && set(0, MAX_STEP + 1).is_err());
    let message = decode(&forged(&network(), 3, 33)).unwrap_err().to_string();
    assert_eq!(
        message,
        "header word `features` is 33; it must be even, from 2 to 256"
    );
}

#[test]
fn part_lengths_must_end_at_the_checksum() {
    let file = network();
    let at = HEADER_WORDS + 1;
    let cases = [
        (0, Error::Trailing { bytes: 64 }),
        (63, Error::Trailing { bytes: 1 }),
        (
            65,
            Error::PartLength {
                part: 0,
                length: 65,
                left: 64,
            },
        ),
        (
            1 << 40,
            Error::PartLength {
                part: 0,
                length: 1 << 40,
                left: 64,
            },
        ),
        (
            u64::MAX,
            Error::PartLength {
                part: 0,
                length: u64::MAX,
                left: 64,
            },
        ),
    ];
    for (length, error) in cases {
        let bytes = forged(&file, at, length);
        let (result, block) = largest_block(|| decode(&bytes));
        assert_eq!(result, Err(error), "{length}");
        assert!(block <= DECODE_BLOCK);
    }
    // A count of 4 over a file of one part: the second part's length is missing.
    let bytes = forged(&file, HEADER_WORDS, 4);
    assert_eq!(decode(&bytes), Err(Error::MissingPart { part: 1 }));
}

#[test]
fn other_versions_and_families_are_refused_by_name() {
    let mut bytes = network();
    for (version, error) in [
        (b'1', Error::Legacy { version: 1 }),
        (b'2', Error::Legacy { version: 2 }),
        (b'4', Error::UnknownVersion { byte: b'4' }),
    ] {
        bytes[7] = version;
        assert_eq!(decode(&bytes), Err(error));
    }
    let message = Error::Legacy { version: 2 }.to_string();
    assert!(
        message.contains("PCTEACH2") && message.contains("re-save"),
        "{message}"
    );
    assert_eq!(decode(b"PCW\x01 an int8 blob"), Err(Error::Magic));
    assert_eq!(decode(b"PCTEA"), Err(Error::Truncated { len: 5 }));
    assert_eq!(decode(b""), Err(Error::Truncated { len: 0 }));
    assert_eq!(decode(b"PCTEACH3"), Err(Error::Truncated { len: 8 }));
    assert!(is_float_weights(b"PCTEACH1") && !is_float_weights(b"PCW\x01"));
}

#[test]
fn the_writer_refuses_what_the_reader_would() {
    let bad = Header { heads: 3, ..HEADER };
    assert!(matches!(
        encode(&bad, &[part(4, 0)]),
        Err(Error::Word { word: "heads", .. })
    ));
    for count in [0, 2, 3, 6] {
        let parts = vec![part(4, 0); count];
        assert_eq!(
            encode(&HEADER, &parts),
            Err(Error::Word {
                word: PARTS_WORD,
                value: count as u64,
                bound: Bound::Parts
            })
        );
    }
}
