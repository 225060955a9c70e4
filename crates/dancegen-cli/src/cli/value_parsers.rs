//! Value parsers several commands share: a capture rate and a rig name.

use dancegen_formats::rig::Rig;

/// `--source-fps N` / `--leader-fps N`: a capture rate in (0, 1000].
pub(crate) fn parse_source_fps(s: &str) -> Result<f64, String> {
    let fps: f64 = s
        .trim()
        .parse()
        .map_err(|_| format!("{s:?} is not a number of frames per second"))?;
    dancegen_formats::dispatch::check_source_fps(fps)
}

/// `--rig NAME`, with the presets listed when the name is unknown.
pub(crate) fn parse_rig(s: &str) -> Result<Rig, String> {
    Rig::from_name(s).map_err(|e| e.to_string())
}
