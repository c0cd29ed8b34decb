//! The JSON pre-pass: runs on the raw JSON before the `gltf` crate sees it.
//!
//! 1. `extensionsRequired` is compared with what we implement, before any buffer is read, so an
//!    unsupported file fails fast with the extension's name.
//! 2. Animations and skins are dropped: a still image uses the rest pose, and Blender's exporter
//!    writes animation channels without `target.node` (`KHR_animation_pointer`), which the typed
//!    parser refuses.
//! 3. The edited JSON is deserialised and validated by the `gltf` crate.

use serde_json::Value;

use crate::Error;

/// Extensions we implement, so a file may require them.
pub const SUPPORTED_EXTENSIONS: &[&str] = &[
    "KHR_lights_punctual",
    "KHR_materials_emissive_strength",
    "KHR_texture_transform",
    "KHR_materials_unlit",
    "KHR_mesh_quantization",
    "EXT_mesh_gpu_instancing",
    "KHR_materials_ior",
    "KHR_materials_specular",
];

/// The validated document plus what the pre-pass removed.
pub(crate) struct Prepared {
    pub document: gltf::Document,
    pub skipped: Vec<String>,
    /// Extensions the file uses that we ignore (allowed: they are not required).
    pub ignored_extensions: Vec<String>,
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

/// Parses, checks and cleans the JSON, then hands it to the `gltf` crate for validation.
pub(crate) fn prepare(json: &[u8]) -> Result<Prepared, Error> {
    let mut root: Value = serde_json::from_slice(json).map_err(|source| Error::Json { source })?;
    if !root.is_object() {
        return Err(Error::Invalid {
            at: "(root)".into(),
            reason: "the document is not a JSON object".into(),
        });
    }
    check_required(&root)?;

    let ignored_extensions = root
        .get("extensionsUsed")
        .and_then(Value::as_array)
        .into_iter()
        .flatten()
        .filter_map(Value::as_str)
        .filter(|e| !SUPPORTED_EXTENSIONS.contains(e))
        .map(str::to_owned)
        .collect();
    let mut skipped = Vec::new();
    let animations = len_of(&root, "animations");
    let skins = len_of(&root, "skins");
    let morphed = root
        .get("meshes")
        .and_then(Value::as_array)
        .map_or(0, |meshes| {
            meshes
                .iter()
                .filter_map(|m| m.get("primitives").and_then(Value::as_array))
                .flatten()
                .filter(|p| p.get("targets").is_some())
                .count()
        });
    if animations > 0 {
        skipped.push(format!("{animations} animation(s) (rest pose)"));
    }
    if skins > 0 {
        skipped.push(format!("{skins} skin(s) (rest pose)"));
    }
    if morphed > 0 {
        skipped.push(format!(
            "morph targets in {morphed} primitive(s) (base shape)"
        ));
    }

    if let Some(obj) = root.as_object_mut() {
        obj.remove("animations");
        obj.remove("skins");
        // Checked above; the gltf crate's own list lacks KHR_mesh_quantization and
        // EXT_mesh_gpu_instancing and would refuse them.
        obj.remove("extensionsRequired");
        if let Some(nodes) = obj.get_mut("nodes").and_then(Value::as_array_mut) {
            for node in nodes.iter_mut().filter_map(Value::as_object_mut) {
                // Would dangle once `skins` is gone.
                node.remove("skin");
            }
        }
    }

    check_position_indices(&root)?;
    check_shapes_the_typed_api_assumes(&mut root)?;
    let json_root: gltf::json::Root =
        serde_json::from_value(root).map_err(|source| Error::Json { source })?;
    let document = gltf::Document::from_json(json_root).map_err(|e| match e {
        gltf::Error::Validation(list) => {
            let (at, reason) = list
                .first()
                .map(|(path, err)| (path.to_string(), err.to_string()))
                .unwrap_or_else(|| ("(root)".into(), "invalid".into()));
            Error::Invalid {
                at,
                reason: if list.len() > 1 {
                    format!("{reason} (and {} more problems)", list.len() - 1)
                } else {
                    reason
                },
            }
        }
        other => Error::Invalid {
            at: "(root)".into(),
            reason: other.to_string(),
        },
    })?;
    Ok(Prepared {
        document,
        skipped,
        ignored_extensions,
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn unsupported_required_extension_is_named() {
        let e = prepare(br#"{"asset":{"version":"2.0"},"extensionsRequired":["KHR_lights_punctual","KHR_draco_mesh_compression"]}"#)
            .err()
            .unwrap();
        assert!(e.to_string().contains("KHR_draco_mesh_compression"), "{e}");
        assert!(matches!(e, Error::UnsupportedExtension { index: 1, .. }));
    }

    #[test]
    fn used_only_extensions_are_ignored_and_required_supported_ones_pass() {
        let p = prepare(br#"{"asset":{"version":"2.0"},"extensionsUsed":["KHR_draco_mesh_compression","EXT_mesh_gpu_instancing"],"extensionsRequired":["EXT_mesh_gpu_instancing","KHR_mesh_quantization"]}"#)
            .unwrap();
        assert_eq!(p.ignored_extensions, ["KHR_draco_mesh_compression"]);
    }

    #[test]
    fn animation_pointer_channels_are_dropped() {
        let p = prepare(br#"{"asset":{"version":"2.0"},"nodes":[{"skin":0}],
            "skins":[{"joints":[0]}],
            "animations":[{"channels":[{"sampler":0,"target":{"path":"pointer"}}],"samplers":[{"input":5,"output":6}]}]}"#)
            .unwrap();
        assert_eq!(p.skipped.len(), 2);
        assert_eq!(p.document.animations().count(), 0);
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
