//! The JSON pre-pass: runs on the raw JSON before the `gltf` crate sees it.
//!
//! 1. `extensionsRequired` is compared with what we implement, before any buffer is read, so an
//!    unsupported file fails fast with the extension's name.
//! 2. Animations are taken out of what the `gltf` crate sees: Blender's exporter writes channels
//!    without `target.node` (`KHR_animation_pointer`), which the typed parser refuses; the loader
//!    reads them from the kept JSON instead (`animation.rs`).
//! 3. The edited JSON is deserialised and validated by the `gltf` crate.

use serde_json::Value;

use crate::error::Error;

/// Extensions we implement, so a file may require them.
pub const SUPPORTED_EXTENSIONS: &[&str] = &[
    "KHR_lights_punctual",
    "KHR_materials_emissive_strength",
    "KHR_texture_transform",
    "KHR_materials_unlit",
    "KHR_mesh_quantization",
    "EXT_mesh_gpu_instancing",
    "EXT_lights_image_based",
    "KHR_materials_ior",
    "KHR_materials_specular",
    "KHR_draco_mesh_compression",
    "EXT_meshopt_compression",
    "KHR_meshopt_compression",
    "KHR_node_visibility",
    "KHR_animation_pointer",
    "KHR_materials_transmission",
    "KHR_materials_volume",
    "KHR_materials_clearcoat",
    "KHR_materials_sheen",
    "KHR_materials_anisotropy",
    "KHR_materials_iridescence",
    "KHR_materials_dispersion",
    "KHR_materials_diffuse_transmission",
    "KHR_materials_variants",
    "KHR_materials_pbrSpecularGlossiness",
    "EXT_texture_webp",
    "KHR_texture_basisu",
];

/// What aperture does with an extension a file uses.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum ExtensionStatus {
    /// Implemented (in [`SUPPORTED_EXTENSIONS`]).
    Supported,
    /// Not implemented and optional (not in `extensionsRequired`): the file renders without it.
    Ignored,
}

/// The validated document plus what the pre-pass removed.
pub(crate) struct Prepared {
    pub document: gltf::Document,
    /// The file's JSON as written (animations, pointers and extension objects are read from it),
    /// except that `nodes` holds one `null` per node (see `COUNTED_ONLY`).
    pub root: Value,
    pub skipped: Vec<String>,
    /// Every extension of `extensionsUsed`, with its status.
    pub extensions: Vec<(String, ExtensionStatus)>,
}

/// Every extension of `extensionsUsed` with its status.
fn extension_statuses(root: &Value) -> Vec<(String, ExtensionStatus)> {
    let used = root.get("extensionsUsed").and_then(Value::as_array);
    let names = used.into_iter().flatten().filter_map(Value::as_str);
    names
        .map(|e| match SUPPORTED_EXTENSIONS.contains(&e) {
            true => (e.to_owned(), ExtensionStatus::Supported),
            false => (e.to_owned(), ExtensionStatus::Ignored),
        })
        .collect()
}

/// The names of the extensions `extensions` marks ignored (optional, not implemented).
pub(crate) fn ignored(extensions: &[(String, ExtensionStatus)]) -> Vec<&str> {
    (extensions.iter())
        .filter(|(_, s)| *s == ExtensionStatus::Ignored)
        .map(|(e, _)| e.as_str())
        .collect()
}

/// Refuses required extensions we do not implement. Runs on the raw JSON, before anything else.
pub(crate) fn check_required(root: &Value) -> Result<(), Error> {
    let Some(required) = root.get("extensionsRequired") else {
        return Ok(());
    };
    let Some(list) = required.as_array() else {
        return Err(Error::Invalid {
            at: "extensionsRequired".into(),
            reason: "not an array".into(),
        });
    };
    for (index, name) in list.iter().enumerate() {
        let Some(name) = name.as_str() else {
            return Err(Error::Invalid {
                at: format!("extensionsRequired[{index}]"),
                reason: format!("{name} is not a string"),
            });
        };
        if !SUPPORTED_EXTENSIONS.contains(&name) {
            return Err(Error::UnsupportedExtension {
                name: name.to_owned(),
                index,
            });
        }
    }
    Ok(())
}

fn len_of(root: &Value, key: &str) -> usize {
    root.get(key).and_then(Value::as_array).map_or(0, Vec::len)
}

/// The `gltf` crate's validation indexes `accessors` with a primitive's `POSITION` before it
/// checks the index, and panics on a bad one: check it first.
fn check_position_indices(root: &Value) -> Result<(), Error> {
    let accessors = len_of(root, "accessors");
    let meshes = root.get("meshes").and_then(Value::as_array);
    for (m, mesh) in meshes.into_iter().flatten().enumerate() {
        let prims = mesh.get("primitives").and_then(Value::as_array);
        for (p, prim) in prims.into_iter().flatten().enumerate() {
            let pos = prim.get("attributes").and_then(|a| a.get("POSITION"));
            if let Some(i) = pos.and_then(Value::as_u64) {
                if i >= accessors as u64 {
                    return Err(Error::Invalid {
                        at: format!("meshes[{m}].primitives[{p}].attributes.POSITION"),
                        reason: format!("accessor {i} does not exist ({accessors} accessors)"),
                    });
                }
            }
        }
    }
    Ok(())
}

/// Shapes the `gltf` crate's typed accessors unwrap without its validation checking them.
/// - A camera's `type` names the projection object it reads.
/// - An image has a `uri` or a `bufferView`; with a `bufferView` it must have a `mimeType`, which
///   some exporters omit: we sniff the format from the bytes anyway, so a neutral one is supplied.
fn check_shapes_the_typed_api_assumes(root: &mut Value) -> Result<(), Error> {
    let cameras = root.get("cameras").and_then(Value::as_array);
    for (i, cam) in cameras.into_iter().flatten().enumerate() {
        if let Some(kind @ ("perspective" | "orthographic")) =
            cam.get("type").and_then(Value::as_str)
        {
            if cam.get(kind).is_none_or(Value::is_null) {
                return Err(Error::Invalid {
                    at: format!("cameras[{i}].{kind}"),
                    reason: format!("missing, but the camera's type is {kind}"),
                });
            }
        }
    }
    let images = root.get_mut("images").and_then(Value::as_array_mut);
    for (i, image) in images.into_iter().flatten().enumerate() {
        let Some(obj) = image.as_object_mut() else {
            continue;
        };
        // serde reads an explicit null as absent.
        let given =
            |o: &serde_json::Map<String, Value>, k: &str| o.get(k).is_some_and(|v| !v.is_null());
        if given(obj, "bufferView") {
            if !given(obj, "mimeType") {
                obj.insert("mimeType".into(), Value::from("application/octet-stream"));
            }
        } else if !given(obj, "uri") {
            return Err(Error::Invalid {
                at: format!("images[{i}]"),
                reason: "neither uri nor bufferView".into(),
            });
        }
    }
    Ok(())
}

/// `EXT_texture_webp`: a texture's WebP image replaces its core `source` (which is a fallback
/// for viewers without WebP, and absent when the file requires the extension, as Blender writes
/// it). Both show the same picture; we decode WebP.
///
/// `KHR_texture_basisu`: its KTX2 image is used only where the texture has no core `source`.
/// Where it has one, that image is the original the KTX2 was encoded from (Basis Universal is
/// lossy), so it is the more accurate of the two.
fn use_extension_sources(root: &mut Value) {
    let textures = root.get_mut("textures").and_then(Value::as_array_mut);
    for tex in textures.into_iter().flatten() {
        let source_of = |name: &str| {
            tex.get("extensions")
                .and_then(|e| e.get(name))
                .and_then(|w| w.get("source"))
                .filter(|s| s.is_u64())
                .cloned()
        };
        let webp = source_of("EXT_texture_webp");
        let basisu = source_of("KHR_texture_basisu").filter(|_| tex.get("source").is_none());
        if let (Some(source), Some(obj)) = (webp.or(basisu), tex.as_object_mut()) {
            obj.insert("source".into(), source);
        }
    }
}

/// The `gltf` crate's validation, less its one rule stricter than glTF 2.0: an accessor may have
/// no `bufferView` (§3.6.2.4: zeros, or the data of a compression extension such as
/// `KHR_draco_mesh_compression`), where the crate asks for one unless the accessor is sparse.
fn validate(json_root: gltf::json::Root) -> Result<gltf::Document, Error> {
    use gltf::json::validation::{Error as Rule, Validate};
    let mut list = Vec::new();
    json_root.validate(&json_root, gltf::json::Path::new, &mut |path, error| {
        let path = path().to_string();
        let spec_allows = matches!(error, Rule::Missing)
            && path.starts_with("accessors[")
            && path.ends_with("].bufferView");
        if !spec_allows {
            list.push((path, error));
        }
    });
    if let Some((at, reason)) = list.first() {
        return Err(Error::Invalid {
            at: at.clone(),
            reason: if list.len() > 1 {
                format!("{reason} (and {} more problems)", list.len() - 1)
            } else {
                reason.to_string()
            },
        });
    }
    Ok(gltf::Document::from_json_without_validation(json_root))
}

/// Top-level keys whose values the loader never reads as JSON trees once the typed document
/// exists: only their element counts are kept (for `KHR_animation_pointer` indices). A file of
/// two million nodes would otherwise hold each node twice as a `serde_json::Value` (about
/// 800 bytes each) beside its typed form.
const COUNTED_ONLY: &[&str] = &["nodes"];

/// Top-level keys the checks above rewrite (image MIME types, `EXT_texture_webp` sources): the
/// typed parser reads these from the kept tree, every other key from the file's own text.
const REWRITTEN: &[&str] = &["images", "textures"];

/// Parses, checks and cleans the JSON, then hands it to the `gltf` crate for validation.
///
/// The document is split into its top-level values without parsing them (`RawValue`s borrowed
/// from `json`); the kept tree holds every value but the [`COUNTED_ONLY`] ones, and the typed
/// parser reads the file's own text again, less the values it must not see, so no value is
/// ever held as a tree twice.
pub(crate) fn prepare(json: &[u8]) -> Result<Prepared, Error> {
    use serde_json::value::RawValue;
    use std::collections::BTreeMap;
    let top: BTreeMap<String, &RawValue> = match serde_json::from_slice(json) {
        Ok(top) => top,
        Err(source) => {
            return Err(match serde_json::from_slice::<&RawValue>(json) {
                Ok(_) => Error::Invalid {
                    at: "(root)".into(),
                    reason: "the document is not a JSON object".into(),
                },
                Err(_) => Error::Json { source },
            })
        }
    };
    let mut kept = serde_json::Map::new();
    for (key, raw) in &top {
        let counted = COUNTED_ONLY
            .contains(&key.as_str())
            .then(|| serde_json::from_str::<Vec<&RawValue>>(raw.get()).ok())
            .flatten();
        let value = match counted {
            Some(items) => Value::Array(vec![Value::Null; items.len()]),
            None => serde_json::from_str(raw.get()).map_err(|source| Error::Json { source })?,
        };
        kept.insert(key.clone(), value);
    }
    let mut root = Value::Object(kept);
    check_required(&root)?;

    let extensions = extension_statuses(&root);
    check_position_indices(&root)?;
    check_shapes_the_typed_api_assumes(&mut root)?;
    use_extension_sources(&mut root);

    // The typed parser sees the file less its animations (read from the kept JSON instead) and
    // extensionsRequired (checked above; the gltf crate's own list lacks KHR_mesh_quantization
    // and EXT_mesh_gpu_instancing and would refuse them), with the images and textures as rewritten above.
    let mut text = String::with_capacity(json.len() + 2);
    text.push('{');
    for (key, raw) in &top {
        if key == "animations" || key == "extensionsRequired" {
            continue;
        }
        if text.len() > 1 {
            text.push(',');
        }
        text.push_str(&Value::from(key.as_str()).to_string());
        text.push(':');
        match root.get(key.as_str()) {
            Some(checked) if REWRITTEN.contains(&key.as_str()) => {
                text.push_str(&checked.to_string())
            }
            _ => text.push_str(raw.get()),
        }
    }
    text.push('}');
    let json_root: gltf::json::Root =
        serde_json::from_str(&text).map_err(|source| Error::Json { source })?;
    drop(text);
    let document = validate(json_root)?;
    Ok(Prepared {
        document,
        root,
        skipped: Vec::new(),
        extensions,
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn unsupported_required_extension_is_named() {
        let e = prepare(br#"{"asset":{"version":"2.0"},"extensionsRequired":["KHR_lights_punctual","EXT_ACME_unknown"]}"#)
            .err()
            .unwrap();
        assert!(e.to_string().contains("EXT_ACME_unknown"), "{e}");
        assert!(matches!(e, Error::UnsupportedExtension { index: 1, .. }));
    }

    #[test]
    fn used_only_extensions_are_ignored_and_required_supported_ones_pass() {
        let p = prepare(br#"{"asset":{"version":"2.0"},"extensionsUsed":["EXT_ACME_unknown","EXT_mesh_gpu_instancing"],"extensionsRequired":["EXT_mesh_gpu_instancing","KHR_mesh_quantization"]}"#)
            .unwrap();
        assert_eq!(ignored(&p.extensions), ["EXT_ACME_unknown"]);
    }

    #[test]
    fn animation_pointer_channels_are_kept_out_of_the_typed_parser() {
        let p = prepare(br#"{"asset":{"version":"2.0"},"nodes":[{"skin":0}],
            "skins":[{"joints":[0]}],
            "animations":[{"channels":[{"sampler":0,"target":{"path":"pointer"}}],"samplers":[{"input":5,"output":6}]}]}"#)
            .unwrap();
        assert_eq!(p.document.animations().count(), 0);
        assert_eq!(p.document.skins().count(), 1);
        assert_eq!(
            p.root["animations"][0]["channels"][0]["target"]["path"],
            "pointer"
        );
    }

    #[test]
    fn webp_sources_replace_the_fallback() {
        let p = prepare(
            br#"{"asset":{"version":"2.0"},"extensionsRequired":["EXT_texture_webp"],
            "images":[{"uri":"a.png"},{"uri":"b.webp"}],
            "textures":[{"extensions":{"EXT_texture_webp":{"source":1}}},
                        {"source":0,"extensions":{"EXT_texture_webp":{"source":1}}},
                        {"source":0}]}"#,
        )
        .unwrap();
        let sources: Vec<usize> = p.document.textures().map(|t| t.source().index()).collect();
        assert_eq!(sources, [1, 1, 0]);
    }

    #[test]
    fn basisu_sources_stand_in_only_for_a_missing_source() {
        let p = prepare(
            br#"{"asset":{"version":"2.0"},"extensionsRequired":["KHR_texture_basisu"],
            "images":[{"uri":"a.png"},{"uri":"b.ktx2","mimeType":"image/ktx2"}],
            "textures":[{"extensions":{"KHR_texture_basisu":{"source":1}}},
                        {"source":0,"extensions":{"KHR_texture_basisu":{"source":1}}}]}"#,
        )
        .unwrap();
        let sources: Vec<usize> = p.document.textures().map(|t| t.source().index()).collect();
        assert_eq!(sources, [1, 0]);
        assert!(ignored(&p.extensions).is_empty());
    }

    #[test]
    fn bad_json_is_an_error() {
        assert!(matches!(prepare(b"{\"asset\":"), Err(Error::Json { .. })));
        assert!(matches!(prepare(b"[1,2]"), Err(Error::Invalid { .. })));
        assert!(matches!(
            prepare(br#"{"asset":{"version":"2.0"},"meshes":[{"primitives":[{"attributes":{"POSITION":3}}]}]}"#),
            Err(Error::Invalid { .. })
        ));
    }
}
