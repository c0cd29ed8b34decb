//! On disk: missing files and folders, streamed bands, late header values, the header alone.

use super::*;

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
                sample_type: crate::model::SampleType::F32,
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
            sample_type: crate::model::SampleType::F32,
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
            sample_type: crate::model::SampleType::F32,
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
    image.placement = Some(crate::model::Placement {
        x: 2,
        y: 4,
        full_width: 9,
        full_height: 8,
    });
    image.layers[0].sample_type = crate::model::SampleType::F16;
    crate::exr::write_exr(&path, &image).unwrap();
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
    assert_eq!(depth.sample_type, crate::model::SampleType::F16);

    let bytes = std::fs::read(&path).unwrap();
    let cut = dir.join("cut.exr");
    std::fs::write(&cut, &bytes[..40]).unwrap();
    let err = read_exr_header(&cut).unwrap_err();
    assert!(err.to_string().contains("cut.exr"), "{err}");
    std::fs::write(&cut, &bytes[..bytes.len() - 10]).unwrap();
    assert!(read_exr_header(&cut).is_ok());
    assert!(read_exr(&cut).is_err());
}
