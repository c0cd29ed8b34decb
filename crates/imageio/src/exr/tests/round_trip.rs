//! Round trips: exact values, metadata, many blocks, random images, half layers, placements.

use super::*;

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
    crate::format::write_image(&path, &image, &Default::default()).unwrap();
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

/// Half layers, a placement inside a larger image, matrices and chromaticities survive a
/// round trip; half rounds to 11 bits.
#[test]
fn half_layers_placement_and_typed_attributes_round_trip() {
    let mut image = Image::new(3, 2);
    image.beauty_type = crate::model::SampleType::F16;
    for (p, px) in image.rgba.iter_mut().enumerate() {
        *px = [0.1 * p as f32, 1.0 / 3.0, 70000.0, 1.0];
    }
    let mut light = Layer::new("Emission", &["R", "G", "B"], vec![1.0 / 3.0; 18]);
    light.sample_type = crate::model::SampleType::F16;
    image.layers.push(light);
    image
        .layers
        .push(Layer::new("Depth", &["Z"], vec![1.0 / 3.0; 6]));
    image.placement = Some(crate::model::Placement {
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
    assert_eq!(back.beauty_type, crate::model::SampleType::F16);
    assert_eq!(back.layers[0].name, "Depth");
    assert_eq!(back.layers[0].sample_type, crate::model::SampleType::F32);
    assert_eq!(back.layers[0].data[0], 1.0 / 3.0);
    assert_eq!(back.layers[1].sample_type, crate::model::SampleType::F16);
    let third = back.layers[1].data[0];
    assert!(
        third != 1.0 / 3.0 && (third - 1.0 / 3.0).abs() < 1e-3,
        "{third}"
    );
    // Above half's range: infinity (callers clamp first, see the renderer's --half).
    assert!(back.rgba[0][2].is_infinite());
    // A placement that does not fit is refused.
    image.placement = Some(crate::model::Placement {
        x: 8,
        y: 0,
        full_width: 10,
        full_height: 9,
    });
    assert!(encode_exr(&image, "t".as_ref()).is_err());
}
