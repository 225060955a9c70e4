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
