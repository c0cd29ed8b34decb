//! Damaged and hostile files: errors, never panics or huge allocations, for every codec.

use super::*;

#[test]
fn damaged_files_give_errors_not_panics() {
    let good = encode_exr(&sample_image(), "t".as_ref()).unwrap();
    let mut cases: Vec<(String, Vec<u8>)> = vec![
        ("empty".into(), Vec::new()),
        (
            "garbage".into(),
            (0..4096u32).map(|i| (i * 7919 % 251) as u8).collect(),
        ),
        ("magic only".into(), good[..4].to_vec()),
    ];
    for len in [
        1,
        7,
        8,
        20,
        100,
        good.len() / 3,
        good.len() / 2,
        good.len() - 1,
    ] {
        cases.push((format!("truncated to {len}"), good[..len].to_vec()));
    }
    // Flipped bytes in the header, the offset table and the compressed data.
    let mut x = 12345u32;
    for i in 0..64 {
        x = x.wrapping_mul(1_103_515_245).wrapping_add(12345);
        let mut bad = good.clone();
        let at = (x as usize >> 4) % bad.len();
        bad[at] ^= 0xff;
        cases.push((format!("flip {i} at {at}"), bad));
    }
    let mut errors = 0;
    for (what, bytes) in &cases {
        let result = std::panic::catch_unwind(|| decode_exr(bytes, "bad.exr".as_ref()));
        match result {
            Err(_) => panic!("{what}: the decoder panicked"),
            Ok(Err(e)) => {
                errors += 1;
                assert!(e.to_string().contains("bad.exr"), "{what}: {e}");
                // ZIP, the codec this crate writes, must fail cleanly, not by a
                // panic turned into an error.
                assert!(!e.to_string().contains("panicked"), "{what}: {e}");
            }
            // A flip inside a value the format does not check (a sample, an
            // attribute's value) still decodes; that is not damage the reader can see.
            Ok(Ok(_)) => assert!(what.starts_with("flip"), "{what}: decoded"),
        }
    }
    assert!(errors >= 11, "only {errors} errors");
}

#[test]
fn header_claiming_a_huge_image_is_refused_before_allocating() {
    let mut bytes = encode_exr(&Image::new(1, 1), "t".as_ref()).unwrap();
    // dataWindow is box2i: xmin, ymin, xmax, ymax; make it 2^29 x 2^29.
    let at = bytes.windows(10).position(|w| w == b"dataWindow").unwrap();
    let value = at + b"dataWindow\0box2i\0".len() + 4;
    bytes[value + 8..value + 12].copy_from_slice(&((1i32 << 29) - 1).to_le_bytes());
    bytes[value + 12..value + 16].copy_from_slice(&((1i32 << 29) - 1).to_le_bytes());
    let err = decode_exr(&bytes, "t".as_ref()).unwrap_err();
    assert!(
        matches!(err, Error::UnsupportedExr { .. } | Error::Exr { .. }),
        "{err}"
    );
}

#[test]
fn damaged_files_of_every_codec_return_errors() {
    // A process abort (failed allocation) would kill this test binary, so reaching the
    // end is part of the assertion.
    let codecs = [
        Compression::Uncompressed,
        Compression::RLE,
        Compression::ZIP1,
        Compression::ZIP16,
        Compression::PIZ,
        Compression::PXR24,
        Compression::B44,
        Compression::DWAA(None),
        Compression::DWAB(None),
    ];
    let mut x = 99u64;
    let mut next = move || {
        x = x
            .wrapping_mul(6_364_136_223_846_793_005)
            .wrapping_add(1_442_695_040_888_963_407);
        (x >> 33) as usize
    };
    for codec in codecs {
        let good = foreign_file(codec);
        let image = decode_exr(&good, "t".as_ref()).unwrap();
        assert_eq!(image.width, 40, "{codec:?}");
        let mut errors = 0;
        for i in 0..150 {
            let mut bad = good.clone();
            for _ in 0..1 + i % 4 {
                let at = next() % bad.len();
                bad[at] = next() as u8;
            }
            if i % 5 == 0 {
                let len = next() % bad.len();
                bad.truncate(len);
            }
            let result = std::panic::catch_unwind(|| decode_exr(&bad, "bad.exr".as_ref()));
            match result.unwrap_or_else(|_| panic!("{codec:?} case {i}: panic escaped")) {
                Ok(_) => {}
                Err(_) => errors += 1,
            }
        }
        // Truncations alone make 30 of the cases undecodable.
        assert!(errors >= 30, "{codec:?}: only {errors} errors");
    }
}

#[test]
fn dwa_files_are_read_and_damaged_ones_refused() {
    for codec in [Compression::DWAA(None), Compression::DWAB(None)] {
        let good = foreign_file(codec);
        let image = decode_exr(&good, "t".as_ref()).unwrap();
        // DWA is lossy (about 0.02 worst here, on values up to 2).
        let wave = |p: usize| (p as f32 * 0.1).sin();
        for (p, px) in image.rgba.iter().enumerate() {
            let expected = [wave(p), 2.0 * wave(p), -wave(p), 1.0];
            for c in 0..4 {
                assert!((px[c] - expected[c]).abs() < 0.05, "{codec:?} {p} {c}");
            }
        }
        // A block whose counter claims exabytes (this aborted the process before the
        // check): find the first block through the offset table, bump its counter 1.
        let meta = MetaData::read_from_buffered(Cursor::new(&good), false).unwrap();
        let tables = guard::walk_header(&good, 8).unwrap().1;
        assert!(meta.headers[0].chunk_count >= 1);
        let first = u64::from_le_bytes(good[tables..tables + 8].try_into().unwrap());
        let counter = first as usize + 8 + 8;
        let mut bad = good.clone();
        bad[counter..counter + 8].copy_from_slice(&(1u64 << 56).to_le_bytes());
        let err = decode_exr(&bad, "t".as_ref()).unwrap_err();
        assert!(matches!(err, Error::Exr { .. }), "{codec:?}: {err}");
    }
}

#[test]
fn tiled_dwa_is_refused() {
    use ::exr::prelude::Vec2;
    let channels = AnyChannels::sort(SmallVec::from_vec(vec![
        AnyChannel::new("R", FlatSamples::F32(vec![0.5; 64])),
        AnyChannel::new("G", FlatSamples::F32(vec![0.5; 64])),
        AnyChannel::new("B", FlatSamples::F32(vec![0.5; 64])),
    ]));
    let encoding = Encoding {
        compression: Compression::DWAA(None),
        blocks: Blocks::Tiles(Vec2(4, 4)),
        line_order: LineOrder::Increasing,
    };
    let layer = ExrLayer::new((8, 8), LayerAttributes::default(), encoding, channels);
    let bytes = layer_bytes(layer);
    let err = decode_exr(&bytes, "t".as_ref()).unwrap_err();
    assert!(matches!(err, Error::UnsupportedExr { .. }), "{err}");
}

/// A panic inside decoding (the `exr` crate's, on some damaged blocks, in builds with overflow
/// checks) is an error naming the file and carrying the panic's message, in every profile.
#[test]
fn a_panic_inside_decoding_is_a_damaged_file_error() {
    let path = std::path::Path::new("damaged.exr");
    let err =
        read::caught_as_damaged(path, || panic!("attempt to subtract with overflow")).unwrap_err();
    assert!(matches!(err, Error::Exr { .. }), "{err}");
    let msg = err.to_string();
    assert!(msg.starts_with("damaged.exr: "), "{msg}");
    assert!(
        msg.contains("panicked") && msg.contains("subtract with overflow"),
        "{msg}"
    );
    let fine = read::caught_as_damaged(path, || Ok(Image::new(1, 1))).unwrap();
    assert_eq!(fine, Image::new(1, 1));
}
