//! The workspace's shape, checked: no import circle spans more than three files in any
//! crate, the station's layers import only from below (core < app < views < commands), and
//! the emulator's world never imports its scenarios or its command line (world < scenarios <
//! cli).
//!
//! A module's imports are read from its source: `use crate::...`, `use super::...` and
//! paths written inline (`crate::a::b::f()`), with comments and `#[cfg(test)] mod` blocks left
//! out (a test module may import what it tests). A path is resolved to the deepest module file
//! it names; a module the crate root re-exports (`pub use a::b;`) resolves to where it lives.
//! Parent/child `mod` declarations are not imports.
//!
//! Run outside cargo, from the workspace, it reports every circle of any size in the crates
//! named and every upward import: `CARGO_MANIFEST_DIR=$PWD/tests rustc --edition 2021 -O
//! tests/tests/module_layers.rs -o /tmp/ml && /tmp/ml protocol robot-firmware emulator`.
#![allow(clippy::unwrap_used, clippy::panic)]

use std::collections::{BTreeMap, BTreeSet};
use std::path::{Path, PathBuf};

/// The source files of a crate's `src/`, by module path (`""` is the crate root).
fn modules(src: &Path) -> BTreeMap<String, PathBuf> {
    let mut out = BTreeMap::new();
    let mut stack = vec![src.to_path_buf()];
    while let Some(dir) = stack.pop() {
        for e in std::fs::read_dir(&dir).unwrap() {
            let p = e.unwrap().path();
            if p.is_dir() {
                stack.push(p);
                continue;
            }
            if p.extension().is_none_or(|x| x != "rs") {
                continue;
            }
            let rel = p.strip_prefix(src).unwrap().with_extension("");
            let mut parts: Vec<String> = rel
                .components()
                .map(|c| c.as_os_str().to_string_lossy().into_owned())
                .collect();
            // A binary's root beside the library's is a crate of its own, outside this tree.
            if parts.len() == 1 && parts[0] == "main" && src.join("lib.rs").exists() {
                continue;
            }
            match parts.last().map(String::as_str) {
                Some("lib") | Some("main") if parts.len() == 1 => parts.clear(),
                Some("mod") => {
                    parts.pop();
                }
                _ => {}
            }
            // Test files (`tests.rs`, `*_tests.rs`, under a `tests/` folder) are cfg(test).
            let is_test = parts.iter().any(|p| p == "tests")
                || parts.last().is_some_and(|p| p.ends_with("_tests"));
            if !is_test {
                out.insert(parts.join("::"), p);
            }
        }
    }
    out
}

/// `text` without comments, string contents and `#[cfg(test)] mod x { ... }` blocks.
fn code_of(text: &str) -> String {
    let mut out = String::with_capacity(text.len());
    let b = text.as_bytes();
    let mut i = 0;
    while i < b.len() {
        if b[i..].starts_with(b"//") {
            while i < b.len() && b[i] != b'\n' {
                i += 1;
            }
        } else if b[i..].starts_with(b"/*") {
            i += 2;
            while i + 1 < b.len() && !b[i..].starts_with(b"*/") {
                i += 1;
            }
            i += 2;
        } else if b[i] == b'"' {
            i += 1;
            while i < b.len() && b[i] != b'"' {
                if b[i] == b'\\' {
                    i += 1;
                }
                i += 1;
            }
            i += 1;
            out.push_str("\"\"");
        } else {
            out.push(b[i] as char);
            i += 1;
        }
    }
    // A test module at the end of a file: everything from its attribute on is test code.
    if let Some(at) = out.find("#[cfg(test)]") {
        let rest = out[at + 12..].trim_start();
        let rest = rest.strip_prefix("pub(crate) ").unwrap_or(rest);
        let rest = rest.strip_prefix("pub(super) ").unwrap_or(rest);
        if rest.starts_with("mod ") && rest.contains('{') {
            out.truncate(at);
        }
    }
    out
}

/// Every `crate::`/`super::`/`self::` path in `code`, braces of `use` lists expanded.
fn paths(code: &str) -> Vec<String> {
    let mut out = Vec::new();
    // `use` statements (with their brace lists).
    let mut rest = code;
    while let Some(at) = rest.find("use ") {
        let before_ok = at == 0 || !rest.as_bytes()[at - 1].is_ascii_alphanumeric();
        let stmt_end = rest[at..].find(';').map_or(rest.len(), |e| at + e);
        if before_ok {
            let stmt = rest[at + 4..stmt_end].trim();
            expand(stmt, &mut out);
        }
        rest = &rest[stmt_end.min(rest.len())..];
        if rest.is_empty() {
            break;
        }
        rest = &rest[1.min(rest.len())..];
    }
    // Inline paths.
    for start in ["crate::", "super::"] {
        let mut s = code;
        while let Some(at) = s.find(start) {
            let ok = at == 0
                || !(s.as_bytes()[at - 1].is_ascii_alphanumeric() || s.as_bytes()[at - 1] == b'_');
            let tail = &s[at..];
            let end = tail
                .find(|c: char| !(c.is_ascii_alphanumeric() || c == '_' || c == ':'))
                .unwrap_or(tail.len());
            if ok {
                out.push(tail[..end].trim_end_matches(':').to_string());
            }
            s = &s[at + start.len()..];
        }
    }
    out.retain(|p| p.starts_with("crate") || p.starts_with("super") || p.starts_with("self"));
    out
}

/// `a::b::{c, d::{e, f}}` into `a::b::c`, `a::b::d::e`, `a::b::d::f`.
fn expand(tree: &str, out: &mut Vec<String>) {
    let tree: String = tree.split_whitespace().collect::<Vec<_>>().join(" ");
    let Some(open) = tree.find('{') else {
        out.push(tree.split(" as ").next().unwrap_or("").trim().to_string());
        return;
    };
    let prefix = tree[..open].trim_end_matches("::").trim();
    let inner = &tree[open + 1..tree.rfind('}').unwrap_or(tree.len())];
    let mut depth = 0;
    let mut item = String::new();
    let mut items = Vec::new();
    for c in inner.chars() {
        match c {
            '{' => depth += 1,
            '}' => depth -= 1,
            ',' if depth == 0 => {
                items.push(std::mem::take(&mut item));
                continue;
            }
            _ => {}
        }
        item.push(c);
    }
    items.push(item);
    for it in items {
        let it = it.trim();
        if it.is_empty() {
            continue;
        }
        if it == "self" {
            out.push(prefix.to_string());
        } else {
            expand(&format!("{prefix}::{it}"), out);
        }
    }
}

/// A path written in module `m` as a module path from the crate root.
fn absolute(m: &str, path: &str) -> String {
    let mut cur: Vec<&str> = if m.is_empty() {
        vec![]
    } else {
        m.split("::").collect()
    };
    let mut parts = path.split("::").peekable();
    if parts.peek() == Some(&"crate") {
        parts.next();
        cur.clear();
    }
    while let Some(&p) = parts.peek() {
        match p {
            "super" => {
                cur.pop();
            }
            "self" => {}
            _ => break,
        }
        parts.next();
    }
    cur.extend(parts);
    cur.join("::")
}

/// The modules the crate root re-exports under a name of their own (`pub use a::b;` or
/// `pub use a::{b, c as d};` naming a module): name -> where the module lives.
fn root_aliases(mods: &BTreeMap<String, PathBuf>) -> BTreeMap<String, String> {
    let mut out = BTreeMap::new();
    let Some(root) = mods.get("") else {
        return out;
    };
    let code = code_of(&std::fs::read_to_string(root).unwrap());
    let mut rest = code.as_str();
    while let Some(at) = rest.find("pub use ") {
        let end = rest[at..].find(';').map_or(rest.len(), |e| at + e);
        let mut items = Vec::new();
        expand(&rest[at + 8..end], &mut items);
        // `expand` keeps `as` renames only on unbraced items; read them here for both.
        let stmt: String = rest[at + 8..end]
            .split_whitespace()
            .collect::<Vec<_>>()
            .join(" ");
        for item in items {
            let target = absolute("", &item);
            if !mods.contains_key(&target) {
                continue;
            }
            let last = target.rsplit("::").next().unwrap_or("").to_string();
            let renamed = stmt
                .split(&format!("{last} as "))
                .nth(1)
                .and_then(|t| t.split(|c: char| !(c.is_alphanumeric() || c == '_')).next())
                .filter(|n| !n.is_empty())
                .map(str::to_string);
            out.insert(renamed.unwrap_or(last), target);
        }
        rest = &rest[end.min(rest.len())..];
        if rest.is_empty() {
            break;
        }
        rest = &rest[1..];
    }
    out.retain(|name, target| name != target);
    out
}

/// The deepest module `path` names, a root re-export followed to where it lives.
fn resolve<'a>(
    path: &str,
    mods: &'a BTreeMap<String, PathBuf>,
    aliases: &BTreeMap<String, String>,
) -> Option<&'a str> {
    let mut parts: Vec<&str> = path.split("::").collect();
    let head;
    if let Some(target) = parts.first().and_then(|p| aliases.get(*p)) {
        if !mods.contains_key(parts[0]) {
            head = target.clone();
            parts.splice(0..1, head.split("::"));
        }
    }
    (0..=parts.len())
        .rev()
        .map(|n| parts[..n].join("::"))
        .find_map(|cand| mods.get_key_value(&cand).map(|(k, _)| k.as_str()))
}

/// The modules that `text`, the source of module `m`, imports (not itself, not the root).
fn imports_of(
    m: &str,
    text: &str,
    mods: &BTreeMap<String, PathBuf>,
    aliases: &BTreeMap<String, String>,
) -> BTreeSet<String> {
    let mut edges = BTreeSet::new();
    for path in paths(&code_of(text)) {
        let a = absolute(m, &path);
        if let Some(t) = resolve(&a, mods, aliases) {
            if !t.is_empty() && t != m {
                edges.insert(t.to_string());
            }
        }
    }
    edges
}

/// The import graph of a crate: module -> modules it imports (not itself, not the root `""`).
fn graph(src: &Path) -> BTreeMap<String, BTreeSet<String>> {
    let mods = modules(src);
    let aliases = root_aliases(&mods);
    mods.iter()
        .map(|(m, p)| {
            let text = std::fs::read_to_string(p).unwrap();
            (m.clone(), imports_of(m, &text, &mods, &aliases))
        })
        .collect()
}

/// Strongly connected components of more than one module (Tarjan).
fn circles(g: &BTreeMap<String, BTreeSet<String>>) -> Vec<Vec<String>> {
    struct T<'a> {
        g: &'a BTreeMap<String, BTreeSet<String>>,
        index: BTreeMap<&'a str, usize>,
        low: BTreeMap<&'a str, usize>,
        stack: Vec<&'a str>,
        on: BTreeSet<&'a str>,
        out: Vec<Vec<String>>,
    }
    fn visit<'a>(t: &mut T<'a>, v: &'a str) {
        let i = t.index.len();
        t.index.insert(v, i);
        t.low.insert(v, i);
        t.stack.push(v);
        t.on.insert(v);
        if let Some(ws) = t.g.get(v) {
            for w in ws {
                let w = w.as_str();
                if !t.index.contains_key(w) {
                    visit(t, w);
                    let lw = t.low[w];
                    let lv = t.low[v];
                    t.low.insert(v, lv.min(lw));
                } else if t.on.contains(w) {
                    let iw = t.index[w];
                    let lv = t.low[v];
                    t.low.insert(v, lv.min(iw));
                }
            }
        }
        if t.low[v] == t.index[v] {
            let mut comp = Vec::new();
            while let Some(w) = t.stack.pop() {
                t.on.remove(w);
                comp.push(w.to_string());
                if w == v {
                    break;
                }
            }
            if comp.len() > 1 {
                comp.sort();
                t.out.push(comp);
            }
        }
    }
    let mut t = T {
        g,
        index: BTreeMap::new(),
        low: BTreeMap::new(),
        stack: Vec::new(),
        on: BTreeSet::new(),
        out: Vec::new(),
    };
    for v in g.keys() {
        if !t.index.contains_key(v.as_str()) {
            visit(&mut t, v);
        }
    }
    t.out
}

fn workspace() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR"))
        .parent()
        .unwrap()
        .to_path_buf()
}

#[test]
fn no_import_circle_spans_more_than_three_files() {
    let mut report = Vec::new();
    for krate in [
        "protocol",
        "robot-firmware",
        "emulator",
        "station-core",
        "station",
        "world-model",
    ] {
        let g = graph(&workspace().join(krate).join("src"));
        for c in circles(&g) {
            if c.len() > 3 {
                report.push(format!("{krate}: {} modules: {}", c.len(), c.join(", ")));
            }
        }
    }
    assert!(report.is_empty(), "import circles:\n{}", report.join("\n"));
}

/// The station crate's layers, lowest first (the core is its own crate, below them all).
fn station_layer(module: &str) -> usize {
    let top = module.split("::").next().unwrap_or("");
    match top {
        "action" | "app" => 0,
        "ui" => 1,
        "replay" if module == "replay::screen" => 1,
        _ => 2,
    }
}

const STATION_LAYERS: [&str; 3] = [
    "the application (action, app)",
    "the views (ui, replay::screen)",
    "the terminal loop and the commands",
];

fn layer_violations() -> Vec<String> {
    let g = graph(&workspace().join("station").join("src"));
    upward(&g, station_layer, &STATION_LAYERS)
}

#[test]
fn the_stations_layers_import_only_from_below() {
    let v = layer_violations();
    assert!(
        v.is_empty(),
        "imports from a layer above:\n{}",
        v.join("\n")
    );
}

/// The emulator's parts, lowest first: the world (arenas, physics, sensors, the UART, `Sim`,
/// fleets, the pty loop: every module not named below), the papers' scenarios on top of it,
/// and the command line on top of both.
fn emulator_layer(module: &str) -> usize {
    match module.split("::").next().unwrap_or("") {
        "scenarios" => 1,
        "cli" => 2,
        _ => 0,
    }
}

const EMULATOR_LAYERS: [&str; 3] = [
    "the world",
    "the scenarios (scenarios::...)",
    "the command line (cli::...)",
];

/// Imports from a layer above, in `krate`'s graph `g`, by the layering `layer`.
fn upward(
    g: &BTreeMap<String, BTreeSet<String>>,
    layer: fn(&str) -> usize,
    names: &[&str],
) -> Vec<String> {
    let mut out = Vec::new();
    for (m, deps) in g {
        if m.is_empty() {
            continue;
        }
        for d in deps {
            let (lm, ld) = (layer(m), layer(d));
            if ld > lm {
                out.push(format!("{m} ({}) imports {d} ({})", names[lm], names[ld]));
            }
        }
    }
    out
}

fn emulator_violations() -> Vec<String> {
    let g = graph(&workspace().join("emulator").join("src"));
    upward(&g, emulator_layer, &EMULATOR_LAYERS)
}

#[test]
fn the_emulators_world_never_imports_its_scenarios_or_its_command_line() {
    let v = emulator_violations();
    assert!(
        v.is_empty(),
        "imports from a layer above:\n{}",
        v.join("\n")
    );
}

/// The check can fail: a world module's import of a scenario or of the command line, in any
/// of the forms code writes it, is an import from a layer above.
#[test]
fn an_upward_import_is_seen() {
    let src = workspace().join("emulator").join("src");
    let mods = modules(&src);
    let aliases = root_aliases(&mods);
    let physics = std::fs::read_to_string(src.join("physics.rs")).unwrap();
    for (added, module) in [
        ("use crate::scenarios::task::Task;", "scenarios::task"),
        (
            "use crate::{geometry::Point, scenarios::contest};",
            "scenarios::contest",
        ),
        ("fn f() { crate::cli::parse_pose(\"1,2\").ok(); }", "cli"),
        ("use super::scenarios::bench as b;", "scenarios::bench"),
    ] {
        let text = format!("{added}\n{physics}");
        let mut g = graph(&src);
        g.insert(
            "physics".to_string(),
            imports_of("physics", &text, &mods, &aliases),
        );
        let v: Vec<String> = upward(&g, emulator_layer, &EMULATOR_LAYERS)
            .into_iter()
            .filter(|l| l.starts_with("physics "))
            .collect();
        assert_eq!(v.len(), 1, "{added}: {v:?}");
        assert!(
            v[0].starts_with(&format!("physics (the world) imports {module} (")),
            "{v:?}"
        );
    }
    // A module the root re-exports is followed to where it lives.
    let mut mods = mods;
    mods.insert(String::new(), src.join("lib.rs"));
    let aliases: BTreeMap<String, String> =
        [("task".to_string(), "scenarios::task".to_string())].into();
    let edges = imports_of("physics", "use crate::task::Task;", &mods, &aliases);
    assert_eq!(edges, BTreeSet::from(["scenarios::task".to_string()]));
}

#[cfg(not(test))]
fn main() {
    for v in layer_violations() {
        println!("station layer: {v}");
    }
    for v in emulator_violations() {
        println!("emulator layer: {v}");
    }
    for krate in std::env::args().skip(1) {
        let g = graph(&Path::new(&krate).join("src"));
        for c in circles(&g) {
            println!("{krate}: {} {:?}", c.len(), c);
        }
    }
}
