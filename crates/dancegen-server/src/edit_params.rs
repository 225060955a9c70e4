//! `edit` of a job's params: a new version of a finished job's dance, as `dancegen generate
//! --edit DANCE --regenerate A-B [--keep-joints SET --from DANCE]` makes it.
//!
//! ```json
//! {"edit": {"of": "JOB_ID", "variation": 0, "regenerate": [[8, 12]], "keep": "arms"}}
//! {"edit": {"of": "JOB_ID", "continue": true}, "end": 60}
//! ```
//!
//! The new job dances to the song of the job it edits, with its system, dancers, start and end;
//! `seed`, `steps`, `variations` and `mp4` are its own. `keep` keeps those joints of the old
//! dance in the regenerated parts too (the web app's "keep arms" / "keep legs"). `continue`
//! keeps the whole dance and dances on to the job's own `end` (the song's end without one),
//! as `--edit DANCE --extend` (the web app's "Continue").

use serde::{Deserialize, Serialize};
use serde_json::{Map, Value};

use dancegen_generate::edit::parse_joint_set;

use crate::error::ApiError;
use crate::files::valid_id;

/// The fields `edit` may have, for the error about an unknown one.
const EDIT_FIELDS: &str = "of, variation, regenerate, keep, continue";

/// Most ranges one edit regenerates.
pub const MAX_RANGES: usize = 16;

/// See the module documentation.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct EditParams {
    /// The job whose dance is edited.
    pub of: String,
    /// Which of its variations (0 = the first).
    #[serde(default)]
    pub variation: usize,
    /// Seconds from the dance's start to make new.
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub regenerate: Vec<[f64; 2]>,
    /// Keep the whole dance and dance on (to the new job's `end`).
    #[serde(
        default,
        rename = "continue",
        skip_serializing_if = "std::ops::Not::not"
    )]
    pub extend: bool,
    /// Joints the regenerated parts keep from the old dance (`arms`, `legs`, `upper`, `lower`
    /// or joint names, as `--keep-joints`).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub keep: Option<String>,
}

impl EditParams {
    /// Parses `edit` (a JSON object, or its JSON text as a form field sends it); every error
    /// names the field (`edit.regenerate[1]`).
    pub fn parse(value: &Value) -> Result<Self, ApiError> {
        let parsed;
        let obj = match value {
            Value::Object(o) => o,
            Value::String(text) => {
                parsed = serde_json::from_str::<Value>(text)
                    .map_err(|e| ApiError::field("edit", format!("not valid JSON: {e}")))?;
                match &parsed {
                    Value::Object(o) => o,
                    _ => return Err(not_an_object()),
                }
            }
            _ => return Err(not_an_object()),
        };
        if let Some(k) = obj
            .keys()
            .find(|k| !EDIT_FIELDS.split(", ").any(|f| f == k.as_str()))
        {
            let field = format!("edit.{k}");
            return Err(ApiError::field(
                &field,
                format!("unknown field (known: {EDIT_FIELDS})"),
            ));
        }
        let of = match obj.get("of") {
            Some(Value::String(s)) if valid_id(s.trim()) => s.trim().to_string(),
            Some(v) => return Err(ApiError::field("edit.of", format!("{v}: not a job id"))),
            None => return Err(ApiError::field("edit.of", "missing: the job to edit")),
        };
        let variation = match obj.get("variation") {
            None | Some(Value::Null) => 0,
            Some(v) => v.as_u64().ok_or_else(|| {
                ApiError::field("edit.variation", format!("{v}: need a whole number ≥ 0"))
            })? as usize,
        };
        let extend = match obj.get("continue") {
            None | Some(Value::Null) => false,
            Some(Value::Bool(b)) => *b,
            Some(v) => {
                return Err(ApiError::field(
                    "edit.continue",
                    format!("{v}: need true or false"),
                ));
            }
        };
        let regenerate = match obj.get("regenerate") {
            None | Some(Value::Null) if extend => Vec::new(),
            _ => ranges(obj)?,
        };
        let keep = match obj.get("keep") {
            None | Some(Value::Null) => None,
            Some(Value::String(s)) if s.trim().is_empty() => None,
            Some(Value::String(s)) => {
                parse_joint_set("edit.keep", s).map_err(|e| ApiError::field("edit.keep", e))?;
                Some(s.trim().to_string())
            }
            Some(v) => return Err(ApiError::field("edit.keep", format!("{v}: need a string"))),
        };
        Ok(EditParams {
            of,
            variation,
            regenerate,
            extend,
            keep,
        })
    }
}

fn not_an_object() -> ApiError {
    ApiError::field(
        "edit",
        "need an object {\"of\": JOB_ID, \"regenerate\": [[A, B], ...]}",
    )
}

/// `edit.regenerate`: one or more `[A, B]` seconds with `0 ≤ A < B` (checked against the
/// dance's length when the job is submitted).
fn ranges(obj: &Map<String, Value>) -> Result<Vec<[f64; 2]>, ApiError> {
    let list = match obj.get("regenerate") {
        Some(Value::Array(list)) if !list.is_empty() => list,
        Some(v) if !v.is_array() => {
            return Err(ApiError::field(
                "edit.regenerate",
                format!("{v}: need a list of [start, end] in seconds"),
            ));
        }
        _ => {
            return Err(ApiError::field(
                "edit.regenerate",
                "missing: say what to make new, [[start, end], ...] in seconds",
            ));
        }
    };
    if list.len() > MAX_RANGES {
        return Err(ApiError::field(
            "edit.regenerate",
            format!("{} ranges; at most {MAX_RANGES}", list.len()),
        ));
    }
    list.iter()
        .enumerate()
        .map(|(i, v)| {
            let field = format!("edit.regenerate[{i}]");
            let pair = v
                .as_array()
                .filter(|p| p.len() == 2)
                .and_then(|p| Some([p[0].as_f64()?, p[1].as_f64()?]))
                .ok_or_else(|| ApiError::field(&field, format!("{v}: need [start, end]")))?;
            if !(pair[0] >= 0.0 && pair[0] < pair[1] && pair[1].is_finite()) {
                return Err(ApiError::field(
                    &field,
                    format!("{v}: need 0 ≤ start < end, in seconds"),
                ));
            }
            Ok(pair)
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;
    use serde_json::json;

    fn field_of(v: Value) -> String {
        let e = EditParams::parse(&v).unwrap_err();
        e.field.clone().unwrap_or_default()
    }

    #[test]
    fn an_edit_parses_from_an_object_or_its_text() {
        let want = EditParams {
            of: "abc123".into(),
            variation: 1,
            regenerate: vec![[8.0, 12.0], [20.0, 21.5]],
            extend: false,
            keep: Some("arms".into()),
        };
        let v = json!({"of": "abc123", "variation": 1, "regenerate": [[8, 12], [20, 21.5]], "keep": "arms"});
        assert_eq!(EditParams::parse(&v).unwrap(), want);
        assert_eq!(
            EditParams::parse(&Value::String(v.to_string())).unwrap(),
            want
        );
        let plain = EditParams::parse(&json!({"of": "x1", "regenerate": [[1, 2]]})).unwrap();
        assert_eq!((plain.variation, plain.keep), (0, None));
        let more = EditParams::parse(&json!({"of": "x1", "continue": true})).unwrap();
        assert!(more.extend && more.regenerate.is_empty());
        let text = serde_json::to_value(&more).unwrap();
        assert_eq!(text, json!({"of": "x1", "variation": 0, "continue": true}));
    }

    #[test]
    fn each_bad_field_is_named() {
        for (v, field) in [
            (json!({"regenerate": [[1, 2]]}), "edit.of"),
            (json!({"of": "../x", "regenerate": [[1, 2]]}), "edit.of"),
            (json!({"of": "x1"}), "edit.regenerate"),
            (json!({"of": "x1", "regenerate": []}), "edit.regenerate"),
            (
                json!({"of": "x1", "regenerate": [[1, 2], [3]]}),
                "edit.regenerate[1]",
            ),
            (
                json!({"of": "x1", "regenerate": [[2, 1]]}),
                "edit.regenerate[0]",
            ),
            (
                json!({"of": "x1", "regenerate": [[-1, 1]]}),
                "edit.regenerate[0]",
            ),
            (
                json!({"of": "x1", "regenerate": [[1, 2]], "keep": "tail"}),
                "edit.keep",
            ),
            (
                json!({"of": "x1", "regenerate": [[1, 2]], "variation": -1}),
                "edit.variation",
            ),
            (json!({"of": "x1", "continue": "yes"}), "edit.continue"),
            (json!({"of": "x1", "continue": false}), "edit.regenerate"),
            (
                json!({"of": "x1", "regenerate": [[1, 2]], "seed": 3}),
                "edit.seed",
            ),
            (json!([1, 2]), "edit"),
            (Value::String("{".into()), "edit"),
        ] {
            assert_eq!(field_of(v.clone()), field, "{v}");
        }
    }
}
