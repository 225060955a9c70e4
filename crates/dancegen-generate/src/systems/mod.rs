//! The systems the generator can run, one module each, and the table of every system name a
//! user may ask for (including the ones not shipped yet, so the error can say so).

pub mod duet;
pub mod group;
mod group_edit;
mod group_options;
mod group_stage;
pub mod holistic;
mod holistic_edit;
mod holistic_options;
pub mod solo;

/// A system users can name.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct SystemInfo {
    /// `--system NAME`.
    pub name: &'static str,
    /// The method it implements.
    pub method: &'static str,
    /// `model.toml` `kind` of its models (empty while not shipped).
    pub model_kind: &'static str,
    pub default_model: &'static str,
    /// Whether this version can run it.
    pub available: bool,
    /// The edits it applies ([`DanceSystem::EDITS`]).
    pub edits: &'static [&'static str],
    /// The least music it dances to, seconds ([`DanceSystem::MIN_SECONDS`]).
    pub min_seconds: f64,
}

use crate::system::DanceSystem;

const fn shipped<S: DanceSystem>(method: &'static str) -> SystemInfo {
    SystemInfo {
        name: S::NAME,
        method,
        model_kind: S::MODEL_KIND,
        default_model: S::DEFAULT_MODEL,
        available: true,
        edits: S::EDITS,
        min_seconds: S::MIN_SECONDS,
    }
}

/// Which system applies which edit, as a text table (`generate --help` and the README).
pub fn edits_table() -> String {
    let ops = crate::edit::OPERATIONS;
    // Each column as wide as its flag or "not yet".
    let width = |op: &str| op.len().max("not yet".len());
    let mut out = String::from("Edits (which system supports what):\n  system    ");
    for op in ops {
        out += &format!(" {op:<w$}", w = width(op));
    }
    for s in SYSTEMS.iter().filter(|s| s.available) {
        out += &format!("\n  {:<10}", s.name);
        for op in ops {
            let yes = if s.edits.contains(&op) {
                "yes"
            } else {
                "not yet"
            };
            out += &format!(" {yes:<w$}", w = width(op));
        }
    }
    out.lines()
        .map(str::trim_end)
        .collect::<Vec<_>>()
        .join("\n")
        + "\nAn edit a system does not apply is refused, naming it, before any work."
}

/// Every system, in the order they are listed to users.
pub const SYSTEMS: [SystemInfo; 4] = [
    shipped::<solo::Solo>("Lodge++"),
    shipped::<duet::Duet>("ReactDance"),
    shipped::<group::Group>("TCDiff++"),
    shipped::<holistic::Holistic>("SoulNet"),
];

/// The system called `name`, or an error listing the choices (and saying which ones this
/// version does not have yet).
pub fn by_name(name: &str) -> Result<SystemInfo, String> {
    let available: Vec<&str> = SYSTEMS
        .iter()
        .filter(|s| s.available)
        .map(|s| s.name)
        .collect();
    match SYSTEMS.iter().find(|s| s.name == name) {
        Some(s) if s.available => Ok(*s),
        Some(s) => Err(format!(
            "the {} system ({}) is not shipped in this version yet; choose one of: {}",
            s.name,
            s.method,
            available.join(", ")
        )),
        None => {
            let coming: Vec<&str> = SYSTEMS
                .iter()
                .filter(|s| !s.available)
                .map(|s| s.name)
                .collect();
            Err(format!(
                "unknown system '{name}'; choose one of: {}{}",
                available.join(", "),
                if coming.is_empty() {
                    String::new()
                } else {
                    format!(" (coming: {})", coming.join(", "))
                }
            ))
        }
    }
}

/// The system whose models have `kind` in their `model.toml`.
pub fn by_model_kind(kind: &str) -> Option<SystemInfo> {
    SYSTEMS
        .iter()
        .find(|s| s.available && s.model_kind == kind)
        .copied()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_readme_shows_the_table_of_edits_the_systems_declare() {
        let readme =
            std::fs::read_to_string(concat!(env!("CARGO_MANIFEST_DIR"), "/../../README.md"))
                .expect("the repository's README");
        let table = edits_table();
        assert!(
            readme.contains(&table),
            "README.md's table of edits is not the systems' own; put this in it:\n{table}"
        );
        assert!(table.contains("solo       yes"), "{table}");
    }
}
