//! Epic's Live Link Face CSV (`face.csv`), the file its iPhone app exports and Unreal's Live
//! Link Face importer, Blender and Maya add-ons read:
//!
//! ```text
//! Timecode,BlendShapeCount,EyeBlinkLeft,…,TongueOut,HeadYaw,HeadPitch,HeadRoll,LeftEyeYaw,…,RightEyeRoll
//! 00:00:00:00.000,61,0.0123,…
//! ```
//!
//! - `Timecode` is `HH:MM:SS:FF.fff`, `FF` counted at the file's frame rate and `.fff` the
//!   sub-frame. We write one row per frame at the motion's rate (30 fps), so `FF` runs 0–29.
//! - `BlendShapeCount` is 61: the 52 ARKit weights and 9 head and eye rotations.
//! - The 9 rotations are written as zeros: the head turns with the body's head bone in every
//!   other output (`.glb`, `.bvh`), and a tool that drives both would turn it twice.
//!
//! The reader matches the 52 weight columns by name (any order, either case of the first
//! letter), ignores the rotations and any extra columns, and checks every value.

use std::io::Write;
use std::path::Path;

use dancegen_motion::face::arkit::{ARKIT_COUNT, FaceError, FaceWeights, arkit_index, pascal_case};

/// Live Link's head and eye rotation columns, after the 52 weights.
pub const ROTATION_COLUMNS: [&str; 9] = [
    "HeadYaw",
    "HeadPitch",
    "HeadRoll",
    "LeftEyeYaw",
    "LeftEyePitch",
    "LeftEyeRoll",
    "RightEyeYaw",
    "RightEyePitch",
    "RightEyeRoll",
];

/// `BlendShapeCount`: weights plus rotations.
pub const BLEND_SHAPE_COUNT: usize = ARKIT_COUNT + ROTATION_COLUMNS.len();

/// The timecode of frame `f` at `fps` frames per second: `HH:MM:SS:FF.000`. A non-integer rate
/// counts frames at its rounded rate, as non-drop-frame SMPTE timecode does.
pub fn timecode(f: usize, fps: f32) -> String {
    let n = (fps.round() as usize).max(1);
    let (whole, ff) = (f / n, f % n);
    let (h, m, s) = (whole / 3600, whole / 60 % 60, whole % 60);
    format!("{h:02}:{m:02}:{s:02}:{ff:02}.000")
}

/// Writes `face` as Live Link Face CSV to `out` (see the module documentation).
pub fn write(face: &FaceWeights, out: &mut dyn Write) -> std::io::Result<()> {
    let mut header = String::from("Timecode,BlendShapeCount");
    for i in 0..ARKIT_COUNT {
        header.push(',');
        header.push_str(&pascal_case(i));
    }
    for c in ROTATION_COLUMNS {
        header.push(',');
        header.push_str(c);
    }
    writeln!(out, "{header}")?;
    for f in 0..face.frames() {
        write!(out, "{},{BLEND_SHAPE_COUNT}", timecode(f, face.fps))?;
        for w in face.frame(f) {
            write!(out, ",{w:.6}")?;
        }
        for _ in ROTATION_COLUMNS {
            write!(out, ",0")?;
        }
        writeln!(out)?;
    }
    Ok(())
}

/// Writes `face` to `path` atomically.
pub fn write_file(face: &FaceWeights, path: &Path) -> Result<(), FaceError> {
    dancegen_io::atomic::write_atomic(path, |w| write(face, w)).map_err(|e| FaceError::File {
        path: path.display().to_string(),
        reason: e.reason,
    })
}

/// Reads Live Link Face CSV text; `fps` is the rate the rows were recorded at (the file does
/// not state it: the app's default is 60, ours is 30). `source` names the file in errors.
pub fn parse(text: &str, fps: f32, source: &str) -> Result<FaceWeights, FaceError> {
    let err = |reason: String| FaceError::File {
        path: source.to_string(),
        reason,
    };
    let mut lines = text
        .lines()
        .enumerate()
        .filter(|(_, l)| !l.trim().is_empty());
    let (_, header) = lines.next().ok_or_else(|| err("empty file".into()))?;
    let columns: Vec<&str> = header.split(',').map(str::trim).collect();
    if columns.first() != Some(&"Timecode") {
        return Err(err(format!(
            "line 1: the first column is `{}`, not `Timecode`: not a Live Link Face CSV",
            columns.first().unwrap_or(&"")
        )));
    }
    let mut slot = [usize::MAX; ARKIT_COUNT];
    for (c, name) in columns.iter().enumerate() {
        if let Some(i) = arkit_index(name) {
            slot[i] = c;
        }
    }
    if let Some(i) = slot.iter().position(|&c| c == usize::MAX) {
        return Err(err(format!(
            "line 1: no `{}` column ({} of the 52 ARKit blendshapes are missing)",
            pascal_case(i),
            slot.iter().filter(|&&c| c == usize::MAX).count()
        )));
    }
    let mut weights = Vec::new();
    for (n, line) in lines {
        let cells: Vec<&str> = line.split(',').map(str::trim).collect();
        if cells.len() < columns.len() {
            return Err(err(format!(
                "line {}: {} values for {} columns",
                n + 1,
                cells.len(),
                columns.len()
            )));
        }
        for (i, &c) in slot.iter().enumerate() {
            let v: f32 = cells[c].parse().map_err(|_| {
                err(format!(
                    "line {}: {} = `{}` is not a number",
                    n + 1,
                    pascal_case(i),
                    cells[c]
                ))
            })?;
            weights.push(v);
        }
    }
    FaceWeights::new(weights, fps).map_err(|e| err(e.to_string()))
}

/// Reads a Live Link Face CSV file (see [`parse`]).
pub fn read_file(path: &Path, fps: f32) -> Result<FaceWeights, FaceError> {
    let text = std::fs::read_to_string(path).map_err(|e| FaceError::File {
        path: path.display().to_string(),
        reason: format!("cannot read: {e}"),
    })?;
    parse(&text, fps, &path.display().to_string())
}

#[cfg(test)]
mod tests {
    use super::*;

    fn sample(frames: usize) -> FaceWeights {
        let w = (0..frames * ARKIT_COUNT)
            .map(|i| ((i as f32 * 0.37).sin() * 0.5 + 0.5).clamp(0.0, 1.0))
            .collect();
        FaceWeights::new(w, 30.0).unwrap()
    }

    #[test]
    fn timecodes_count_frames_within_the_second() {
        assert_eq!(timecode(0, 30.0), "00:00:00:00.000");
        assert_eq!(timecode(29, 30.0), "00:00:00:29.000");
        assert_eq!(timecode(30, 30.0), "00:00:01:00.000");
        assert_eq!(timecode(30 * 3661 + 7, 30.0), "01:01:01:07.000");
        assert_eq!(timecode(61, 60.0), "00:00:01:01.000");
    }

    #[test]
    fn writes_livelink_layout_and_reads_it_back() {
        let face = sample(35);
        let mut buf = Vec::new();
        write(&face, &mut buf).unwrap();
        let text = String::from_utf8(buf).unwrap();
        let mut lines = text.lines();
        let header: Vec<&str> = lines.next().unwrap().split(',').collect();
        assert_eq!(header.len(), 2 + 61);
        assert_eq!(
            &header[..4],
            [
                "Timecode",
                "BlendShapeCount",
                "EyeBlinkLeft",
                "EyeLookDownLeft"
            ]
        );
        assert_eq!(header[2 + 51], "TongueOut");
        assert_eq!(header[2 + 52], "HeadYaw");
        let row: Vec<&str> = lines.nth(31).unwrap().split(',').collect();
        assert_eq!(row[0], "00:00:01:01.000");
        assert_eq!(row[1], "61");
        assert_eq!(row.len(), header.len());
        let back = parse(&text, 30.0, "t.csv").unwrap();
        assert_eq!(back.frames(), 35);
        let err = back
            .as_slice()
            .iter()
            .zip(face.as_slice())
            .map(|(a, b)| (a - b).abs())
            .fold(0.0, f32::max);
        // Six decimals: half a unit of the last place, plus f32 rounding.
        assert!(err <= 1e-6, "{err}");
    }

    #[test]
    fn reads_columns_by_name_in_any_order_and_names_bad_cells() {
        // Reversed weight columns, camelCase, no rotation columns, an extra column.
        let names: Vec<String> = (0..ARKIT_COUNT)
            .rev()
            .map(|i| dancegen_motion::face::ARKIT_NAMES[i].to_string())
            .collect();
        let vals: Vec<String> = (0..ARKIT_COUNT)
            .rev()
            .map(|i| format!("{}", i as f32 / 100.0))
            .collect();
        let text = format!(
            "Timecode,{},Extra\n00:00:00:00.000,{},9\n",
            names.join(","),
            vals.join(",")
        );
        let w = parse(&text, 60.0, "rev.csv").unwrap();
        assert_eq!(w.fps, 60.0);
        assert_eq!(w.frame(0)[17], 0.17);
        let missing = text.replacen("jawOpen", "jawOpened", 1);
        let e = parse(&missing, 30.0, "m.csv").unwrap_err().to_string();
        assert!(e.contains("m.csv") && e.contains("JawOpen"), "{e}");
        let bad = text.replacen("0.17", "x", 1);
        let e = parse(&bad, 30.0, "b.csv").unwrap_err().to_string();
        assert!(e.contains("line 2: JawOpen = `x`"), "{e}");
        let range = text.replacen("0.17", "1.7", 1);
        let e = parse(&range, 30.0, "r.csv").unwrap_err().to_string();
        assert!(e.contains("jawOpen = 1.7"), "{e}");
        assert!(
            parse("a,b\n", 30.0, "x.csv")
                .unwrap_err()
                .to_string()
                .contains("Timecode")
        );
    }
}
