//! The EXR reader's and writer's tests, by topic; the sample images they share are here.

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
use crate::error::{Error, NameKind};
use crate::model::{Image, Layer, MetaValue};

mod damaged;
mod files;
mod foreign;
mod round_trip;

/// One layer written as an EXR file in memory.
fn layer_bytes(layer: ExrLayer<AnyChannels<FlatSamples>>) -> Vec<u8> {
    let mut bytes = Vec::new();
    ExrImage::from_layer(layer)
        .write()
        .to_buffered(Cursor::new(&mut bytes))
        .unwrap();
    bytes
}

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
    layer_bytes(layer)
}
