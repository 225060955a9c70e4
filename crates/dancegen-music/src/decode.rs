//! Streaming audio decoding (WAV, FLAC, OGG/Vorbis, MP3, AIFF, MP4/AAC) to a mono float32 stream.
//!
//! librosa loads through libsndfile and averages the channels in float32; we do the same per
//! frame, so a decoded block can be handed straight to the resampler and the full multi-channel
//! file is never held in memory (a one-hour stereo song would otherwise need ~1.3 GB).

use std::fs::File;
use std::io::{Cursor, Read, Seek, SeekFrom};
use std::panic::{AssertUnwindSafe, catch_unwind};
use std::path::{Path, PathBuf};

use symphonia::core::codecs::audio::{AudioDecoder, AudioDecoderOptions};
use symphonia::core::errors::Error as SymError;
use symphonia::core::formats::probe::Hint;
use symphonia::core::formats::{FormatOptions, FormatReader, TrackType};
use symphonia::core::io::{MediaSource, MediaSourceStream};
use symphonia::core::meta::MetadataOptions;

use crate::error::{MusicError, Result};
use crate::wav_guard::{WAVE_HEAD_BYTES, check_wave_head};

/// Where a song comes from: a file, or bytes in memory (the bundled demo song, an upload).
#[derive(Clone, Debug)]
pub enum AudioSource {
    File(PathBuf),
    /// `name` is used for messages and as the format hint (its extension). Shared, so a
    /// long-running process can hand one upload to several jobs without copying it.
    Bytes {
        name: PathBuf,
        bytes: std::sync::Arc<[u8]>,
    },
}

impl AudioSource {
    /// The path or name shown in messages.
    pub fn label(&self) -> &Path {
        match self {
            AudioSource::File(p) => p,
            AudioSource::Bytes { name, .. } => name,
        }
    }
}

impl From<&Path> for AudioSource {
    fn from(p: &Path) -> Self {
        AudioSource::File(p.to_path_buf())
    }
}

/// An opened audio file that yields mono float32 blocks at its native sample rate.
pub struct MonoDecoder {
    path: PathBuf,
    format: Box<dyn FormatReader>,
    decoder: Box<dyn AudioDecoder>,
    track_id: u32,
    sample_rate: u32,
    channels: usize,
    interleaved: Vec<f32>,
    /// Number of packets that failed to decode and were skipped (as libsndfile/ffmpeg do).
    skipped_packets: usize,
    decoded_any: bool,
    total_frames: Option<u64>,
    decoded_frames: u64,
}

impl MonoDecoder {
    /// Opens `path` and prepares its default audio track for decoding.
    pub fn open(path: &Path) -> Result<Self> {
        Self::open_source(&AudioSource::File(path.to_path_buf()))
    }

    /// Opens a file or an in-memory song.
    pub fn open_source(source: &AudioSource) -> Result<Self> {
        let path = source.label();
        let (media, len, head): (Box<dyn MediaSource>, u64, Vec<u8>) = match source {
            AudioSource::File(p) => {
                let open_err = |err| MusicError::Open {
                    path: p.clone(),
                    err,
                };
                let mut file = File::open(p).map_err(open_err)?;
                let len = file.metadata().map(|m| m.len()).unwrap_or(0);
                let mut head = Vec::new();
                (&mut file)
                    .take(WAVE_HEAD_BYTES as u64)
                    .read_to_end(&mut head)
                    .and_then(|_| file.seek(SeekFrom::Start(0)))
                    .map_err(open_err)?;
                (Box::new(file), len, head)
            }
            AudioSource::Bytes { bytes, .. } => {
                let head = bytes[..bytes.len().min(WAVE_HEAD_BYTES)].to_vec();
                (
                    Box::new(Cursor::new(bytes.clone())),
                    bytes.len() as u64,
                    head,
                )
            }
        };
        if len == 0 {
            return Err(MusicError::EmptyFile {
                path: path.to_path_buf(),
            });
        }
        check_wave_head(&head).map_err(|reason| MusicError::UnknownFormat {
            path: path.to_path_buf(),
            reason,
        })?;
        let mss = MediaSourceStream::new(media, Default::default());
        let mut hint = Hint::new();
        if let Some(ext) = path.extension().and_then(|e| e.to_str()) {
            hint.with_extension(ext);
        }
        let format = decoder_call(path, "reading the container header", || {
            symphonia::default::get_probe().probe(
                &hint,
                mss,
                FormatOptions::default(),
                MetadataOptions::default(),
            )
        })?
        .map_err(|e| match e {
            // The container was recognised but holds an encoding we have no decoder for.
            SymError::Unsupported(what) if !what.contains("format reader") => {
                MusicError::UnsupportedCodec {
                    path: path.to_path_buf(),
                    reason: what.to_string(),
                }
            }
            e => MusicError::UnknownFormat {
                path: path.to_path_buf(),
                reason: e.to_string(),
            },
        })?;
        let track =
            format
                .default_track(TrackType::Audio)
                .ok_or_else(|| MusicError::NoAudioTrack {
                    path: path.to_path_buf(),
                })?;
        let track_id = track.id;
        let total_frames = track.num_frames;
        let params = track
            .codec_params
            .as_ref()
            .and_then(|p| p.audio())
            .ok_or_else(|| MusicError::NoAudioTrack {
                path: path.to_path_buf(),
            })?
            .clone();
        let decoder = decoder_call(path, "setting up the decoder", || {
            symphonia::default::get_codecs()
                .make_audio_decoder(&params, &AudioDecoderOptions::default())
        })?
        .map_err(|e| MusicError::UnsupportedCodec {
            path: path.to_path_buf(),
            reason: e.to_string(),
        })?;
        let sample_rate = params.sample_rate.unwrap_or(0);
        let channels = params.channels.as_ref().map(|c| c.count()).unwrap_or(0);
        Ok(Self {
            path: path.to_path_buf(),
            format,
            decoder,
            track_id,
            sample_rate,
            channels,
            interleaved: Vec::new(),
            skipped_packets: 0,
            decoded_any: false,
            total_frames,
            decoded_frames: 0,
        })
    }

    /// Native sample rate as declared by the container (0 if unknown until the first block).
    pub fn sample_rate(&self) -> u32 {
        self.sample_rate
    }

    /// Path this decoder reads, for error messages.
    pub fn path(&self) -> &Path {
        &self.path
    }

    /// Fraction of the declared length decoded so far (0 when the container does not say).
    pub fn progress(&self) -> f64 {
        match self.total_frames {
            Some(n) if n > 0 => (self.decoded_frames as f64 / n as f64).min(1.0),
            _ => 0.0,
        }
    }

    /// Frames (samples per channel) the container declares, if it does.
    pub fn total_frames(&self) -> Option<u64> {
        self.total_frames
    }

    /// Packets that failed to decode and were skipped.
    pub fn skipped_packets(&self) -> usize {
        self.skipped_packets
    }

    /// Appends the next decoded block, averaged to mono, to `out`.
    ///
    /// Returns `Ok(false)` at the end of the stream.
    pub fn next_block(&mut self, out: &mut Vec<f32>) -> Result<bool> {
        loop {
            let format = &mut self.format;
            let packet =
                match decoder_call(&self.path, "reading a packet", || format.next_packet())? {
                    Ok(Some(p)) => p,
                    Ok(None) => {
                        self.check_complete()?;
                        return Ok(false);
                    }
                    Err(SymError::IoError(e)) if e.kind() == std::io::ErrorKind::UnexpectedEof => {
                        // The container promised more bytes than the file has. A missing tail is
                        // lost music: say so rather than silently analysing part of the song.
                        if self.decoded_any {
                            return Err(self.truncated(format!(
                                "stream ends inside a packet after {:.2} s of audio",
                                self.decoded_seconds()
                            )));
                        }
                        return Err(self.corrupt(e.to_string()));
                    }
                    Err(SymError::ResetRequired) => {
                        return Err(self.corrupt("stream changes its format mid-file".into()));
                    }
                    Err(e) => return Err(self.corrupt(e.to_string())),
                };
            if packet.track_id != self.track_id {
                continue;
            }
            let decoder = &mut self.decoder;
            let buf = match decoder_call(&self.path, "decoding a packet", || {
                decoder.decode(&packet)
            })? {
                Ok(buf) => buf,
                Err(SymError::DecodeError(e)) => {
                    self.skipped_packets += 1;
                    tracing::debug!("{}: skipping undecodable packet: {e}", self.path.display());
                    if self.skipped_packets > 64 && !self.decoded_any {
                        return Err(self.corrupt(format!("no packet decodes ({e})")));
                    }
                    continue;
                }
                Err(SymError::IoError(e)) => {
                    self.skipped_packets += 1;
                    tracing::debug!("{}: skipping packet: {e}", self.path.display());
                    continue;
                }
                Err(e) => return Err(self.corrupt(e.to_string())),
            };
            let spec = buf.spec();
            let channels = spec.channels().count().max(1);
            let rate = spec.rate();
            if self.sample_rate == 0 {
                self.sample_rate = rate;
            } else if rate != self.sample_rate {
                return Err(self.corrupt(format!(
                    "sample rate changes mid-stream ({} -> {rate} Hz)",
                    self.sample_rate
                )));
            }
            self.channels = channels;
            let frames = buf.frames();
            if frames == 0 {
                continue;
            }
            self.interleaved.clear();
            buf.copy_to_vec_interleaved(&mut self.interleaved);
            self.decoded_any = true;
            self.decoded_frames += frames as u64;
            mix_to_mono(&self.interleaved, channels, out);
            return Ok(true);
        }
    }

    fn decoded_seconds(&self) -> f64 {
        self.decoded_frames as f64 / self.sample_rate.max(1) as f64
    }

    /// At the end of the stream: did we get as many frames as the container declares?
    fn check_complete(&self) -> Result<()> {
        // One codec packet of slack: containers may count encoder padding differently.
        const SLACK_FRAMES: u64 = 8192;
        if let Some(total) = self.total_frames
            && self.decoded_frames + SLACK_FRAMES < total
        {
            let sr = self.sample_rate.max(1) as f64;
            return Err(self.truncated(format!(
                "decoded {:.2} s of the {:.2} s its header declares",
                self.decoded_frames as f64 / sr,
                total as f64 / sr
            )));
        }
        Ok(())
    }

    fn truncated(&self, reason: String) -> MusicError {
        MusicError::Truncated {
            path: self.path.clone(),
            reason,
        }
    }

    fn corrupt(&self, reason: String) -> MusicError {
        MusicError::Corrupt {
            path: self.path.clone(),
            reason,
        }
    }
}

/// Runs one call into symphonia, turning a panic inside it into an error that names the file.
///
/// symphonia is the one dependency that parses songs from anyone (web uploads, batch folders);
/// a bug in it on one hostile file must cost that file, not the server or the batch. After a
/// panic the reader's state is unknown; the error ends the decode, as every decode error does.
fn decoder_call<T>(path: &Path, what: &str, call: impl FnOnce() -> T) -> Result<T> {
    catch_unwind(AssertUnwindSafe(call)).map_err(|panic| {
        let detail = panic
            .downcast_ref::<&str>()
            .map(|s| s.to_string())
            .or_else(|| panic.downcast_ref::<String>().cloned())
            .unwrap_or_else(|| "no message".into());
        MusicError::Corrupt {
            path: path.to_path_buf(),
            reason: format!("the audio decoder failed while {what} ({detail})"),
        }
    })
}

/// Averages interleaved channels in float32, the way `numpy.mean(y, axis=0)` does for few channels.
fn mix_to_mono(interleaved: &[f32], channels: usize, out: &mut Vec<f32>) {
    if channels == 1 {
        out.extend_from_slice(interleaved);
        return;
    }
    let inv = channels as f32;
    out.extend(interleaved.chunks_exact(channels).map(|frame| {
        let s: f32 = frame.iter().sum();
        s / inv
    }));
}

/// Decodes a whole file to mono float32 at its native rate. Returns (samples, sample_rate).
pub fn decode_mono(path: &Path) -> Result<(Vec<f32>, u32)> {
    let mut dec = MonoDecoder::open(path)?;
    let mut out = Vec::new();
    while dec.next_block(&mut out)? {}
    finish(&dec, out)
}

fn finish(dec: &MonoDecoder, out: Vec<f32>) -> Result<(Vec<f32>, u32)> {
    if out.is_empty() {
        return Err(MusicError::NoSamples {
            path: dec.path.clone(),
        });
    }
    if dec.sample_rate == 0 {
        return Err(MusicError::BadSampleRate {
            path: dec.path.clone(),
            rate: 0,
        });
    }
    Ok((out, dec.sample_rate))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_panic_inside_the_decoder_is_the_files_error() {
        let path = Path::new("songs/hostile.wav");
        let err = decoder_call(path, "reading a packet", || -> u32 {
            panic!("attempt to multiply with overflow")
        })
        .unwrap_err()
        .to_string();
        assert_eq!(
            err,
            "songs/hostile.wav: audio stream is corrupt or truncated: the audio decoder failed \
             while reading a packet (attempt to multiply with overflow)"
        );
        assert_eq!(decoder_call(path, "x", || 7).unwrap(), 7);
    }
}
