//! The table on stdout and the `--json` object.

use std::collections::BTreeMap;
use std::path::Path;

use anyhow::{Context, Result};
use dancegen_metrics::protocol::Protocol;
use serde_json::{Value, json};

pub fn print_table(
    summary: &BTreeMap<String, Value>,
    protocol: &Protocol,
    n_pred: usize,
    n_gt: usize,
) {
    println!(
        "protocol {} ({n_pred} generated, {n_gt} ground-truth clips)",
        protocol.name
    );
    for (k, v) in summary {
        print_value(k, v);
    }
}

/// One line per value; an object (the `genre` report) as `key.field` lines.
fn print_value(k: &str, v: &Value) {
    match v {
        Value::Object(fields) => {
            for (f, x) in fields {
                print_value(&format!("{k}.{f}"), x);
            }
        }
        Value::String(s) => println!("{k:<14} {s}"),
        Value::Number(n) if n.is_u64() || n.is_i64() => println!("{k:<14} {n}"),
        _ => match v.as_f64() {
            Some(x) => println!("{k:<14} {x:.6}"),
            None => println!("{k:<14} undefined"),
        },
    }
}

/// One object: the metric names as keys, `protocol`, and `per_clip` (written atomically).
pub fn write_json(
    out: &Path,
    summary: &BTreeMap<String, Value>,
    protocol: &Protocol,
    per_clip: Vec<Value>,
) -> Result<()> {
    let mut obj = serde_json::Map::new();
    for (k, v) in summary {
        obj.insert(k.clone(), v.clone());
    }
    obj.insert("protocol".into(), json!(protocol.name));
    obj.insert("per_clip".into(), Value::Array(per_clip));
    let text = serde_json::to_string_pretty(&Value::Object(obj))?;
    dancegen_io::write_atomic(out, |w| {
        w.write_all(text.as_bytes())?;
        w.write_all(b"\n")
    })
    .with_context(|| format!("writing {}", out.display()))?;
    Ok(())
}
