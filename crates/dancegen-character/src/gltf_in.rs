//! Reading a character file: binary glTF (`.glb`, and `.vrm`, which is a GLB) or glTF JSON
//! (`.gltf`) with data-URI or external buffers and images.
//!
//! The whole JSON document is kept as a [`serde_json::Value`] and every byte of every buffer and
//! external image is kept too, because the output is the user's own file with only its
//! animations replaced: meshes, materials, textures, morph targets and extensions (VRM's
//! humanoid, spring bones, MToon materials, …) must survive untouched, including the parts this
//! crate does not understand. The format is told by content, not by file extension (a `.vrm` is
//! a GLB, and people rename files).

use std::path::{Path, PathBuf};

use base64::Engine;
use serde_json::Value;

use super::error::CharacterError;
use dancegen_formats::glb_container::{GlbError, split_glb};

/// A glTF document with its binary data resolved.
#[derive(Debug, Clone)]
pub(crate) struct GltfAsset {
    /// The JSON document, as read.
    pub json: Value,
    /// `buffers[i]` holds the bytes of JSON buffer `i`, exactly `byteLength` long.
    pub buffers: Vec<Vec<u8>>,
    /// `images[i]` holds the bytes of JSON image `i` when it is given by `uri` (data URI or
    /// file); images stored in a bufferView are `None` (their bytes are in `buffers`).
    pub images: Vec<Option<ImageBytes>>,
}

/// An image that was referenced by URI, to be embedded in the output GLB.
#[derive(Debug, Clone, PartialEq)]
pub(crate) struct ImageBytes {
    pub data: Vec<u8>,
    pub mime_type: String,
}

/// The GLB magic as the file's first bytes.
const GLB_MAGIC: &[u8; 4] = b"glTF";

/// Reads a character file from disk; external buffers and images are resolved next to it.
pub(crate) fn read_gltf(path: &Path) -> Result<GltfAsset, CharacterError> {
    let bytes = std::fs::read(path).map_err(|e| CharacterError::Read {
        path: path.to_path_buf(),
        reason: e.to_string(),
    })?;
    let base = path.parent().map(Path::to_path_buf).unwrap_or_default();
    parse_gltf(path, &bytes, Some(&base))
}

/// Parses a character from bytes. `path` names the file in errors; `base_dir` resolves relative
/// URIs (`None`: external files are an error).
pub(crate) fn parse_gltf(
    path: &Path,
    bytes: &[u8],
    base_dir: Option<&Path>,
) -> Result<GltfAsset, CharacterError> {
    let invalid = |reason: String| CharacterError::Invalid {
        path: path.to_path_buf(),
        reason,
    };
    let (json_bytes, bin) = if bytes.starts_with(GLB_MAGIC) {
        let (j, b) = split_glb(bytes).map_err(|e| match e {
            GlbError::Unsupported(reason) => CharacterError::Unsupported {
                path: path.to_path_buf(),
                reason,
            },
            GlbError::Invalid(reason) => invalid(reason),
        })?;
        (j, b)
    } else {
        (bytes, None)
    };
    let json_bytes = strip_bom(json_bytes);
    let json_bytes = trim_trailing_padding(json_bytes);
    let json: Value = match serde_json::from_slice(json_bytes) {
        Ok(v) => v,
        Err(e) if bytes.starts_with(GLB_MAGIC) => {
            return Err(invalid(format!("the GLB's JSON chunk does not parse: {e}")));
        }
        Err(_) => {
            return Err(CharacterError::NotGltf {
                path: path.to_path_buf(),
                reason: "neither binary glTF (which starts with 'glTF') nor JSON".into(),
            });
        }
    };
    let Some(asset) = json.get("asset").and_then(Value::as_object) else {
        return Err(CharacterError::NotGltf {
            path: path.to_path_buf(),
            reason: "JSON without the glTF \"asset\" object".into(),
        });
    };
    let version = asset.get("version").and_then(Value::as_str).unwrap_or("");
    if !version.starts_with("2.") {
        return Err(CharacterError::Unsupported {
            path: path.to_path_buf(),
            reason: format!(
                "glTF version {version:?}; only glTF 2.0 is read (re-export the model as glTF 2.0)"
            ),
        });
    }

    let buffers = read_buffers(path, &json, bin, base_dir)?;
    check_buffer_views(path, &json, &buffers)?;
    let images = read_images(path, &json, base_dir)?;
    Ok(GltfAsset {
        json,
        buffers,
        images,
    })
}

fn strip_bom(b: &[u8]) -> &[u8] {
    b.strip_prefix(&[0xEF, 0xBB, 0xBF]).unwrap_or(b)
}

/// Some exporters pad the JSON chunk with NULs instead of spaces.
fn trim_trailing_padding(mut b: &[u8]) -> &[u8] {
    while let [rest @ .., 0] = b {
        b = rest;
    }
    b
}

/// `index`-th entries of a top-level array (empty when absent).
pub(crate) fn array<'a>(json: &'a Value, key: &str) -> &'a [Value] {
    json.get(key)
        .and_then(Value::as_array)
        .map(Vec::as_slice)
        .unwrap_or(&[])
}

fn read_buffers(
    path: &Path,
    json: &Value,
    bin: Option<&[u8]>,
    base_dir: Option<&Path>,
) -> Result<Vec<Vec<u8>>, CharacterError> {
    let invalid = |reason: String| CharacterError::Invalid {
        path: path.to_path_buf(),
        reason,
    };
    let mut out = Vec::new();
    for (i, b) in array(json, "buffers").iter().enumerate() {
        let len = b
            .get("byteLength")
            .and_then(Value::as_u64)
            .ok_or_else(|| invalid(format!("buffer {i} has no byteLength")))?
            as usize;
        let mut data = match b.get("uri").and_then(Value::as_str) {
            None => match (i, bin) {
                (0, Some(bin)) => bin.to_vec(),
                _ => {
                    return Err(invalid(format!(
                        "buffer {i} has no uri and is not the GLB's binary chunk"
                    )));
                }
            },
            Some(uri) => {
                load_uri(path, uri, base_dir)
                    .map_err(|reason| invalid(format!("buffer {i}: {reason}")))?
                    .0
            }
        };
        if data.len() < len {
            return Err(invalid(format!(
                "buffer {i} has {} bytes but byteLength says {len}",
                data.len()
            )));
        }
        data.truncate(len);
        out.push(data);
    }
    Ok(out)
}

fn check_buffer_views(
    path: &Path,
    json: &Value,
    buffers: &[Vec<u8>],
) -> Result<(), CharacterError> {
    for (i, v) in array(json, "bufferViews").iter().enumerate() {
        let buffer = v.get("buffer").and_then(Value::as_u64).map(|b| b as usize);
        let offset = v.get("byteOffset").and_then(Value::as_u64).unwrap_or(0) as usize;
        let len = v
            .get("byteLength")
            .and_then(Value::as_u64)
            .map(|l| l as usize);
        let ok = match (buffer.and_then(|b| buffers.get(b)), len) {
            (Some(data), Some(len)) => offset.checked_add(len).is_some_and(|e| e <= data.len()),
            _ => false,
        };
        if !ok {
            return Err(CharacterError::Invalid {
                path: path.to_path_buf(),
                reason: format!("bufferView {i} does not lie inside an existing buffer"),
            });
        }
    }
    Ok(())
}

fn read_images(
    path: &Path,
    json: &Value,
    base_dir: Option<&Path>,
) -> Result<Vec<Option<ImageBytes>>, CharacterError> {
    let mut out = Vec::new();
    for (i, img) in array(json, "images").iter().enumerate() {
        let Some(uri) = img.get("uri").and_then(Value::as_str) else {
            out.push(None);
            continue;
        };
        let (data, declared) =
            load_uri(path, uri, base_dir).map_err(|reason| CharacterError::Invalid {
                path: path.to_path_buf(),
                reason: format!("image {i}: {reason}"),
            })?;
        let mime_type = sniff_image(&data)
            .map(str::to_string)
            .or(declared)
            .or_else(|| {
                img.get("mimeType")
                    .and_then(Value::as_str)
                    .map(str::to_string)
            })
            .or_else(|| mime_from_extension(uri).map(str::to_string))
            .ok_or_else(|| CharacterError::Unsupported {
                path: path.to_path_buf(),
                reason: format!("image {i} ({uri}) is not PNG, JPEG, WebP or KTX2"),
            })?;
        out.push(Some(ImageBytes { data, mime_type }));
    }
    Ok(out)
}

/// The bytes behind a URI and the media type a data URI declares.
fn load_uri(
    path: &Path,
    uri: &str,
    base_dir: Option<&Path>,
) -> Result<(Vec<u8>, Option<String>), String> {
    if let Some(rest) = uri.strip_prefix("data:") {
        let (header, payload) = rest
            .split_once(',')
            .ok_or_else(|| "data URI without a ',' before its data".to_string())?;
        let base64 = header.ends_with(";base64");
        let media = header.trim_end_matches(";base64");
        let media = (!media.is_empty()).then(|| media.to_string());
        let data = if base64 {
            base64::engine::general_purpose::STANDARD
                .decode(payload.trim())
                .map_err(|e| format!("bad base64 in data URI: {e}"))?
        } else {
            percent_decode(payload)
        };
        return Ok((data, media));
    }
    if uri.contains("://") {
        return Err(format!(
            "refers to {uri:?}; only embedded data and files next to {} are read",
            path.display()
        ));
    }
    let Some(base) = base_dir else {
        return Err(format!("refers to the external file {uri:?}"));
    };
    let decoded = String::from_utf8(percent_decode(uri))
        .map_err(|_| format!("URI {uri:?} is not UTF-8 after percent-decoding"))?;
    let file: PathBuf = base.join(decoded);
    std::fs::read(&file)
        .map(|d| (d, None))
        .map_err(|e| format!("cannot read {}: {e}", file.display()))
}

/// RFC 3986 percent-decoding (`%20` → space); malformed escapes are kept literally.
fn percent_decode(s: &str) -> Vec<u8> {
    let b = s.as_bytes();
    let mut out = Vec::with_capacity(b.len());
    let mut i = 0;
    while i < b.len() {
        if b[i] == b'%'
            && let Some(v) = b
                .get(i + 1..i + 3)
                .and_then(|h| std::str::from_utf8(h).ok())
                .and_then(|h| u8::from_str_radix(h, 16).ok())
        {
            out.push(v);
            i += 3;
            continue;
        }
        out.push(b[i]);
        i += 1;
    }
    out
}

/// The image type from its first bytes (the signatures of PNG, JPEG, WebP and KTX2).
fn sniff_image(d: &[u8]) -> Option<&'static str> {
    if d.starts_with(&[0x89, b'P', b'N', b'G']) {
        Some("image/png")
    } else if d.starts_with(&[0xFF, 0xD8, 0xFF]) {
        Some("image/jpeg")
    } else if d.len() >= 12 && &d[0..4] == b"RIFF" && &d[8..12] == b"WEBP" {
        Some("image/webp")
    } else if d.starts_with(&[0xAB, b'K', b'T', b'X', b' ', b'2', b'0', 0xBB]) {
        Some("image/ktx2")
    } else {
        None
    }
}

fn mime_from_extension(uri: &str) -> Option<&'static str> {
    let ext = uri.rsplit('.').next()?.to_ascii_lowercase();
    match ext.as_str() {
        "png" => Some("image/png"),
        "jpg" | "jpeg" => Some("image/jpeg"),
        "webp" => Some("image/webp"),
        "ktx2" => Some("image/ktx2"),
        _ => None,
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn glb(json: &str, bin: &[u8]) -> Vec<u8> {
        dancegen_formats::glb_container::assemble_glb(json.as_bytes().to_vec(), bin.to_vec())
            .unwrap()
    }

    #[test]
    fn reads_glb_and_data_uris() {
        let p = Path::new("x.glb");
        let a = parse_gltf(
            p,
            &glb(
                r#"{"asset":{"version":"2.0"},"buffers":[{"byteLength":3}],
                "bufferViews":[{"buffer":0,"byteLength":3}]}"#,
                &[1, 2, 3],
            ),
            None,
        )
        .unwrap();
        assert_eq!(a.buffers, vec![vec![1, 2, 3]]);

        let png = base64::engine::general_purpose::STANDARD.encode([0x89, b'P', b'N', b'G', 0]);
        let text = format!(
            r#"{{"asset":{{"version":"2.0"}},
            "buffers":[{{"byteLength":2,"uri":"data:application/octet-stream;base64,AAE="}}],
            "images":[{{"uri":"data:image/png;base64,{png}"}}]}}"#
        );
        let a = parse_gltf(Path::new("x.gltf"), text.as_bytes(), None).unwrap();
        assert_eq!(a.buffers, vec![vec![0, 1]]);
        assert_eq!(a.images[0].as_ref().unwrap().mime_type, "image/png");
    }

    #[test]
    fn rejects_non_gltf_and_broken_files() {
        let p = Path::new("song.mp3");
        let e = parse_gltf(p, b"ID3\x04garbage", None).unwrap_err();
        assert!(matches!(e, CharacterError::NotGltf { .. }), "{e}");
        assert!(
            e.to_string().starts_with("song.mp3: not a glTF file"),
            "{e}"
        );
        let e = parse_gltf(p, br#"{"hello": 1}"#, None).unwrap_err();
        assert!(matches!(e, CharacterError::NotGltf { .. }), "{e}");
        let e = parse_gltf(p, br#"{"asset": {"version": "1.0"}}"#, None).unwrap_err();
        assert!(e.to_string().contains("only glTF 2.0"), "{e}");
        // Truncated GLB and out-of-range views never panic.
        let mut g = glb(r#"{"asset":{"version":"2.0"}}"#, &[]);
        g.truncate(g.len() - 3);
        assert!(matches!(
            parse_gltf(p, &g, None),
            Err(CharacterError::Invalid { .. })
        ));
        let g = glb(
            r#"{"asset":{"version":"2.0"},"buffers":[{"byteLength":4}],
            "bufferViews":[{"buffer":0,"byteOffset":2,"byteLength":4}]}"#,
            &[0; 4],
        );
        let e = parse_gltf(p, &g, None).unwrap_err();
        assert!(e.to_string().contains("bufferView 0"), "{e}");
        for n in 0..20 {
            let _ = parse_gltf(p, &glb(r#"{"asset":{"version":"2.0"}}"#, &[1])[..n], None);
        }
    }

    #[test]
    fn percent_decoding() {
        assert_eq!(percent_decode("a%20b%zz"), b"a b%zz");
    }
}
