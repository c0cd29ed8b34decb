//! The crate root's tests: formats by extension, image validation.

use super::*;

#[test]
fn format_by_extension_is_case_insensitive() {
    assert_eq!(Format::from_path("a/b.EXR".as_ref()).unwrap(), Format::Exr);
    assert_eq!(Format::from_path("b.Png".as_ref()).unwrap(), Format::Png);
    for bad in ["b.jpg", "b", "exr", "b.exr.tmp", ".png.x"] {
        assert!(
            matches!(
                Format::from_path(bad.as_ref()),
                Err(Error::UnknownFormat { .. })
            ),
            "{bad}"
        );
    }
}

#[test]
fn write_image_refuses_unknown_extension_and_writes_nothing() {
    let dir = atomic::tests::scratch_dir("unknown-ext");
    let path = dir.join("out.jpg");
    let err = write_image(&path, &Image::new(1, 1), &PngOptions::default()).unwrap_err();
    assert!(matches!(err, Error::UnknownFormat { .. }));
    assert!(atomic::tests::entries(&dir).is_empty());
}

#[test]
fn validate_catches_bad_buffers_and_names() {
    let good = Image::new(2, 1);
    good.validate().unwrap();

    let mut short = good.clone();
    short.rgba.pop();
    assert!(matches!(
        short.validate(),
        Err(Error::BufferSize {
            expected: 2,
            found: 1,
            ..
        })
    ));

    assert!(matches!(
        Image::new(0, 3).validate(),
        Err(Error::EmptyImage { .. })
    ));

    let layer = |name: &str, channels: &[&str], n: usize| Layer::new(name, channels, vec![0.0; n]);
    let cases = [
        (layer("depth", &["Z"], 3), "data size"),
        (layer("depth", &["a.b"], 2), "dot in channel"),
        (layer("depth", &[""], 2), "empty channel"),
        (layer("", &["R"], 2), "clashes with beauty"),
        (layer("n", &[], 0), "no channels"),
    ];
    for (bad, why) in cases {
        let mut image = good.clone();
        image.layers.push(bad);
        assert!(image.validate().is_err(), "{why}");
    }

    let mut twice = good.clone();
    twice.layers.push(layer("depth", &["Z"], 2));
    twice.layers.push(layer("depth", &["Z"], 2));
    assert!(matches!(
        twice.validate(),
        Err(Error::InvalidName {
            kind: NameKind::Channel,
            ..
        })
    ));

    let mut meta = good.clone();
    meta.metadata.push(("k".into(), MetaValue::Int(1)));
    meta.metadata.push(("k".into(), MetaValue::Int(2)));
    assert!(matches!(
        meta.validate(),
        Err(Error::InvalidName {
            kind: NameKind::Metadata,
            ..
        })
    ));
    meta.metadata.truncate(1);
    meta.metadata.push((String::new(), MetaValue::Int(2)));
    assert!(meta.validate().is_err());
}
