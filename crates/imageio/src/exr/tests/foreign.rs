//! Files other tools write: RGB half without alpha, Blender multilayer, luminance.

use super::*;

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
    layer_bytes(layer)
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
        layer_bytes(layer)
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
    assert_eq!(image.beauty_layer, "ViewLayer.Combined");
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

/// Blender 5 writes a multilayer EXR as one part per pass, each named as its layer and holding
/// channels with their full names (`ViewLayer.Depth.Z` in part `ViewLayer.Depth`).
#[test]
fn reads_blender_5_multi_part_files() {
    let n = 4;
    let part = |name: &str, channels: &[(&str, f32)]| {
        let list = channels
            .iter()
            .map(|(c, v)| {
                AnyChannel::new(
                    Text::from(format!("{name}.{c}").as_str()),
                    FlatSamples::F32(vec![*v; n]),
                )
            })
            .collect();
        ExrLayer::new(
            (2, 2),
            LayerAttributes::named(name),
            Encoding::FAST_LOSSLESS,
            AnyChannels::sort(list),
        )
    };
    let layers: SmallVec<[_; 2]> = [
        part(
            "ViewLayer.Combined",
            &[("R", 1.0), ("G", 2.0), ("B", 3.0), ("A", 0.5)],
        ),
        part("ViewLayer.Depth", &[("Z", 7.0)]),
        part(
            "ViewLayer.Denoising Albedo",
            &[("R", 0.1), ("G", 0.2), ("B", 0.3)],
        ),
    ]
    .into_iter()
    .collect();
    let mut bytes = Vec::new();
    ExrImage::from_layers(
        ::exr::meta::header::ImageAttributes::new(::exr::prelude::IntegerBounds::from_dimensions(
            (2, 2),
        )),
        layers,
    )
    .write()
    .to_buffered(Cursor::new(&mut bytes))
    .unwrap();
    let image = decode_exr(&bytes, "t".as_ref()).unwrap();
    assert!(image.rgba.iter().all(|px| *px == [1.0, 2.0, 3.0, 0.5]));
    let names: Vec<&str> = image.layers.iter().map(|l| l.name.as_str()).collect();
    assert_eq!(names, ["ViewLayer.Denoising Albedo", "ViewLayer.Depth"]);
    assert_eq!(image.layers[0].channels, ["R", "G", "B"]);
    let dir = scratch_dir("blender5");
    let path = dir.join("multi.exr");
    std::fs::write(&path, &bytes).unwrap();
    let names: Vec<String> = read_exr_header(&path)
        .unwrap()
        .channels
        .into_iter()
        .map(|c| c.name)
        .collect();
    assert!(names.iter().any(|c| c == "ViewLayer.Depth.Z"), "{names:?}");
}
