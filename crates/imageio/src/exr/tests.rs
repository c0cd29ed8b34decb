//! Round trips, foreign files and damaged files.

use std::io::Cursor;

use ::exr::image::{AnyChannel, AnyChannels, Encoding, FlatSamples, Image as ExrImage};
use ::exr::image::{Blocks, Layer as ExrLayer};
use ::exr::meta::attribute::{AttributeValue, Text};
use ::exr::meta::header::LayerAttributes;
use ::exr::meta::MetaData;
use ::exr::prelude::traits::WritableImage;
use ::exr::prelude::{Compression, LineOrder, SmallVec};

use super::*;
use crate::atomic::tests::{entries, scratch_dir};
use crate::{Error, Image, Layer, MetaValue, NameKind};

fn sample_image() -> Image {
    let (w, h) = (5u32, 3u32);
    let n = (w * h) as usize;
    let values = [
        0.0, -0.0, 1.0, -2.5, 1e-30, 1e-42, 65504.0, 1e30, 0.18, -1e-7, 3.25, 7.0, 0.5, 2.0, 100.0,
    ];
    let mut image = Image::new(w, h);
    for (p, px) in image.rgba.iter_mut().enumerate() {
        *px = [
            values[p % values.len()],
            values[(p + 3) % values.len()],
            -values[(p + 7) % values.len()],
            values[(p + 11) % values.len()],
        ];
    }
    image.layers = vec![
        Layer::new(
            "depth",
            &["Z"],
            (0..n).map(|p| p as f32 * 0.25 + 1.0).collect(),
        ),
        Layer::new(
            "normal",
            &["X", "Y", "Z"],
            (0..3 * n).map(|i| (i as f32).sin()).collect(),
        ),
        Layer::new("samples", &["Y"], vec![64.0; n]),
    ];
    image.metadata = vec![
        ("aperture".into(), MetaValue::Float(2.8)),
        ("aperture:radius".into(), MetaValue::Float(0.0125)),
        (
            "camera".into(),
            MetaValue::Text("Camera.001 — ünïcødé".into()),
        ),
        (
            "comments".into(),
            MetaValue::Text("rendered by aperture".into()),
        ),
        ("focus".into(), MetaValue::Float(3.5)),
        ("render:time_s".into(), MetaValue::Float(-0.0)),
        ("samples".into(), MetaValue::Int(64)),
        ("seed".into(), MetaValue::Int(-7)),
    ];
    image
}

#[test]
fn round_trip_is_exact() {
    let image = sample_image();
    let bytes = encode_exr(&image, "t.exr".as_ref()).unwrap();
    let back = decode_exr(&bytes, "t.exr".as_ref()).unwrap();
    assert_eq!(back.width, image.width);
    assert_eq!(back.height, image.height);
    // Bitwise, so -0.0 vs 0.0 and denormals count.
    let bits = |im: &Image| -> Vec<u32> { im.rgba.iter().flatten().map(|v| v.to_bits()).collect() };
    assert_eq!(bits(&back), bits(&image));
    assert_eq!(back.layers, image.layers);
    assert_eq!(back.metadata, image.metadata);
    assert_eq!(back, image);
}

#[test]
fn round_trip_through_a_file() {
    let dir = scratch_dir("exr-file");
    let path = dir.join("out.EXR");
    let image = sample_image();
    crate::write_image(&path, &image, &Default::default()).unwrap();
    assert_eq!(read_exr(&path).unwrap(), image);
    assert_eq!(entries(&dir), vec!["out.EXR".to_string()]);
}

#[test]
fn metadata_comes_back_sorted_and_layers_canonically_ordered() {
    let mut image = sample_image();
    image.metadata.reverse();
    image.layers.reverse();
    image.layers[0].channels.reverse(); // samples: one channel, unchanged
    let back = decode_exr(&encode_exr(&image, "t".as_ref()).unwrap(), "t".as_ref()).unwrap();
    assert_eq!(back, sample_image());
}

#[test]
fn encoding_is_deterministic() {
    let mut image = sample_image();
    for i in 0..40 {
        image
            .metadata
            .push((format!("key{i:02}"), MetaValue::Int(i)));
    }
    let first = encode_exr(&image, "t".as_ref()).unwrap();
    for _ in 0..5 {
        assert_eq!(encode_exr(&image, "t".as_ref()).unwrap(), first);
    }
    assert_eq!(decode_exr(&first, "t".as_ref()).unwrap().metadata.len(), 48);
}

#[test]
fn large_image_round_trips_through_many_blocks() {
    let (w, h) = (37u32, 70u32);
    let mut image = Image::new(w, h);
    for (p, px) in image.rgba.iter_mut().enumerate() {
        let v = (p as f32 * 0.37).sin() * 4.0;
        *px = [v, -v, v * v, 1.0];
    }
    let bytes = encode_exr(&image, "t".as_ref()).unwrap();
    assert_eq!(decode_exr(&bytes, "t".as_ref()).unwrap(), image);
    // Blocks are compressed in parallel but must land in order.
    assert_eq!(encode_exr(&image, "t".as_ref()).unwrap(), bytes);
}

#[test]
fn standard_attribute_with_wrong_type_or_reserved_name_is_refused() {
    for (key, value) in [
        ("focus", MetaValue::Text("near".into())),
        ("owner", MetaValue::Int(3)),
        ("channels", MetaValue::Int(3)),
        ("dataWindow", MetaValue::Text("x".into())),
    ] {
        let mut image = Image::new(1, 1);
        image.metadata.push((key.into(), value));
        let err = encode_exr(&image, "t".as_ref()).unwrap_err();
        assert!(
            matches!(&err, Error::InvalidName { kind: NameKind::Metadata, name, .. } if name == key),
            "{err}"
        );
    }
}

#[test]
fn long_metadata_key_round_trips() {
    let mut image = Image::new(1, 1);
    image.metadata.push(("k".repeat(255), MetaValue::Int(1)));
    let bytes = encode_exr(&image, "t".as_ref()).unwrap();
    assert_eq!(
        decode_exr(&bytes, "t".as_ref()).unwrap().metadata,
        image.metadata
    );
    image.metadata[0].0.push('k');
    assert!(encode_exr(&image, "t".as_ref()).is_err());
}

/// An RGB-only half-float file, as Mitsuba or Blender write, with a bare `Z`.
fn foreign_rgb_half(path_name: &str) -> Vec<u8> {
    use ::exr::prelude::f16;
    let n = 6;
    let channel =
        |name: &str, v: f32| AnyChannel::new(name, FlatSamples::F16(vec![f16::from_f32(v); n]));
    let channels = AnyChannels::sort(SmallVec::from_vec(vec![
        channel("R", 0.5),
        channel("G", 0.25),
        channel("B", 2.0),
        channel("Z", 9.0),
    ]));
    let mut attrs = LayerAttributes {
        software_name: Some(Text::from(path_name)),
        ..Default::default()
    };
    attrs.other.insert(
        Text::from("renderTime"),
        AttributeValue::F64(1.5), // a type this crate skips
    );
    let layer = ExrLayer::new((3, 2), attrs, Encoding::FAST_LOSSLESS, channels);
    let mut bytes = Vec::new();
    ExrImage::from_layer(layer)
        .write()
        .to_buffered(Cursor::new(&mut bytes))
        .unwrap();
    bytes
}

#[test]
fn reads_foreign_rgb_half_without_alpha() {
    let bytes = foreign_rgb_half("mitsuba");
    let image = decode_exr(&bytes, "t".as_ref()).unwrap();
    assert_eq!((image.width, image.height), (3, 2));
    assert!(image.rgba.iter().all(|px| *px == [0.5, 0.25, 2.0, 1.0]));
    assert_eq!(image.layers.len(), 1);
    assert_eq!(image.layers[0].name, "");
    assert_eq!(image.layers[0].channels, vec!["Z".to_string()]);
    assert_eq!(
        image.metadata,
        vec![("software".into(), MetaValue::Text("mitsuba".into()))]
    );
    // And it can be written back.
    encode_exr(&image, "t".as_ref()).unwrap();
}

#[test]
fn reads_blender_multilayer_and_luminance_files() {
    let n = 4;
    let write = |names: &[(&str, f32)]| {
        let channels = AnyChannels::sort(
            names
                .iter()
                .map(|(name, v)| AnyChannel::new(*name, FlatSamples::F32(vec![*v; n])))
                .collect(),
        );
        let layer = ExrLayer::new(
            (2, 2),
            LayerAttributes::default(),
            Encoding::FAST_LOSSLESS,
            channels,
        );
        let mut bytes = Vec::new();
        ExrImage::from_layer(layer)
            .write()
            .to_buffered(Cursor::new(&mut bytes))
            .unwrap();
        bytes
    };
    let blender = write(&[
        ("ViewLayer.Combined.R", 1.0),
        ("ViewLayer.Combined.G", 2.0),
        ("ViewLayer.Combined.B", 3.0),
        ("ViewLayer.Combined.A", 0.5),
        ("ViewLayer.Depth.Z", 7.0),
        ("ViewLayer.Normal.R", 0.0),
        ("ViewLayer.Normal.G", 0.0),
        ("ViewLayer.Normal.B", 1.0),
    ]);
    let image = decode_exr(&blender, "t".as_ref()).unwrap();
    assert!(image.rgba.iter().all(|px| *px == [1.0, 2.0, 3.0, 0.5]));
    let names: Vec<&str> = image.layers.iter().map(|l| l.name.as_str()).collect();
    assert_eq!(names, ["ViewLayer.Depth", "ViewLayer.Normal"]);
    assert_eq!(image.layers[1].channels, ["R", "G", "B"]);
    assert_eq!(image.layers[1].data[..3], [0.0, 0.0, 1.0]);

    let grey = decode_exr(&write(&[("Y", 0.25)]), "t".as_ref()).unwrap();
    assert!(grey.rgba.iter().all(|px| *px == [0.25, 0.25, 0.25, 1.0]));
    assert!(grey.layers.is_empty());

    let none = decode_exr(&write(&[("depth.Z", 1.0)]), "t".as_ref()).unwrap_err();
    assert!(matches!(none, Error::NoBeauty { .. }), "{none}");
}

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
fn read_missing_file_is_io_error() {
    let dir = scratch_dir("exr-missing");
    let err = read_exr(&dir.join("nope.exr")).unwrap_err();
    assert!(matches!(err, Error::Io { .. }), "{err}");
}

#[test]
fn write_into_missing_folder_errors_and_leaves_nothing() {
    let dir = scratch_dir("exr-missing-folder");
    let err = write_exr(&dir.join("sub").join("a.exr"), &sample_image()).unwrap_err();
    assert!(matches!(err, Error::Io { .. }), "{err}");
    assert!(entries(&dir).is_empty());
}

#[test]
fn invalid_image_writes_nothing() {
    let dir = scratch_dir("exr-invalid");
    let mut image = sample_image();
    image.layers[0].data.pop();
    let err = write_exr(&dir.join("a.exr"), &image).unwrap_err();
    assert!(matches!(err, Error::BufferSize { .. }), "{err}");
    assert!(entries(&dir).is_empty());
}

/// A small RGB file (f32 R, half G and B) in the given codec, as another tool writes it.
fn foreign_file(compression: Compression) -> Vec<u8> {
    use ::exr::prelude::{f16, Vec2};
    let (w, h) = (40usize, 37usize);
    let wave: Vec<f32> = (0..w * h).map(|p| (p as f32 * 0.1).sin()).collect();
    let half =
        |scale: f32| FlatSamples::F16(wave.iter().map(|v| f16::from_f32(v * scale)).collect());
    let channels = AnyChannels::sort(SmallVec::from_vec(vec![
        AnyChannel::new("R", FlatSamples::F32(wave.clone())),
        AnyChannel::new("G", half(2.0)),
        AnyChannel::new("B", half(-1.0)),
    ]));
    // Tiles too, for one codec, so the tile path is exercised.
    let blocks = if compression == Compression::RLE {
        Blocks::Tiles(Vec2(16, 16))
    } else {
        Blocks::ScanLines
    };
    let encoding = Encoding {
        compression,
        blocks,
        line_order: LineOrder::Increasing,
    };
    let layer = ExrLayer::new((w, h), LayerAttributes::default(), encoding, channels);
    let mut bytes = Vec::new();
    ExrImage::from_layer(layer)
        .write()
        .to_buffered(Cursor::new(&mut bytes))
        .unwrap();
    bytes
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
    let mut bytes = Vec::new();
    ExrImage::from_layer(layer)
        .write()
        .to_buffered(Cursor::new(&mut bytes))
        .unwrap();
    let err = decode_exr(&bytes, "t".as_ref()).unwrap_err();
    assert!(matches!(err, Error::UnsupportedExr { .. }), "{err}");
}

/// Bit patterns, so NaN payloads, infinities and -0.0 count.
type Bits = (Vec<u32>, Vec<(String, Vec<String>, Vec<u32>)>, Vec<String>);

fn bits(image: &Image) -> Bits {
    let rgba = image.rgba.iter().flatten().map(|v| v.to_bits()).collect();
    let layers = image
        .layers
        .iter()
        .map(|l| {
            let data = l.data.iter().map(|v| v.to_bits()).collect();
            (l.name.clone(), l.channels.clone(), data)
        })
        .collect();
    let meta = image
        .metadata
        .iter()
        .map(|(k, v)| match v {
            MetaValue::Float(f) => format!("{k}=f{:08x}", f.to_bits()),
            other => format!("{k}={other:?}"),
        })
        .collect();
    (rgba, layers, meta)
}

#[test]
fn random_images_round_trip_bit_exactly() {
    let mut x = 2024u64;
    let mut next = move || {
        x = x
            .wrapping_mul(6_364_136_223_846_793_005)
            .wrapping_add(1_442_695_040_888_963_407);
        (x >> 32) as u32
    };
    for case in 0..40 {
        let (w, h) = (1 + next() % 40, 1 + next() % 40);
        let n = (w * h) as usize;
        let mut image = Image::new(w, h);
        for px in &mut image.rgba {
            *px = [0; 4].map(|_| f32::from_bits(next()));
        }
        // Layers sorted by name, channels in the reader's canonical order.
        let sets: [&[&str]; 4] = [&["Z"], &["X", "Y", "Z"], &["R", "G", "B", "A"], &["id"]];
        for name in ["albedo", "depth", "normal"] {
            if next() % 2 == 0 {
                let channels = sets[next() as usize % sets.len()];
                let data = (0..n * channels.len())
                    .map(|_| f32::from_bits(next()))
                    .collect();
                image.layers.push(Layer::new(name, channels, data));
            }
        }
        for i in 0..next() % 6 {
            let value = match next() % 3 {
                0 => MetaValue::Int(next() as i32),
                1 => MetaValue::Float(f32::from_bits(next())),
                _ => MetaValue::Text(
                    (0..next() % 20)
                        .filter_map(|_| char::from_u32(next() % 0x3000))
                        .collect(),
                ),
            };
            image
                .metadata
                .push((format!("m{i}:{}", next() % 100), value));
        }
        let bytes = encode_exr(&image, "t".as_ref()).unwrap();
        let back = decode_exr(&bytes, "t".as_ref()).unwrap();
        assert_eq!((back.width, back.height), (w, h), "case {case}");
        assert_eq!(bits(&back), bits(&image), "case {case}");
    }
}

/// Rows pushed in uneven bands give the same file, byte for byte, as the whole image at once.
#[test]
fn streamed_bands_equal_the_whole_image() {
    let (w, h) = (23u32, 41u32);
    let mut image = Image::new(w, h);
    for (p, px) in image.rgba.iter_mut().enumerate() {
        *px = [p as f32, -(p as f32), 0.5, 1.0];
    }
    let n = (w * h) as usize;
    image.layers.push(Layer::new(
        "Depth",
        &["Z"],
        (0..n).map(|p| p as f32 * 0.5).collect(),
    ));
    image
        .metadata
        .push(("aperture:spp".into(), MetaValue::Int(4)));
    let dir = scratch_dir("exr-streamed");
    let whole = dir.join("whole.exr");
    write_exr(&whole, &image).unwrap();
    let banded = dir.join("banded.exr");
    let layout = ExrLayout {
        width: w,
        height: h,
        placement: None,
        channels: ["R", "G", "B", "A", "Depth.Z"]
            .map(|name| ChannelSpec {
                name: name.into(),
                sample_type: crate::SampleType::F32,
            })
            .into(),
        metadata: image.metadata.clone(),
    };
    write_exr_streamed::<Error>(&banded, &layout, |rows| {
        let mut y = 0;
        for band in [1usize, 7, 16, 3, 14] {
            let mut values = Vec::new();
            for p in y * w as usize..(y + band) * w as usize {
                values.extend_from_slice(&image.rgba[p]);
                values.push(image.layers[0].data[p]);
            }
            rows.push_rows(&values)?;
            y += band;
        }
        assert_eq!(y, h as usize);
        Ok(vec![("aperture:spp".into(), MetaValue::Int(4))])
    })
    .unwrap();
    assert_eq!(
        std::fs::read(&banded).unwrap(),
        std::fs::read(&whole).unwrap()
    );
}

/// A producer that fails, or stops short, leaves no file (and no temporary file) behind.
#[test]
fn failed_or_short_streams_leave_nothing() {
    let dir = scratch_dir("exr-stream-fail");
    let layout = ExrLayout {
        width: 4,
        height: 40,
        channels: vec![ChannelSpec {
            name: "Y".into(),
            sample_type: crate::SampleType::F32,
        }],
        ..ExrLayout::default()
    };
    let path = dir.join("a.exr");
    // Two full blocks written, then an error.
    let err = write_exr_streamed::<Error>(&path, &layout, |rows| {
        rows.push_rows(&[1.0; 4 * 33])?;
        Err(Error::InvalidOption {
            option: "test",
            value: "stop".into(),
            reason: "the producer gave up",
        })
    })
    .unwrap_err();
    assert!(
        matches!(err, Error::InvalidOption { option: "test", .. }),
        "{err}"
    );
    let err = write_exr_streamed::<Error>(&path, &layout, |rows| {
        rows.push_rows(&[1.0; 4 * 39]).map(|()| vec![])
    })
    .unwrap_err();
    assert!(
        matches!(
            err,
            Error::BufferSize {
                expected: 40,
                found: 39,
                ..
            }
        ),
        "{err}"
    );
    let err = write_exr_streamed::<Error>(&path, &layout, |rows| {
        rows.push_rows(&[1.0; 4 * 41]).map(|()| vec![])
    })
    .unwrap_err();
    assert!(matches!(err, Error::BufferSize { .. }), "{err}");
    assert!(entries(&dir).is_empty(), "{:?}", entries(&dir));
}

/// Half layers, a placement inside a larger image, matrices and chromaticities survive a
/// round trip; half rounds to 11 bits.
#[test]
fn half_layers_placement_and_typed_attributes_round_trip() {
    let mut image = Image::new(3, 2);
    image.beauty_type = crate::SampleType::F16;
    for (p, px) in image.rgba.iter_mut().enumerate() {
        *px = [0.1 * p as f32, 1.0 / 3.0, 70000.0, 1.0];
    }
    let mut light = Layer::new("Emission", &["R", "G", "B"], vec![1.0 / 3.0; 18]);
    light.sample_type = crate::SampleType::F16;
    image.layers.push(light);
    image
        .layers
        .push(Layer::new("Depth", &["Z"], vec![1.0 / 3.0; 6]));
    image.placement = Some(crate::Placement {
        x: 5,
        y: 7,
        full_width: 10,
        full_height: 9,
    });
    let m: [f32; 16] = std::array::from_fn(|i| i as f32 * 0.5 - 2.0);
    image.metadata = vec![
        (
            "chromaticities".into(),
            MetaValue::Chromaticities([0.64, 0.33, 0.3, 0.6, 0.15, 0.06, 0.3127, 0.329]),
        ),
        (
            "colorInteropID".into(),
            MetaValue::Text("lin_rec709_scene".into()),
        ),
        ("worldToCamera".into(), MetaValue::Matrix(m)),
        ("worldToNDC".into(), MetaValue::Matrix(m.map(|v| -v))),
    ];
    let back = decode_exr(&encode_exr(&image, "t".as_ref()).unwrap(), "t".as_ref()).unwrap();
    assert_eq!(back.placement, image.placement);
    assert_eq!(back.metadata, image.metadata);
    assert_eq!(back.beauty_type, crate::SampleType::F16);
    assert_eq!(back.layers[0].name, "Depth");
    assert_eq!(back.layers[0].sample_type, crate::SampleType::F32);
    assert_eq!(back.layers[0].data[0], 1.0 / 3.0);
    assert_eq!(back.layers[1].sample_type, crate::SampleType::F16);
    let third = back.layers[1].data[0];
    assert!(
        third != 1.0 / 3.0 && (third - 1.0 / 3.0).abs() < 1e-3,
        "{third}"
    );
    // Above half's range: infinity (callers clamp first, see the renderer's --half).
    assert!(back.rgba[0][2].is_infinite());
    // A placement that does not fit is refused.
    image.placement = Some(crate::Placement {
        x: 8,
        y: 0,
        full_width: 10,
        full_height: 9,
    });
    assert!(encode_exr(&image, "t".as_ref()).is_err());
}

/// Values known only after the pixels replace the layout's placeholders; a late value
/// without a placeholder of its type is an error and leaves no file.
#[test]
fn late_values_are_patched_into_the_header() {
    let dir = scratch_dir("exr-late");
    let mut layout = ExrLayout {
        width: 2,
        height: 2,
        channels: vec![ChannelSpec {
            name: "Y".into(),
            sample_type: crate::SampleType::F32,
        }],
        ..ExrLayout::default()
    };
    layout.metadata = vec![
        ("aperture:renderTime".into(), MetaValue::Float(0.0)),
        ("aperture:droppedSamples".into(), MetaValue::Int(0)),
        ("aperture:camera".into(), MetaValue::Text("cam".into())),
    ];
    let path = dir.join("late.exr");
    write_exr_streamed::<Error>(&path, &layout, |rows| {
        rows.push_rows(&[0.5; 4])?;
        Ok(vec![
            ("aperture:renderTime".into(), MetaValue::Float(12.5)),
            ("aperture:droppedSamples".into(), MetaValue::Int(-3)),
        ])
    })
    .unwrap();
    let back = read_exr(&path).unwrap();
    assert_eq!(
        back.meta("aperture:renderTime"),
        Some(&MetaValue::Float(12.5))
    );
    assert_eq!(
        back.meta("aperture:droppedSamples"),
        Some(&MetaValue::Int(-3))
    );
    std::fs::remove_file(&path).unwrap();
    for bad in [
        ("aperture:renderTime", MetaValue::Int(1)),
        ("aperture:missing", MetaValue::Float(1.0)),
        ("aperture:camera", MetaValue::Float(1.0)),
    ] {
        let err = write_exr_streamed::<Error>(&path, &layout, |rows| {
            rows.push_rows(&[0.5; 4])?;
            Ok(vec![(bad.0.into(), bad.1.clone())])
        })
        .unwrap_err();
        assert!(matches!(err, Error::InvalidName { .. }), "{err}");
    }
    assert!(entries(&dir).is_empty());
}

/// The header alone says what the whole read says about size, placement, channels and
/// metadata; a truncated header is an error naming the file, a truncated body is not
/// noticed (only the pixel read finds it).
#[test]
fn header_alone_matches_the_whole_read() {
    let dir = scratch_dir("header-only");
    let path = dir.join("part.exr");
    let mut image = sample_image();
    image.placement = Some(crate::Placement {
        x: 2,
        y: 4,
        full_width: 9,
        full_height: 8,
    });
    image.layers[0].sample_type = crate::SampleType::F16;
    crate::write_exr(&path, &image).unwrap();
    let whole = read_exr(&path).unwrap();
    let header = read_exr_header(&path).unwrap();
    assert_eq!((header.width, header.height), (whole.width, whole.height));
    assert_eq!(header.placement, whole.placement);
    assert_eq!(header.metadata, whole.metadata);
    assert_eq!(header.meta("samples"), Some(&MetaValue::Int(64)));
    let names: Vec<&str> = header.channels.iter().map(|c| c.name.as_str()).collect();
    assert_eq!(names[..4], ["A", "B", "G", "R"]);
    assert!(names.contains(&"depth.Z") && names.contains(&"normal.Y"));
    let depth = header
        .channels
        .iter()
        .find(|c| c.name == "depth.Z")
        .unwrap();
    assert_eq!(depth.sample_type, crate::SampleType::F16);

    let bytes = std::fs::read(&path).unwrap();
    let cut = dir.join("cut.exr");
    std::fs::write(&cut, &bytes[..40]).unwrap();
    let err = read_exr_header(&cut).unwrap_err();
    assert!(err.to_string().contains("cut.exr"), "{err}");
    std::fs::write(&cut, &bytes[..bytes.len() - 10]).unwrap();
    assert!(read_exr_header(&cut).is_ok());
    assert!(read_exr(&cut).is_err());
}
