//! Writers: PNG (one frame), GIF (fixed palette) and MP4 (ffmpeg), all atomic.

use std::io::{Read, Write};
use std::path::{Path, PathBuf};
use std::process::{Command, Stdio};

use dancegen_io::write_atomic;

use crate::yuv::Yuv420pStream;
use crate::{RenderError, RgbImage};

fn io_other(e: impl std::fmt::Display) -> std::io::Error {
    std::io::Error::other(e.to_string())
}

/// Encodes one image as an 8-bit RGB PNG.
pub fn encode_png(w: &mut dyn Write, img: &RgbImage) -> std::io::Result<()> {
    let mut enc = png::Encoder::new(w, img.width, img.height);
    enc.set_color(png::ColorType::Rgb);
    enc.set_depth(png::BitDepth::Eight);
    let mut wr = enc.write_header().map_err(io_other)?;
    wr.write_image_data(&img.data).map_err(io_other)?;
    wr.finish().map_err(io_other)
}

/// Writes one image as a PNG, atomically.
pub fn write_png(path: &Path, img: &RgbImage) -> Result<(), RenderError> {
    write_atomic(path, |w| encode_png(w, img))?;
    Ok(())
}

/// The fixed GIF palette: a 6×7×6 RGB cube (252 colours) plus 4 greys.
pub fn gif_palette() -> Vec<u8> {
    let mut p = Vec::with_capacity(768);
    for r in 0..6u32 {
        for g in 0..7u32 {
            for b in 0..6u32 {
                p.extend([
                    (r * 255 / 5) as u8,
                    (g * 255 / 6) as u8,
                    (b * 255 / 5) as u8,
                ]);
            }
        }
    }
    for v in [32u8, 96, 160, 224] {
        p.extend([v, v, v]);
    }
    p
}

const BAYER4: [[f32; 4]; 4] = [
    [0.0, 8.0, 2.0, 10.0],
    [12.0, 4.0, 14.0, 6.0],
    [3.0, 11.0, 1.0, 9.0],
    [15.0, 7.0, 13.0, 5.0],
];

/// Palette indices for `img` (ordered 4×4 dithering onto [`gif_palette`]'s cube).
pub fn quantize_gif(img: &RgbImage) -> Vec<u8> {
    let lut = dither_lut();
    let (w, h) = (img.width as usize, img.height as usize);
    let mut out = Vec::with_capacity(w * h);
    for (y, row) in img.data.chunks_exact(w * 3).take(h).enumerate() {
        for (x, p) in row.chunks_exact(3).enumerate() {
            let t = &lut[(y & 3) * 4 + (x & 3)];
            out.push(t[0][p[0] as usize] + t[1][p[1] as usize] + t[2][p[2] as usize]);
        }
    }
    out
}

/// Per Bayer cell and channel, what each 8-bit value adds to the palette index (red level
/// × 42, green level × 6, blue level), evaluated once with the dithering formula, so that
/// quantising a pixel is three table reads instead of three float roundings.
type DitherLut = [[[u8; 256]; 3]; 16];

fn dither_lut() -> &'static DitherLut {
    static LUT: std::sync::OnceLock<Box<DitherLut>> = std::sync::OnceLock::new();
    LUT.get_or_init(|| {
        let mut lut = Box::new([[[0u8; 256]; 3]; 16]);
        for (cell, t) in lut.iter_mut().enumerate() {
            let th = (BAYER4[cell / 4][cell % 4] + 0.5) / 16.0 - 0.5;
            let channels = [(6.0f32, 42u32), (7.0, 6), (6.0, 1)];
            for (table, (levels, weight)) in t.iter_mut().zip(channels) {
                for (v, out) in table.iter_mut().enumerate() {
                    *out = (quantize_level(v as u8, levels, th) * weight) as u8;
                }
            }
        }
        lut
    })
}

/// One channel's dithered level: `v` scaled to `0..levels − 1`, offset by the threshold `th`.
fn quantize_level(v: u8, levels: f32, th: f32) -> u32 {
    let f = v as f32 / 255.0 * (levels - 1.0) + th;
    f.round().clamp(0.0, levels - 1.0) as u32
}

/// [`quantize_gif`] as it was written first, a float rounding per channel (the tests check the
/// table against it).
#[cfg(test)]
pub(crate) fn quantize_gif_reference(img: &RgbImage) -> Vec<u8> {
    let (w, h) = (img.width as usize, img.height as usize);
    let mut out = Vec::with_capacity(w * h);
    for y in 0..h {
        for x in 0..w {
            let i = (y * w + x) * 3;
            let th = (BAYER4[y & 3][x & 3] + 0.5) / 16.0 - 0.5;
            let (r, g, b) = (
                quantize_level(img.data[i], 6.0, th),
                quantize_level(img.data[i + 1], 7.0, th),
                quantize_level(img.data[i + 2], 6.0, th),
            );
            out.push((r * 42 + g * 6 + b) as u8);
        }
    }
    out
}

/// Frames drawn ahead of the encoder (about 28 MB at 640x480).
const PIPELINE_FRAMES: usize = 32;

/// Runs `consume` on `items` while a second thread keeps pulling the next ones, so drawing
/// frames (the renderer's parallel batches) overlaps encoding them (the GIF encoder and the
/// pipe to ffmpeg are sequential): without it, the cores sat idle whenever the encoder had a
/// batch to work through. Stopping early (an error, a cancelled job) stops the producer at its
/// next frame.
pub fn pipelined<T: Send, R>(
    items: impl Iterator<Item = T> + Send,
    consume: impl FnOnce(&mut dyn Iterator<Item = T>) -> R,
) -> R {
    std::thread::scope(|s| {
        let (tx, rx) = std::sync::mpsc::sync_channel(PIPELINE_FRAMES);
        s.spawn(move || {
            for item in items {
                if tx.send(item).is_err() {
                    break;
                }
            }
        });
        let mut received = rx.into_iter();
        let r = consume(&mut received);
        // Dropping the receiver ends a producer that is still drawing.
        drop(received);
        r
    })
}

/// Writes an infinitely looping GIF at `fps` (delays in 1/100 s, rounded without drift).
/// Frames are drawn ahead on another thread while earlier ones are encoded.
pub fn write_gif(
    path: &Path,
    frames: impl Iterator<Item = RgbImage> + Send,
    fps: f32,
) -> Result<usize, RenderError> {
    pipelined(frames, |frames| write_gif_from(path, frames, fps))
}

fn write_gif_from(
    path: &Path,
    frames: &mut dyn Iterator<Item = RgbImage>,
    fps: f32,
) -> Result<usize, RenderError> {
    if !(fps.is_finite() && fps > 0.0) {
        return Err(RenderError::Invalid(format!("frame rate {fps}")));
    }
    let mut count = 0usize;
    let palette = gif_palette();
    write_atomic(path, |w| {
        let mut enc: Option<gif::Encoder<&mut dyn Write>> = None;
        let mut w = Some(w);
        let mut prev: Option<Vec<u8>> = None;
        for (k, img) in frames.enumerate() {
            if enc.is_none() {
                let (gw, gh) = (
                    u16::try_from(img.width).map_err(io_other)?,
                    u16::try_from(img.height).map_err(io_other)?,
                );
                let mut e = gif::Encoder::new(w.take().expect("writer"), gw, gh, &palette)
                    .map_err(io_other)?;
                e.set_repeat(gif::Repeat::Infinite).map_err(io_other)?;
                enc = Some(e);
            }
            let e = enc.as_mut().expect("encoder");
            let cs = |k: usize| (k as f64 * 100.0 / fps as f64).round() as i64;
            let delay = (cs(k + 1) - cs(k)).clamp(2, 65535) as u16;
            let idx = quantize_gif(&img);
            // Only the rectangle that changed since the previous frame is stored (the camera
            // is fixed, so that is the dancers and their shadows).
            let (left, top, fw, fh) = match &prev {
                Some(p) => changed_rect(p, &idx, img.width as usize, img.height as usize),
                None => (0, 0, img.width as usize, img.height as usize),
            };
            let w = img.width as usize;
            let mut buf = Vec::with_capacity(fw * fh);
            for y in top..top + fh {
                buf.extend_from_slice(&idx[y * w + left..y * w + left + fw]);
            }
            let frame = gif::Frame {
                left: left as u16,
                top: top as u16,
                width: fw as u16,
                height: fh as u16,
                buffer: std::borrow::Cow::Owned(buf),
                delay,
                dispose: gif::DisposalMethod::Keep,
                ..gif::Frame::default()
            };
            e.write_frame(&frame).map_err(io_other)?;
            prev = Some(idx);
            count += 1;
        }
        if enc.is_none() {
            return Err(io_other("no frames"));
        }
        Ok(())
    })?;
    Ok(count)
}

/// Bounding rectangle `(left, top, width, height)` of the pixels that differ (at least 1×1).
fn changed_rect(a: &[u8], b: &[u8], w: usize, h: usize) -> (usize, usize, usize, usize) {
    let (mut x0, mut y0, mut x1, mut y1) = (w, h, 0, 0);
    for y in 0..h {
        let (ra, rb) = (&a[y * w..(y + 1) * w], &b[y * w..(y + 1) * w]);
        if ra == rb {
            continue;
        }
        let first = ra.iter().zip(rb).position(|(p, q)| p != q).unwrap_or(0);
        let last = w
            - 1
            - ra.iter()
                .rev()
                .zip(rb.iter().rev())
                .position(|(p, q)| p != q)
                .unwrap_or(0);
        x0 = x0.min(first);
        x1 = x1.max(last + 1);
        y0 = y0.min(y);
        y1 = y + 1;
    }
    if x1 <= x0 || y1 <= y0 {
        return (0, 0, 1, 1);
    }
    (x0, y0, x1 - x0, y1 - y0)
}

/// The ffmpeg executable: `$DANCEGEN_FFMPEG` if set, else `ffmpeg` from PATH.
pub fn ffmpeg_program() -> PathBuf {
    std::env::var_os("DANCEGEN_FFMPEG")
        .map(PathBuf::from)
        .unwrap_or_else(|| PathBuf::from("ffmpeg"))
}

/// Whether ffmpeg can be started.
pub fn ffmpeg_available() -> bool {
    Command::new(ffmpeg_program())
        .arg("-version")
        .stdout(Stdio::null())
        .stderr(Stdio::null())
        .status()
        .is_ok_and(|s| s.success())
}

/// x264 speed preset and quality of the MP4 previews. Measured on the 45 s preview of
/// `bench/preview.sh` (1350 frames, 640x480; PSNR / SSIM of the video decoded back to RGB
/// against the rendered RGB frames; x264's CPU seconds; video bytes), with this crate's YUV
/// conversion: `superfast` + CRF 20: 42.87 dB / 0.99392, 1.6 s, 3.7 MB; CRF 19: 43.05 dB /
/// 0.99426, 1.75 s, 4.1 MB; CRF 22: 42.39 dB / 0.99302; `veryfast` + CRF 20: 40.96 dB /
/// 0.99149, 2.2 s, 1.4 MB. The previews made before (ffmpeg's conversion, `medium` + CRF 20)
/// scored 41.03 dB / 0.99308 in 1.5 MB at about 3 s. `superfast` + CRF 20 is closer to the
/// rendered frames on both measures for half the encoder time, in a file about 2.5x larger
/// (about 0.65 Mbit/s of video, still small for a preview).
const X264_PRESET: &str = "superfast";
const X264_CRF: &str = "20";

/// Encodes H.264/yuv420p MP4 through ffmpeg (raw frames on its stdin, converted to YUV 4:2:0
/// by [`Yuv420pStream`] on the way), with `audio` muxed
/// as AAC and cut to the shorter of the two. Written to a temporary `.mp4` in the output's
/// directory and renamed into place on success. Frames are drawn ahead on another thread
/// while earlier ones go to ffmpeg.
/// The sound of a video: `seconds` of the audio file `path` from `start_s`, decoded by ffmpeg
/// itself so that every channel of the song is kept (a stereo song stays stereo).
#[derive(Clone, Copy, Debug)]
pub struct AudioClip<'a> {
    pub path: &'a Path,
    pub start_s: f64,
    /// `None`: to the end of the file (the video's length cuts it, `-shortest`).
    pub seconds: Option<f64>,
}

impl<'a> AudioClip<'a> {
    /// The whole file from its start.
    pub fn whole(path: &'a Path) -> Self {
        AudioClip {
            path,
            start_s: 0.0,
            seconds: None,
        }
    }
}

pub fn write_mp4(
    path: &Path,
    frames: impl Iterator<Item = RgbImage> + Send,
    width: u32,
    height: u32,
    fps: f32,
    audio: Option<AudioClip<'_>>,
) -> Result<usize, RenderError> {
    pipelined(frames, |frames| {
        write_mp4_from(path, frames, width, height, fps, audio)
    })
}

fn write_mp4_from(
    path: &Path,
    frames: &mut dyn Iterator<Item = RgbImage>,
    width: u32,
    height: u32,
    fps: f32,
    audio: Option<AudioClip<'_>>,
) -> Result<usize, RenderError> {
    if !width.is_multiple_of(2) || !height.is_multiple_of(2) {
        return Err(RenderError::Invalid(format!(
            "MP4 (yuv420p) needs an even width and height, got {width}x{height}"
        )));
    }
    if let Some(a) = audio
        && !a.path.is_file()
    {
        return Err(RenderError::Invalid(format!(
            "{}: no such audio file",
            a.path.display()
        )));
    }
    let dir = match path.parent() {
        Some(d) if !d.as_os_str().is_empty() => d,
        _ => Path::new("."),
    };
    let wr_err = |reason: String| dancegen_io::atomic::WriteError {
        path: path.to_path_buf(),
        reason,
    };
    if !dir.is_dir() {
        return Err(wr_err(format!("directory {} does not exist", dir.display())).into());
    }
    let tmp = tempfile::Builder::new()
        .prefix(".dancegen-")
        .suffix(".mp4")
        .tempfile_in(dir)
        .map_err(|e| wr_err(e.to_string()))?;
    let mut cmd = Command::new(ffmpeg_program());
    cmd.args(["-hide_banner", "-loglevel", "error", "-nostdin", "-y"])
        .args(["-f", "rawvideo", "-pix_fmt", "yuv420p"])
        .args(["-s", &format!("{width}x{height}")])
        .args(["-framerate", &format!("{fps}")])
        .args(["-i", "pipe:0"]);
    if let Some(a) = audio {
        // Input options: decode from `start_s`, for `seconds` (sample-accurate for audio).
        cmd.args(["-ss", &format!("{:.6}", a.start_s.max(0.0))]);
        if let Some(s) = a.seconds {
            cmd.args(["-t", &format!("{s:.6}")]);
        }
        cmd.arg("-i").arg(a.path);
        cmd.args([
            "-map",
            "0:v:0",
            "-map",
            "1:a:0",
            "-c:a",
            "aac",
            "-b:a",
            "192k",
            "-shortest",
        ]);
    }
    cmd.args(["-c:v", "libx264", "-pix_fmt", "yuv420p"])
        .args(["-preset", X264_PRESET, "-crf", X264_CRF])
        .args(["-movflags", "+faststart", "-f", "mp4"])
        .arg(tmp.path())
        .stdin(Stdio::piped())
        .stdout(Stdio::null())
        .stderr(Stdio::piped());
    let mut child = match cmd.spawn() {
        Ok(c) => c,
        Err(e) if e.kind() == std::io::ErrorKind::NotFound => {
            return Err(RenderError::FfmpegMissing);
        }
        Err(e) => return Err(RenderError::Ffmpeg(format!("cannot start: {e}"))),
    };
    let mut stderr = child.stderr.take().expect("piped stderr");
    let reader = std::thread::spawn(move || {
        let mut s = String::new();
        let _ = stderr.read_to_string(&mut s);
        s
    });
    let mut count = 0usize;
    let mut write_err = None;
    {
        let mut stdin = child.stdin.take().expect("piped stdin");
        let mut yuv = Yuv420pStream::new();
        for img in frames {
            if img.width != width || img.height != height {
                write_err = Some(format!("frame {count} is {}x{}", img.width, img.height));
                break;
            }
            if let Err(e) = stdin.write_all(yuv.convert(img)) {
                write_err = Some(e.to_string());
                break;
            }
            count += 1;
        }
    }
    let status = child.wait()?;
    let log = reader.join().unwrap_or_default();
    if !status.success() || write_err.is_some() {
        let msg = log.trim();
        return Err(RenderError::Ffmpeg(if msg.is_empty() {
            write_err.unwrap_or_else(|| status.to_string())
        } else {
            msg.to_string()
        }));
    }
    #[cfg(unix)]
    {
        use std::os::unix::fs::PermissionsExt;
        tmp.as_file()
            .set_permissions(std::fs::Permissions::from_mode(0o644))
            .map_err(|e| wr_err(e.to_string()))?;
    }
    tmp.persist(path).map_err(|e| wr_err(e.error.to_string()))?;
    Ok(count)
}
