//! The batch manifest (`dancegen batch`): one JSON object per line, each a `generate` call.
//!
//! A line's keys are `generate`'s options by their long names (`snake_case` or `kebab-case`),
//! plus `id` (required; the song's folder under `--out`), `song` and `outputs` (file names).
//! Each line is turned into the argument list of `dancegen generate` and parsed by the very
//! same clap definition, so a manifest accepts exactly what the command accepts and a batch
//! song is byte-identical to the `generate` call its `done.json` records.

use std::collections::HashMap;
use std::path::{Path, PathBuf};

use serde_json::{Map, Value};

use crate::flags::GenerateFlags;

/// `generate` options a batch decides itself.
const RESERVED_KEYS: [&str; 3] = ["output", "o", "progress"];

/// One manifest line that parsed.
#[derive(Debug, Clone)]
pub struct Entry {
    /// 1-based line number, for messages.
    pub line: usize,
    pub id: String,
    /// The seed used: the line's, or [`seed_for`] of the id.
    pub seed: u64,
    /// Output file names (empty: `generate`'s default file).
    pub outputs: Vec<String>,
    /// `generate`'s arguments without any `-o` (the batch adds them under the song's folder).
    pub args: Vec<String>,
}

/// A manifest line that did not parse, with the id when it could be read.
#[derive(Debug, Clone)]
pub struct BadLine {
    pub line: usize,
    pub id: Option<String>,
    pub error: String,
}

/// The seed of a line without one: FNV-1a (64-bit) of the id's UTF-8 bytes, folded to 32 bits
/// so it is short enough to retype and exact in any JSON reader. Stable across versions and
/// machines (no `std` hasher, whose output may change).
pub fn seed_for(id: &str) -> u64 {
    // FNV-1a parameters (64-bit offset basis and prime), http://www.isthe.com/chongo/tech/comp/fnv/
    const OFFSET: u64 = 0xcbf2_9ce4_8422_2325;
    const PRIME: u64 = 0x0000_0100_0000_01b3;
    let h = id
        .bytes()
        .fold(OFFSET, |h, b| (h ^ u64::from(b)).wrapping_mul(PRIME));
    (h ^ (h >> 32)) & 0xffff_ffff
}

/// Parses every non-blank line of `text` (the manifest at `path`). Line `i` (0-based, counting
/// blank lines, so shards agree whatever they skip) is returned with its 1-based number.
pub fn parse(text: &str, path: &Path) -> Vec<(usize, Result<Entry, BadLine>)> {
    let base = path.parent().unwrap_or(Path::new(""));
    let mut first_line_of: HashMap<String, usize> = HashMap::new();
    let mut out = Vec::new();
    for (index, raw) in text.lines().enumerate() {
        if raw.trim().is_empty() {
            continue;
        }
        let line = index + 1;
        let mut parsed = parse_line(raw, line, base);
        // A repeated id would write two songs into one folder: the first line keeps it.
        if let Ok(e) = &parsed {
            if let Some(first) = first_line_of.get(&e.id) {
                parsed = Err(BadLine {
                    line,
                    id: Some(e.id.clone()),
                    error: format!("id '{}' is used again (first on line {first})", e.id),
                });
            } else {
                first_line_of.insert(e.id.clone(), line);
            }
        }
        out.push((index, parsed));
    }
    out
}

fn parse_line(raw: &str, line: usize, base: &Path) -> Result<Entry, BadLine> {
    let bad = |id: Option<&str>, error: String| BadLine {
        line,
        id: id.map(str::to_string),
        error,
    };
    let value: Value =
        serde_json::from_str(raw).map_err(|e| bad(None, format!("not JSON: {e}")))?;
    let Value::Object(mut fields) = value else {
        return Err(bad(None, "not a JSON object".into()));
    };
    let id = match fields.remove("id") {
        Some(Value::String(s)) => s,
        Some(other) => return Err(bad(None, format!("\"id\" must be a string, not {other}"))),
        None => return Err(bad(None, "no \"id\"".into())),
    };
    check_id(&id).map_err(|e| bad(Some(&id), e))?;
    let outputs = take_outputs(&mut fields).map_err(|e| bad(Some(&id), e))?;
    let seed = match fields.get("seed") {
        None | Some(Value::Null) => seed_for(&id),
        Some(Value::Number(n)) if n.as_u64().is_some() => n.as_u64().unwrap_or_default(),
        Some(other) => {
            return Err(bad(
                Some(&id),
                format!("\"seed\" must be a whole number ≥ 0, not {other}"),
            ));
        }
    };
    fields.insert("seed".into(), Value::from(seed));
    let args = generate_args(&fields, base).map_err(|e| bad(Some(&id), e))?;
    // Parse now so a typo fails this line before any song is generated.
    parse_generate_args(&args).map_err(|e| bad(Some(&id), e))?;
    Ok(Entry {
        line,
        id,
        seed,
        outputs,
        args,
    })
}

/// An id names a folder under `--out`: one plain path component.
fn check_id(id: &str) -> Result<(), String> {
    let ok = !id.is_empty()
        && !id.starts_with('.')
        && id.len() <= 200
        && id
            .chars()
            .all(|c| c.is_alphanumeric() || matches!(c, '-' | '_' | '.' | '+' | '@' | '='));
    if ok {
        Ok(())
    } else {
        Err(format!(
            "id '{id}' cannot name a folder: use letters, digits and - _ . + @ = (not starting \
             with '.', at most 200 bytes)"
        ))
    }
}

fn take_outputs(fields: &mut Map<String, Value>) -> Result<Vec<String>, String> {
    let names = match fields.remove("outputs") {
        None | Some(Value::Null) => return Ok(Vec::new()),
        Some(Value::String(s)) => vec![s],
        Some(Value::Array(items)) => items
            .into_iter()
            .map(|v| match v {
                Value::String(s) => Ok(s),
                other => Err(format!("\"outputs\" holds file names, not {other}")),
            })
            .collect::<Result<_, _>>()?,
        Some(other) => {
            return Err(format!(
                "\"outputs\" must be a list of file names, not {other}"
            ));
        }
    };
    for name in &names {
        let plain = Path::new(name).file_name().and_then(|n| n.to_str()) == Some(name.as_str());
        if !plain || name.starts_with('.') {
            return Err(format!(
                "output '{name}' must be a plain file name (it goes into the song's folder)"
            ));
        }
    }
    Ok(names)
}

/// `generate`'s argument list for a line's remaining keys (the song last, after `--`); paths
/// resolved against the manifest's folder.
fn generate_args(fields: &Map<String, Value>, base: &Path) -> Result<Vec<String>, String> {
    crate::flags::args_from_named(
        fields,
        &RESERVED_KEYS,
        "is set by the batch (list file names in \"outputs\")",
        &|path| resolve(base, path),
    )
}

/// A path from the manifest: relative paths are taken from the manifest's folder, or, when
/// nothing is there, from the current folder (a manifest written next to its songs works
/// from anywhere; one written with paths from where the batch runs works too). A path that
/// exists in neither place is an error naming both.
fn resolve(base: &Path, path: &str) -> Result<String, String> {
    let p = Path::new(path);
    let candidates: Vec<PathBuf> = if p.is_absolute() {
        vec![p.to_path_buf()]
    } else {
        vec![base.join(p), p.to_path_buf()]
    };
    match candidates.iter().find(|c| c.exists()) {
        Some(c) => Ok(c.display().to_string()),
        None => Err(format!(
            "{path}: no such file (looked in {})",
            candidates
                .iter()
                .map(|c| c.display().to_string())
                .collect::<Vec<_>>()
                .join(" and ")
        )),
    }
}

/// Parses an argument list as `dancegen generate` would.
pub fn parse_generate_args(args: &[String]) -> Result<GenerateFlags, String> {
    crate::flags::parse(args)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn one(line: &str) -> Result<Entry, BadLine> {
        let dir = tempfile::tempdir().unwrap();
        std::fs::write(dir.path().join("a.wav"), b"").unwrap();
        let manifest = dir.path().join("m.jsonl");
        parse(line, &manifest).remove(0).1
    }

    #[test]
    fn options_become_generate_arguments() {
        let e = one(
            r#"{"id": "s1", "song": "a.wav", "system": "solo", "seed": 7, "outputs": ["dance.glb", "dance.npy"], "no_foot_lock": true, "no-beat-align": false, "end": 8.5, "start": null}"#,
        )
        .unwrap();
        assert_eq!(e.seed, 7);
        assert_eq!(e.outputs, ["dance.glb", "dance.npy"]);
        for a in ["--system=solo", "--seed=7", "--no-foot-lock", "--end=8.5"] {
            assert!(e.args.contains(&a.to_string()), "{a} in {:?}", e.args);
        }
        assert!(
            !e.args
                .iter()
                .any(|a| a.contains("beat-align") || a.contains("start"))
        );
        assert_eq!(e.args[e.args.len() - 2], "--");
        assert!(e.args.last().unwrap().ends_with("a.wav"));
        let g = parse_generate_args(&e.args).unwrap();
        assert_eq!(g.seed, Some(7));
        assert!(g.no_foot_lock && !g.no_beat_align);
        assert_eq!(g.end, Some(8.5));
    }

    #[test]
    fn seed_defaults_to_a_stable_hash_of_the_id() {
        let e = one(r#"{"id": "song-42"}"#).unwrap();
        assert_eq!(e.seed, seed_for("song-42"));
        assert!(e.args.contains(&format!("--seed={}", e.seed)));
        // Pinned: the default seed must not change between versions.
        assert_eq!(seed_for(""), 0xcbf2_9ce4 ^ 0x8422_2325);
        assert_ne!(seed_for("a"), seed_for("b"));
        assert!(seed_for("song-42") <= u64::from(u32::MAX));
    }

    #[test]
    fn lists_repeat_the_option() {
        let e = one(r#"{"id": "d", "leader": "a.wav", "guidance_levels": [1.5, 0.5]}"#).unwrap();
        assert!(e.args.contains(&"--guidance-levels=1.5".to_string()));
        assert!(e.args.contains(&"--guidance-levels=0.5".to_string()));
    }

    #[test]
    fn bad_lines_say_what_is_wrong() {
        let err = |l: &str| one(l).unwrap_err().error;
        assert!(err("{not json").starts_with("not JSON"));
        assert!(err("[1, 2]").contains("not a JSON object"));
        assert!(err(r#"{"song": "a.wav"}"#).contains("no \"id\""));
        assert!(err(r#"{"id": "../x"}"#).contains("cannot name a folder"));
        assert!(err(r#"{"id": "x", "song": "missing.wav"}"#).contains("missing.wav: no such file"));
        assert!(err(r#"{"id": "x", "colour": "red"}"#).contains("no --colour"));
        assert!(err(r#"{"id": "x", "outputs": ["../d.glb"]}"#).contains("plain file name"));
        assert!(err(r#"{"id": "x", "output": "d.glb"}"#).contains("set by the batch"));
        assert!(err(r#"{"id": "x", "seed": -1}"#).contains("whole number"));
        assert!(err(r#"{"id": "x", "unison": "yes"}"#).contains("switch"));
        assert!(err(r#"{"id": "x", "steps": "many"}"#).contains("many"));
        // clap's whole message, on one line.
        let e = err(r#"{"id": "x", "guidance_levels": [2]}"#);
        assert!(e.contains("not provided: --leader <FILE>"), "{e}");
    }

    #[test]
    fn a_repeated_id_fails_its_later_line_and_line_numbers_count_blank_lines() {
        let dir = tempfile::tempdir().unwrap();
        let m = dir.path().join("m.jsonl");
        let lines = parse("{\"id\": \"a\"}\n\n{\"id\": \"b\"}\n{\"id\": \"a\"}\n", &m);
        let indices: Vec<usize> = lines.iter().map(|(i, _)| *i).collect();
        assert_eq!(indices, [0, 2, 3]);
        let dup = lines[2].1.as_ref().unwrap_err();
        assert_eq!(dup.line, 4);
        assert!(dup.error.contains("first on line 1"), "{}", dup.error);
    }
}
