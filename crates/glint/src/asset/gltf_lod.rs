//! glTF `MSFT_lod`: levels of detail an author made. A node with a mesh names
//! other nodes as its coarser levels, finest first (`extensions.MSFT_lod.ids`);
//! those nodes stay out of the scene and their meshes are drawn only as levels.
//!
//! Primitive `p` of the node's mesh takes primitive `p` of each level node's
//! mesh as its coarser level, while that primitive is a triangle list with the
//! same material, its node has the same skin and transform, and it has the
//! same vertex streams; the chain stops (with a warning) at the first that is
//! not. A level node met in the scene is skipped, with its children. A
//! primitive with morph targets keeps no given levels: the levels would not
//! follow its targets. Each level's error is measured against full detail
//! ([`with_given_levels`]); the `MSFT_screencoverage` hints are not read, since
//! the renderer chooses by projected error as it does for every mesh.

use super::model::Morph;
use crate::scene::levels::{with_given_levels, MAX_LEVELS};
use crate::scene::Mesh;
use std::collections::HashSet;

/// Each node's coarser levels, finest first (empty without `MSFT_lod`). Read
/// from the document's JSON with these few types rather than the gltf crate's
/// `extensions` feature, which keeps every unknown extension of every object
/// and adds about 20 KB to each module of the web page.
pub(super) struct NodeLevels(Vec<Vec<usize>>);

#[derive(serde::Deserialize)]
struct Document {
    #[serde(default)]
    nodes: Vec<Node>,
}

#[derive(serde::Deserialize)]
struct Node {
    #[serde(default)]
    extensions: Option<Extensions>,
}

#[derive(serde::Deserialize)]
struct Extensions {
    #[serde(rename = "MSFT_lod")]
    lod: Option<MsftLod>,
}

#[derive(serde::Deserialize)]
struct MsftLod {
    ids: Vec<usize>,
}

impl NodeLevels {
    /// The levels `bytes` (a `.gltf`'s JSON or a `.glb`) names: each id must
    /// be another of its `nodes` nodes.
    pub(super) fn read(bytes: &[u8], nodes: usize) -> Result<Self, String> {
        let json = match bytes.starts_with(b"glTF") {
            true => gltf::binary::Glb::from_slice(bytes).map_err(|e| e.to_string())?.json,
            false => std::borrow::Cow::Borrowed(bytes),
        };
        let document: Document = gltf::json::deserialize::from_slice(&json).map_err(|e| format!("MSFT_lod: {e}"))?;
        let levels: Vec<Vec<usize>> = document
            .nodes
            .into_iter()
            .map(|n| n.extensions.and_then(|e| e.lod).map_or(Vec::new(), |l| l.ids))
            .collect();
        for (node, ids) in levels.iter().enumerate() {
            if let Some(id) = ids.iter().find(|&&id| id >= nodes || id == node) {
                return Err(format!("node {node}: MSFT_lod names node {id}, which is not another node"));
            }
        }
        Ok(Self(levels))
    }

    /// The nodes `node` names as its coarser levels, finest first.
    pub(super) fn of(&self, node: usize) -> &[usize] {
        self.0.get(node).map_or(&[], Vec::as_slice)
    }

    /// Every node some node names as a coarser level: drawn only as that level.
    pub(super) fn level_nodes(&self) -> HashSet<usize> {
        self.0.iter().flatten().copied().collect()
    }
}

/// Reads one triangle primitive (`None` for other modes), as the loader does
/// for full detail.
pub(super) type ReadPrimitive<'r> = dyn Fn(&gltf::Primitive) -> Result<Option<(Mesh, Option<Morph>)>, String> + 'r;

/// `full` (primitive `primitive` of `node`'s mesh) with the levels `node`
/// names (see the module documentation). A level the file gets wrong is an
/// error (as full detail's would be); one that does not match, or has no fewer
/// triangles than the one before, is a warning.
pub(super) fn with_node_levels(
    at: (&gltf::Document, &NodeLevels),
    (node, primitive): (&gltf::Node, &gltf::Primitive),
    full: Mesh,
    read: &ReadPrimitive,
    warnings: &mut Vec<String>,
) -> Result<Mesh, String> {
    let coarser = read_levels(at, (node, primitive, &full), read, warnings)?;
    let mesh = with_given_levels(full, &coarser).map_err(|e| e.to_string())?;
    if mesh.given_levels().len() < coarser.len() {
        warnings.push(format!(
            "node {}: {} of its {} MSFT_lod levels are used (each must have fewer triangles than the one before)",
            node.index(),
            mesh.given_levels().len(),
            coarser.len()
        ));
    }
    Ok(mesh)
}

/// The coarser levels of primitive `primitive` of `node`'s mesh (see the module
/// documentation), at most `MAX_LEVELS - 1`.
fn read_levels(
    (document, levels): (&gltf::Document, &NodeLevels),
    (node, primitive, full): (&gltf::Node, &gltf::Primitive, &Mesh),
    read: &ReadPrimitive,
    warnings: &mut Vec<String>,
) -> Result<Vec<Mesh>, String> {
    let ids = levels.of(node.index());
    if ids.len() >= MAX_LEVELS {
        warnings.push(format!(
            "node {}: MSFT_lod names {} levels; the first {} are used",
            node.index(),
            ids.len(),
            MAX_LEVELS - 1
        ));
    }
    let mut coarser = Vec::new();
    for &id in ids.iter().take(MAX_LEVELS - 1) {
        let at = format!("node {}: MSFT_lod level node {id}", node.index());
        let Some(level) = document.nodes().nth(id) else { return Err(format!("{at} does not exist")) };
        let mesh = level.mesh();
        let found = mesh.as_ref().and_then(|m| m.primitives().nth(primitive.index()));
        let mismatch = match &found {
            None => Some(format!("has no primitive {}", primitive.index())),
            Some(p) if p.material().index() != primitive.material().index() => Some("has another material".into()),
            Some(_) if level.skin().map(|s| s.index()) != node.skin().map(|s| s.index()) => {
                Some("has another skin".into())
            }
            // A level stands where full detail stands; glint does not move its vertices.
            Some(_) if level.transform().matrix() != node.transform().matrix() => Some("has another transform".into()),
            Some(_) => None,
        };
        if let Some(why) = mismatch {
            warnings.push(format!("{at} {why}; levels stop before it"));
            break;
        }
        let (Some(p), Some(mesh)) = (found, mesh) else { break };
        let where_ = format!("mesh {} primitive {}", mesh.index(), p.index());
        let Some((mesh, _)) = read(&p).map_err(|e| format!("{where_}: {e}"))? else {
            warnings.push(format!("{at}: {where_} is not triangles; levels stop before it"));
            break;
        };
        if !mesh.has_streams_of(full) {
            warnings.push(format!("{at}: {where_} has other vertex streams than full detail; levels stop before it"));
            break;
        }
        coarser.push(mesh);
    }
    Ok(coarser)
}
