//! Which `KHR_materials_variants` variant a load selects (`--variant`).

use crate::error::Error;
use serde_json::Value;

/// The names of the file's `KHR_materials_variants` (`variants[i]` when unnamed).
pub(super) fn variant_names(root: &Value) -> Vec<String> {
    let list = root
        .get("extensions")
        .and_then(|e| e.get("KHR_materials_variants"))
        .and_then(|v| v.get("variants"))
        .and_then(Value::as_array);
    list.into_iter()
        .flatten()
        .enumerate()
        .map(|(i, v)| {
            v.get("name")
                .and_then(Value::as_str)
                .map_or_else(|| format!("variants[{i}]"), str::to_owned)
        })
        .collect()
}

/// The index of the variant `--variant` names (a name, else an index written as digits).
pub(super) fn resolve_variant(
    names: &[String],
    wanted: Option<&str>,
) -> Result<Option<usize>, Error> {
    let Some(wanted) = wanted else {
        return Ok(None);
    };
    if let Some(i) = names.iter().position(|n| n == wanted) {
        return Ok(Some(i));
    }
    match wanted.parse::<usize>() {
        Ok(i) if i < names.len() => Ok(Some(i)),
        _ => Err(Error::NoSuchVariant {
            wanted: format!("{wanted:?}"),
            available: if names.is_empty() {
                "none".into()
            } else {
                names
                    .iter()
                    .map(|n| format!("{n:?}"))
                    .collect::<Vec<_>>()
                    .join(", ")
            },
        }),
    }
}
