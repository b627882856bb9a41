//! glTF `MSFT_lod`: levels of detail an author made. A node with a mesh names
//! other nodes as its coarser levels, finest first (`extensions.MSFT_lod.ids`);
//! those nodes stay out of the scene and their meshes are drawn only as levels.
//!
//! Primitive `p` of the node's mesh takes primitive `p` of each level node's
//! mesh as its coarser level, while that primitive is a triangle list with the
//! same material, its node has the same skin, and it has the same vertex
//! streams; the chain stops (with a warning) at the first that is not. A
//! primitive with morph targets keeps no given levels: the levels would not
//! follow its targets. Each level's error is measured against full detail
//! ([`with_given_levels`]); the `MSFT_screencoverage` hints are not read, since
//! the renderer chooses by projected error as it does for every mesh.

use super::model::Morph;
use crate::scene::levels::MAX_LEVELS;
use crate::scene::Mesh;
use gltf::json;
use json::Value;
use std::collections::HashSet;

/// The nodes `node` names as its coarser levels, finest first (empty without
/// `MSFT_lod`); not checked against the node count (`gltf_check` does that).
pub(super) fn lod_ids(node: &json::Node) -> Result<Vec<usize>, String> {
    let Some(lod) = node.extensions.as_ref().and_then(|e| e.others.get("MSFT_lod")) else {
        return Ok(Vec::new());
    };
    let ids = lod.get("ids").and_then(Value::as_array).ok_or("MSFT_lod: expected \"ids\", an array of node indices")?;
    (ids.iter())
        .map(|id| {
            let index = id.as_u64().and_then(|i| usize::try_from(i).ok());
            index.ok_or_else(|| format!("MSFT_lod: expected node indices in \"ids\", found {id}"))
        })
        .collect()
}

/// Every node some node names as a coarser level: drawn only as that level.
pub(super) fn level_nodes(root: &json::Root) -> HashSet<usize> {
    root.nodes.iter().flat_map(|node| lod_ids(node).unwrap_or_default()).collect()
}

/// Reads one triangle primitive (`None` for other modes), as the loader does
/// for full detail.
pub(super) type ReadPrimitive<'r> = dyn Fn(&gltf::Primitive) -> Result<Option<(Mesh, Option<Morph>)>, String> + 'r;

/// The coarser levels of primitive `primitive` of `node`'s mesh (see the module
/// documentation), at most `MAX_LEVELS - 1`. A level the file gets wrong is an
/// error (as full detail's would be); one that does not match is a warning.
pub(super) fn read_levels(
    document: &gltf::Document,
    (node, primitive, full): (&gltf::Node, &gltf::Primitive, &Mesh),
    read: &ReadPrimitive,
    warnings: &mut Vec<String>,
) -> Result<Vec<Mesh>, String> {
    let ids = lod_ids(&document.as_json().nodes[node.index()])?;
    if ids.len() >= MAX_LEVELS {
        warnings.push(format!(
            "node {}: MSFT_lod names {} levels; the first {} are used",
            node.index(),
            ids.len(),
            MAX_LEVELS - 1
        ));
    }
    let mut levels = Vec::new();
    for id in ids.into_iter().take(MAX_LEVELS - 1) {
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
        levels.push(mesh);
    }
    Ok(levels)
}
