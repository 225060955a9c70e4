//! The crates are layers and the files of a crate do not go round in circles (issue 42).
//!
//! Layers: every crate of the workspace sits in one layer of
//! `[workspace.metadata.layers]` in the workspace `Cargo.toml`, and depends (dev- and
//! build-dependencies included) only on crates of lower layers. `cargo metadata` gives both
//! the layers and the dependencies, so a crate that gains an upward or sideways dependency, or
//! a new crate nobody placed, fails here with the arrow named.
//!
//! Files: within a crate, no two files may depend on each other, directly or through others
//! (a file depends on the module of every `crate::…` or `super::…` path in its non-test code).
//! A module's own parent does not count: it declares the child and may re-export it.

use std::collections::BTreeMap;
use std::path::Path;
use std::process::Command;

use serde_json::Value;

fn metadata() -> Value {
    let out = Command::new(env!("CARGO"))
        .args([
            "metadata",
            "--format-version",
            "1",
            "--no-deps",
            "--offline",
        ])
        .current_dir(Path::new(env!("CARGO_MANIFEST_DIR")))
        .output()
        .expect("cargo metadata runs");
    assert!(
        out.status.success(),
        "cargo metadata failed:\n{}",
        String::from_utf8_lossy(&out.stderr)
    );
    serde_json::from_slice(&out.stdout).expect("cargo metadata prints JSON")
}

/// Layer of each crate, from keys "N-name" of `[workspace.metadata.layers]`.
fn layers(meta: &Value) -> BTreeMap<String, (u32, String)> {
    let table = meta["metadata"]["layers"]
        .as_object()
        .expect("the workspace Cargo.toml has [workspace.metadata.layers]");
    let mut layer_of = BTreeMap::new();
    for (key, crates) in table {
        let rank: u32 = key
            .split('-')
            .next()
            .and_then(|n| n.parse().ok())
            .unwrap_or_else(|| panic!("layer key {key:?} does not start with its rank, as 3-name"));
        for c in crates.as_array().expect("a layer is a list of crate names") {
            let name = c.as_str().expect("crate names are strings").to_string();
            let previous = layer_of.insert(name.clone(), (rank, key.clone()));
            assert!(previous.is_none(), "{name} is in two layers");
        }
    }
    layer_of
}

/// Every breach of the layering in `meta`, one line each.
fn violations(meta: &Value) -> Vec<String> {
    let layer_of = layers(meta);
    let packages = meta["packages"].as_array().expect("packages");
    let members: Vec<&str> = packages
        .iter()
        .map(|p| p["name"].as_str().expect("name"))
        .collect();
    let mut wrong = Vec::new();
    for name in &members {
        if !layer_of.contains_key(*name) {
            wrong.push(format!(
                "{name} is in no layer of [workspace.metadata.layers]"
            ));
        }
    }
    for name in layer_of.keys() {
        if !members.contains(&name.as_str()) {
            wrong.push(format!(
                "the layers name {name}, which is not a workspace crate"
            ));
        }
    }
    for p in packages {
        let name = p["name"].as_str().expect("name");
        let Some((rank, layer)) = layer_of.get(name) else {
            continue;
        };
        for d in p["dependencies"].as_array().expect("dependencies") {
            let dep = d["name"].as_str().expect("dependency name");
            let Some((dep_rank, dep_layer)) = layer_of.get(dep) else {
                continue; // not a workspace crate
            };
            if dep_rank >= rank {
                let kind = d["kind"].as_str().unwrap_or("normal");
                wrong.push(format!(
                    "{name} ({layer}) depends on {dep} ({dep_layer}) as a {kind} dependency"
                ));
            }
        }
    }
    wrong
}

#[test]
fn every_crate_depends_only_on_lower_layers() {
    let meta = metadata();
    let wrong = violations(&meta);
    assert!(
        wrong.is_empty(),
        "crate layering broken:\n  {}",
        wrong.join("\n  ")
    );
}

/// The check can fail: an arrow from the bottom layer to the top, a sideways arrow and an
/// unplaced crate are each named.
#[test]
fn upward_and_sideways_dependencies_and_unplaced_crates_are_named() {
    let mut meta = metadata();
    let packages = meta["packages"].as_array_mut().expect("packages");
    let add_dep = |packages: &mut Vec<Value>, from: &str, to: &str, kind: Value| {
        packages
            .iter_mut()
            .find(|p| p["name"] == from)
            .unwrap_or_else(|| panic!("{from} is a member"))["dependencies"]
            .as_array_mut()
            .expect("dependencies")
            .push(serde_json::json!({"name": to, "kind": kind}));
    };
    add_dep(packages, "dancegen-io", "dancegen-cli", Value::Null);
    add_dep(
        packages,
        "dancegen-formats",
        "dancegen-refine",
        "dev".into(),
    );
    packages.push(serde_json::json!({"name": "dancegen-new", "dependencies": []}));
    let wrong = violations(&meta);
    assert_eq!(wrong.len(), 3, "{wrong:#?}");
    assert!(
        wrong
            .iter()
            .any(|w| w.contains("dancegen-io (1-io) depends on dancegen-cli"))
    );
    assert!(
        wrong
            .iter()
            .any(|w| w.contains("dancegen-formats") && w.contains("dev dependency"))
    );
    assert!(
        wrong
            .iter()
            .any(|w| w.contains("dancegen-new is in no layer"))
    );
}

/// The files of one crate's `src/` as modules: `a/b.rs` and `a/b/mod.rs` are `a::b`,
/// `lib.rs` and `main.rs` the root (empty path).
fn modules(src: &Path) -> BTreeMap<Vec<String>, std::path::PathBuf> {
    let mut out = BTreeMap::new();
    let mut stack = vec![src.to_path_buf()];
    while let Some(dir) = stack.pop() {
        for entry in std::fs::read_dir(&dir).expect("src folder readable") {
            let path = entry.expect("entry").path();
            if path.is_dir() {
                stack.push(path);
            } else if path.extension().is_some_and(|e| e == "rs") {
                let rel = path
                    .strip_prefix(src)
                    .expect("under src")
                    .with_extension("");
                let mut parts: Vec<String> = rel
                    .components()
                    .map(|c| c.as_os_str().to_string_lossy().into_owned())
                    .collect();
                if matches!(
                    parts.last().map(String::as_str),
                    Some("mod" | "lib" | "main")
                ) {
                    parts.pop();
                }
                out.insert(parts, path);
            }
        }
    }
    out
}

/// The code of a file without comments and without its test module (`#[cfg(test)] mod …`,
/// at the end of a file, may use anything). A `#[cfg(test)]` on a single item mid-file (a
/// reference implementation, say) does not end the code.
fn code_of(text: &str) -> String {
    let test_module = text.match_indices("#[cfg(test)]").find(|(i, m)| {
        let rest = text[i + m.len()..].trim_start();
        rest.starts_with("mod ") || rest.starts_with("pub mod ")
    });
    let text = &text[..test_module.map_or(text.len(), |(i, _)| i)];
    text.lines()
        .map(|l| match l.find("//") {
            Some(i) => &l[..i],
            None => l,
        })
        .collect::<Vec<_>>()
        .join("\n")
}

/// Every path that starts at `anchor` (`crate::` or `super::`) in `code`, brace groups
/// expanded: `crate::{a::b, c}` gives `a::b` and `c`.
fn paths_after(code: &str, anchor: &str) -> Vec<Vec<String>> {
    fn ident(s: &[u8], i: &mut usize) -> Option<String> {
        let start = *i;
        while *i < s.len() && (s[*i].is_ascii_alphanumeric() || s[*i] == b'_') {
            *i += 1;
        }
        (*i > start).then(|| String::from_utf8_lossy(&s[start..*i]).into_owned())
    }
    fn skip_ws(s: &[u8], i: &mut usize) {
        while *i < s.len() && s[*i].is_ascii_whitespace() {
            *i += 1;
        }
    }
    // Reads `seg::seg::{...}` at `i`, appending each full path to `out`.
    fn tree(s: &[u8], i: &mut usize, prefix: Vec<String>, out: &mut Vec<Vec<String>>) {
        skip_ws(s, i);
        if *i < s.len() && s[*i] == b'{' {
            *i += 1;
            loop {
                skip_ws(s, i);
                if *i >= s.len() || s[*i] == b'}' {
                    *i += 1;
                    return;
                }
                tree(s, i, prefix.clone(), out);
                skip_ws(s, i);
                if *i < s.len() && s[*i] == b',' {
                    *i += 1;
                }
            }
        }
        let mut path = prefix;
        while let Some(seg) = ident(s, i) {
            path.push(seg);
            if s[*i..].starts_with(b"::") {
                *i += 2;
                if *i < s.len() && s[*i] == b'{' {
                    tree(s, i, path, out);
                    return;
                }
            } else {
                break;
            }
        }
        // `as name` and the like end the path.
        out.push(path);
    }
    let bytes = code.as_bytes();
    let mut out = Vec::new();
    let mut from = 0;
    while let Some(k) = code[from..].find(anchor) {
        let at = from + k;
        from = at + anchor.len();
        let before = at.checked_sub(1).map(|b| bytes[b]);
        if before.is_some_and(|b| b.is_ascii_alphanumeric() || b == b'_' || b == b':') {
            continue; // `dancegen_crate::`, `super::super::` counted from its first `super`
        }
        let mut i = from;
        let mut ups = 0;
        if anchor == "super::" {
            ups = 1;
            while bytes[i..].starts_with(b"super::") {
                ups += 1;
                i += "super::".len();
            }
        }
        let mut found = Vec::new();
        tree(bytes, &mut i, Vec::new(), &mut found);
        for p in found {
            let mut marked = vec![format!("^{ups}")];
            marked.extend(p);
            out.push(marked);
        }
    }
    out
}

/// Module-to-module edges of one crate: a file that names `crate::a::b` or `super::x` depends
/// on the deepest module of that path. A module and its own ancestors are one unit (the
/// parent declares the child and may re-export it), so those references are not edges.
fn file_edges(src: &Path) -> BTreeMap<Vec<String>, std::collections::BTreeSet<Vec<String>>> {
    let mods = modules(src);
    let mut edges = BTreeMap::new();
    for (m, path) in &mods {
        let code = code_of(&std::fs::read_to_string(path).expect("source readable"));
        let mut targets = std::collections::BTreeSet::new();
        for anchor in ["crate::", "super::"] {
            for marked in paths_after(&code, anchor) {
                let ups: usize = marked[0][1..].parse().expect("marker");
                let rest = &marked[1..];
                let base: Vec<String> = if anchor == "crate::" {
                    Vec::new()
                } else {
                    // `super` of a/x.rs and of a/x/mod.rs (both module a::x) is a.
                    m[..m.len().saturating_sub(ups)].to_vec()
                };
                let full: Vec<String> = base.iter().chain(rest).cloned().collect();
                let Some(target) = (0..=full.len())
                    .rev()
                    .map(|k| full[..k].to_vec())
                    .find(|p| mods.contains_key(p))
                else {
                    continue;
                };
                let ancestor_or_self = target.len() <= m.len() && m[..target.len()] == target[..];
                if !ancestor_or_self {
                    targets.insert(target);
                }
            }
        }
        edges.insert(m.clone(), targets);
    }
    edges
}

/// The file cycles of one crate: strongly connected sets of more than one module.
fn file_cycles(src: &Path) -> Vec<Vec<String>> {
    let edges = file_edges(src);
    let names: Vec<&Vec<String>> = edges.keys().collect();
    let index: BTreeMap<&Vec<String>, usize> =
        names.iter().enumerate().map(|(i, n)| (*n, i)).collect();
    let adj: Vec<Vec<usize>> = names
        .iter()
        .map(|n| edges[*n].iter().map(|t| index[t]).collect())
        .collect();
    // Reachability by depth-first search from every module (small graphs: at most a few
    // hundred files); two modules are in one cycle when each reaches the other.
    let reach: Vec<Vec<bool>> = (0..names.len())
        .map(|s| {
            let mut seen = vec![false; names.len()];
            let mut stack = adj[s].clone();
            while let Some(v) = stack.pop() {
                if !seen[v] {
                    seen[v] = true;
                    stack.extend(&adj[v]);
                }
            }
            seen
        })
        .collect();
    let mut done = vec![false; names.len()];
    let mut cycles = Vec::new();
    for a in 0..names.len() {
        if done[a] || !reach[a][a] {
            continue;
        }
        let members: Vec<usize> = (0..names.len())
            .filter(|&b| reach[a][b] && reach[b][a])
            .collect();
        for &b in &members {
            done[b] = true;
        }
        if members.len() > 1 {
            cycles.push(
                members
                    .iter()
                    .map(|&b| match names[b].join("::") {
                        s if s.is_empty() => "(crate root)".to_string(),
                        s => s,
                    })
                    .collect(),
            );
        }
    }
    cycles
}

#[test]
fn no_file_depends_on_itself_through_others() {
    let meta = metadata();
    let mut found = Vec::new();
    for p in meta["packages"].as_array().expect("packages") {
        let manifest = Path::new(p["manifest_path"].as_str().expect("manifest path"));
        let src = manifest.parent().expect("crate folder").join("src");
        for cycle in file_cycles(&src) {
            found.push(format!(
                "{}: {}",
                p["name"].as_str().unwrap_or("?"),
                cycle.join(" <-> ")
            ));
        }
    }
    assert!(
        found.is_empty(),
        "files that depend on each other:\n  {}",
        found.join("\n  ")
    );
}

/// The cycle finder sees `use crate::{..}` groups, `super::` paths and plain `crate::` paths,
/// skips comments and test modules, and reads on past a single `#[cfg(test)]` item.
#[test]
fn a_file_cycle_is_found() {
    let dir = tempfile::tempdir().expect("temp dir");
    let src = dir.path().join("src");
    std::fs::create_dir_all(src.join("systems")).expect("dirs");
    std::fs::write(
        src.join("lib.rs"),
        "mod request;\nmod systems;\nmod song;\n",
    )
    .unwrap();
    std::fs::write(
        src.join("request.rs"),
        "use crate::{song::Song, systems::solo::SoloOptions};\n// crate::nothing here\n",
    )
    .unwrap();
    std::fs::write(src.join("systems/mod.rs"), "pub mod solo;\n").unwrap();
    std::fs::write(
        src.join("systems/solo.rs"),
        "#[cfg(test)]\nfn reference() {}\npub struct SoloOptions(super::super::request::Common);\n",
    )
    .unwrap();
    std::fs::write(
        src.join("song.rs"),
        "pub struct Song;\n#[cfg(test)]\nmod tests {\n    use crate::request;\n}\n",
    )
    .unwrap();
    let cycles = file_cycles(&src);
    assert_eq!(
        cycles,
        vec![vec!["request".to_string(), "systems::solo".to_string()]]
    );
    // Untied: solo no longer names request.
    std::fs::write(src.join("systems/solo.rs"), "pub struct SoloOptions;\n").unwrap();
    assert!(file_cycles(&src).is_empty());
}
