//! The layers of `DESIGN.md`, read from glint's sources: each module of
//! `crates/glint/src` names (`crate::…`, also through the crate root's
//! re-exports) only modules in rows below its own, or its own row's where the
//! row allows it:
//!
//! | row | modules | may use |
//! | --- | --- | --- |
//! | 3 | `world`, `compare` | everything below |
//! | 2 | `asset`, `sim`, `render` | rows 0 and 1 (not each other) |
//! | 1 | `gpu`, `shader` | row 0 and each other |
//! | 0 | `scene`, `text` | row 0 |
//!
//! No file crosses the table (the last crossings, asset ↔ sim over the
//! simulations' parameters and the cloth mesh's file reading, went in issue 46).
//!
//! Inside `render/`, no two files import each other, even through others:
//! each file's `crate::render::…` paths (in `use` trees and in code, tests
//! left out) point at the files that define what they name, and following
//! those arrows never leads back to where it started. So the rooms
//! (`frame/`, `passes/`, `gpu_driven/`, `resources/`, `debug/`) stack: a
//! reader can take each file with only the ones below it in mind. Paths
//! name the defining module (`crate::render::error::RenderError`, not the
//! re-export `crate::render::RenderError`): a `mod.rs` that only declares and
//! re-exports has no arrows of its own.

use std::collections::{BTreeMap, BTreeSet};
use std::path::{Path, PathBuf};

/// Each module's row, and whether it may use the other modules of its row.
const ROWS: [(&str, u8, bool); 9] = [
    ("scene", 0, true),
    ("text", 0, true),
    ("gpu", 1, true),
    ("shader", 1, true),
    ("asset", 2, false),
    ("sim", 2, false),
    ("render", 2, false),
    ("world", 3, false),
    ("compare", 3, false),
];

/// The crate root's re-exports and items, by the module they come from
/// (`Error` gathers every module's errors: it stands with `world`).
const ROOT: [(&str, &str); 9] = [
    ("Diagnostic", "asset"),
    ("Texture", "asset"),
    ("Gpu", "gpu"),
    ("GpuError", "gpu"),
    ("OffscreenTarget", "gpu"),
    ("WindowSurface", "gpu"),
    ("World", "world"),
    ("Error", "world"),
    ("FrameStats", "render"),
];

fn row(module: &str) -> Option<(u8, bool)> {
    ROWS.iter().find(|(m, ..)| *m == module).map(|&(_, r, same)| (r, same))
}

/// Whether a file of `from` may name `to`.
fn allowed(from: &str, to: &str) -> bool {
    match (row(from), row(to)) {
        (Some((a, same)), Some((b, _))) => from == to || b < a || (a == b && same),
        _ => true,
    }
}

/// The modules the code of `text` names through `crate::` (comments left out).
fn named(text: &str) -> BTreeSet<String> {
    let mut out = BTreeSet::new();
    let code: Vec<&str> = text.lines().map(|line| line.split("//").next().unwrap_or("")).collect();
    let code = code.join("\n");
    {
        let mut rest = code.as_str();
        while let Some(at) = rest.find("crate::") {
            let tail = &rest[at + "crate::".len()..];
            if let Some(group) = tail.strip_prefix('{') {
                let end = group.find('}').unwrap_or(group.len());
                for name in group[..end].split(',').map(|n| n.trim().split("::").next().unwrap_or("")) {
                    out.extend(module_of(name));
                }
            } else {
                let name: String = tail.chars().take_while(|c| c.is_alphanumeric() || *c == '_').collect();
                out.extend(module_of(&name));
            }
            rest = tail;
        }
    }
    out
}

/// The module `name` (after `crate::`) belongs to.
fn module_of(name: &str) -> Option<String> {
    if row(name).is_some() {
        return Some(name.to_string());
    }
    if let Some(&(_, module)) = ROOT.iter().find(|(n, _)| *n == name) {
        return Some(module.to_string());
    }
    // The root's `pub use render::{…}` and `pub use scene::{…}` lists.
    let render = ["FrameMode", "RenderError", "Renderer", "Shadows"];
    if render.contains(&name) {
        return Some("render".into());
    }
    (!name.is_empty() && name.chars().next().is_some_and(char::is_uppercase)).then(|| "scene".into())
}

fn files(dir: &Path, out: &mut Vec<PathBuf>) {
    for entry in std::fs::read_dir(dir).expect("read src") {
        let path = entry.expect("entry").path();
        if path.is_dir() {
            files(&path, out);
        } else if path.extension().is_some_and(|e| e == "rs") {
            out.push(path);
        }
    }
}

#[test]
fn no_module_names_one_its_row_may_not_use() {
    let src = Path::new(env!("CARGO_MANIFEST_DIR")).join("src");
    let mut all = Vec::new();
    files(&src, &mut all);
    let mut found = BTreeSet::new();
    for path in &all {
        let relative = path.strip_prefix(&src).expect("under src").to_string_lossy().replace('\\', "/");
        let module = relative.split(['/', '.']).next().expect("a name").to_string();
        let text = std::fs::read_to_string(path).expect("read");
        for to in named(&text).into_iter().filter(|to| !allowed(&module, to)) {
            found.insert((relative.clone(), to));
        }
    }
    assert!(found.is_empty(), "files naming a module their row may not use (DESIGN.md's layers): {found:?}");
}

#[test]
fn the_reader_finds_crossings_and_lets_the_rows_below_through() {
    let text = "use crate::render::Renderer;\nuse crate::{\n    FrameStats,\n    Mesh, // crate::world in a comment\n    World,\n};\n";
    let names: Vec<String> = named(text).into_iter().collect();
    assert_eq!(names, ["render", "scene", "world"]);
    assert!(!allowed("sim", "render") && !allowed("scene", "gpu") && !allowed("asset", "sim"));
    assert!(allowed("render", "gpu") && allowed("gpu", "shader") && allowed("world", "render"));
}

/// The code of `text` before its first `#[cfg(test)]`, comments left out.
fn code(text: &str) -> String {
    let text = text.split("#[cfg(test)]").next().unwrap_or("");
    let lines: Vec<&str> = text.lines().map(|line| line.split("//").next().unwrap_or("")).collect();
    lines.join("\n")
}

/// Every path a `crate::render::` tree in `code` spells out, as segments
/// after `render` (`{a::B, c::{D, E}}` gives `a::B`, `c::D`, `c::E`).
fn paths(code: &str) -> Vec<Vec<String>> {
    let mut out = Vec::new();
    let mut rest = code;
    while let Some(at) = rest.find("crate::render::") {
        rest = &rest[at + "crate::render::".len()..];
        let (tree, _) = read_tree(rest);
        expand(&tree, &mut Vec::new(), &mut out);
    }
    out
}

/// A use tree: a segment with what follows it.
#[derive(Debug)]
enum Tree {
    Path(String, Option<Box<Tree>>),
    Group(Vec<Tree>),
}

/// The tree at the start of `text`, and what follows it.
fn read_tree(text: &str) -> (Tree, &str) {
    let text = text.trim_start();
    if let Some(inner) = text.strip_prefix('{') {
        let mut items = Vec::new();
        let mut rest = inner;
        loop {
            rest = rest.trim_start();
            if let Some(after) = rest.strip_prefix('}') {
                return (Tree::Group(items), after);
            }
            if rest.is_empty() {
                return (Tree::Group(items), rest);
            }
            let (item, after) = read_tree(rest);
            items.push(item);
            rest = after.trim_start().strip_prefix(',').unwrap_or(after);
        }
    }
    let name: String = text.chars().take_while(|c| c.is_alphanumeric() || *c == '_').collect();
    let after = &text[name.len()..];
    match after.strip_prefix("::") {
        Some(next) if next.starts_with(|c: char| c == '{' || c.is_alphabetic() || c == '_') => {
            let (tail, rest) = read_tree(next);
            (Tree::Path(name, Some(Box::new(tail))), rest)
        }
        _ => (Tree::Path(name, None), after),
    }
}

fn expand(tree: &Tree, prefix: &mut Vec<String>, out: &mut Vec<Vec<String>>) {
    match tree {
        Tree::Group(items) => items.iter().for_each(|t| expand(t, prefix, out)),
        Tree::Path(name, tail) => {
            prefix.push(name.clone());
            match tail {
                Some(tail) => expand(tail, prefix, out),
                None => out.push(prefix.clone()),
            }
            prefix.pop();
        }
    }
}

/// The file a path after `crate::render::` leads into: the deepest module
/// file its segments walk through (a folder's `mod.rs` where it stops at one).
fn target(render: &Path, path: &[String]) -> Option<PathBuf> {
    let mut dir = render.to_path_buf();
    for segment in path {
        if segment == "self" {
            break;
        }
        let file = dir.join(format!("{segment}.rs"));
        if file.is_file() {
            return Some(file);
        }
        let folder = dir.join(segment);
        if !folder.join("mod.rs").is_file() {
            break;
        }
        dir = folder;
    }
    Some(dir.join("mod.rs"))
}

/// Each file of `render` (relative to it) with the files it imports.
fn arrows(render: &Path) -> BTreeMap<String, BTreeSet<String>> {
    let mut all = Vec::new();
    files(render, &mut all);
    let name = |p: &Path| p.strip_prefix(render).expect("under render").to_string_lossy().replace('\\', "/");
    let mut graph = BTreeMap::new();
    for path in &all {
        let text = std::fs::read_to_string(path).expect("read");
        let to: BTreeSet<String> = (paths(&code(&text)).iter())
            .filter_map(|p| target(render, p))
            .map(|t| name(&t))
            .filter(|t| *t != name(path))
            .collect();
        graph.insert(name(path), to);
    }
    graph
}

/// A cycle of `graph`, as the files around it, if there is one.
fn cycle(graph: &BTreeMap<String, BTreeSet<String>>) -> Option<Vec<String>> {
    // 0 unseen, 1 on the path, 2 done.
    fn visit<'a>(
        at: &'a str,
        graph: &'a BTreeMap<String, BTreeSet<String>>,
        state: &mut BTreeMap<&'a str, u8>,
        path: &mut Vec<&'a str>,
    ) -> Option<Vec<String>> {
        state.insert(at, 1);
        path.push(at);
        for next in graph.get(at).into_iter().flatten() {
            match state.get(next.as_str()).copied().unwrap_or(0) {
                1 => {
                    let from = path.iter().position(|p| *p == next).expect("on the path");
                    return Some(path[from..].iter().map(|s| s.to_string()).collect());
                }
                0 => {
                    if let Some(found) = visit(next, graph, state, path) {
                        return Some(found);
                    }
                }
                _ => {}
            }
        }
        path.pop();
        state.insert(at, 2);
        None
    }
    let mut state = BTreeMap::new();
    graph.keys().find_map(|start| match state.get(start.as_str()) {
        None => visit(start, graph, &mut state, &mut Vec::new()),
        _ => None,
    })
}

#[test]
fn no_two_files_of_render_import_each_other_even_through_others() {
    let render = Path::new(env!("CARGO_MANIFEST_DIR")).join("src/render");
    let graph = arrows(&render);
    assert!(graph.len() > 40, "render/'s files are read: {}", graph.len());
    if let Some(found) = cycle(&graph) {
        let names: Vec<String> = found.iter().map(|f| format!("{f} → {:?}", graph[f])).collect();
        panic!("an import cycle in render/: {}\n{}", found.join(" → "), names.join("\n"));
    }
}

#[test]
fn the_reader_follows_use_trees_into_files_and_finds_a_cycle() {
    let text = "use crate::render::{debug::stats::{FrameStats, Laps}, frame::state::Frame};\n\
                fn f() { crate::render::error::RenderError::Lost; } // crate::render::view::X\n\
                #[cfg(test)]\nmod tests { use crate::render::views::ViewGpu; }";
    let found: Vec<String> = paths(&code(text)).iter().map(|p| p.join("::")).collect();
    assert_eq!(
        found,
        ["debug::stats::FrameStats", "debug::stats::Laps", "frame::state::Frame", "error::RenderError::Lost"]
    );
    let render = Path::new(env!("CARGO_MANIFEST_DIR")).join("src/render");
    let file = |p: &[&str]| {
        let p: Vec<String> = p.iter().map(|s| s.to_string()).collect();
        target(&render, &p).map(|t| t.strip_prefix(&render).expect("under").to_string_lossy().replace('\\', "/"))
    };
    assert_eq!(file(&["debug", "stats", "FrameStats"]).as_deref(), Some("debug/stats.rs"));
    assert_eq!(file(&["resources", "Resources"]).as_deref(), Some("resources/mod.rs"));
    assert_eq!(file(&["Renderer"]).as_deref(), Some("mod.rs"));
    let graph: BTreeMap<String, BTreeSet<String>> = [("a", "b"), ("b", "c"), ("c", "a"), ("d", "a")]
        .iter()
        .map(|(f, t)| (f.to_string(), BTreeSet::from([t.to_string()])))
        .collect();
    assert_eq!(cycle(&graph), Some(vec!["a".into(), "b".into(), "c".into()]));
    let acyclic: BTreeMap<String, BTreeSet<String>> =
        [("a", "b"), ("b", "c")].iter().map(|(f, t)| (f.to_string(), BTreeSet::from([t.to_string()]))).collect();
    assert_eq!(cycle(&acyclic), None);
}
