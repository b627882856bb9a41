//! Beginner layer: [`Mesh`], a shape's vertices ([`Vertex`], 48 bytes, and
//! [`SkinVertex`] for skinned shapes) and triangle indices, with its bounds
//! ([`Aabb`], [`BoundingSphere`]), normals and tangents.

use glam::{Vec2, Vec3};
use std::collections::HashMap;

/// One vertex of glint's single interleaved vertex layout (48 bytes).
///
/// Vertex shader inputs: `@location(0) position`, `@location(1) normal`,
/// `@location(2) uv`, `@location(3) tangent` (xyz, w = bitangent sign:
/// `bitangent = cross(normal, tangent.xyz) * tangent.w` points up the image, towards
/// decreasing v, as in glTF).
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq, bytemuck::Pod, bytemuck::Zeroable)]
pub struct Vertex {
    /// Object-space position (12 bytes).
    pub position: [f32; 3],
    /// Unit normal (12 bytes).
    pub normal: [f32; 3],
    /// Texture coordinate, origin at the image's top-left (8 bytes).
    pub uv: [f32; 2],
    /// Unit tangent along +u and bitangent sign (16 bytes).
    pub tangent: [f32; 4],
}
const _: () = assert!(std::mem::size_of::<Vertex>() == 48);

/// The joints that move one vertex of a skinned mesh, and how much each does
/// (24 bytes; vertex shader inputs `@location(6) joints`, `@location(7) weights`).
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq, bytemuck::Pod, bytemuck::Zeroable)]
pub struct SkinVertex {
    /// Up to four joints: indices into the entity's joint matrices.
    pub joints: [u16; 4],
    /// Their weights, summing to 1.
    pub weights: [f32; 4],
}

/// Axis-aligned bounding box.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Aabb {
    /// Smallest corner.
    pub min: Vec3,
    /// Largest corner.
    pub max: Vec3,
}

impl Aabb {
    /// The box around `points`; `None` for no points.
    pub fn from_points(points: impl IntoIterator<Item = Vec3>) -> Option<Self> {
        let mut it = points.into_iter();
        let first = it.next()?;
        Some(it.fold(Self { min: first, max: first }, |b, p| Self { min: b.min.min(p), max: b.max.max(p) }))
    }

    /// Centre of the box.
    pub fn center(&self) -> Vec3 {
        (self.min + self.max) * 0.5
    }

    /// Half the size of the box along each axis.
    pub fn half_extent(&self) -> Vec3 {
        (self.max - self.min) * 0.5
    }
}

/// A sphere enclosing a mesh.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct BoundingSphere {
    /// Centre (the AABB's centre).
    pub center: Vec3,
    /// Radius reaching the farthest vertex.
    pub radius: f32,
}

/// Why vertex data was rejected.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum MeshError {
    /// No vertices or no triangles.
    #[error("mesh has no triangles")]
    Empty,
    /// Index count not a multiple of 3.
    #[error("index count {0} is not a multiple of 3")]
    NotTriangles(usize),
    /// An index past the vertex array.
    #[error("index {index} is out of range ({vertices} vertices)")]
    IndexOutOfRange {
        /// The bad index.
        index: u32,
        /// How many vertices there are.
        vertices: usize,
    },
    /// A position, normal or uv that is NaN or infinite.
    #[error("vertex {0} has a non-finite component")]
    NonFinite(usize),
    /// The attribute arrays differ in length.
    #[error("attribute arrays differ in length")]
    AttributeLengths,
    /// A level of detail whose vertex streams differ from full detail's.
    #[error("a level of detail must have the vertex streams (colours, second uvs, skin) of full detail")]
    LevelStreams,
}

/// A triangle mesh on the CPU: interleaved vertices, u32 indices (counter-clockwise
/// front faces) and its local bounds. Upload it with
/// [`Renderer::add_shape`](crate::Renderer::add_shape).
#[derive(Clone, Debug)]
pub struct Mesh {
    vertices: Vec<Vertex>,
    /// Linear RGBA per vertex, multiplied into the material's base colour.
    colors: Option<Vec<[f32; 4]>>,
    /// A second texture coordinate set (glTF `TEXCOORD_1`).
    uv1: Option<Vec<[f32; 2]>>,
    /// Joints and weights per vertex (skinned meshes).
    skin: Option<Vec<SkinVertex>>,
    indices: Vec<u32>,
    /// Coarser levels its author made (glTF `MSFT_lod`), over vertices appended
    /// after full detail's; empty when glint makes the levels itself.
    given_levels: Vec<crate::scene::levels::DetailLevel>,
    aabb: Aabb,
    sphere: BoundingSphere,
}

impl Mesh {
    /// Build a mesh from attribute arrays; tangents are generated with MikkTSpace.
    ///
    /// Preconditions (checked): equal-length arrays, finite values, at least one
    /// triangle, every index in range.
    pub fn from_attributes(
        positions: &[Vec3],
        normals: &[Vec3],
        uvs: &[Vec2],
        indices: Vec<u32>,
    ) -> Result<Self, MeshError> {
        if positions.len() != normals.len() || positions.len() != uvs.len() {
            return Err(MeshError::AttributeLengths);
        }
        let vertices = positions
            .iter()
            .zip(normals)
            .zip(uvs)
            .map(|((p, n), uv)| Vertex {
                position: p.to_array(),
                normal: n.normalize_or(Vec3::Y).to_array(),
                uv: uv.to_array(),
                tangent: [1.0, 0.0, 0.0, 1.0],
            })
            .collect();
        let mut mesh = Self::from_vertices(vertices, indices)?;
        mesh.generate_tangents();
        Ok(mesh)
    }

    /// Build a mesh from finished vertices (tangents included) and indices.
    /// Triangles that name one vertex twice cover nothing and are dropped (they
    /// also crash tangent generation).
    pub fn from_vertices(vertices: Vec<Vertex>, mut indices: Vec<u32>) -> Result<Self, MeshError> {
        if indices.len() % 3 != 0 {
            return Err(MeshError::NotTriangles(indices.len()));
        }
        if indices.chunks_exact(3).any(|t| t[0] == t[1] || t[1] == t[2] || t[0] == t[2]) {
            indices = indices
                .chunks_exact(3)
                .filter(|t| t[0] != t[1] && t[1] != t[2] && t[0] != t[2])
                .flatten()
                .copied()
                .collect();
        }
        if indices.is_empty() || vertices.is_empty() {
            return Err(MeshError::Empty);
        }
        if let Some(&index) = indices.iter().find(|&&i| i as usize >= vertices.len()) {
            return Err(MeshError::IndexOutOfRange { index, vertices: vertices.len() });
        }
        if let Some(i) =
            vertices.iter().position(|v| !(v.position.iter().chain(&v.normal).chain(&v.uv)).all(|c| c.is_finite()))
        {
            return Err(MeshError::NonFinite(i));
        }
        let positions: Vec<Vec3> = vertices.iter().map(|v| Vec3::from(v.position)).collect();
        let (aabb, sphere) = bounds_of(&positions).ok_or(MeshError::Empty)?;
        Ok(Self { vertices, colors: None, uv1: None, skin: None, indices, given_levels: Vec::new(), aabb, sphere })
    }

    /// Give every vertex a linear RGBA colour, multiplied into the material's base
    /// colour (a second vertex stream, and the `VERTEX_COLOR` shader variant).
    pub fn with_colors(mut self, colors: Vec<[f32; 4]>) -> Result<Self, MeshError> {
        self.colors = Some(checked_stream(colors, self.vertices.len(), |c| c.iter().all(|x| x.is_finite()))?);
        Ok(self)
    }

    /// Give every vertex a second texture coordinate (a third vertex stream, and
    /// the `UV1` shader variant); materials pick a set per map.
    pub fn with_uv1(mut self, uv1: Vec<[f32; 2]>) -> Result<Self, MeshError> {
        self.uv1 = Some(checked_stream(uv1, self.vertices.len(), |uv| uv.iter().all(|x| x.is_finite()))?);
        Ok(self)
    }

    /// Make the mesh skinned: four joints and weights per vertex (a vertex stream
    /// of its own, and the `SKINNED` shader variant). Weights are normalised to
    /// sum to 1; a vertex with no weight follows joint 0. Draw it with an entity
    /// that has joint matrices ([`Entity::with_joints`](super::Entity::with_joints)).
    pub fn with_skin(mut self, mut skin: Vec<SkinVertex>) -> Result<Self, MeshError> {
        for s in &mut skin {
            let w = s.weights.map(|w| if w.is_finite() { w.max(0.0) } else { 0.0 });
            let sum: f32 = w.iter().sum();
            s.weights = if sum > 0.0 { w.map(|x| x / sum) } else { [1.0, 0.0, 0.0, 0.0] };
        }
        self.skin = Some(checked_stream(skin, self.vertices.len(), |_| true)?);
        Ok(self)
    }

    /// The interleaved vertices.
    pub fn vertices(&self) -> &[Vertex] {
        &self.vertices
    }

    /// Per-vertex colours, if the mesh has them.
    pub fn colors(&self) -> Option<&[[f32; 4]]> {
        self.colors.as_deref()
    }

    /// The second texture coordinate set, if the mesh has one.
    pub fn uv1(&self) -> Option<&[[f32; 2]]> {
        self.uv1.as_deref()
    }

    /// Joints and weights per vertex, if the mesh is skinned.
    pub fn skin(&self) -> Option<&[SkinVertex]> {
        self.skin.as_deref()
    }

    /// The largest joint index any vertex names (0 for an unskinned mesh).
    pub fn max_joint(&self) -> u16 {
        self.skin().into_iter().flatten().flat_map(|s| s.joints).max().unwrap_or(0)
    }

    /// Replace the positions and normals (morph targets applied on the CPU),
    /// keeping everything else but the levels its author gave (their errors
    /// were measured against the old surface; the shape's levels are made
    /// again, or it stays at full detail when it deforms). Returns whether the
    /// lengths matched and every value was finite (otherwise the mesh is
    /// unchanged).
    pub fn set_positions_normals(&mut self, positions: &[Vec3], normals: &[Vec3]) -> bool {
        let n = self.vertices.len();
        if positions.len() != n || normals.len() != n || !positions.iter().chain(normals).all(|v| v.is_finite()) {
            return false;
        }
        for ((v, p), nrm) in self.vertices.iter_mut().zip(positions).zip(normals) {
            v.position = p.to_array();
            v.normal = nrm.normalize_or(Vec3::Y).to_array();
        }
        (self.aabb, self.sphere) = bounds_of(positions).unwrap_or((self.aabb, self.sphere));
        self.given_levels.clear();
        true
    }

    /// Whether it has the vertex streams `other` has (colours, second uvs, skin),
    /// and no others.
    pub fn has_streams_of(&self, other: &Mesh) -> bool {
        (self.colors.is_some(), self.uv1.is_some(), self.skin.is_some())
            == (other.colors.is_some(), other.uv1.is_some(), other.skin.is_some())
    }

    /// The coarser levels its author made, finest first (see
    /// [`levels::with_given_levels`](crate::scene::levels::with_given_levels));
    /// empty when glint makes them.
    pub fn given_levels(&self) -> &[crate::scene::levels::DetailLevel] {
        &self.given_levels
    }

    /// Append `other`'s vertices (every stream, which must be the ones this mesh
    /// has) after this mesh's, growing the bounds to hold them; its triangles are
    /// not added. Returns the index of its first vertex here.
    pub(super) fn append_vertices(&mut self, other: &Mesh) -> Result<u32, MeshError> {
        if !self.has_streams_of(other) {
            return Err(MeshError::LevelStreams);
        }
        let base = u32::try_from(self.vertices.len()).map_err(|_| MeshError::AttributeLengths)?;
        self.vertices.extend_from_slice(&other.vertices);
        self.colors.iter_mut().zip(&other.colors).for_each(|(m, t)| m.extend_from_slice(t));
        self.uv1.iter_mut().zip(&other.uv1).for_each(|(m, t)| m.extend_from_slice(t));
        self.skin.iter_mut().zip(&other.skin).for_each(|(m, t)| m.extend_from_slice(t));
        let positions: Vec<Vec3> = self.vertices.iter().map(|v| Vec3::from(v.position)).collect();
        (self.aabb, self.sphere) = bounds_of(&positions).unwrap_or((self.aabb, self.sphere));
        Ok(base)
    }

    /// Set the levels its author made (indices over this mesh's vertices).
    pub(super) fn set_given_levels(&mut self, levels: Vec<crate::scene::levels::DetailLevel>) {
        self.given_levels = levels;
    }

    /// Triangle-list indices, counter-clockwise front faces.
    pub fn indices(&self) -> &[u32] {
        &self.indices
    }

    /// Local-space bounding box.
    pub fn aabb(&self) -> Aabb {
        self.aabb
    }

    /// Local-space bounding sphere.
    pub fn bounding_sphere(&self) -> BoundingSphere {
        self.sphere
    }

    fn generate_tangents(&mut self) {
        /// The mesh's vertices and only its triangles with area: mikktspace 0.3
        /// reads out of bounds on some zero-area triangles (found by fuzzing:
        /// an OBJ quad naming one position three times), and they shade nothing.
        struct Geometry<'a> {
            vertices: &'a mut [Vertex],
            faces: Vec<[u32; 3]>,
        }
        impl Geometry<'_> {
            fn vertex(&self, face: usize, vert: usize) -> &Vertex {
                &self.vertices[self.faces[face][vert] as usize]
            }
        }
        impl mikktspace::Geometry for Geometry<'_> {
            fn num_faces(&self) -> usize {
                self.faces.len()
            }
            fn num_vertices_of_face(&self, _face: usize) -> usize {
                3
            }
            fn position(&self, face: usize, vert: usize) -> [f32; 3] {
                self.vertex(face, vert).position
            }
            fn normal(&self, face: usize, vert: usize) -> [f32; 3] {
                self.vertex(face, vert).normal
            }
            fn tex_coord(&self, face: usize, vert: usize) -> [f32; 2] {
                self.vertex(face, vert).uv
            }
            fn set_tangent_encoded(&mut self, tangent: [f32; 4], face: usize, vert: usize) {
                // Shared vertices get one tangent; smooth shapes agree across faces.
                // MikkTSpace's bitangent follows +v, which runs down the image here;
                // glint (like glTF) wants it up the image, so the sign flips.
                let i = self.faces[face][vert] as usize;
                self.vertices[i].tangent = [tangent[0], tangent[1], tangent[2], -tangent[3]];
            }
        }
        let position = |i: u32| Vec3::from(self.vertices[i as usize].position);
        let faces: Vec<[u32; 3]> = self
            .indices
            .chunks_exact(3)
            .map(|t| [t[0], t[1], t[2]])
            .filter(|&[a, b, c]| (position(b) - position(a)).cross(position(c) - position(a)).length_squared() > 0.0)
            .collect();
        if !faces.is_empty() {
            if !mikktspace_is_affordable(&self.vertices, &faces) {
                log::debug!("{} triangles crowd one edge or corner: tangents without MikkTSpace", faces.len());
                accumulate_tangents(&mut self.vertices, &faces);
            } else if !mikktspace::generate_tangents(&mut Geometry { vertices: &mut self.vertices, faces }) {
                log::warn!("tangent generation failed; normal maps on this mesh will be flat");
            }
        }
        // Degenerate UVs leave tangents unusable: fall back to any vector ⟂ normal.
        for v in &mut self.vertices {
            let n = Vec3::from(v.normal);
            let t = Vec3::new(v.tangent[0], v.tangent[1], v.tangent[2]);
            if !t.is_finite() || t.length_squared() < 1e-12 || t.cross(n).length_squared() < 1e-12 {
                let any = n.any_orthonormal_vector();
                v.tangent = [any.x, any.y, any.z, 1.0];
            }
        }
    }
}

/// Whether MikkTSpace finishes these faces in about linear time. It welds
/// corners with equal position, normal and uv, then scans every face on an edge
/// for its neighbour, compares every face around a welded vertex with every other
/// (copying a buffer as long as the largest such fan for each), compares the
/// corners at one position with each distinct corner there, and recurses once per
/// face around a vertex. Real meshes cost a few dozen steps per corner; a hostile
/// file's thousands of faces on one edge or corner would cost their square (or
/// overflow the stack), so above a budget of steps per corner the caller uses
/// [`accumulate_tangents`] instead.
fn mikktspace_is_affordable(vertices: &[Vertex], faces: &[[u32; 3]]) -> bool {
    /// Steps allowed per corner, and for any mesh.
    const PER_CORNER: u64 = 256;
    const ANY_MESH: u64 = 1 << 22;
    /// Most faces around one vertex (recursion depth).
    const MOST_AROUND_A_VERTEX: u64 = 4096;
    // -0.0 and 0.0 weld too.
    let bits = |x: f32| if x == 0.0 { 0 } else { x.to_bits() };
    let key = |v: &Vertex| {
        let [p, n, uv] = [&v.position[..], &v.normal[..], &v.uv[..]];
        let mut k = [0u32; 8];
        for (slot, x) in k.iter_mut().zip(p.iter().chain(n).chain(uv)) {
            *slot = bits(*x);
        }
        k
    };
    let mut welded: HashMap<[u32; 8], u32> = HashMap::with_capacity(vertices.len());
    let ids: Vec<u32> = vertices
        .iter()
        .map(|v| {
            let next = welded.len() as u32;
            *welded.entry(key(v)).or_insert(next)
        })
        .collect();
    let corners = faces.len() as u64 * 3;
    let mut around = vec![0u64; welded.len()];
    for &i in faces.iter().flatten() {
        around[ids[i as usize] as usize] += 1;
    }
    let most_around = around.iter().copied().max().unwrap_or(0);
    if most_around > MOST_AROUND_A_VERTEX {
        return false;
    }
    let mut edges: HashMap<(u32, u32), u64> = HashMap::with_capacity(faces.len() * 3 / 2);
    for face in faces {
        let w = face.map(|i| ids[i as usize]);
        for k in 0..3 {
            let (a, b) = (w[k], w[(k + 1) % 3]);
            *edges.entry((a.min(b), a.max(b))).or_insert(0) += 1;
        }
    }
    // Corners at each position, and distinct welded vertices there.
    let mut at_position: HashMap<[u32; 3], (u64, u64)> = HashMap::new();
    for (k, &id) in &welded {
        let here = at_position.entry([k[0], k[1], k[2]]).or_insert((0, 0));
        here.0 += around[id as usize];
        here.1 += 1;
    }
    let square = |n: u64| n.saturating_mul(n);
    let cost = corners
        .saturating_mul(most_around)
        .saturating_add(around.iter().map(|&n| square(n)).fold(0, u64::saturating_add))
        .saturating_add(edges.values().map(|&n| square(n)).fold(0, u64::saturating_add))
        .saturating_add(at_position.values().map(|&(c, d)| c.saturating_mul(d)).fold(0, u64::saturating_add));
    cost <= corners.saturating_mul(PER_CORNER).saturating_add(ANY_MESH)
}

/// Per-vertex tangents in one pass over the faces: each face adds its
/// texture-space u and v directions to its corners; the sum's part perpendicular
/// to the normal is the tangent, and the sign says whether v runs up the image
/// along normal × tangent, as MikkTSpace's does after [`Mesh::generate_tangents`]
/// flips it. Used where MikkTSpace would take quadratic time; vertices with no
/// usable direction are fixed up by the caller.
fn accumulate_tangents(vertices: &mut [Vertex], faces: &[[u32; 3]]) {
    let mut sums = vec![(Vec3::ZERO, Vec3::ZERO); vertices.len()];
    for face in faces {
        let [a, b, c] = face.map(|i| &vertices[i as usize]);
        let [pa, pb, pc] = [a, b, c].map(|v| Vec3::from(v.position));
        let [ta, tb, tc] = [a, b, c].map(|v| Vec2::from(v.uv));
        let (e1, e2, d1, d2) = (pb - pa, pc - pa, tb - ta, tc - ta);
        let det = d1.x * d2.y - d2.x * d1.y;
        if det == 0.0 || !det.is_finite() {
            continue;
        }
        let du = (e1 * d2.y - e2 * d1.y) / det;
        let dv = (e2 * d1.x - e1 * d2.x) / det;
        for &i in face {
            let sum = &mut sums[i as usize];
            sum.0 += du;
            sum.1 += dv;
        }
    }
    for (v, (du, dv)) in vertices.iter_mut().zip(sums) {
        let n = Vec3::from(v.normal);
        let t = (du - n * n.dot(du)).normalize_or_zero();
        // glint's uvs run down the image, so "up" is -dv.
        let w = if n.cross(t).dot(-dv) < 0.0 { -1.0 } else { 1.0 };
        v.tangent = [t.x, t.y, t.z, w];
    }
}

/// The box around `positions` and the sphere about its centre that holds them
/// (none for no points).
fn bounds_of(positions: &[Vec3]) -> Option<(Aabb, BoundingSphere)> {
    let aabb = Aabb::from_points(positions.iter().copied())?;
    let center = aabb.center();
    let radius = positions.iter().map(|p| p.distance(center)).fold(0.0, f32::max);
    Some((aabb, BoundingSphere { center, radius }))
}

/// `stream` if it has one value per vertex and each passes `finite`.
fn checked_stream<T>(stream: Vec<T>, vertices: usize, finite: impl Fn(&T) -> bool) -> Result<Vec<T>, MeshError> {
    if stream.len() != vertices {
        return Err(MeshError::AttributeLengths);
    }
    match stream.iter().position(|x| !finite(x)) {
        Some(i) => Err(MeshError::NonFinite(i)),
        None => Ok(stream),
    }
}

/// Smooth vertex normals for a triangle list without them: each triangle adds its
/// face normal weighted by its corner angle to every vertex at that corner's
/// position, so vertices split by texture seams share one normal. Degenerate
/// triangles add nothing; a vertex no triangle lights gets +Y.
pub fn smooth_normals(positions: &[Vec3], indices: &[u32]) -> Vec<Vec3> {
    smooth_normals_in_groups(positions, indices, &[])
}

/// [`smooth_normals`] within smoothing groups: `groups[i]` is vertex `i`'s group
/// (an empty slice puts every vertex in one), and only vertices at one position
/// *and* in one group share a normal. A vertex in a group of its own triangle
/// alone gets that triangle's face normal (flat shading).
pub fn smooth_normals_in_groups(positions: &[Vec3], indices: &[u32], groups: &[u64]) -> Vec<Vec3> {
    let key = |i: usize| {
        let p = positions[i];
        (p.x.to_bits(), p.y.to_bits(), p.z.to_bits(), groups.get(i).copied().unwrap_or(0))
    };
    let mut sums: HashMap<(u32, u32, u32, u64), Vec3> = HashMap::new();
    for tri in indices.chunks_exact(3) {
        let corners = [tri[0] as usize, tri[1] as usize, tri[2] as usize];
        if corners.iter().any(|&i| i >= positions.len()) {
            continue;
        }
        let [a, b, c] = corners.map(|i| positions[i]);
        let face = (b - a).cross(c - a).normalize_or_zero();
        for (corner, (p, u, v)) in corners.into_iter().zip([(a, b, c), (b, c, a), (c, a, b)]) {
            let angle = (u - p).normalize_or_zero().dot((v - p).normalize_or_zero()).clamp(-1.0, 1.0).acos();
            *sums.entry(key(corner)).or_insert(Vec3::ZERO) += face * angle;
        }
    }
    (0..positions.len()).map(|i| sums.get(&key(i)).map_or(Vec3::Y, |n| n.normalize_or(Vec3::Y))).collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn zero_area_triangles_do_not_reach_tangent_generation() {
        // The fuzz find: a quad naming one position three times (split by UVs).
        let v = |x: f32, u: f32| Vertex {
            position: [x, 0.0, 0.0],
            normal: [0.0, 1.0, 0.0],
            uv: [u, 0.0],
            ..Vertex::default()
        };
        let vertices = vec![v(0.0, 0.0), v(1.0, 0.1), v(0.0, 0.2), v(0.0, 0.3)];
        let mesh = Mesh::from_vertices(vertices, vec![0, 1, 2, 0, 2, 3]).expect("kept: drawing them is harmless");
        let mut mesh = mesh;
        mesh.generate_tangents();
        assert!(mesh.vertices().iter().all(|v| v.tangent.iter().all(|c| c.is_finite())));
    }

    #[test]
    fn triangles_naming_a_vertex_twice_are_dropped() {
        let v = |x: f32, y: f32| Vertex { position: [x, y, 0.0], normal: [0.0, 0.0, 1.0], ..Vertex::default() };
        let vertices = vec![v(0.0, 0.0), v(1.0, 0.0), v(0.0, 1.0)];
        let mesh = Mesh::from_vertices(vertices.clone(), vec![0, 1, 2, 2, 2, 2, 0, 0, 1]).expect("one good triangle");
        assert_eq!(mesh.indices(), &[0, 1, 2]);
        assert_eq!(Mesh::from_vertices(vertices, vec![1, 1, 1]).unwrap_err(), MeshError::Empty);
    }

    #[test]
    fn smooth_normals_are_shared_by_vertices_at_one_position() {
        // Two triangles of a flat square, the diagonal's ends duplicated (a UV seam).
        let p = [Vec3::ZERO, Vec3::X, Vec3::Y, Vec3::X, Vec3::new(1.0, 1.0, 0.0), Vec3::Y];
        let normals = smooth_normals(&p, &[0, 1, 2, 3, 4, 5]);
        assert!(normals.iter().all(|n| (*n - Vec3::Z).length() < 1e-6), "{normals:?}");
        assert_eq!(smooth_normals(&[Vec3::ZERO], &[]), vec![Vec3::Y], "an unused vertex gets +Y");
    }

    /// An n × n grid of quads in z = 0, its uvs from `uv(x, y)`.
    fn grid(n: u32, uv: impl Fn(f32, f32) -> Vec2) -> (Vec<Vertex>, Vec<[u32; 3]>) {
        let mut vertices = Vec::new();
        for y in 0..=n {
            for x in 0..=n {
                let (fx, fy) = (x as f32, y as f32);
                let normal = [0.0, 0.0, 1.0];
                vertices.push(Vertex {
                    position: [fx, fy, 0.0],
                    normal,
                    uv: uv(fx, fy).to_array(),
                    ..Vertex::default()
                });
            }
        }
        let at = |x: u32, y: u32| y * (n + 1) + x;
        let mut faces = Vec::new();
        for y in 0..n {
            for x in 0..n {
                faces.push([at(x, y), at(x + 1, y), at(x + 1, y + 1)]);
                faces.push([at(x, y), at(x + 1, y + 1), at(x, y + 1)]);
            }
        }
        (vertices, faces)
    }

    #[test]
    fn linear_tangents_agree_with_mikktspace() {
        // Sheared, rotated and mirrored uv layouts: the direction and the sign.
        let layouts: [&dyn Fn(f32, f32) -> Vec2; 3] =
            [&|x, y| Vec2::new(0.1 * x + 0.02 * y, 0.1 * y), &|x, y| Vec2::new(0.1 * y, 0.1 * x), &|x, y| {
                Vec2::new(-0.1 * x, -0.1 * y)
            }];
        for (k, uv) in layouts.into_iter().enumerate() {
            let (vertices, faces) = grid(4, uv);
            assert!(mikktspace_is_affordable(&vertices, &faces), "a grid is cheap");
            let indices = faces.iter().flatten().copied().collect();
            let mikk = Mesh::from_attributes(
                &vertices.iter().map(|v| Vec3::from(v.position)).collect::<Vec<_>>(),
                &vertices.iter().map(|v| Vec3::from(v.normal)).collect::<Vec<_>>(),
                &vertices.iter().map(|v| Vec2::from(v.uv)).collect::<Vec<_>>(),
                indices,
            )
            .expect("valid");
            let mut linear = vertices.clone();
            accumulate_tangents(&mut linear, &faces);
            for (m, l) in mikk.vertices().iter().zip(&linear) {
                let (tm, tl) = (Vec3::from_slice(&m.tangent[..3]), Vec3::from_slice(&l.tangent[..3]));
                assert!(tm.dot(tl) > 0.999, "layout {k}: {tm} vs {tl}");
                assert_eq!(m.tangent[3], l.tangent[3], "layout {k}: the sign");
            }
        }
    }

    #[test]
    fn crowded_edges_and_corners_skip_mikktspace() {
        // A face repeated 20,000 times: MikkTSpace's neighbour search would
        // compare each copy's edges with every other's.
        let (vertices, faces) = grid(1, Vec2::new);
        let repeated = vec![faces[0]; 20_000];
        assert!(!mikktspace_is_affordable(&vertices, &repeated));
        // Copies of the three vertices do not help: MikkTSpace welds equal ones.
        let copies: Vec<Vertex> = (0..20_000).flat_map(|_| faces[0].map(|i| vertices[i as usize])).collect();
        let separate: Vec<[u32; 3]> = (0..20_000u32).map(|f| [3 * f, 3 * f + 1, 3 * f + 2]).collect();
        assert!(!mikktspace_is_affordable(&copies, &separate));
        // A fan of 10,000 triangles round one vertex (MikkTSpace recurses once per triangle).
        let mut fan = vec![Vertex { normal: [0.0, 0.0, 1.0], ..Vertex::default() }];
        fan.extend((0..=10_000).map(|i| {
            let a = i as f32 * 1e-4 * std::f32::consts::PI;
            Vertex { position: [a.cos(), a.sin(), 0.0], normal: [0.0, 0.0, 1.0], ..Vertex::default() }
        }));
        let fan_faces: Vec<[u32; 3]> = (1..=10_000u32).map(|i| [0, i, i + 1]).collect();
        assert!(!mikktspace_is_affordable(&fan, &fan_faces));
        // Either way every vertex gets a usable tangent.
        let p: Vec<Vec3> = copies.iter().map(|v| Vec3::from(v.position)).collect();
        let mesh = Mesh::from_attributes(&p, &vec![Vec3::Z; p.len()], &vec![Vec2::ZERO; p.len()], separate.concat())
            .expect("valid");
        assert!(mesh.vertices().iter().all(|v| v.tangent.iter().all(|c| c.is_finite())));
    }
}
