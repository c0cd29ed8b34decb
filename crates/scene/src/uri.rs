//! Buffer and image URIs, resolved safely: `data:` URIs are decoded in memory; anything else must be
//! a relative path inside the scene file's folder (no `..`, no absolute path, no `http:`).

use std::path::{Component, Path, PathBuf};

use base64::Engine;
use percent_encoding::percent_decode_str;

use crate::error::Error;

fn refuse(at: &str, uri: &str, reason: &str) -> Error {
    Error::ForbiddenUri {
        at: at.into(),
        uri: uri.into(),
        reason: reason.into(),
    }
}

/// The URI's scheme (`data`, `http`, ...), if it has one (RFC 3986 §3.1).
fn scheme(uri: &str) -> Option<&str> {
    let (head, _) = uri.split_once(':')?;
    let mut chars = head.chars();
    let first = chars.next()?;
    (first.is_ascii_alphabetic()
        && chars.all(|c| c.is_ascii_alphanumeric() || matches!(c, '+' | '-' | '.')))
    .then_some(head)
}

/// Decodes a `data:` URI (`data:[<media type>][;base64],<data>`).
fn decode_data_uri(uri: &str, at: &str) -> Result<Vec<u8>, Error> {
    let rest = &uri["data:".len()..];
    let (meta, data) = rest.split_once(',').ok_or_else(|| Error::DataUri {
        at: at.into(),
        reason: "no ',' separating the media type from the data".into(),
    })?;
    if meta.ends_with(";base64") {
        base64::engine::general_purpose::STANDARD
            .decode(data.trim())
            .map_err(|e| Error::DataUri {
                at: at.into(),
                reason: e.to_string(),
            })
    } else {
        Ok(percent_decode_str(data).collect())
    }
}

/// Resolves a relative URI to a path inside `base_dir`, refusing every way out of it.
pub(crate) fn resolve_path(base_dir: &Path, uri: &str, at: &str) -> Result<PathBuf, Error> {
    if let Some(s) = scheme(uri) {
        let reason = match s.to_ascii_lowercase().as_str() {
            "http" | "https" => "remote resources are not fetched; put the file beside the scene",
            _ if s.len() == 1 => "absolute paths are not allowed",
            _ => "only relative paths and data: URIs are allowed",
        };
        return Err(refuse(at, uri, reason));
    }
    let decoded = percent_decode_str(uri)
        .decode_utf8()
        .map_err(|_| refuse(at, uri, "percent-decoded name is not UTF-8"))?;
    if decoded.starts_with('/') || decoded.starts_with('\\') {
        return Err(refuse(at, uri, "absolute paths are not allowed"));
    }
    let mut path = base_dir.to_path_buf();
    // Split on both separators so a `..\` written on Windows is caught too.
    for part in decoded.split(['/', '\\']) {
        match part {
            "" | "." => {}
            ".." => return Err(refuse(at, uri, "'..' would leave the scene's folder")),
            _ => {
                let p = Path::new(part);
                if !p.components().all(|c| matches!(c, Component::Normal(_))) {
                    return Err(refuse(at, uri, "absolute paths are not allowed"));
                }
                path.push(p);
            }
        }
    }
    // A symbolic link could still point outside: compare canonical paths when both exist.
    if let (Ok(real), Ok(base)) = (path.canonicalize(), base_dir.canonicalize()) {
        if !real.starts_with(&base) {
            return Err(refuse(
                at,
                uri,
                "the file resolves outside the scene's folder",
            ));
        }
    }
    Ok(path)
}

/// Loads the bytes a URI names.
pub(crate) fn load(base_dir: &Path, uri: &str, at: &str) -> Result<Vec<u8>, Error> {
    // `get`, not indexing: byte 5 may fall inside a character ("dataơ…", found by fuzzing).
    if uri
        .get(..5)
        .is_some_and(|head| head.eq_ignore_ascii_case("data:"))
    {
        return decode_data_uri(uri, at);
    }
    let path = resolve_path(base_dir, uri, at)?;
    std::fs::read(&path).map_err(|source| Error::MissingFile {
        at: at.into(),
        path,
        source,
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    fn err(uri: &str) -> String {
        resolve_path(Path::new("/tmp/scene"), uri, "buffers[0].uri")
            .unwrap_err()
            .to_string()
    }

    #[test]
    fn escapes_are_refused() {
        assert!(err("../secret.bin").contains("'..'"));
        assert!(err("a/../../secret.bin").contains("'..'"));
        assert!(err("%2e%2e/secret.bin").contains("'..'"));
        assert!(err("/etc/passwd").contains("absolute"));
        assert!(err("%2Fetc/passwd").contains("absolute"));
        assert!(err("C:/Windows/x.bin").contains("absolute"));
        assert!(err("http://example.com/a.bin").contains("remote"));
        assert!(err("HTTPS://example.com/a.bin").contains("remote"));
        assert!(err("file:///etc/passwd").contains("only relative"));
    }

    #[test]
    fn percent_encoded_and_utf8_names() {
        let p = resolve_path(Path::new("/s"), "Box%20With%20Spaces.bin", "x").unwrap();
        assert_eq!(p, Path::new("/s/Box With Spaces.bin"));
        let p = resolve_path(Path::new("/s"), "sub/Unicode%E2%9D%A4.png", "x").unwrap();
        assert_eq!(p, Path::new("/s/sub/Unicode❤.png"));
        let p = resolve_path(Path::new("/s"), "./Unicode❤♻Texture.png", "x").unwrap();
        assert_eq!(p, Path::new("/s/Unicode❤♻Texture.png"));
    }

    #[test]
    fn data_uris() {
        let d = load(
            Path::new("/s"),
            "data:application/octet-stream;base64,AQID",
            "x",
        )
        .unwrap();
        assert_eq!(d, [1, 2, 3]);
        assert!(matches!(
            load(
                Path::new("/s"),
                "data:application/octet-stream;base64,@@@",
                "x"
            ),
            Err(Error::DataUri { .. })
        ));
    }
}
