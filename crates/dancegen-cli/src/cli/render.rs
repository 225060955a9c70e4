//! `dancegen render`: dancers drawn as a picture, an animation or a video.

use std::path::PathBuf;

use clap::Args;

use dancegen_generate::flags::values::parse_source_fps;

#[derive(Args, Debug)]
pub struct RenderArgs {
    /// Motion files (any format `convert` reads); each dancer of a group file is drawn too,
    /// one colour per dancer.
    #[arg(required = true)]
    pub motions: Vec<PathBuf>,
    /// Output: .png (one frame), .gif or .mp4 (needs ffmpeg on PATH).
    #[arg(short, long)]
    pub output: PathBuf,
    /// Song to mux into an .mp4 (the video is cut to the shorter of the two).
    #[arg(long)]
    pub audio: Option<PathBuf>,
    /// Output frame rate (default: the motion's; at most 15 for .gif unless given).
    #[arg(long)]
    pub fps: Option<f32>,
    /// Read the motion files as sampled at this rate, whatever their headers say (the frames
    /// stay the same, their times change), e.g. 60 for the CMU salsa BVHs.
    #[arg(long, value_name = "FPS", value_parser = parse_source_fps)]
    pub source_fps: Option<f64>,
    /// Image width in pixels.
    #[arg(long, default_value_t = 640)]
    pub width: u32,
    /// Image height in pixels.
    #[arg(long, default_value_t = 480)]
    pub height: u32,
    /// .png: the frame to draw, counted at the output frame rate (default: the middle one).
    #[arg(long)]
    pub frame: Option<usize>,
    /// No anti-aliasing and no shadows (several times faster).
    #[arg(long)]
    pub draft: bool,
}
