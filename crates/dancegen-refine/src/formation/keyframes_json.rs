//! Reads FORMATION.json into keyframes, naming the JSON field of every shape error.
//!
//! A derived `Deserialize` would report "invalid type: string, expected f64 at line 4 column
//! 9"; walking a `serde_json::Value` instead lets every message say
//! `keyframes[2].positions[1]`, the path the user edits. Values are only checked for shape
//! here; [`super::keyframes::Formation::new`] checks what they mean.

use super::StagePos;
use super::keyframes::{Formation, Keyframe};
use super::keyframes_error::{FormationError, FormationProblem};
use serde_json::{Map, Value};
use std::path::Path;

/// The fields of the top-level object.
const TOP_FIELDS: &[&str] = &["keyframes"];
/// The fields of one keyframe.
const KEYFRAME_FIELDS: &[&str] = &["t", "positions"];

/// The file's entry points, here beside the reader so that the keyframes do not depend on it.
impl Formation {
    /// Parses and validates FORMATION.json text for `dancers` dancers and a song of
    /// `song_seconds`; `path_label` names the file in errors.
    pub fn parse(
        path_label: &str,
        json: &str,
        dancers: usize,
        song_seconds: f64,
    ) -> Result<Formation, FormationError> {
        let keyframes = keyframes_from_json(json).map_err(|problem| FormationError {
            file: path_label.to_string(),
            problem,
        })?;
        Formation::new(path_label, keyframes, dancers, song_seconds)
    }

    /// Reads, parses and validates a FORMATION.json file ([`Formation::parse`]).
    pub fn read(
        path: &Path,
        dancers: usize,
        song_seconds: f64,
    ) -> Result<Formation, FormationError> {
        let label = path.display().to_string();
        let json = std::fs::read_to_string(path).map_err(|e| FormationError {
            file: label.clone(),
            problem: FormationProblem::Read(e.to_string()),
        })?;
        Formation::parse(&label, &json, dancers, song_seconds)
    }
}

/// The keyframes of a FORMATION.json document, in file order and unvalidated.
pub(super) fn keyframes_from_json(json: &str) -> Result<Vec<Keyframe>, FormationProblem> {
    let root: Value =
        serde_json::from_str(json).map_err(|e| FormationProblem::Json(e.to_string()))?;
    let top = object(&root, "(top level)", "an object {\"keyframes\": [...]}")?;
    check_fields(top, "", TOP_FIELDS)?;
    let list = match top.get("keyframes") {
        None => return Err(missing("keyframes")),
        Some(Value::Array(list)) => list,
        Some(other) => return Err(wrong_type("keyframes", "a list of keyframes", other)),
    };
    list.iter()
        .enumerate()
        .map(|(k, item)| keyframe(item, &format!("keyframes[{k}]")))
        .collect()
}

fn keyframe(item: &Value, field: &str) -> Result<Keyframe, FormationProblem> {
    let fields = object(item, field, "an object {\"t\": ..., \"positions\": [...]}")?;
    check_fields(fields, field, KEYFRAME_FIELDS)?;
    let t_field = format!("{field}.t");
    let t = match fields.get("t") {
        None => return Err(missing(&t_field)),
        Some(value) => number(value, &t_field, "a time in seconds")?,
    };
    let positions_field = format!("{field}.positions");
    let positions = match fields.get("positions") {
        None => return Err(missing(&positions_field)),
        Some(Value::Array(list)) => list,
        Some(other) => {
            return Err(wrong_type(
                &positions_field,
                "a list with one [x, z] or null per dancer",
                other,
            ));
        }
    };
    let positions = positions
        .iter()
        .enumerate()
        .map(|(d, p)| position(p, &format!("{positions_field}[{d}]")))
        .collect::<Result<_, _>>()?;
    Ok(Keyframe { t, positions })
}

fn position(value: &Value, field: &str) -> Result<Option<StagePos>, FormationProblem> {
    const EXPECTED: &str = "[x, z] in metres, or null for a free dancer";
    match value {
        Value::Null => Ok(None),
        Value::Array(xz) if xz.len() == 2 => Ok(Some([
            number(&xz[0], &format!("{field}[0]"), "x in metres")?,
            number(&xz[1], &format!("{field}[1]"), "z in metres")?,
        ])),
        other => Err(wrong_type(field, EXPECTED, other)),
    }
}

fn object<'a>(
    value: &'a Value,
    field: &str,
    expected: &'static str,
) -> Result<&'a Map<String, Value>, FormationProblem> {
    value
        .as_object()
        .ok_or_else(|| wrong_type(field, expected, value))
}

fn number(value: &Value, field: &str, expected: &'static str) -> Result<f64, FormationProblem> {
    value
        .as_f64()
        .ok_or_else(|| wrong_type(field, expected, value))
}

/// Unknown fields are errors, not ignored: a misspelt `"time"` must not leave a keyframe that
/// silently means something else.
fn check_fields(
    fields: &Map<String, Value>,
    parent: &str,
    allowed: &'static [&'static str],
) -> Result<(), FormationProblem> {
    match fields.keys().find(|k| !allowed.contains(&k.as_str())) {
        None => Ok(()),
        Some(key) => Err(FormationProblem::UnknownField {
            field: if parent.is_empty() {
                key.clone()
            } else {
                format!("{parent}.{key}")
            },
            allowed: allowed.join(", "),
        }),
    }
}

fn missing(field: &str) -> FormationProblem {
    FormationProblem::Missing {
        field: field.to_string(),
    }
}

fn wrong_type(field: &str, expected: &'static str, found: &Value) -> FormationProblem {
    let found = match found {
        Value::Null => "null".to_string(),
        Value::Bool(b) => b.to_string(),
        Value::Number(n) => format!("the number {n}"),
        Value::String(s) => format!("the text {s:?}"),
        Value::Array(list) => format!("a list of {}", list.len()),
        Value::Object(_) => "an object".to_string(),
    };
    FormationProblem::WrongType {
        field: field.to_string(),
        expected,
        found,
    }
}
