//! Bytes: the GLB container, buffers (relative files, `data:` base64 URIs, the GLB `BIN`
//! chunk), and the URI decoding they need.

use ::gltf::json;

use crate::import::error::{ImportError, Source};
use crate::import::options::Loader;

/// The JSON and BIN chunks of a GLB file.
pub(super) fn split_glb<'a>(
    source: &Source,
    bytes: &'a [u8],
) -> Result<(&'a [u8], Option<&'a [u8]>), ImportError> {
    let u32_at = |at: usize| {
        bytes
            .get(at..at + 4)
            .map(|b| u32::from_le_bytes([b[0], b[1], b[2], b[3]]) as usize)
    };
    let (Some(version), Some(length)) = (u32_at(4), u32_at(8)) else {
        return Err(source.truncated("the 12-byte GLB header is cut off"));
    };
    if version != 2 {
        return Err(source.unsupported("GLB header", format!("glTF version {version}")));
    }
    if length > bytes.len() {
        return Err(source.truncated(format!(
            "the GLB header says {length} bytes, the file has {}",
            bytes.len()
        )));
    }
    let bytes = &bytes[..length];
    let mut at = 12;
    let mut json = None;
    let mut bin = None;
    let mut index = 0;
    while at < bytes.len() {
        let (Some(len), Some(kind)) = (u32_at(at), u32_at(at + 4)) else {
            return Err(source.truncated(format!("GLB chunk {index} header is cut off")));
        };
        let start = at + 8;
        let end = start
            .checked_add(len)
            .filter(|&e| e <= bytes.len())
            .ok_or_else(|| {
                source.truncated(format!(
                    "GLB chunk {index} claims {len} bytes, {} remain",
                    bytes.len() - start.min(bytes.len())
                ))
            })?;
        match (kind, index) {
            (0x4E4F_534A, 0) => json = Some(&bytes[start..end]),
            (0x004E_4942, 1) => bin = Some(&bytes[start..end]),
            (_, 0) => {
                return Err(source.malformed("GLB chunk 0", "the first chunk is not JSON"));
            }
            _ => {}
        }
        at = end;
        index += 1;
    }
    let json = json.ok_or_else(|| source.malformed("GLB", "no JSON chunk"))?;
    Ok((json, bin))
}

/// Every buffer's bytes, at least its `byteLength` of them.
pub(super) fn load_buffers(
    source: &Source,
    root: &json::Root,
    blob: Option<&[u8]>,
    load: &mut Loader<'_>,
) -> Result<Vec<Vec<u8>>, ImportError> {
    let mut buffers = Vec::with_capacity(root.buffers.len());
    for (i, buffer) in root.buffers.iter().enumerate() {
        let declared = buffer.byte_length.0;
        let (data, what) = match buffer.uri.as_deref() {
            None => match blob {
                Some(blob) if i == 0 => (blob.to_vec(), format!("buffer {i} (GLB BIN chunk)")),
                _ => {
                    return Err(source
                        .malformed(format!("buffer {i}"), "no uri and no GLB BIN chunk to read"))
                }
            },
            Some(uri) => {
                let what = format!("buffer {i}");
                if let Some(rest) = uri.strip_prefix("data:") {
                    let payload = rest.split_once(";base64,").map(|(_, p)| p).ok_or_else(|| {
                        source.unsupported(&what, "data URI without base64 encoding")
                    })?;
                    let data = decode_base64(payload)
                        .ok_or_else(|| source.malformed(&what, "data URI is not valid base64"))?;
                    (data, what)
                } else {
                    let file = decode_uri(source, &what, uri)?;
                    let what = format!("{what} ('{file}')");
                    let data = load(&file).map_err(|e| source.io(&what, e))?;
                    (data, what)
                }
            }
        };
        if (data.len() as u64) < declared {
            return Err(source.truncated(format!(
                "{what} has {} bytes, its byteLength is {declared}",
                data.len()
            )));
        }
        buffers.push(data);
    }
    Ok(buffers)
}

/// A relative URI to a file name: percent-decoded, UTF-8, no scheme.
pub(super) fn decode_uri(source: &Source, what: &str, uri: &str) -> Result<String, ImportError> {
    if let Some((scheme, _)) = uri.split_once(':') {
        if !scheme.is_empty()
            && scheme
                .chars()
                .all(|c| c.is_ascii_alphanumeric() || "+-.".contains(c))
            && scheme.len() > 1
        {
            return Err(source.unsupported(
                what,
                format!("URI scheme '{scheme}:' (only relative paths and data URIs are read)"),
            ));
        }
    }
    let bytes = uri.as_bytes();
    let mut out = Vec::with_capacity(bytes.len());
    let mut i = 0;
    while i < bytes.len() {
        if bytes[i] == b'%' {
            let hex = bytes
                .get(i + 1..i + 3)
                .and_then(|h| std::str::from_utf8(h).ok())
                .and_then(|h| u8::from_str_radix(h, 16).ok())
                .ok_or_else(|| {
                    source.malformed(what, format!("bad percent-encoding in '{uri}'"))
                })?;
            out.push(hex);
            i += 3;
        } else {
            out.push(bytes[i]);
            i += 1;
        }
    }
    String::from_utf8(out)
        .map_err(|_| source.malformed(what, format!("'{uri}' does not decode to UTF-8")))
}

/// Standard base64 (padding optional); `None` if any other character appears.
pub(super) fn decode_base64(text: &str) -> Option<Vec<u8>> {
    let mut out = Vec::with_capacity(text.len() / 4 * 3);
    let mut acc = 0u32;
    let mut bits = 0;
    for c in text.trim_end_matches('=').bytes() {
        let v = match c {
            b'A'..=b'Z' => c - b'A',
            b'a'..=b'z' => c - b'a' + 26,
            b'0'..=b'9' => c - b'0' + 52,
            b'+' => 62,
            b'/' => 63,
            _ => return None,
        };
        acc = (acc << 6) | u32::from(v);
        bits += 6;
        if bits >= 8 {
            bits -= 8;
            out.push((acc >> bits) as u8);
            acc &= (1 << bits) - 1;
        }
    }
    Some(out)
}
