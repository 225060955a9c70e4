//! A small CPU renderer for motion previews: shaded capsule ("stick") figures, one colour per
//! dancer, seen from one fixed camera over a floor grid with soft blob shadows.
//!
//! - **Scene** ([`Scene::new`]): the camera looks at the centre of the bounding box of all
//!   dancers over the whole clip from the front diagonal (+Z front, +X side, slightly above,
//!   Y-up, see `dancegen_motion::conventions`) and is pulled back until every joint of every
//!   frame fits. The floor is the plane at the lowest joint height of the clip minus the
//!   capsule radius, so feet rest on it. Units are whatever the motion uses (metres for SMPL,
//!   file units for BVH); sizes (capsule radius, grid spacing) follow the figure's height.
//! - **Figures**: a capsule around every parent→child bone; joints whose parents are unknown
//!   (raw joint arrays) are drawn as spheres only. The topmost leaf joint (the head) gets a
//!   larger sphere. Ray-cast per pixel inside each primitive's screen box, z-buffered, Lambert
//!   shading plus a sky/ground ambient term; 2×2 supersampling by default.
//! - **Output** ([`write`]): PNG (one frame), GIF (fixed 256-colour palette with ordered
//!   dithering) and MP4 (H.264 through an `ffmpeg` subprocess, fed YUV 4:2:0 frames that
//!   [`yuv`] converts), all written atomically.
//!
//! Frames are rendered in parallel with rayon ([`FrameStream`] renders batches of frames and
//! yields them in order, so long clips never sit in memory at once).

mod math;
mod scene;
pub mod write;
pub mod yuv;

pub use scene::{DancerTrack, RenderOptions, Scene};

use std::path::Path;

use dancegen_formats::dispatch::{LoadedMotion, joint_positions};
use dancegen_motion::skeleton::Skeleton;

/// Why a clip could not be rendered or written.
#[derive(Debug, thiserror::Error)]
pub enum RenderError {
    #[error("nothing to render: {0}")]
    Empty(String),
    #[error("invalid input: {0}")]
    Invalid(String),
    #[error(
        "ffmpeg was not found on PATH: install ffmpeg (e.g. `apt install ffmpeg`) to write MP4, or write a .gif instead"
    )]
    FfmpegMissing,
    #[error("ffmpeg failed: {0}")]
    Ffmpeg(String),
    #[error(transparent)]
    Write(#[from] dancegen_io::atomic::WriteError),
    #[error(transparent)]
    Motion(#[from] dancegen_formats::dispatch::FormatError),
    #[error("{0}")]
    Io(#[from] std::io::Error),
}

/// An 8-bit RGB image, row-major, top row first.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct RgbImage {
    pub width: u32,
    pub height: u32,
    /// `width × height × 3` bytes.
    pub data: Vec<u8>,
}

impl RgbImage {
    pub fn pixel(&self, x: u32, y: u32) -> [u8; 3] {
        let i = ((y * self.width + x) * 3) as usize;
        [self.data[i], self.data[i + 1], self.data[i + 2]]
    }
}

/// The dancers of a loaded motion file as render tracks (a group file gives several).
///
/// SMPL motions get the SMPL 24 parents, BVH its own hierarchy (in file units). Raw joint
/// arrays get the bones of the skeleton dancegen writes with that many joints (SMPL 24, the
/// holistic SMPL-H 52) when every such bone keeps its length through the clip, as a rigid
/// skeleton's do ([`bones_of_joint_array`]); otherwise no parents (spheres only).
pub fn tracks_from_motion(path: &Path, m: &LoadedMotion) -> Result<Vec<DancerTrack>, RenderError> {
    let fps = m.fps();
    let (shape, data) = joint_positions(path, m)?;
    let tracks = match m {
        LoadedMotion::Smpl(_) => vec![DancerTrack {
            joints: data,
            parents: Skeleton::smpl24().parents().to_vec(),
            fps,
        }],
        LoadedMotion::Group(_) => {
            let per = shape[1] * shape[2] * shape[3];
            data.chunks(per.max(1))
                .map(|c| DancerTrack {
                    joints: c.to_vec(),
                    parents: Skeleton::smpl24().parents().to_vec(),
                    fps,
                })
                .collect()
        }
        LoadedMotion::Bvh(b) => vec![DancerTrack {
            joints: data,
            parents: b.joints.iter().map(|j| j.parent).collect(),
            fps,
        }],
        LoadedMotion::Joints {
            dancers, joints, ..
        } => data
            .chunks((data.len() / dancers.max(&1)).max(1))
            .map(|c| DancerTrack {
                joints: c.to_vec(),
                parents: bones_of_joint_array(c, *joints).unwrap_or_else(|| vec![None; *joints]),
                fps,
            })
            .collect(),
    };
    Ok(tracks)
}

/// Largest spread (max − min over the clip) of a bone's length, relative to its mean, for a
/// joint array to be drawn with that skeleton's bones. Joint positions computed from one
/// skeleton keep every bone's length to float precision; another skeleton's joints with the
/// same count give bones that stretch by tens of per cent.
const RIGID_BONE_SPREAD: f64 = 0.02;

/// The parents of the skeleton dancegen writes with `joints` joints (SMPL 24, SMPL-H 52), if
/// every one of its bones keeps its length over the frames of `positions` (`[T, joints, 3]`,
/// flat) within [`RIGID_BONE_SPREAD`].
pub fn bones_of_joint_array(positions: &[f32], joints: usize) -> Option<Vec<Option<usize>>> {
    let skeleton = match joints {
        24 => Skeleton::smpl24(),
        52 => Skeleton::smplh52_approx(),
        _ => return None,
    };
    let frames = positions.len() / (joints * 3);
    if frames == 0 {
        return None;
    }
    let at = |f: usize, j: usize| {
        let i = (f * joints + j) * 3;
        [0, 1, 2].map(|k| f64::from(positions[i + k]))
    };
    let rigid = skeleton.parents().iter().enumerate().all(|(j, p)| {
        let Some(p) = *p else { return true };
        let lengths: Vec<f64> = (0..frames)
            .map(|f| {
                let (a, b) = (at(f, j), at(f, p));
                (0..3).map(|k| (a[k] - b[k]).powi(2)).sum::<f64>().sqrt()
            })
            .collect();
        let mean = lengths.iter().sum::<f64>() / frames as f64;
        let (lo, hi) = lengths
            .iter()
            .fold((f64::MAX, f64::MIN), |(lo, hi), &l| (lo.min(l), hi.max(l)));
        mean > 0.0 && (hi - lo) <= RIGID_BONE_SPREAD * mean
    });
    rigid.then(|| skeleton.parents().to_vec())
}

/// Renders the whole clip at `out_fps` into memory (convenient for short clips and tests; use
/// [`Scene::stream`] for long ones).
pub fn render_frames(
    tracks: &[DancerTrack],
    out_fps: f32,
    width: u32,
    height: u32,
) -> Result<Vec<RgbImage>, RenderError> {
    let scene = Scene::new(tracks, &RenderOptions::new(width, height))?;
    Ok(scene.stream(out_fps).collect())
}

/// Frames of a clip rendered in parallel batches, yielded in order.
pub struct FrameStream<'a> {
    scene: &'a Scene,
    times: Vec<f32>,
    next: usize,
    batch: std::vec::IntoIter<RgbImage>,
}

impl FrameStream<'_> {
    /// Number of frames the stream yields in total.
    pub fn total(&self) -> usize {
        self.times.len()
    }
}

impl Iterator for FrameStream<'_> {
    type Item = RgbImage;

    fn next(&mut self) -> Option<RgbImage> {
        use rayon::prelude::*;
        if let Some(img) = self.batch.next() {
            return Some(img);
        }
        if self.next >= self.times.len() {
            return None;
        }
        let n = (rayon::current_num_threads() * 2).clamp(2, 32);
        let end = (self.next + n).min(self.times.len());
        let imgs: Vec<RgbImage> = self.times[self.next..end]
            .par_iter()
            .map(|&t| self.scene.render_at(t))
            .collect();
        self.next = end;
        self.batch = imgs.into_iter();
        self.batch.next()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A SMPL 24 T-pose standing on y = 0, `frames` frames, shifted by `dx` along x and
    /// swaying slowly.
    fn tpose(frames: usize, dx: f32) -> DancerTrack {
        let sk = Skeleton::smpl24();
        let rest = sk.rest_positions();
        let min_y = rest.iter().map(|p| p[1]).fold(f64::INFINITY, f64::min);
        let mut joints = Vec::new();
        for f in 0..frames {
            let sway = (f as f32 * 0.1).sin() * 0.05;
            for p in &rest {
                joints.extend([p[0] as f32 + dx + sway, (p[1] - min_y) as f32, p[2] as f32]);
            }
        }
        DancerTrack {
            joints,
            parents: sk.parents().to_vec(),
            fps: 30.0,
        }
    }

    fn is_figure(p: [u8; 3]) -> bool {
        // Background and floor are near-grey; dancers are saturated.
        let mx = p.iter().copied().max().unwrap() as i32;
        let mn = p.iter().copied().min().unwrap() as i32;
        mx - mn > 60
    }

    fn save(name: &str, img: &RgbImage) {
        if let Some(dir) = std::env::var_os("DANCEGEN_RENDER_TEST_OUT") {
            write::write_png(&std::path::Path::new(&dir).join(name), img).unwrap();
        }
    }

    #[test]
    fn a_group_joints_file_gives_one_track_per_dancer() {
        // generate --dancers 3 -o x.npy: (3, T, 24, 3), dancer after dancer.
        let (n, t) = (3, 4);
        let positions: Vec<f32> = (0..n * t * 24 * 3).map(|i| i as f32).collect();
        let m = LoadedMotion::Joints {
            fps: 30.0,
            dancers: n,
            joints: 24,
            positions: positions.clone(),
        };
        let tracks = tracks_from_motion(std::path::Path::new("x.npy"), &m).unwrap();
        assert_eq!(tracks.len(), n);
        let per = t * 24 * 3;
        for (d, tr) in tracks.iter().enumerate() {
            assert_eq!(tr.joints, positions[d * per..(d + 1) * per]);
        }
    }

    #[test]
    fn a_joint_array_of_a_rigid_smpl_skeleton_is_drawn_with_its_bones() {
        use dancegen_motion::fk::{LocalRotations, forward_kinematics};
        let sk = Skeleton::smpl24();
        let t = 20;
        let rot: Vec<f64> = (0..t * 72).map(|i| 0.8 * (i as f64 * 0.37).sin()).collect();
        let trans: Vec<f64> = (0..t * 3).map(|i| (i as f64 * 0.1).cos()).collect();
        let joints: Vec<f32> =
            forward_kinematics(&sk, LocalRotations::AxisAngle(&rot), &trans, false)
                .unwrap()
                .positions
                .iter()
                .map(|&v| v as f32)
                .collect();
        assert_eq!(
            bones_of_joint_array(&joints, 24).as_deref(),
            Some(sk.parents())
        );
        // Another skeleton's 24 joints (two of them swapped): its "bones" stretch.
        let mut other = joints.clone();
        for f in 0..t {
            for k in 0..3 {
                other.swap((f * 24 + 4) * 3 + k, (f * 24 + 20) * 3 + k);
            }
        }
        assert_eq!(bones_of_joint_array(&other, 24), None);
        // No skeleton of that size.
        assert_eq!(bones_of_joint_array(&joints[..t * 23 * 3], 23), None);
    }

    #[test]
    fn tpose_is_drawn_in_the_centre_over_a_grid() {
        let frames = render_frames(&[tpose(3, 0.0)], 30.0, 320, 240).unwrap();
        assert_eq!(frames.len(), 3);
        let img = &frames[1];
        save("tpose.png", img);
        // What the GIF palette makes of it.
        let pal = write::gif_palette();
        let q = write::quantize_gif(img);
        let data = q
            .iter()
            .flat_map(|&i| pal[i as usize * 3..i as usize * 3 + 3].to_vec())
            .collect();
        save(
            "tpose_gif.png",
            &RgbImage {
                width: 320,
                height: 240,
                data,
            },
        );
        assert_eq!(img.data.len(), 320 * 240 * 3);
        let (mut n, mut cx, mut cy) = (0usize, 0.0f64, 0.0f64);
        let mut outside = 0usize;
        for y in 0..240 {
            for x in 0..320 {
                if is_figure(img.pixel(x, y)) {
                    n += 1;
                    cx += x as f64;
                    cy += y as f64;
                    if !(40..280).contains(&x) || !(20..220).contains(&y) {
                        outside += 1;
                    }
                }
            }
        }
        assert!(n > 1500, "only {n} figure pixels");
        assert_eq!(outside, 0);
        let (cx, cy) = (cx / n as f64, cy / n as f64);
        assert!(
            (cx - 160.0).abs() < 50.0 && (cy - 120.0).abs() < 50.0,
            "{cx} {cy}"
        );
        // The floor grid: along the bottom rows, grey pixels alternate between the floor
        // colour and darker grid lines.
        let row: Vec<u8> = (0..320).map(|x| img.pixel(x, 230)[0]).collect();
        let dark = row.iter().filter(|&&v| v < 175).count();
        let light = row.iter().filter(|&&v| v > 190).count();
        assert!(dark > 5 && light > 100, "dark {dark} light {light}");
        // Sky at the top.
        let top = img.pixel(160, 2);
        assert!(top[2] > top[0], "{top:?}");
    }

    #[test]
    fn two_dancers_get_two_colours() {
        let img = &render_frames(&[tpose(2, -0.9), tpose(2, 0.9)], 30.0, 320, 240).unwrap()[0];
        save("two.png", img);
        let (mut blue, mut orange) = (0, 0);
        for y in 0..240 {
            for x in 0..320 {
                let p = img.pixel(x, y);
                if !is_figure(p) {
                    continue;
                }
                if p[2] as i32 > p[0] as i32 + 40 {
                    blue += 1;
                } else if p[0] as i32 > p[2] as i32 + 60 {
                    orange += 1;
                }
            }
        }
        assert!(blue > 300 && orange > 300, "blue {blue} orange {orange}");
    }

    #[test]
    fn raw_joints_draw_spheres_and_time_is_resampled() {
        let mut t = tpose(31, 0.0);
        t.parents = vec![None; 24];
        let frames = render_frames(&[t], 10.0, 160, 120).unwrap();
        // 1 s at 30 fps = 31 frames -> 11 frames at 10 fps.
        assert_eq!(frames.len(), 11);
        let n = frames[5]
            .data
            .chunks(3)
            .filter(|p| is_figure([p[0], p[1], p[2]]))
            .count();
        assert!(n > 100, "{n}");
    }

    #[test]
    fn bad_tracks_are_errors() {
        let mut t = tpose(2, 0.0);
        t.joints.pop();
        assert!(render_frames(&[t], 30.0, 64, 48).is_err());
        assert!(render_frames(&[], 30.0, 64, 48).is_err());
    }

    #[test]
    fn gif_round_trips_and_stores_only_changes() {
        let dir = tempfile::tempdir().unwrap();
        let p = dir.path().join("a.gif");
        let scene = Scene::new(&[tpose(20, 0.0)], &RenderOptions::new(160, 120)).unwrap();
        let n = write::write_gif(&p, scene.stream(15.0), 15.0).unwrap();
        assert_eq!(n, scene.frame_count(15.0));
        let mut opts = gif::DecodeOptions::new();
        opts.set_color_output(gif::ColorOutput::Indexed);
        let mut d = opts.read_info(std::fs::File::open(&p).unwrap()).unwrap();
        let mut count = 0;
        while let Some(f) = d.read_next_frame().unwrap() {
            if count > 0 {
                assert!(f.width < 160 || f.height < 120);
            }
            assert!(f.delay == 7 || f.delay == 6, "{}", f.delay);
            count += 1;
        }
        assert_eq!(count, n);
    }

    /// A track whose every joint moves by `shift(f)` at frame `f`.
    fn moved(mut t: DancerTrack, shift: impl Fn(usize) -> [f32; 3]) -> DancerTrack {
        let j = t.num_joints();
        for f in 0..t.frames() {
            let d = shift(f);
            for p in t.joints[f * j * 3..(f + 1) * j * 3].chunks_exact_mut(3) {
                for (v, dv) in p.iter_mut().zip(d) {
                    *v += dv;
                }
            }
        }
        t
    }

    /// The dirty-rectangle renderer must give exactly the full-frame renderer's pixels: two
    /// dancers that cross and overlap, one walking from one edge of the view to the other and
    /// jumping (shadows that spread and move), a raw-joint figure (spheres only), at 1x, 2x and
    /// 3x supersampling, with and without shadows, and at a size where the dancers reach past
    /// the image edges.
    #[test]
    fn fast_frames_equal_full_frame_rendering() {
        let frames = 40;
        let a = moved(tpose(frames, 0.0), |f| {
            let u = f as f32 / (frames - 1) as f32;
            [
                -2.5 + 5.0 * u,
                (u * 9.0).sin().abs() * 0.6,
                0.3 * (u * 5.0).cos(),
            ]
        });
        let b = moved(tpose(frames, 0.0), |f| {
            let u = f as f32 / (frames - 1) as f32;
            [0.8 - 1.6 * u, 0.0, -0.4 + 0.8 * u]
        });
        let mut c = moved(tpose(frames, 1.2), |f| [0.0, 0.1 * (f % 7) as f32, 0.0]);
        c.parents = vec![None; c.parents.len()];
        let mut checked = 0;
        for (w, h, ss, shadows) in [
            (160, 120, 2, true),
            (96, 64, 3, true),
            (120, 90, 1, true),
            (128, 96, 2, false),
        ] {
            let opts = RenderOptions {
                width: w,
                height: h,
                supersample: ss,
                shadows,
            };
            let scene = Scene::new(&[a.clone(), b.clone(), c.clone()], &opts).unwrap();
            for k in 0..frames {
                let t = k as f32 / 30.0 + 0.013;
                let fast = scene.render_at(t);
                let full = scene.render_full_at(t);
                assert_eq!(fast.data.len(), full.data.len());
                let bad = fast
                    .data
                    .iter()
                    .zip(&full.data)
                    .filter(|(x, y)| x != y)
                    .count();
                assert_eq!(
                    bad, 0,
                    "{w}x{h} ss {ss} shadows {shadows} t {t}: {bad} bytes differ"
                );
                checked += 1;
            }
        }
        // The camera is fitted to every third frame of a long clip: the frames in between are
        // free to leave the view, reach the image edges or come up to (and behind) the camera.
        let n = 1201;
        let long = moved(tpose(n, 0.0), |f| match f % 3 {
            1 => [1.2 * (f % 5) as f32 - 2.4, 0.2 * (f % 4) as f32, 0.0],
            2 => {
                let k = 2.0 + 1.5 * (f % 11) as f32;
                [0.55 * k, 0.32 * k - 0.5, 1.0 * k]
            }
            _ => [0.0; 3],
        });
        let scene = Scene::new(&[long, tpose(n, 0.7)], &RenderOptions::new(160, 120)).unwrap();
        for f in (1..60).filter(|f| f % 3 != 0) {
            let t = f as f32 / 30.0;
            assert_eq!(scene.render_at(t), scene.render_full_at(t), "frame {f}");
            checked += 1;
        }
        assert_eq!(checked, 4 * frames + 40);
    }

    /// The dithering table gives the float formula's index for every value at every Bayer
    /// position and channel.
    #[test]
    fn gif_dither_table_matches_the_formula() {
        let (w, h) = (256u32, 16u32);
        let mut data = Vec::new();
        for y in 0..h {
            for x in 0..w {
                // Each row runs every channel through all 256 values; every fourth row shifts
                // them by one, so each value meets all 16 Bayer cells.
                let s = y / 4;
                data.extend([x + s, x * 7 + s, 255 - x + s].map(|v| (v % 256) as u8));
            }
        }
        let img = RgbImage {
            width: w,
            height: h,
            data,
        };
        assert_eq!(
            write::quantize_gif(&img),
            write::quantize_gif_reference(&img)
        );
    }

    /// An MP4 decoded back to RGB by ffmpeg shows the rendered frames: the YUV conversion
    /// uses the matrix and range that decoders assume for untagged video (a wrong one shifts
    /// every colour, which PSNR and the dancer's mean colour catch). Needs ffmpeg, which
    /// `tools/test.sh` installs.
    #[test]
    fn mp4_decodes_back_to_the_rendered_frames() {
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("v.mp4");
        let (w, h) = (160u32, 120u32);
        let scene = Scene::new(&[tpose(30, 0.0)], &RenderOptions::new(w, h)).unwrap();
        let frames: Vec<RgbImage> = scene.stream(10.0).collect();
        let n = write::write_mp4(&path, frames.clone().into_iter(), w, h, 10.0, None).unwrap();
        assert_eq!(n, frames.len());
        let out = std::process::Command::new(write::ffmpeg_program())
            .args(["-v", "error", "-i"])
            .arg(&path)
            .args(["-f", "rawvideo", "-pix_fmt", "rgb24", "-"])
            .output()
            .expect("ffmpeg runs (tools/test.sh installs it)");
        assert!(
            out.status.success(),
            "{}",
            String::from_utf8_lossy(&out.stderr)
        );
        let want: Vec<u8> = frames.iter().flat_map(|f| f.data.iter().copied()).collect();
        assert_eq!(out.stdout.len(), want.len());
        let mse = out
            .stdout
            .iter()
            .zip(&want)
            .map(|(&a, &b)| (a as f64 - b as f64).powi(2))
            .sum::<f64>()
            / want.len() as f64;
        let psnr = 10.0 * (255.0f64 * 255.0 / mse).log10();
        assert!(psnr > 35.0, "PSNR {psnr:.2} dB");
        // Mean colours of the background and of the figure's inner pixels (two pixels from
        // any edge, where 4:2:0 chroma does not mix in the floor) stay within 3 levels per
        // channel (measured on 100 preview frames: decoded minus rendered means −0.9 to −1.2
        // per channel over all pixels). A wrong range moves the near-white floor by about 15
        // levels (limited range maps v to 16 + 219/255·v); a Y offset of 8 instead of 16
        // already fails the PSNR bound above (27 dB).
        let (wi, hi) = (w as usize, h as usize);
        let mut sums = [[[0.0f64; 3]; 2]; 2];
        let mut counts = [0.0f64; 2];
        for (f, r) in want.chunks_exact(wi * hi * 3).enumerate() {
            let fig = |x: usize, y: usize| {
                let i = (y * wi + x) * 3;
                is_figure([r[i], r[i + 1], r[i + 2]])
            };
            for y in 2..hi - 2 {
                for x in 2..wi - 2 {
                    let around: Vec<bool> = (y - 2..=y + 2)
                        .flat_map(|yy| (x - 2..=x + 2).map(move |xx| (xx, yy)))
                        .map(|(xx, yy)| fig(xx, yy))
                        .collect();
                    let kind = if around.iter().all(|&b| b) {
                        1
                    } else if around.iter().all(|&b| !b) {
                        0
                    } else {
                        continue;
                    };
                    let i = f * wi * hi * 3 + (y * wi + x) * 3;
                    for c in 0..3 {
                        sums[kind][0][c] += out.stdout[i + c] as f64;
                        sums[kind][1][c] += want[i + c] as f64;
                    }
                    counts[kind] += 1.0;
                }
            }
        }
        assert!(counts[1] > 500.0, "{} inner figure pixels", counts[1]);
        for (kind, name) in [(0, "background"), (1, "figure")] {
            let [decoded, rendered] = sums[kind];
            for (c, (d, r)) in decoded.iter().zip(rendered).enumerate() {
                let (got, exp) = (d / counts[kind], r / counts[kind]);
                assert!(
                    (got - exp).abs() < 3.0,
                    "{name} channel {c}: decoded {got:.2}, rendered {exp:.2}"
                );
            }
        }
    }

    #[test]
    fn missing_ffmpeg_is_a_clear_error() {
        // Only the error path; the CLI test covers a real ffmpeg when there is one.
        let e = RenderError::FfmpegMissing.to_string();
        assert!(e.contains("install ffmpeg") && e.contains(".gif"));
    }
}
