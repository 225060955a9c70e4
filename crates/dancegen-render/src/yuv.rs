//! RGB to YUV 4:2:0 (the MP4 previews' pixel format), done here instead of by ffmpeg.
//!
//! The conversion is ITU-R BT.601 with limited ("TV") range, the matrix and range ffmpeg's
//! swscale used when it converted our RGB frames, so players show the same colours. Chroma is
//! the mean of each 2×2 block (the frame size is even; [`crate::write::write_mp4`] checks).
//! Converting here lets the pipe to ffmpeg carry half the bytes and takes swscale (about a
//! quarter of ffmpeg's CPU time for a preview) off the encoder's side.

use crate::RgbImage;

/// Fixed-point scale of the coefficients (16 fractional bits).
const ONE: i32 = 1 << 16;
const HALF: i32 = 1 << 15;

/// `round(c · 2^16)` of a BT.601 coefficient already scaled to limited range: luma
/// `219/255 · (0.299, 0.587, 0.114)`, chroma `224/255 · (−0.168736, −0.331264, 0.5)` and
/// `224/255 · (0.5, −0.418688, −0.081312)` (Rec. ITU-R BT.601-7, §2.5).
const fn fixed(c: f64) -> i32 {
    let v = c * ONE as f64;
    (if v < 0.0 { v - 0.5 } else { v + 0.5 }) as i32
}
const Y_R: i32 = fixed(219.0 / 255.0 * 0.299);
const Y_G: i32 = fixed(219.0 / 255.0 * 0.587);
const Y_B: i32 = fixed(219.0 / 255.0 * 0.114);
const U_R: i32 = fixed(224.0 / 255.0 * -0.168_736);
const U_G: i32 = fixed(224.0 / 255.0 * -0.331_264);
const U_B: i32 = fixed(224.0 / 255.0 * 0.5);
const V_R: i32 = fixed(224.0 / 255.0 * 0.5);
const V_G: i32 = fixed(224.0 / 255.0 * -0.418_688);
const V_B: i32 = fixed(224.0 / 255.0 * -0.081_312);

/// Bytes of one `width × height` YUV 4:2:0 frame (both even).
pub fn yuv420p_len(width: u32, height: u32) -> usize {
    let (w, h) = (width as usize, height as usize);
    w * h + 2 * (w / 2) * (h / 2)
}

/// Writes `img` as planar YUV 4:2:0 (the Y plane, then U, then V) into `out`, which is
/// resized to [`yuv420p_len`]. `img` must have an even width and height.
pub fn rgb_to_yuv420p(img: &RgbImage, out: &mut Vec<u8>) {
    out.resize(yuv420p_len(img.width, img.height), 0);
    for cy in 0..img.height as usize / 2 {
        convert_span(img, out, cy, 0, img.width as usize / 2);
    }
}

/// Converts a stream of frames, redoing only what changed since the previous frame: a preview
/// has a fixed camera, so most of every frame is the same floor and sky. For each pair of pixel
/// rows (one chroma row) the span between the first and the last differing pixel is converted
/// again; the rest of the previous frame's YUV stays. The bytes are exactly
/// [`rgb_to_yuv420p`]'s.
#[derive(Default)]
pub struct Yuv420pStream {
    prev: Option<RgbImage>,
    out: Vec<u8>,
}

impl Yuv420pStream {
    pub fn new() -> Self {
        Self::default()
    }

    /// The YUV 4:2:0 bytes of `img` (even width and height).
    pub fn convert(&mut self, img: RgbImage) -> &[u8] {
        match self.prev.take() {
            Some(prev) if prev.width == img.width && prev.height == img.height => {
                let w3 = img.width as usize * 3;
                for cy in 0..img.height as usize / 2 {
                    // The differing bytes of either row, as whole 2-pixel (6-byte) blocks.
                    let mut span: Option<(usize, usize)> = None;
                    for y in [2 * cy, 2 * cy + 1] {
                        let rows = y * w3..(y + 1) * w3;
                        if let Some((f, l)) = differing(&prev.data[rows.clone()], &img.data[rows]) {
                            span = Some(span.map_or((f, l), |(a, b)| (a.min(f), b.max(l))));
                        }
                    }
                    if let Some((first, last)) = span {
                        convert_span(&img, &mut self.out, cy, first / 6, last / 6 + 1);
                    }
                }
            }
            _ => rgb_to_yuv420p(&img, &mut self.out),
        }
        self.prev = Some(img);
        &self.out
    }
}

/// The first and last index where `a` and `b` differ, if they do.
fn differing(a: &[u8], b: &[u8]) -> Option<(usize, usize)> {
    if a == b {
        return None;
    }
    // Eight bytes at a time up to the first and the last differing word, then bytewise.
    const W: usize = 8;
    let words = a.len() / W;
    let same_word = |k: usize| a[k * W..(k + 1) * W] == b[k * W..(k + 1) * W];
    let first_word = (0..words).find(|&k| !same_word(k)).unwrap_or(words);
    let first = (first_word * W..a.len()).find(|&i| a[i] != b[i])?;
    let tail = words * W;
    let last = (tail..a.len()).rev().find(|&i| a[i] != b[i]).or_else(|| {
        let k = (0..words).rev().find(|&k| !same_word(k))?;
        (k * W..(k + 1) * W).rev().find(|&i| a[i] != b[i])
    })?;
    Some((first, last))
}

/// Converts chroma blocks `x0..x1` of chroma row `cy`: the luma of pixels `2·x0..2·x1` of rows
/// `2·cy` and `2·cy + 1`, and those blocks' U and V. `out` holds [`yuv420p_len`] bytes.
fn convert_span(img: &RgbImage, out: &mut [u8], cy: usize, x0: usize, x1: usize) {
    let (w, h) = (img.width as usize, img.height as usize);
    debug_assert!(w.is_multiple_of(2) && h.is_multiple_of(2));
    let (luma, chroma) = out.split_at_mut(w * h);
    let (u_plane, v_plane) = chroma.split_at_mut((w / 2) * (h / 2));
    let cw = w / 2;
    let row = |y: usize| &img.data[(y * w + 2 * x0) * 3..(y * w + 2 * x1) * 3];
    let (top, bottom) = (row(2 * cy), row(2 * cy + 1));
    for (y, rgb) in [(2 * cy, top), (2 * cy + 1, bottom)] {
        let ys = &mut luma[y * w + 2 * x0..y * w + 2 * x1];
        for (o, p) in ys.iter_mut().zip(rgb.chunks_exact(3)) {
            let (r, g, b) = (p[0] as i32, p[1] as i32, p[2] as i32);
            *o = ((Y_R * r + Y_G * g + Y_B * b + HALF) >> 16) as u8 + 16;
        }
    }
    let us = &mut u_plane[cy * cw + x0..cy * cw + x1];
    let vs = &mut v_plane[cy * cw + x0..cy * cw + x1];
    for (((t, b), u), v) in top
        .chunks_exact(6)
        .zip(bottom.chunks_exact(6))
        .zip(us.iter_mut())
        .zip(vs.iter_mut())
    {
        // Sums of the four pixels' channels: the coefficients apply to 4× the mean.
        let r = t[0] as i32 + t[3] as i32 + b[0] as i32 + b[3] as i32;
        let g = t[1] as i32 + t[4] as i32 + b[1] as i32 + b[4] as i32;
        let bl = t[2] as i32 + t[5] as i32 + b[2] as i32 + b[5] as i32;
        *u = (((U_R * r + U_G * g + U_B * bl + 4 * HALF) >> 18) + 128) as u8;
        *v = (((V_R * r + V_G * g + V_B * bl + 4 * HALF) >> 18) + 128) as u8;
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn solid(w: u32, h: u32, c: [u8; 3]) -> RgbImage {
        RgbImage {
            width: w,
            height: h,
            data: c.repeat((w * h) as usize),
        }
    }

    fn convert(img: &RgbImage) -> Vec<u8> {
        let mut out = Vec::new();
        rgb_to_yuv420p(img, &mut out);
        out
    }

    /// The BT.601 limited-range values every video tool agrees on.
    #[test]
    fn primaries_and_greys_get_their_bt601_values() {
        for (rgb, yuv) in [
            ([0, 0, 0], [16, 128, 128]),
            ([255, 255, 255], [235, 128, 128]),
            ([255, 0, 0], [81, 90, 240]),
            ([0, 255, 0], [145, 54, 34]),
            ([0, 0, 255], [41, 240, 110]),
            ([128, 128, 128], [126, 128, 128]),
        ] {
            let out = convert(&solid(4, 2, rgb));
            assert_eq!(out.len(), 8 + 2 + 2);
            assert!(
                out[..8].iter().all(|&y| y == yuv[0]),
                "{rgb:?}: Y {:?}",
                &out[..8]
            );
            assert_eq!(&out[8..10], &[yuv[1]; 2], "{rgb:?}: U");
            assert_eq!(&out[10..12], &[yuv[2]; 2], "{rgb:?}: V");
        }
    }

    /// Against the formula in floating point, on every pixel of a varied image: within the
    /// rounding to integers (0.5) plus the 16-bit coefficients' own rounding (at most
    /// 3 · 255 · 2⁻¹⁷ ≈ 0.006), hence 0.51.
    #[test]
    fn matches_the_bt601_formula_within_rounding() {
        let (w, h) = (10u32, 6u32);
        let data: Vec<u8> = (0..w * h * 3).map(|i| (i * 37 % 251) as u8).collect();
        let img = RgbImage {
            width: w,
            height: h,
            data,
        };
        let out = convert(&img);
        let px = |x: usize, y: usize| {
            let i = (y * w as usize + x) * 3;
            [0, 1, 2].map(|c| img.data[i + c] as f64)
        };
        for y in 0..h as usize {
            for x in 0..w as usize {
                let [r, g, b] = px(x, y);
                let want = 16.0 + 219.0 / 255.0 * (0.299 * r + 0.587 * g + 0.114 * b);
                let got = out[y * w as usize + x] as f64;
                assert!((got - want).abs() <= 0.51, "Y at {x},{y}: {got} vs {want}");
            }
        }
        let cw = w as usize / 2;
        let planes = (w * h) as usize;
        for cy in 0..h as usize / 2 {
            for cx in 0..cw {
                let mut m = [0.0; 3];
                for (dx, dy) in [(0, 0), (1, 0), (0, 1), (1, 1)] {
                    let p = px(2 * cx + dx, 2 * cy + dy);
                    for c in 0..3 {
                        m[c] += p[c] / 4.0;
                    }
                }
                let u = 128.0 + 224.0 / 255.0 * (-0.168736 * m[0] - 0.331264 * m[1] + 0.5 * m[2]);
                let v = 128.0 + 224.0 / 255.0 * (0.5 * m[0] - 0.418688 * m[1] - 0.081312 * m[2]);
                let gu = out[planes + cy * cw + cx] as f64;
                let gv = out[planes + cw * (h as usize / 2) + cy * cw + cx] as f64;
                assert!((gu - u).abs() <= 0.51, "U at {cx},{cy}: {gu} vs {u}");
                assert!((gv - v).abs() <= 0.51, "V at {cx},{cy}: {gv} vs {v}");
            }
        }
    }

    /// A stream of frames with small moving changes (and a size change) converts to exactly
    /// what each frame converts to on its own.
    #[test]
    fn stream_conversion_equals_whole_frame_conversion() {
        let (w, h) = (16u32, 10u32);
        let mut stream = Yuv420pStream::new();
        let mut img = solid(w, h, [90, 120, 200]);
        for k in 0..40usize {
            // A changing pixel here and there, some on odd columns and rows, some spanning
            // both rows of a pair.
            let i = (k * 7 % h as usize) * w as usize + (k * 5 % w as usize);
            img.data[i * 3..i * 3 + 3].copy_from_slice(&[(k * 31) as u8, (k * 17) as u8, 3]);
            if k % 3 == 0 {
                let j = (i + w as usize + 3) % (w * h) as usize;
                img.data[j * 3 + 1] ^= 0x55;
            }
            let want = convert(&img);
            assert_eq!(stream.convert(img.clone()), &want[..], "frame {k}");
            // The same frame again changes nothing.
            assert_eq!(stream.convert(img.clone()), &want[..], "frame {k} repeated");
        }
        let other = solid(8, 4, [1, 2, 3]);
        assert_eq!(stream.convert(other.clone()), &convert(&other)[..]);
    }
}
