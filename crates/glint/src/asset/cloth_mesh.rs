//! Cloth meshes read from files ([`read_cloth_mesh`]): an OBJ or the
//! plain-text `*Nodes` / `*Triangles` format of published DEP benchmarks, into
//! a [`ClothMesh`], with errors at the line of the node or triangle at fault.

use super::{Diagnostic, Files, MAX_MODEL_BYTES};
use crate::scene::cloth::{ClothMesh, ClothMeshError};
use glam::DVec3;
use std::path::Path;

/// Where each node and triangle of a mesh file was read, for errors found after reading.
#[derive(Default)]
struct Lines {
    nodes: Vec<usize>,
    triangles: Vec<usize>,
}

/// The line of a file that holds what `error` finds wrong, where `lines` says
/// where each node and triangle was read.
fn error_line(error: &ClothMeshError, lines: &Lines) -> Option<usize> {
    match *error {
        ClothMeshError::NodeOutOfRange { triangle, .. }
        | ClothMeshError::Degenerate(triangle)
        | ClothMeshError::NonManifold(_, _, triangle) => lines.triangles.get(triangle).copied(),
        ClothMeshError::NotFinite(node) | ClothMeshError::OutOfRange(node) => lines.nodes.get(node).copied(),
        ClothMeshError::Empty | ClothMeshError::TooLarge { .. } => None,
    }
}

/// Read a cloth mesh from disk: `.obj` through tobj (positions and faces,
/// triangulated; other data ignored), anything else as the `*Nodes` /
/// `*Triangles` text format.
pub fn load_cloth_mesh(path: &Path) -> Result<ClothMesh, Diagnostic> {
    read_cloth_mesh(path, &Files::Disk)
}

/// [`load_cloth_mesh`] from `files`. Errors name the line of the node or
/// triangle at fault, and never quote the file.
pub fn read_cloth_mesh(path: &Path, files: &Files) -> Result<ClothMesh, Diagnostic> {
    let bytes = files.read(path, MAX_MODEL_BYTES)?;
    let text = std::str::from_utf8(&bytes).map_err(|e| Diagnostic::file(path, format!("not UTF-8 text: {e}")))?;
    let (mesh, lines) = if path.extension().is_some_and(|e| e.eq_ignore_ascii_case("obj")) {
        parse_obj(path, text)?
    } else {
        parse_text(path, text)?
    };
    mesh.topology().map_err(|e| match error_line(&e, &lines) {
        Some(line) => Diagnostic::at(path, line, e.to_string()),
        None => Diagnostic::file(path, e.to_string()),
    })?;
    Ok(mesh)
}

/// Parse the text format of published DEP benchmarks: a `*Nodes` section of
/// `x,y,z` lines (node ids implicit, 1-based, in file order) and a
/// `*Triangles` section of `i,j,k` lines (1-based node ids). Headers are
/// case-insensitive; `#` comment lines and blank lines are skipped.
pub fn parse_nodes_triangles(path: &Path, text: &str) -> Result<ClothMesh, Diagnostic> {
    parse_text(path, text).map(|(mesh, _)| mesh)
}

/// Positions and faces of an OBJ, triangulated as fans (other data
/// ignored). `v` and `f` lines are checked first, so that every problem
/// tobj would report without a line has one.
fn parse_obj(path: &Path, text: &str) -> Result<(ClothMesh, Lines), Diagnostic> {
    let mut lines = Lines::default();
    for (k, raw) in text.lines().enumerate() {
        let at = |m: &str| Diagnostic::at(path, k + 1, m);
        let mut words = raw.split_whitespace();
        match words.next() {
            Some("v") => {
                let xyz: Vec<Option<f64>> = words.take(3).map(|w| w.parse::<f64>().ok()).collect();
                if xyz.len() < 3 || xyz.iter().any(|v| !v.is_some_and(f64::is_finite)) {
                    return Err(at("expected a vertex of three finite numbers: v x y z"));
                }
                lines.nodes.push(k + 1);
            }
            Some("f") => {
                let corners: Vec<&str> = words.collect();
                let valid = |c: &&str| {
                    let index = c.split('/').next().and_then(|i| i.parse::<i64>().ok());
                    let count = lines.nodes.len() as i64;
                    index.is_some_and(|i| (1..=count).contains(&i) || (-count..=-1).contains(&i))
                };
                if corners.len() < 3 || !corners.iter().all(valid) {
                    return Err(at("expected a face of three or more vertex numbers of vertices read so far"));
                }
                lines.triangles.extend(std::iter::repeat_n(k + 1, corners.len() - 2));
            }
            _ => {}
        }
    }
    let options = tobj::LoadOptions { triangulate: true, ..Default::default() };
    let bytes = text.as_bytes();
    let (models, _) =
        tobj::load_obj_buf(&mut std::io::Cursor::new(bytes), &options, |_| Err(tobj::LoadError::OpenFileFailed))
            .map_err(|e| Diagnostic::file(path, format!("cannot read OBJ: {e}")))?;
    let mut mesh = ClothMesh { nodes: Vec::new(), triangles: Vec::new() };
    for model in models {
        let first = u32::try_from(mesh.nodes.len()).map_err(|_| Diagnostic::file(path, "too many nodes"))?;
        let m = &model.mesh;
        mesh.nodes.extend(m.positions.chunks_exact(3).map(|p| DVec3::new(p[0].into(), p[1].into(), p[2].into())));
        mesh.triangles.extend(m.indices.chunks_exact(3).map(|t| [first + t[0], first + t[1], first + t[2]]));
    }
    if mesh.triangles.len() != lines.triangles.len() {
        lines.triangles.clear(); // tobj ordered the faces its own way: no lines to give
    }
    Ok((mesh, lines))
}

/// [`parse_nodes_triangles`], with each node's and triangle's line.
fn parse_text(path: &Path, text: &str) -> Result<(ClothMesh, Lines), Diagnostic> {
    #[derive(PartialEq)]
    enum Section {
        None,
        Nodes,
        Triangles,
    }
    let mut section = Section::None;
    let mut nodes = Vec::new();
    let mut lines = Lines::default();
    let mut triangles: Vec<([u32; 3], usize)> = Vec::new();
    for (i, raw) in text.lines().enumerate() {
        let line = i + 1;
        let content = raw.trim();
        if content.is_empty() || content.starts_with('#') {
            continue;
        }
        if let Some(header) = content.strip_prefix('*') {
            section = match header.trim().to_ascii_lowercase().as_str() {
                "nodes" => Section::Nodes,
                "triangles" => Section::Triangles,
                _ => {
                    return Err(Diagnostic::at(path, line, "unknown section, expected *Nodes or *Triangles"));
                }
            };
            continue;
        }
        let fields: Vec<&str> = content.split(',').map(str::trim).collect();
        match section {
            Section::None => {
                return Err(Diagnostic::at(path, line, "data before any section: expected a *Nodes header first"))
            }
            Section::Nodes => {
                let xyz = numbers::<f64>(&fields, "x,y,z", |v: &f64| v.is_finite())
                    .map_err(|m| Diagnostic::at(path, line, m))?;
                nodes.push(DVec3::from(xyz));
                lines.nodes.push(line);
            }
            Section::Triangles => {
                let ids = numbers::<u32>(&fields, "i,j,k (1-based node ids)", |&v| v >= 1)
                    .map_err(|m| Diagnostic::at(path, line, m))?;
                triangles.push((ids.map(|v| v - 1), line));
            }
        }
    }
    if nodes.is_empty() {
        return Err(Diagnostic::file(path, "no nodes: expected a *Nodes section of x,y,z lines"));
    }
    if triangles.is_empty() {
        return Err(Diagnostic::file(path, "no triangles: expected a *Triangles section of i,j,k lines"));
    }
    for (ids, line) in &triangles {
        if let Some(bad) = ids.iter().find(|&&v| v as usize >= nodes.len()) {
            let message = format!("node {} does not exist (there are {} nodes)", bad + 1, nodes.len());
            return Err(Diagnostic::at(path, *line, message));
        }
    }
    lines.triangles = triangles.iter().map(|(_, line)| *line).collect();
    Ok((ClothMesh { nodes, triangles: triangles.into_iter().map(|(t, _)| t).collect() }, lines))
}

/// Exactly three comma-separated values of `T`, each passing `ok`.
fn numbers<T: std::str::FromStr + Copy + Default>(
    fields: &[&str],
    what: &str,
    ok: impl Fn(&T) -> bool,
) -> Result<[T; 3], String> {
    if fields.len() != 3 {
        return Err(format!("found {} values, expected {what}", fields.len()));
    }
    let mut out = [T::default(); 3];
    for (k, (slot, field)) in out.iter_mut().zip(fields).enumerate() {
        // The value itself is not quoted: messages never echo a file's bytes.
        *slot = field
            .parse::<T>()
            .ok()
            .filter(|v| ok(v))
            .ok_or_else(|| format!("value {} of 3 is bad, expected {what}", k + 1))?;
    }
    Ok(out)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_text_format_reads_and_reports_lines() {
        let path = Path::new("plate.txt");
        let text = "# a plate\n*Nodes\n0,0,0\n1, 0, 0\n\n0,1,0\n*TRIANGLES\n1,2,3\n";
        let mesh = parse_nodes_triangles(path, text).unwrap();
        assert_eq!(mesh.nodes[1], DVec3::X);
        assert_eq!(mesh.triangles, [[0, 1, 2]]);
        for (text, expected) in [
            ("0,0,0\n", "plate.txt:1: data before any section"),
            ("*Nodes\n0,0\n", "plate.txt:2: found 2 values, expected x,y,z"),
            ("*Nodes\n0,x,0\n", "plate.txt:2: value 2 of 3 is bad, expected x,y,z"),
            ("*Nodes\n0,inf,0\n", "plate.txt:2: value 2 of 3 is bad"),
            ("*Edges\n", "plate.txt:1: unknown section, expected *Nodes or *Triangles"),
            (
                "*Nodes\n0,0,0\n1,0,0\n0,1,0\n*Triangles\n1,2,4\n",
                "plate.txt:6: node 4 does not exist (there are 3 nodes)",
            ),
            ("*Nodes\n0,0,0\n*Triangles\n0,1,1\n", "plate.txt:4: value 1 of 3 is bad, expected i,j,k"),
            ("*Nodes\n0,0,0\n", "plate.txt: no triangles"),
        ] {
            let err = parse_nodes_triangles(path, text).unwrap_err().to_string();
            assert!(err.starts_with(expected), "{text:?}: {err}");
        }
    }

    #[test]
    fn obj_and_topology_errors_name_their_line() {
        let dir = std::env::temp_dir().join(format!("glint-cloth-obj-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let read = |name: &str, text: &str| {
            let path = dir.join(name);
            std::fs::write(&path, text).unwrap();
            load_cloth_mesh(&path).map(|_| ()).unwrap_err()
        };
        let square = "v 0 0 0\nv 1 0 0\nv 0 1 0\nv 1 1 0\n";
        for (text, line, expected) in [
            (format!("{square}f 1 2 3\nf 2 4 9\n"), 6, "expected a face of three or more vertex numbers"),
            (format!("{square}v nan 0 0\n"), 5, "expected a vertex of three finite numbers"),
            (format!("{square}f 1 2 3\nf 1 2 2\n"), 6, "is degenerate"),
            (format!("{square}v 0 -1 0\nf 1 2 3\nf 2 1 4\nf 1 2 5\n"), 8, "shared by more than two triangles"),
        ] {
            let err = read("m.obj", &text);
            assert_eq!(err.line, Some(line), "{text:?}: {err}");
            assert!(err.message.contains(expected), "{text:?}: {err}");
        }
        let err = read("m.txt", "*Nodes\n0,0,0\n1,0,0\n0,1,0\n*Triangles\n1,2,3\n2,1,3\n1,3,2\n");
        assert_eq!(err.line, Some(8), "the third triangle on edge 1-2: {err}");
        std::fs::remove_dir_all(&dir).unwrap();
    }
}
