//! Preview rendering benchmark: the README's `dancegen generate -o dance.mp4` preview (640x480,
//! 30 fps MP4 with the song) and the GIF preview (640x480, 15 fps) of a real motion capture take.
//!
//! ```sh
//! cargo run --release -p dancegen-render --example preview_bench -- \
//!     OUT_DIR AUDIO|- MOTION [MOTION ...]
//! ```
//!
//! Every MOTION is converted to SMPL 24 at 30 fps (as `dancegen convert --to smpl24 --fps 30`
//! does); the takes are joined end to end until there is enough motion and the first 45 s are
//! kept, the length of the README command's demo song (no single take in the shared data is
//! that long). Writes `OUT_DIR/preview.mp4` and `OUT_DIR/preview.gif` and prints, per output, the
//! frame count, the seconds spent and the frames per second, plus a hash of every rendered RGB
//! frame so two renderers can be checked for identical pictures.
//!
//! Only the API that the CLI uses is called, so this program builds against older revisions of
//! the renderer too (`bench/preview.sh` runs it against a baseline revision).

use std::io::Write;
use std::path::PathBuf;
use std::time::Instant;

use dancegen_formats::dispatch::{ConvertOptions, convert_motion, load_motion_file};
use dancegen_render::{DancerTrack, RenderOptions, RgbImage, Scene, tracks_from_motion, write};

/// The README command's song is 45 s long; its preview holds 45 s × 30 fps frames.
const SECONDS: f32 = 45.0;
const FPS: f32 = 30.0;
const GIF_FPS: f32 = 15.0;
const WIDTH: u32 = 640;
const HEIGHT: u32 = 480;

/// FNV-1a-style mixing of all frame bytes, eight at a time, in order (cheap next to
/// rendering, and the same cost for both renderers).
struct FrameHash(u64);

impl FrameHash {
    fn new() -> Self {
        FrameHash(0xcbf2_9ce4_8422_2325)
    }
    fn add(&mut self, img: &RgbImage) {
        let mut chunks = img.data.chunks_exact(8);
        for c in &mut chunks {
            let w = u64::from_le_bytes(c.try_into().expect("8 bytes"));
            self.0 = (self.0 ^ w).wrapping_mul(0x0100_0000_01b3);
        }
        for &b in chunks.remainder() {
            self.0 = (self.0 ^ u64::from(b)).wrapping_mul(0x0100_0000_01b3);
        }
    }
}

fn load_track(paths: &[PathBuf]) -> Result<DancerTrack, Box<dyn std::error::Error>> {
    let want = (SECONDS * FPS).round() as usize;
    let mut joined: Option<DancerTrack> = None;
    for p in paths {
        let m = load_motion_file(p)?;
        let m = convert_motion(
            p,
            m,
            &ConvertOptions {
                to_smpl24: true,
                fps: Some(FPS),
                ..Default::default()
            },
        )?;
        let mut tracks = tracks_from_motion(p, &m)?;
        if tracks.len() != 1 {
            return Err(format!("{}: {} dancers, want one", p.display(), tracks.len()).into());
        }
        let t = tracks.remove(0);
        match &mut joined {
            None => joined = Some(t),
            Some(j) => {
                if j.parents != t.parents {
                    return Err(format!("{}: another skeleton", p.display()).into());
                }
                j.joints.extend_from_slice(&t.joints);
            }
        }
        if joined.as_ref().is_some_and(|j| j.frames() >= want) {
            break;
        }
    }
    let mut t = joined.ok_or("no motion files")?;
    if t.frames() < want {
        return Err(format!("only {} frames, want {want}", t.frames()).into());
    }
    t.joints.truncate(want * t.num_joints() * 3);
    Ok(t)
}

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let args: Vec<String> = std::env::args().skip(1).collect();
    if args.len() < 3 {
        return Err("usage: preview_bench OUT_DIR AUDIO|- MOTION [MOTION ...]".into());
    }
    let out = PathBuf::from(&args[0]);
    let audio = (args[1] != "-").then(|| PathBuf::from(&args[1]));
    let motions: Vec<PathBuf> = args[2..].iter().map(PathBuf::from).collect();
    let track = load_track(&motions)?;
    let scene = Scene::new(&[track], &RenderOptions::new(WIDTH, HEIGHT))?;

    // For `bench/preview.sh`'s untimed quality run: the MP4's rendered RGB frames, as they
    // were before encoding, to compare the decoded video with.
    let mut raw = match std::env::var_os("PREVIEW_BENCH_RAW_FRAMES") {
        Some(p) => Some(std::io::BufWriter::new(std::fs::File::create(p)?)),
        None => None,
    };
    let mut raw_err: Option<std::io::Error> = None;
    let mut hash = FrameHash::new();
    let t0 = Instant::now();
    let n = write::write_mp4(
        &out.join("preview.mp4"),
        scene.stream(FPS).inspect(|f| {
            hash.add(f);
            if let Some(w) = raw.as_mut()
                && raw_err.is_none()
                && let Err(e) = w.write_all(&f.data)
            {
                raw_err = Some(e);
            }
        }),
        WIDTH,
        HEIGHT,
        FPS,
        audio.as_deref().map(write::AudioClip::whole),
    )?;
    report("mp4", n, t0.elapsed().as_secs_f64(), hash.0);
    if let Some(e) = raw_err {
        return Err(format!("PREVIEW_BENCH_RAW_FRAMES: {e}").into());
    }
    if let Some(mut w) = raw {
        w.flush()?;
    }

    let mut hash = FrameHash::new();
    let t0 = Instant::now();
    let n = write::write_gif(
        &out.join("preview.gif"),
        scene.stream(GIF_FPS).inspect(|f| hash.add(f)),
        GIF_FPS,
    )?;
    report("gif", n, t0.elapsed().as_secs_f64(), hash.0);
    Ok(())
}

fn report(kind: &str, frames: usize, secs: f64, hash: u64) {
    println!(
        "{kind}: {frames} frames in {secs:.3} s = {:.1} frames/s (rgb fnv {hash:016x})",
        frames as f64 / secs
    );
}
