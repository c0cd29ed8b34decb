//! Every buffer of a file read into memory: the GLB BIN chunk, `data:` URIs or files beside the
//! scene.

use std::borrow::Cow;
use std::collections::HashMap;
use std::path::Path;

use serde_json::Value;

use crate::accessor::Buffers;
use crate::error::Error;
use crate::uri;

/// Reads every buffer: the GLB BIN chunk, `data:` URIs or files beside the scene.
pub(crate) fn load_buffers<'f>(
    doc: &gltf::Document,
    root: &Value,
    bin: Option<&'f [u8]>,
    base_dir: &Path,
    budget: &aperture_budget::MemoryBudget,
) -> Result<Buffers<'f>, Error> {
    let mut data = Vec::with_capacity(doc.buffers().len());
    for b in doc.buffers() {
        let at = format!("buffers[{}]", b.index());
        if crate::meshopt::is_fallback(root, b.index()) {
            // The meshopt extension's placeholder: no bytes; its views are decoded instead.
            data.push(Cow::Borrowed(&[][..]));
            continue;
        }
        let bytes: Cow<'f, [u8]> = match b.source() {
            // Borrowed: a copy of the chunk was the load's largest temporary (issue 59).
            gltf::buffer::Source::Bin => Cow::Borrowed(bin.ok_or_else(|| Error::Invalid {
                at: at.clone(),
                reason: "refers to the GLB BIN chunk, which is missing".into(),
            })?),
            gltf::buffer::Source::Uri(u) => uri::load(base_dir, u, &format!("{at}.uri"))?.into(),
        };
        let claimed = b.length() as u64;
        if (bytes.len() as u64) < claimed {
            return Err(Error::BufferTooShort {
                buffer: b.index(),
                claimed,
                actual: bytes.len() as u64,
            });
        }
        // Padding past byteLength is not part of the buffer.
        data.push(match bytes {
            Cow::Borrowed(s) => Cow::Borrowed(&s[..b.length()]),
            Cow::Owned(mut v) => {
                v.truncate(b.length());
                Cow::Owned(v)
            }
        });
    }
    let total = data.iter().map(|d| d.len() as u64).sum();
    Ok(Buffers {
        data,
        total,
        decoded: HashMap::new(),
        charged: Default::default(),
        budget: *budget,
    })
}
