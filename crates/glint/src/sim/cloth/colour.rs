//! Vertex colouring for a parallel block Gauss–Seidel solve: nodes of one
//! colour share no edge and no hinge, so each can take its own Newton step
//! on its own local energy at the same time as the others, each reading only
//! nodes of other colours ([`super::dynamics::gpu`]).
//!
//! The colouring is greedy in node order (each node takes the lowest colour
//! none of its element neighbours has), so the same mesh always gets the
//! same colours. Inside a regular sheet (`ClothMesh::sheet`, its diagonals
//! alternating) a node shares an edge or hinge with 8 or 12 others; greedy
//! colouring gives the sheet 7 colours (6 at 3 × 3).

use super::Topology;

/// The free nodes of each colour, in node order; colours in order.
pub fn colour_nodes(nodes: usize, topology: &Topology, free: &[bool]) -> Vec<Vec<u32>> {
    // Every pair of nodes sharing an element, each node's list of the others.
    let mut neighbours: Vec<Vec<u32>> = vec![Vec::new(); nodes];
    let elements = topology.edges.iter().map(|e| &e[..]).chain(topology.hinges.iter().map(|h| &h[..]));
    for element in elements {
        for &a in element {
            neighbours[a as usize].extend(element.iter().filter(|&&b| b != a));
        }
    }
    let mut colour_of: Vec<Option<usize>> = vec![None; nodes];
    let mut colours: Vec<Vec<u32>> = Vec::new();
    let mut taken: Vec<bool> = Vec::new();
    for node in (0..nodes).filter(|&n| free.get(n).copied().unwrap_or(true)) {
        taken.clear();
        taken.resize(colours.len() + 1, false);
        for &other in &neighbours[node] {
            if let Some(c) = colour_of[other as usize] {
                taken[c] = true;
            }
        }
        let colour = taken.iter().position(|t| !t).expect("one more colour than there are");
        if colour == colours.len() {
            colours.push(Vec::new());
        }
        colours[colour].push(node as u32);
        colour_of[node] = Some(colour);
    }
    colours
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::scene::cloth::ClothMesh;

    #[test]
    fn no_two_nodes_of_a_colour_share_an_element_and_every_free_node_has_one() {
        let mesh = ClothMesh::sheet(1.0, 1.0, 17, 13);
        let topology = mesh.topology().unwrap();
        let free: Vec<bool> = (0..mesh.nodes.len()).map(|n| n % 17 != 0).collect();
        let colours = colour_nodes(mesh.nodes.len(), &topology, &free);
        let mut colour_of = vec![None; mesh.nodes.len()];
        for (c, nodes) in colours.iter().enumerate() {
            for &n in nodes {
                assert!(colour_of[n as usize].replace(c).is_none(), "node {n} coloured twice");
            }
        }
        for (n, f) in free.iter().enumerate() {
            assert_eq!(colour_of[n].is_some(), *f, "node {n}: coloured exactly when free");
        }
        let elements = topology.edges.iter().map(|e| &e[..]).chain(topology.hinges.iter().map(|h| &h[..]));
        for element in elements {
            for (i, &a) in element.iter().enumerate() {
                for &b in &element[i + 1..] {
                    let (ca, cb) = (colour_of[a as usize], colour_of[b as usize]);
                    assert!(ca.is_none() || ca != cb, "nodes {a} and {b} share an element and colour {ca:?}");
                }
            }
        }
        // Each node has 12 element neighbours inside the sheet, so at least 13 could
        // be needed in the worst case; greedy order does better on the lattice.
        assert!((5..=13).contains(&colours.len()), "{} colours", colours.len());
    }
}
