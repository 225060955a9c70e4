//! The report as people read it: a table, one metric per line ([`print_table`]), and the
//! `--json` object written atomically ([`write_json`]).

use std::path::Path;

use anyhow::{Context, Result};
use serde_json::Value;

use crate::Report;

/// The table on stdout.
pub fn print_table(report: &Report) {
    println!(
        "protocol {} ({} generated, {} ground-truth clips)",
        report.protocol.name, report.pred_clips, report.gt_clips
    );
    for (k, v) in &report.summary {
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

/// [`Report::to_json`], pretty, to `out` (atomically).
pub fn write_json(out: &Path, report: &Report) -> Result<()> {
    let text = serde_json::to_string_pretty(&report.to_json())?;
    dancegen_io::write_atomic(out, |w| {
        w.write_all(text.as_bytes())?;
        w.write_all(b"\n")
    })
    .with_context(|| format!("writing {}", out.display()))?;
    Ok(())
}
