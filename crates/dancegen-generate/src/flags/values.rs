//! Value parsers of options several commands share: a capture rate, a rig name and a range of
//! seconds (the CLI's `convert`, `eval` and `render` use them too).

use dancegen_formats::rig::Rig;

/// `--source-fps N` / `--leader-fps N`: a capture rate in (0, 1000].
pub fn parse_source_fps(s: &str) -> Result<f64, String> {
    let fps: f64 = s
        .trim()
        .parse()
        .map_err(|_| format!("{s:?} is not a number of frames per second"))?;
    dancegen_formats::dispatch::check_source_fps(fps)
}

/// `--rig NAME`, with the presets listed when the name is unknown.
pub fn parse_rig(s: &str) -> Result<Rig, String> {
    Rig::from_name(s).map_err(|e| e.to_string())
}

/// `--regenerate A-B`: two times in seconds, `A < B`.
pub fn parse_range(s: &str) -> Result<[f64; 2], String> {
    let bad = || format!("{s:?} is not a range of seconds START-END, e.g. 8-12.5");
    let (a, b) = s.trim().split_once('-').ok_or_else(bad)?;
    let a: f64 = a.trim().parse().map_err(|_| bad())?;
    let b: f64 = b.trim().parse().map_err(|_| bad())?;
    if !(a.is_finite() && b.is_finite() && a < b) {
        return Err(format!("{s:?}: START must be before END"));
    }
    Ok([a, b])
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn ranges_parse_and_bad_ones_say_why() {
        assert_eq!(parse_range("8-12.5"), Ok([8.0, 12.5]));
        assert_eq!(parse_range(" 0 - 1 "), Ok([0.0, 1.0]));
        for bad in ["8", "a-b", "12-8", "-1-2", "1-inf"] {
            assert!(parse_range(bad).is_err(), "{bad}");
        }
    }
}
