//! The binary glTF container (glTF 2.0 §4.4): a 12-byte header, a JSON chunk, an optional BIN chunk.
//! Every length is checked against the bytes actually present, so a truncated file is an error.

use crate::error::Error;

const MAGIC: &[u8; 4] = b"glTF";
const CHUNK_JSON: u32 = 0x4E4F_534A;
const CHUNK_BIN: u32 = 0x004E_4942;

/// The two chunks of a GLB file, borrowed from its bytes.
#[derive(Debug)]
pub(crate) struct Glb<'a> {
    pub json: &'a [u8],
    pub bin: Option<&'a [u8]>,
}

/// True when the bytes start with the GLB magic (the file extension is not trusted).
pub(crate) fn is_glb(bytes: &[u8]) -> bool {
    bytes.starts_with(MAGIC)
}

fn u32_at(bytes: &[u8], at: usize) -> Option<u32> {
    let b = bytes.get(at..at.checked_add(4)?)?;
    Some(u32::from_le_bytes([b[0], b[1], b[2], b[3]]))
}

fn bad(reason: impl Into<String>) -> Error {
    Error::Glb {
        reason: reason.into(),
    }
}

/// Splits a GLB file into its chunks.
pub(crate) fn parse(bytes: &[u8]) -> Result<Glb<'_>, Error> {
    if bytes.len() < 12 {
        return Err(bad(format!(
            "truncated: {} bytes, the header alone needs 12",
            bytes.len()
        )));
    }
    if !is_glb(bytes) {
        return Err(bad("bad magic (expected \"glTF\")"));
    }
    let version = u32_at(bytes, 4).unwrap_or(0);
    if version != 2 {
        return Err(bad(format!("version {version}, only 2 is supported")));
    }
    let length = u32_at(bytes, 8).unwrap_or(0) as usize;
    if length > bytes.len() {
        return Err(bad(format!(
            "truncated: header says {length} bytes, the file has {}",
            bytes.len()
        )));
    }
    if length < 12 {
        return Err(bad(format!(
            "header length {length} is smaller than the header"
        )));
    }
    // Trailing bytes past `length` are ignored, as the specification allows readers to.
    let bytes = &bytes[..length];
    let mut json = None;
    let mut bin = None;
    let mut at = 12usize;
    let mut chunk = 0usize;
    while at < bytes.len() {
        let (Some(len), Some(kind)) = (u32_at(bytes, at), u32_at(bytes, at + 4)) else {
            return Err(bad(format!("truncated: chunk {chunk} header at byte {at}")));
        };
        let start = at + 8;
        let end = start
            .checked_add(len as usize)
            .filter(|&e| e <= bytes.len())
            .ok_or_else(|| {
                bad(format!(
                    "truncated: chunk {chunk} claims {len} bytes at byte {start}, the file ends at {}",
                    bytes.len()
                ))
            })?;
        let data = &bytes[start..end];
        match (chunk, kind) {
            (0, CHUNK_JSON) => json = Some(data),
            (0, _) => return Err(bad("the first chunk is not JSON")),
            (1, CHUNK_BIN) => bin = Some(data),
            // Unknown chunk types must be ignored (glTF 2.0 §4.4.3.1).
            _ => {}
        }
        // Chunks are 4-byte aligned; tolerate a missing pad at the very end.
        at = end.saturating_add((4 - len as usize % 4) % 4);
        chunk += 1;
    }
    let json = json.ok_or_else(|| bad("no JSON chunk"))?;
    Ok(Glb { json, bin })
}

/// The JSON and binary chunk of a GLB container, or the bytes as JSON.
pub(crate) fn split(bytes: &[u8]) -> Result<(&[u8], Option<&[u8]>), Error> {
    if is_glb(bytes) {
        let g = parse(bytes)?;
        Ok((g.json, g.bin))
    } else {
        Ok((bytes, None))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn glb(json: &[u8], bin: Option<&[u8]>) -> Vec<u8> {
        let mut out = Vec::new();
        let pad = |v: &mut Vec<u8>, b: u8| {
            while v.len() % 4 != 0 {
                v.push(b)
            }
        };
        let mut j = json.to_vec();
        pad(&mut j, b' ');
        let mut chunks = Vec::new();
        chunks.extend((j.len() as u32).to_le_bytes());
        chunks.extend(CHUNK_JSON.to_le_bytes());
        chunks.extend(&j);
        if let Some(bin) = bin {
            let mut b = bin.to_vec();
            pad(&mut b, 0);
            chunks.extend((b.len() as u32).to_le_bytes());
            chunks.extend(CHUNK_BIN.to_le_bytes());
            chunks.extend(&b);
        }
        out.extend(MAGIC);
        out.extend(2u32.to_le_bytes());
        out.extend(((12 + chunks.len()) as u32).to_le_bytes());
        out.extend(chunks);
        out
    }

    #[test]
    fn round_trip() {
        let f = glb(b"{}", Some(&[1, 2, 3]));
        let g = parse(&f).unwrap();
        assert_eq!(g.json, b"{}  ");
        assert_eq!(g.bin.unwrap(), &[1, 2, 3, 0]);
    }

    #[test]
    fn every_truncation_is_an_error() {
        let f = glb(b"{\"asset\":{}}", Some(&[7; 20]));
        for n in 0..f.len() {
            assert!(parse(&f[..n]).is_err(), "prefix of {n} bytes");
        }
    }

    #[test]
    fn bad_magic_and_version() {
        let mut f = glb(b"{}", None);
        f[0] = b'x';
        assert!(matches!(parse(&f), Err(Error::Glb { .. })));
        let mut f = glb(b"{}", None);
        f[4] = 1;
        assert!(parse(&f).unwrap_err().to_string().contains("version 1"));
    }
}
