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

use std::collections::BTreeSet;
use std::path::Path;

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

fn files(dir: &Path, out: &mut Vec<std::path::PathBuf>) {
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
