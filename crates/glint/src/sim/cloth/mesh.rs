//! The cloth's mesh: nodes and triangles, from a procedural sheet, an OBJ file or
//! the plain-text `*Nodes` / `*Triangles` format of published DEP benchmarks;
//! and its topology: unique edges and the hinges of interior edges.

use crate::asset::{Diagnostic, MAX_MODEL_BYTES};
use glam::DVec3;
use std::collections::HashMap;
use std::path::Path;

/// Nodes (rest positions, metres) and triangles (node indices) of a cloth.
#[derive(Clone, Debug, PartialEq)]
pub struct ClothMesh {
    /// Rest positions.
    pub nodes: Vec<DVec3>,
    /// Triangles as indices into `nodes`.
    pub triangles: Vec<[u32; 3]>,
}

/// Edges and hinges of a [`ClothMesh`].
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Topology {
    /// Unique triangle edges, lower index first.
    pub edges: Vec<[u32; 2]>,
    /// Interior edges with their opposite nodes: [x₀, x₁, x₂, x₃], x₂ in the
    /// first triangle (x₀, x₁, x₂ in its winding order) and x₃ in the second.
    pub hinges: Vec<[u32; 4]>,
}

/// Why a mesh cannot be simulated.
#[derive(Debug, thiserror::Error, PartialEq)]
pub enum ClothMeshError {
    /// A triangle names a node past the end.
    #[error("triangle {triangle} names node {node}, but there are {nodes} nodes")]
    NodeOutOfRange {
        /// Triangle index.
        triangle: usize,
        /// The bad node index (0-based).
        node: u32,
        /// Node count.
        nodes: usize,
    },
    /// A triangle with a repeated node or no area.
    #[error("triangle {0} is degenerate (a repeated node or no area)")]
    Degenerate(usize),
    /// An edge shared by more than two triangles (the third is the last number).
    #[error("edge {0}-{1} is shared by more than two triangles")]
    NonManifold(u32, u32, usize),
    /// No triangles at all.
    #[error("the mesh has no triangles")]
    Empty,
    /// The cloth's sparse linear system would take more memory than glint allows
    /// (see `MAX_SYSTEM_BYTES`), checked before it is allocated.
    #[error(
        "a cloth of {nodes} nodes is too large: its linear system would take about {} MiB, more than the {} MiB glint allows",
        bytes.div_ceil(1 << 20),
        max >> 20
    )]
    TooLarge {
        /// Nodes of the mesh.
        nodes: usize,
        /// Estimated bytes of its system.
        bytes: u64,
        /// The limit.
        max: u64,
    },
    /// A position is NaN or infinite.
    #[error("node {0} is not a finite position")]
    NotFinite(usize),
}

impl ClothMeshError {
    /// The line of a file that holds what is wrong: `triangle_lines` and
    /// `node_lines` give each triangle's and node's line, as read.
    fn line(&self, node_lines: &[usize], triangle_lines: &[usize]) -> Option<usize> {
        match *self {
            Self::NodeOutOfRange { triangle, .. } | Self::Degenerate(triangle) | Self::NonManifold(_, _, triangle) => {
                triangle_lines.get(triangle).copied()
            }
            Self::NotFinite(node) => node_lines.get(node).copied(),
            Self::Empty | Self::TooLarge { .. } => None,
        }
    }
}

/// Where each node and triangle of a mesh file was read, for errors found after reading.
#[derive(Default)]
struct Lines {
    nodes: Vec<usize>,
    triangles: Vec<usize>,
}

impl ClothMesh {
    /// A mesh from nodes and triangles, checked: indices in range, no
    /// degenerate triangle, no edge in more than two triangles, finite positions.
    pub fn new(nodes: Vec<DVec3>, triangles: Vec<[u32; 3]>) -> Result<Self, ClothMeshError> {
        let mesh = Self { nodes, triangles };
        mesh.topology()?;
        Ok(mesh)
    }

    /// A `width` × `height` sheet in the XY plane (corner at the origin) of
    /// `nx` × `ny` nodes (each at least 2), every quad split into two triangles
    /// with diagonals alternating so the sheet has no preferred direction.
    pub fn sheet(width: f64, height: f64, nx: u32, ny: u32) -> Self {
        let (nx, ny) = (nx.max(2), ny.max(2));
        let nodes = (0..ny)
            .flat_map(|j| {
                (0..nx).map(move |i| {
                    DVec3::new(width * f64::from(i) / f64::from(nx - 1), height * f64::from(j) / f64::from(ny - 1), 0.0)
                })
            })
            .collect();
        let mut triangles = Vec::with_capacity(2 * ((nx - 1) * (ny - 1)) as usize);
        for j in 0..ny - 1 {
            for i in 0..nx - 1 {
                let (a, b, c, d) = (j * nx + i, j * nx + i + 1, (j + 1) * nx + i + 1, (j + 1) * nx + i);
                if (i + j) % 2 == 0 {
                    triangles.extend([[a, b, c], [a, c, d]]);
                } else {
                    triangles.extend([[a, b, d], [b, c, d]]);
                }
            }
        }
        Self { nodes, triangles }
    }

    /// Read a mesh: `.obj` through tobj (positions and faces, triangulated; other
    /// data ignored), anything else as the `*Nodes` / `*Triangles` text format.
    pub fn load(path: &Path) -> Result<Self, Diagnostic> {
        Self::read(path, &crate::asset::Files::Disk)
    }

    /// [`ClothMesh::load`] from `files`. Errors name the line of the node or
    /// triangle at fault, and never quote the file.
    pub fn read(path: &Path, files: &crate::asset::Files) -> Result<Self, Diagnostic> {
        let bytes = files.read(path, MAX_MODEL_BYTES)?;
        let text = std::str::from_utf8(&bytes).map_err(|e| Diagnostic::file(path, format!("not UTF-8 text: {e}")))?;
        let (mesh, lines) = if path.extension().is_some_and(|e| e.eq_ignore_ascii_case("obj")) {
            Self::parse_obj(path, text)?
        } else {
            Self::parse_text(path, text)?
        };
        mesh.topology().map_err(|e| match e.line(&lines.nodes, &lines.triangles) {
            Some(line) => Diagnostic::at(path, line, e.to_string()),
            None => Diagnostic::file(path, e.to_string()),
        })?;
        Ok(mesh)
    }

    /// Positions and faces of an OBJ, triangulated as fans (other data
    /// ignored). `v` and `f` lines are checked first, so that every problem
    /// tobj would report without a line has one.
    fn parse_obj(path: &Path, text: &str) -> Result<(Self, Lines), Diagnostic> {
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
        let mut mesh = Self { nodes: Vec::new(), triangles: Vec::new() };
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

    /// Parse the text format of published DEP benchmarks: a `*Nodes` section of
    /// `x,y,z` lines (node ids implicit, 1-based, in file order) and a
    /// `*Triangles` section of `i,j,k` lines (1-based node ids). Headers are
    /// case-insensitive; `#` comment lines and blank lines are skipped.
    pub fn parse_nodes_triangles(path: &Path, text: &str) -> Result<Self, Diagnostic> {
        Self::parse_text(path, text).map(|(mesh, _)| mesh)
    }

    /// [`ClothMesh::parse_nodes_triangles`], with each node's and triangle's line.
    fn parse_text(path: &Path, text: &str) -> Result<(Self, Lines), Diagnostic> {
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
        Ok((Self { nodes, triangles: triangles.into_iter().map(|(t, _)| t).collect() }, lines))
    }

    /// Unique edges and the hinges of edges shared by two triangles.
    pub fn topology(&self) -> Result<Topology, ClothMeshError> {
        if self.triangles.is_empty() {
            return Err(ClothMeshError::Empty);
        }
        if let Some(i) = self.nodes.iter().position(|p| !p.is_finite()) {
            return Err(ClothMeshError::NotFinite(i));
        }
        // Each edge's triangles, as (opposite node, whether the edge runs low→high in it).
        let mut faces: HashMap<[u32; 2], Vec<(u32, bool)>> = HashMap::with_capacity(self.triangles.len() * 3 / 2);
        let mut order = Vec::with_capacity(self.triangles.len() * 3 / 2);
        for (t, tri) in self.triangles.iter().enumerate() {
            if let Some(&node) = tri.iter().find(|&&v| v as usize >= self.nodes.len()) {
                return Err(ClothMeshError::NodeOutOfRange { triangle: t, node, nodes: self.nodes.len() });
            }
            let [a, b, c] = tri.map(|v| self.nodes[v as usize]);
            if (b - a).cross(c - a).length_squared() <= f64::MIN_POSITIVE {
                return Err(ClothMeshError::Degenerate(t));
            }
            for k in 0..3 {
                let (u, v, w) = (tri[k], tri[(k + 1) % 3], tri[(k + 2) % 3]);
                let key = [u.min(v), u.max(v)];
                let list = faces.entry(key).or_insert_with(|| {
                    order.push(key);
                    Vec::new()
                });
                if list.len() == 2 {
                    return Err(ClothMeshError::NonManifold(key[0], key[1], t));
                }
                list.push((w, u < v));
            }
        }
        let mut topology = Topology { edges: order.clone(), hinges: Vec::new() };
        for key in order {
            if let [(x2, forward), (x3, _)] = faces[&key][..] {
                // x₀ → x₁ in the first triangle's winding, so x₂ is on its left.
                let [x0, x1] = if forward { key } else { [key[1], key[0]] };
                topology.hinges.push([x0, x1, x2, x3]);
            }
        }
        Ok(topology)
    }
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
    fn sheet_edges_and_hinges_are_counted_right() {
        let mesh = ClothMesh::sheet(1.0, 2.0, 4, 3);
        assert_eq!((mesh.nodes.len(), mesh.triangles.len()), (12, 12));
        let topology = mesh.topology().unwrap();
        // Edges: 3·3 horizontal + 4·2 vertical + 6 diagonals; interior ones all but the 10 on the border.
        assert_eq!(topology.edges.len(), 9 + 8 + 6);
        assert_eq!(topology.hinges.len(), 23 - 10);
        for h in &topology.hinges {
            let x: [DVec3; 4] = h.map(|i| mesh.nodes[i as usize]);
            assert_eq!(super::super::energy::hinge_angle(&x), 0.0, "flat sheet");
            // x₂ left of x₀→x₁ and x₃ right of it, seen from +Z.
            let e = x[1] - x[0];
            assert!(e.cross(x[2] - x[0]).z > 0.0 && e.cross(x[3] - x[0]).z < 0.0, "{h:?}");
        }
    }

    #[test]
    fn the_text_format_reads_and_reports_lines() {
        let path = Path::new("plate.txt");
        let text = "# a plate\n*Nodes\n0,0,0\n1, 0, 0\n\n0,1,0\n*TRIANGLES\n1,2,3\n";
        let mesh = ClothMesh::parse_nodes_triangles(path, text).unwrap();
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
            let err = ClothMesh::parse_nodes_triangles(path, text).unwrap_err().to_string();
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
            ClothMesh::load(&path).map(|_| ()).unwrap_err()
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

    #[test]
    fn bad_meshes_are_errors() {
        let nodes = vec![DVec3::ZERO, DVec3::X, DVec3::Y, DVec3::new(1.0, 1.0, 0.0), DVec3::Z];
        assert_eq!(ClothMesh::new(nodes.clone(), vec![]), Err(ClothMeshError::Empty));
        assert_eq!(ClothMesh::new(nodes.clone(), vec![[0, 1, 1]]), Err(ClothMeshError::Degenerate(0)));
        assert!(matches!(ClothMesh::new(nodes.clone(), vec![[0, 1, 9]]), Err(ClothMeshError::NodeOutOfRange { .. })));
        let fan = vec![[0, 1, 2], [1, 0, 3], [0, 1, 4]];
        assert_eq!(ClothMesh::new(nodes, fan), Err(ClothMeshError::NonManifold(0, 1, 2)));
    }
}
