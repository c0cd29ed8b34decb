//! The bokeh images (`aperture_image`) of a file's cameras, loaded with the file: a path
//! relative to the glTF file (as its images' URIs, never outside its folder), a texture index of
//! the file, or a command-line path; and again after an edit of the key, which reads only the
//! image it names (the others are kept). Posing looks them up by reference; nothing is read then.

use std::collections::HashMap;
use std::path::Path;
use std::sync::Arc;

use serde_json::Value;

use super::layer::{aperture_image, Ctx, ImageRef};
use crate::error::Error;
use crate::types::{ApertureImage, Texels};

/// The loaded bokeh images, by what names them.
pub(crate) type ApertureImages = HashMap<ImageRef, Arc<ApertureImage>>;

/// Where the file's images come from, for [`load_all`].
pub(crate) struct Sources<'a> {
    /// The document and its buffers, for a texture index: only while the file is loaded (an
    /// edit naming a texture not loaded then loads the file again, [`needs_file`]).
    pub file: Option<(&'a gltf::Document, &'a crate::accessor::Buffers<'a>)>,
    pub base_dir: &'a Path,
    /// Skip decoding (`info`): each image is a 1×1 white placeholder.
    pub skip: bool,
    pub budget: &'a aperture_budget::MemoryBudget,
}

/// Every image a camera's `extras`, its node's `extras` or the command line names: taken from
/// `kept` (the images loaded before) when there, else loaded. `cameras`: per glTF camera, its
/// name for messages and its `extras`; `nodes`: per camera node, the camera's name and the
/// node's `extras`. A bad value or an unreadable image is an error naming the camera, the key
/// and the value.
pub(crate) fn load_all(
    src: &Sources<'_>,
    cameras: &[(String, Option<&Value>)],
    nodes: &[(String, Option<&Value>)],
    command_line: Option<&Path>,
    kept: &ApertureImages,
) -> Result<ApertureImages, Error> {
    let mut out = ApertureImages::new();
    let sources = [(cameras, "cameras.extras."), (nodes, "nodes.extras.")];
    for (list, prefix) in sources {
        for (camera, extras) in list {
            let ctx = Ctx {
                camera,
                prefix,
                base_dir: src.base_dir,
            };
            // Only this key: the others (a lens file among them) are read when posing.
            let value = extras.and_then(|e| e.get("aperture_image"));
            if let Some(r) = value
                .map(|v| aperture_image("aperture_image", v, &ctx))
                .transpose()?
            {
                if let std::collections::hash_map::Entry::Vacant(slot) = out.entry(r) {
                    let image = match kept.get(slot.key()) {
                        Some(image) => Arc::clone(image),
                        None => Arc::new(
                            load(src, slot.key()).map_err(|e| image_error(&ctx, slot.key(), e))?,
                        ),
                    };
                    slot.insert(image);
                }
            }
        }
    }
    if let Some(path) = command_line {
        let r = ImageRef::File(path.to_path_buf());
        let ctx = Ctx {
            camera: "every camera",
            prefix: "command line ",
            base_dir: src.base_dir,
        };
        let image = match kept.get(&r) {
            Some(image) => Arc::clone(image),
            None => Arc::new(load(src, &r).map_err(|e| image_error(&ctx, &r, e))?),
        };
        out.insert(r, image);
    }
    Ok(out)
}

/// True when an `aperture_image` value names a texture of the file that `kept` lacks: only a
/// load of the file can read it (a path is read from the file's folder at any time).
pub(crate) fn needs_file(value: &Value, kept: &ApertureImages) -> bool {
    let texture = value.as_u64().and_then(|i| usize::try_from(i).ok());
    texture.is_some_and(|i| !kept.contains_key(&ImageRef::Texture(i)))
}

/// What an edit setting an `aperture_image` to `value` keeps of `kept`: all but the image a
/// path names, which the edit reads again (the file may have changed since it was read).
pub(crate) fn kept_for_edit(value: &Value, kept: &ApertureImages) -> ApertureImages {
    let mut out = kept.clone();
    if let Value::String(path) = value {
        out.remove(&ImageRef::Uri(path.clone()));
    }
    out
}

/// An image's error as the key's.
fn image_error(ctx: &Ctx<'_>, r: &ImageRef, e: Error) -> Error {
    ctx.err("aperture_image", r, &e.to_string())
}

/// Reads and decodes one image as transmissions.
fn load(src: &Sources<'_>, r: &ImageRef) -> Result<ApertureImage, Error> {
    let source = match r {
        ImageRef::Uri(u) => u.clone(),
        ImageRef::Texture(i) => format!("texture {i}"),
        ImageRef::File(p) => p.display().to_string(),
    };
    let bytes: Vec<u8> = match r {
        ImageRef::Uri(u) => crate::uri::load(src.base_dir, u, "aperture_image")?,
        ImageRef::File(p) => std::fs::read(p).map_err(|source| Error::MissingFile {
            at: "aperture_image".into(),
            path: p.clone(),
            source,
        })?,
        ImageRef::Texture(i) => {
            let (doc, buffers) = src.file.ok_or_else(|| Error::Invalid {
                at: "aperture_image".into(),
                reason: "a texture's image is read with the file: load the file again".into(),
            })?;
            let tex = doc.textures().nth(*i).ok_or_else(|| Error::Invalid {
                at: "aperture_image".into(),
                reason: format!("no textures[{i}] (the file has {})", doc.textures().len()),
            })?;
            let image = tex.source().index();
            crate::texels::image_bytes(doc, buffers, src.base_dir, image)?.into_owned()
        }
    };
    if src.skip {
        return Ok(from_texels(source, 1, 1, &Texels::Rgba8(vec![[255; 4]])));
    }
    let (w, h, texels) = crate::texels::decode_texture(&bytes, 0, src.budget.limit)?;
    let image = from_texels(source, w, h, &texels);
    if !image.luminance.iter().any(|&l| l > 0.0) {
        return Err(Error::Invalid {
            at: "aperture_image".into(),
            reason: "the image is black: no light would pass the aperture".into(),
        });
    }
    Ok(image)
}

/// Transmissions of decoded texels: Rec.709 luminance of the stored values (no colour
/// transform: the image is data, like Blender's Non-Color), times alpha.
fn from_texels(source: String, width: u32, height: u32, t: &Texels) -> ApertureImage {
    let lum = |[r, g, b, a]: [f32; 4]| (0.2126 * r + 0.7152 * g + 0.0722 * b) * a;
    let luminance: Vec<f32> = match t {
        Texels::Rgba8(v) => v
            .iter()
            .map(|c| lum(c.map(|x| f32::from(x) / 255.0)))
            .collect(),
        Texels::Rgba32F(v) => v.iter().map(|&c| lum(c)).collect(),
    };
    ApertureImage::new(source, width, height, luminance).unwrap_or(ApertureImage {
        source: String::new(),
        width: 1,
        height: 1,
        luminance: vec![1.0],
        hash: 0,
    })
}
