//! The picture of a finished dance in the "My dances" library: its first variation's `.glb`
//! (every dancer, a duet's leader too) drawn by `dancegen_render` at 40 % of the dance, small,
//! as `thumb.png` in the job's folder (written atomically). A dance that cannot be drawn just
//! has no picture: the job stays done.

use std::path::Path;

use dancegen_formats::dispatch::load_motion_file;
use dancegen_render::{RenderOptions, Scene, tracks_from_motion, write};

/// The picture's file name in the job folder.
pub const THUMBNAIL: &str = "thumb.png";
/// Its size: 4:3, twice the library's display size for sharp screens.
const WIDTH: u32 = 320;
const HEIGHT: u32 = 240;
/// Where in the dance it is drawn: past the start, where the dancers are under way.
const AT: f32 = 0.4;

/// Draws `dir/dance.glb` into `dir/thumb.png`.
pub fn write_thumbnail(dir: &Path) -> Result<(), String> {
    let glb = dir.join("dance.glb");
    let motion = load_motion_file(&glb).map_err(|e| e.to_string())?;
    let tracks = tracks_from_motion(&glb, &motion).map_err(|e| e.to_string())?;
    let scene =
        Scene::new(&tracks, &RenderOptions::new(WIDTH, HEIGHT)).map_err(|e| e.to_string())?;
    let image = scene.render_at(scene.duration() * AT);
    write::write_png(&dir.join(THUMBNAIL), &image).map_err(|e| e.to_string())
}
