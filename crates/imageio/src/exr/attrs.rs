//! Header attributes: metadata in and out of the EXR header, and sorting the written header.

use ::exr::math::Vec2;
use ::exr::meta::attribute::{AttributeValue, Chromaticities, Matrix4x4, Text};
use ::exr::meta::header::{standard_names, ImageAttributes, LayerAttributes};

use super::guard;
use crate::error::{Error, NameKind};
use crate::model::MetaValue;

/// EXR text holds bytes; storing UTF-8 keeps any Rust string exact. `Text::from(&str)` would
/// panic on characters above U+00FF.
pub(super) fn text(s: &str) -> Text {
    Text::from_slice_unchecked(s.as_bytes())
}

/// UTF-8 when valid (what this crate and Blender write), otherwise Latin-1, which the EXR
/// text type was meant as; never fails.
pub(super) fn string(bytes: &[u8]) -> String {
    match std::str::from_utf8(bytes) {
        Ok(s) => s.to_owned(),
        Err(_) => bytes.iter().map(|&b| char::from(b)).collect(),
    }
}

/// The standard attributes with a plain text type, by file name.
fn text_fields(a: &mut LayerAttributes) -> [(&'static str, &mut Option<Text>); 8] {
    [
        ("owner", &mut a.owner),
        ("comments", &mut a.comments),
        ("capDate", &mut a.capture_date),
        ("software", &mut a.software_name),
        ("renderingTransform", &mut a.rendering_transform_name),
        ("lookModTransform", &mut a.look_modification_transform_name),
        ("wrapmodes", &mut a.wrap_mode_name),
        ("view", &mut a.view_name),
    ]
}

/// The standard attributes with a plain f32 type, by file name.
fn float_fields(a: &mut LayerAttributes) -> [(&'static str, &mut Option<f32>); 14] {
    [
        ("whiteLuminance", &mut a.white_luminance),
        ("xDensity", &mut a.horizontal_density),
        ("utcOffset", &mut a.utc_offset),
        ("longitude", &mut a.longitude),
        ("latitude", &mut a.latitude),
        ("altitude", &mut a.altitude),
        ("focus", &mut a.focus),
        ("expTime", &mut a.exposure),
        ("aperture", &mut a.aperture),
        ("isoSpeed", &mut a.iso_speed),
        ("near", &mut a.near_clip_plane),
        ("far", &mut a.far_clip_plane),
        ("fieldOfViewHorizontal", &mut a.horizontal_field_of_view),
        ("fieldOfViewVertical", &mut a.vertical_field_of_view),
    ]
}

/// Stores one metadata entry: in its standard field when the name is a standard attribute
/// (the decoder would move it there anyway), else as a custom attribute.
pub(super) fn set_attribute(
    image: &mut ImageAttributes,
    attrs: &mut LayerAttributes,
    key: &str,
    value: &MetaValue,
) -> Result<(), Error> {
    let refuse = |reason| Error::InvalidName {
        kind: NameKind::Metadata,
        name: key.to_owned(),
        reason,
    };
    if let Some((_, slot)) = text_fields(attrs).into_iter().find(|(n, _)| *n == key) {
        let MetaValue::Text(s) = value else {
            return Err(refuse("standard EXR attribute of text type"));
        };
        *slot = Some(text(s));
        return Ok(());
    }
    if let Some((_, slot)) = float_fields(attrs).into_iter().find(|(n, _)| *n == key) {
        let MetaValue::Float(f) = value else {
            return Err(refuse("standard EXR attribute of float type"));
        };
        *slot = Some(*f);
        return Ok(());
    }
    if let Some((_, slot)) = matrix_fields(attrs).into_iter().find(|(n, _)| *n == key) {
        let MetaValue::Matrix(m) = value else {
            return Err(refuse("standard EXR attribute of m44f type"));
        };
        *slot = Some(*m);
        return Ok(());
    }
    if key == "chromaticities" {
        let MetaValue::Chromaticities(c) = value else {
            return Err(refuse("standard EXR attribute of chromaticities type"));
        };
        image.chromaticities = Some(Chromaticities {
            red: Vec2(c[0], c[1]),
            green: Vec2(c[2], c[3]),
            blue: Vec2(c[4], c[5]),
            white: Vec2(c[6], c[7]),
        });
        return Ok(());
    }
    if standard_names::ALL.contains(&key.as_bytes()) {
        return Err(refuse("reserved by the EXR format"));
    }
    let value = match value {
        MetaValue::Text(s) => AttributeValue::Text(text(s)),
        MetaValue::Float(f) => AttributeValue::F32(*f),
        MetaValue::Int(i) => AttributeValue::I32(*i),
        MetaValue::Matrix(m) => AttributeValue::Matrix4x4(*m),
        MetaValue::Chromaticities(_) => {
            return Err(refuse(
                "chromaticities may only be stored as `chromaticities`",
            ))
        }
    };
    attrs.other.insert(text(key), value);
    Ok(())
}

/// The standard attributes with an m44f type, by file name.
fn matrix_fields(a: &mut LayerAttributes) -> [(&'static str, &mut Option<Matrix4x4>); 2] {
    [
        ("worldToCamera", &mut a.world_to_camera),
        ("worldToNDC", &mut a.world_to_normalized_device),
    ]
}

/// The file's chromaticities as metadata, if it has them.
pub(super) fn chromaticities(image: &ImageAttributes) -> Option<(String, MetaValue)> {
    image.chromaticities.map(|c| {
        let v = [
            c.red.0, c.red.1, c.green.0, c.green.1, c.blue.0, c.blue.1, c.white.0, c.white.1,
        ];
        ("chromaticities".to_owned(), MetaValue::Chromaticities(v))
    })
}

/// The metadata a part's attributes hold: custom text/f32/i32 ones and the plain standard ones.
pub(super) fn get_attributes(attrs: &LayerAttributes) -> Vec<(String, MetaValue)> {
    let mut copy = attrs.clone();
    let mut out = Vec::new();
    for (name, slot) in text_fields(&mut copy) {
        if let Some(t) = slot {
            out.push((name.to_owned(), MetaValue::Text(string(t.as_slice()))));
        }
    }
    for (name, slot) in float_fields(&mut copy) {
        if let Some(f) = slot {
            out.push((name.to_owned(), MetaValue::Float(*f)));
        }
    }
    for (name, slot) in matrix_fields(&mut copy) {
        if let Some(m) = slot {
            out.push((name.to_owned(), MetaValue::Matrix(*m)));
        }
    }
    for (name, value) in &attrs.other {
        if let Some(value) = meta_value(value) {
            out.push((string(name.as_slice()), value));
        }
    }
    out
}

pub(super) fn meta_value(value: &AttributeValue) -> Option<MetaValue> {
    match value {
        AttributeValue::Text(t) => Some(MetaValue::Text(string(t.as_slice()))),
        AttributeValue::F32(f) => Some(MetaValue::Float(*f)),
        AttributeValue::I32(i) => Some(MetaValue::Int(*i)),
        AttributeValue::Matrix4x4(m) => Some(MetaValue::Matrix(*m)),
        _ => None,
    }
}

/// Sorts the attributes of a single-part EXR header by name, in place. The header keeps its
/// length, so the chunk offsets after it stay valid. Returns false (bytes untouched) when the
/// layout is not the simple one this crate writes.
pub(super) fn sort_header_attributes(bytes: &mut [u8]) -> bool {
    const MULTIPART: u32 = 0x1000;
    if bytes.len() < 8 || bytes[..4] != [0x76, 0x2f, 0x31, 0x01] {
        return false;
    }
    let flags = u32::from_le_bytes([bytes[4], bytes[5], bytes[6], bytes[7]]);
    if flags & MULTIPART != 0 {
        return false;
    }
    let Some((records, after)) = guard::walk_header(bytes, 8) else {
        return false;
    };
    // The header's closing NUL stays where it is.
    let at = after - 1;
    let (start, end) = (8, at);
    let mut sorted_records = records;
    sorted_records.sort_by(|a, b| bytes[a.0..a.1].cmp(&bytes[b.0..b.1]));
    let mut header = Vec::with_capacity(end - start);
    for &(s, _, e) in &sorted_records {
        header.extend_from_slice(&bytes[s..e]);
    }
    bytes[start..end].copy_from_slice(&header);
    true
}

/// Overwrites the value of the header attribute `key` in the EXR `bytes` (a single-part file
/// this crate wrote) with `value`, which must have the attribute's type and size (an f32 or
/// i32): how values known only after the pixels (render time) reach a header written before
/// them. Returns false, changing nothing, when there is no such attribute of that type.
pub(super) fn patch_attribute(bytes: &mut [u8], key: &str, value: &MetaValue) -> bool {
    let Some((records, _)) = guard::walk_header(bytes, 8) else {
        return false;
    };
    let (kind, new): (&[u8], [u8; 4]) = match value {
        MetaValue::Float(f) => (b"float", f.to_le_bytes()),
        MetaValue::Int(i) => (b"int", i.to_le_bytes()),
        _ => return false,
    };
    for (start, name_end, end) in records {
        let name = &bytes[start..name_end];
        let type_start = name_end + 1;
        let type_end = type_start + kind.len();
        if name == key.as_bytes()
            && bytes.get(type_start..type_end) == Some(kind)
            && bytes.get(type_end) == Some(&0)
            && end == type_end + 1 + 4 + 4
        {
            bytes[end - 4..end].copy_from_slice(&new);
            return true;
        }
    }
    false
}
