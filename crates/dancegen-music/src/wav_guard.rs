//! A look at a WAVE file's `fmt ` chunk before symphonia parses it.
//!
//! symphonia-format-riff 0.6.1 multiplies the declared channel count by the bytes per sample in
//! 16 bits (`wave/chunks.rs`, `read_pcm_fmt`), so a 92-byte file that declares 35,329 channels
//! panics with an overflow in builds with overflow checks (found by `fuzz/` target `audio`; the
//! input is `fuzz/findings/audio_riff_fmt_multiply_overflow.wav`). A count that large is not
//! music, and symphonia refuses any count its channel mask cannot hold a moment later anyway, so
//! we refuse it first, with words that name the count.

/// The most channels a WAVE song may declare. symphonia's channel mask is 32 bits wide and it
/// refuses larger counts itself; with at most 32 channels of at most 4 bytes, every product the
/// reader forms fits in 16 bits.
pub const MAX_WAV_CHANNELS: u16 = 32;

/// How much of the file's start [`check_wave_head`] needs to see: the `fmt ` chunk comes within
/// the first few hundred bytes of every real file (after at most a `JUNK`/`LIST` chunk).
pub const WAVE_HEAD_BYTES: usize = 64 * 1024;

/// Checks the channel count of the first `fmt ` chunk found in `head` (the file's first bytes).
/// Files that are not RIFF/RF64 WAVE, or whose `fmt ` chunk lies past `head`, pass unchecked:
/// symphonia reads them. Returns the reason for refusing otherwise.
pub fn check_wave_head(head: &[u8]) -> Result<(), String> {
    let is_wave = head.len() >= 12
        && (head.starts_with(b"RIFF") || head.starts_with(b"RF64"))
        && &head[8..12] == b"WAVE";
    if !is_wave {
        return Ok(());
    }
    let mut pos = 12usize;
    while let Some(header) = pos.checked_add(8).and_then(|end| head.get(pos..end)) {
        let size = u32::from_le_bytes([header[4], header[5], header[6], header[7]]) as usize;
        let body = pos + 8;
        if &header[..4] == b"fmt " {
            let Some(fields) = head.get(body..body + 4) else {
                return Ok(());
            };
            let channels = u16::from_le_bytes([fields[2], fields[3]]);
            if channels == 0 || channels > MAX_WAV_CHANNELS {
                return Err(format!(
                    "its WAVE fmt chunk declares {channels} channels (a song has 1 to {MAX_WAV_CHANNELS})"
                ));
            }
            return Ok(());
        }
        // Chunks are padded to an even length.
        pos = body.saturating_add(size).saturating_add(size & 1);
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    fn wave(channels: u16, before_fmt: &[u8]) -> Vec<u8> {
        let mut v = b"RIFF\0\0\0\0WAVE".to_vec();
        v.extend_from_slice(before_fmt);
        v.extend_from_slice(b"fmt \x10\0\0\0\x01\0");
        v.extend_from_slice(&channels.to_le_bytes());
        v.extend_from_slice(&[0; 12]);
        v
    }

    #[test]
    fn refuses_absurd_and_zero_channel_counts() {
        assert!(check_wave_head(&wave(2, b"")).is_ok());
        assert!(check_wave_head(&wave(32, b"")).is_ok());
        let err = check_wave_head(&wave(35329, b"")).unwrap_err();
        assert!(err.contains("35329 channels"), "{err}");
        assert!(check_wave_head(&wave(0, b"")).is_err());
    }

    #[test]
    fn finds_fmt_after_other_chunks_including_odd_sized_ones() {
        // A 3-byte LIST chunk is padded to 4.
        let list = b"LIST\x03\0\0\0abc\0";
        assert!(check_wave_head(&wave(40, list)).is_err());
        assert!(check_wave_head(&wave(1, list)).is_ok());
    }

    #[test]
    fn other_files_and_truncated_heads_pass_to_symphonia() {
        assert!(check_wave_head(b"OggS\0\0\0\0\0\0\0\0\0").is_ok());
        assert!(check_wave_head(b"RIFF").is_ok());
        assert!(check_wave_head(&wave(40, b"")[..22]).is_ok());
        // A chunk size pointing past the end stops the walk without overflow.
        let mut v = b"RIFF\0\0\0\0WAVEJUNK\xff\xff\xff\xff".to_vec();
        v.extend_from_slice(&wave(40, b"")[12..]);
        assert!(check_wave_head(&v).is_ok());
    }
}
