//! glTF buffer URIs: `data:` URIs decoded with a size limit, relative paths resolved
//! inside an allowed folder. Nothing else (no `file:`, no absolute paths, no other
//! schemes), so a glTF file from elsewhere cannot make the loader read outside the
//! scene's folder.

use std::path::{Path, PathBuf};

use super::{MeshError, invalid, read_bounded};

/// The bytes a buffer URI names, at most `limit` of them.
///
/// `gltf_dir` is the folder of the glTF file (relative URIs are relative to it);
/// `root` is the folder the resolved file must lie in (symbolic links resolved).
pub(crate) fn read_uri(
    element: &str,
    uri: &str,
    gltf_dir: &Path,
    root: &Path,
    limit: u64,
) -> Result<Vec<u8>, MeshError> {
    if let Some(rest) = uri.strip_prefix("data:") {
        let Some((header, payload)) = rest.split_once(',') else {
            return Err(invalid(
                element,
                "data URI without a `,`: expected data:[<type>];base64,<data>",
            ));
        };
        if !header.ends_with(";base64") {
            return Err(invalid(
                element,
                format!("data URI `data:{header},…`: expected base64 data (`;base64,`)"),
            ));
        }
        // 3 bytes per 4 characters: refuse before decoding anything.
        let decoded = (payload.len() as u64).div_ceil(4) * 3;
        if decoded > limit {
            return Err(MeshError::Limit {
                what: format!("bytes of the data URI of {element}"),
                count: decoded,
                limit,
                field: "max_file_bytes",
            });
        }
        return base64_decode(payload).map_err(|problem| invalid(element, problem));
    }
    let scheme_end = uri.find(':');
    let path_start = uri.find(['/', '\\']);
    if let Some(c) = scheme_end
        && path_start.is_none_or(|p| c < p)
    {
        return Err(invalid(
            element,
            format!(
                "URI `{}`: expected a relative path or a data: URI (no URI schemes)",
                clip(uri)
            ),
        ));
    }
    let decoded = percent_decode(uri).ok_or_else(|| {
        invalid(
            element,
            format!("URI `{}`: bad percent-encoding (expected UTF-8)", clip(uri)),
        )
    })?;
    let rel = Path::new(&decoded);
    if decoded.is_empty() || rel.is_absolute() || decoded.starts_with(['/', '\\']) {
        return Err(invalid(
            element,
            format!(
                "URI `{}`: expected a relative path inside {}",
                clip(uri),
                root.display()
            ),
        ));
    }
    let joined = gltf_dir.join(rel);
    let resolved = joined.canonicalize().map_err(|source| MeshError::Io {
        file: joined.clone(),
        source,
    })?;
    if !resolved.starts_with(root) {
        return Err(invalid(
            element,
            format!(
                "URI `{}` resolves to {}: expected a file inside {} (paths may not leave the scene's folder)",
                clip(uri),
                resolved.display(),
                root.display()
            ),
        ));
    }
    if !resolved.is_file() {
        return Err(invalid(
            element,
            format!("URI `{}`: {} is not a file", clip(uri), resolved.display()),
        ));
    }
    read_bounded(&resolved, limit)
}

/// The folder a glTF file's buffers must lie in: the scene's folder if the glTF file
/// lies inside it, else the glTF file's own folder (the scene's author chose to put it
/// there), both canonical.
pub(crate) fn allowed_root(
    scene_dir: &Path,
    gltf_file: &Path,
) -> Result<(PathBuf, PathBuf), MeshError> {
    let canon = |p: &Path| {
        p.canonicalize().map_err(|source| MeshError::Io {
            file: p.to_path_buf(),
            source,
        })
    };
    let file = canon(gltf_file)?;
    let gltf_dir = file.parent().map(Path::to_path_buf).unwrap_or_default();
    let scene_dir = canon(if scene_dir.as_os_str().is_empty() {
        Path::new(".")
    } else {
        scene_dir
    })?;
    let root = if gltf_dir.starts_with(&scene_dir) {
        scene_dir
    } else {
        gltf_dir.clone()
    };
    Ok((gltf_dir, root))
}

/// `%XX` escapes decoded; None if an escape is malformed or the result is not UTF-8.
fn percent_decode(s: &str) -> Option<String> {
    let b = s.as_bytes();
    let mut out = Vec::with_capacity(b.len());
    let mut i = 0;
    while i < b.len() {
        if b[i] == b'%' {
            let hex = std::str::from_utf8(b.get(i + 1..i + 3)?).ok()?;
            out.push(u8::from_str_radix(hex, 16).ok()?);
            i += 3;
        } else {
            out.push(b[i]);
            i += 1;
        }
    }
    String::from_utf8(out).ok()
}

/// Standard base64 (RFC 4648, `=` padding optional; no whitespace).
fn base64_decode(s: &str) -> Result<Vec<u8>, String> {
    let s = s.trim_end_matches('=');
    let mut out = Vec::with_capacity(s.len() / 4 * 3 + 3);
    let (mut acc, mut bits) = (0u32, 0u32);
    for (i, c) in s.bytes().enumerate() {
        let v = match c {
            b'A'..=b'Z' => c - b'A',
            b'a'..=b'z' => c - b'a' + 26,
            b'0'..=b'9' => c - b'0' + 52,
            b'+' => 62,
            b'/' => 63,
            _ => {
                return Err(format!(
                    "data URI: byte {c:#04x} at offset {i} of the base64 data: expected A-Z, a-z, 0-9, + or /"
                ));
            }
        };
        acc = (acc << 6) | u32::from(v);
        bits += 6;
        if bits >= 8 {
            bits -= 8;
            out.push((acc >> bits) as u8);
            acc &= (1 << bits) - 1;
        }
    }
    if bits >= 6 {
        return Err("data URI: the base64 data has a dangling character: expected a length of 4n, 4n+2 or 4n+3".into());
    }
    Ok(out)
}

/// A URI shortened to 80 characters for a message (data URIs can be megabytes).
fn clip(s: &str) -> String {
    let mut out: String = s.chars().take(80).collect();
    if out.len() < s.len() {
        out.push('…');
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn base64_round_trips_and_refuses_junk() {
        assert_eq!(base64_decode("TWFu").as_deref(), Ok(&b"Man"[..]));
        assert_eq!(base64_decode("TWE=").as_deref(), Ok(&b"Ma"[..]));
        assert_eq!(base64_decode("TQ==").as_deref(), Ok(&b"M"[..]));
        assert_eq!(base64_decode("").as_deref(), Ok(&b""[..]));
        assert!(base64_decode("TWF").is_ok());
        assert!(base64_decode("T").is_err());
        assert!(base64_decode("TW!u").is_err());
    }

    #[test]
    fn percent_decoding() {
        assert_eq!(percent_decode("a%20b.bin").as_deref(), Some("a b.bin"));
        assert_eq!(percent_decode("%2e%2e/x"), Some("../x".into()));
        assert_eq!(percent_decode("%zz"), None);
        assert_eq!(percent_decode("%4"), None);
    }
}
