//! The GLB container (glTF 2.0 binary, spec §4.4): a 12-byte header, a JSON chunk padded with
//! spaces and a BIN chunk padded with zeros, each to 4 bytes. One reader and one writer of it
//! serve every glTF output (`gltf.rs` here, the character writer of `dancegen-character`).

/// `"glTF"` read as a little-endian `u32` (spec §4.4.2).
pub const GLB_MAGIC: u32 = 0x4654_6C67;
/// Chunk types `"JSON"` and `"BIN\0"` (spec §4.4.3).
pub const CHUNK_JSON: u32 = 0x4E4F_534A;
pub const CHUNK_BIN: u32 = 0x004E_4942;
/// The container version this writes and reads.
const GLB_VERSION: u32 = 2;

/// A GLB file of `json` and `bin` (no BIN chunk when `bin` is empty); an error when the file
/// would pass GLB's 32-bit length fields.
pub fn assemble_glb(mut json: Vec<u8>, mut bin: Vec<u8>) -> Result<Vec<u8>, String> {
    while !json.len().is_multiple_of(4) {
        json.push(b' ');
    }
    while !bin.len().is_multiple_of(4) {
        bin.push(0);
    }
    let bin_chunk = if bin.is_empty() { 0 } else { 8 + bin.len() };
    let total = 12 + 8 + json.len() + bin_chunk;
    let total32 = u32::try_from(total)
        .map_err(|_| format!("the file would be {total} bytes, over GLB's 4 GiB limit"))?;
    let mut out = Vec::with_capacity(total);
    for v in [
        GLB_MAGIC,
        GLB_VERSION,
        total32,
        json.len() as u32,
        CHUNK_JSON,
    ] {
        out.extend(v.to_le_bytes());
    }
    out.extend(&json);
    if !bin.is_empty() {
        out.extend((bin.len() as u32).to_le_bytes());
        out.extend(CHUNK_BIN.to_le_bytes());
        out.extend(&bin);
    }
    Ok(out)
}

/// Why bytes are not a GLB this reads.
#[derive(Debug, Clone, PartialEq, Eq)]
pub enum GlbError {
    /// A GLB of another container version.
    Unsupported(String),
    /// Not a well-formed GLB.
    Invalid(String),
}

impl std::fmt::Display for GlbError {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            GlbError::Unsupported(s) | GlbError::Invalid(s) => f.write_str(s),
        }
    }
}

/// Splits a GLB into its JSON chunk and its first BIN chunk; every length is checked against
/// the bytes present before it is used.
pub fn split_glb(bytes: &[u8]) -> Result<(&[u8], Option<&[u8]>), GlbError> {
    let u32_at = |o: usize| -> Option<u32> {
        bytes
            .get(o..o + 4)
            .map(|b| u32::from_le_bytes([b[0], b[1], b[2], b[3]]))
    };
    let (Some(version), Some(length)) = (u32_at(4), u32_at(8)) else {
        return Err(GlbError::Invalid(
            "GLB header is shorter than 12 bytes".into(),
        ));
    };
    if version != 2 {
        return Err(GlbError::Unsupported(format!(
            "binary glTF version {version}; only version 2 (glTF 2.0) is read"
        )));
    }
    let length = length as usize;
    if length > bytes.len() {
        return Err(GlbError::Invalid(format!(
            "truncated: the GLB header says {length} bytes, the file has {}",
            bytes.len()
        )));
    }
    let mut offset = 12;
    let mut json = None;
    let mut bin = None;
    while offset + 8 <= length {
        let chunk_len = u32_at(offset).unwrap_or(0) as usize;
        let kind = u32_at(offset + 4).unwrap_or(0);
        let start = offset + 8;
        let Some(end) = start.checked_add(chunk_len).filter(|&e| e <= length) else {
            return Err(GlbError::Invalid(format!(
                "chunk at byte {offset} claims {chunk_len} bytes, past the end of the file"
            )));
        };
        let data = &bytes[start..end];
        match kind {
            CHUNK_JSON if json.is_none() => json = Some(data),
            CHUNK_BIN if bin.is_none() && json.is_some() => bin = Some(data),
            _ => {} // unknown chunks are skipped, as the specification says
        }
        if json.is_none() {
            return Err(GlbError::Invalid("the first GLB chunk is not JSON".into()));
        }
        offset = end;
    }
    match json {
        Some(j) => Ok((j, bin)),
        None => Err(GlbError::Invalid("the GLB has no JSON chunk".into())),
    }
}
