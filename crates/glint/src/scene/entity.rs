//! Beginner layer: [`Entity`], a shape and a material drawn at one or many
//! instance transforms (with tiles, density and compact records for
//! vegetation, joints for skinned meshes).

use super::{Aabb, MaterialId, ShapeId, Tiles};
use glam::Mat4;
use std::sync::atomic::{AtomicU64, Ordering};

/// The largest y or scale a compact instance holds (half float's largest
/// finite value; [`Entity::with_compact_instances`]).
pub const MAX_COMPACT_HALF: f32 = 65504.0;

/// A thing to draw: a shape, a material and one transform per instance.
///
/// All instances of an entity go in one instanced draw, and entities that share
/// shape and material are merged into that same draw.
///
/// The renderer keeps each entity's transforms on the GPU between frames: it
/// re-uploads them only when they were changed through [`Entity::transforms_mut`]
/// or [`Entity::set_transform`], which bump the entity's version (its dirty flag).
#[derive(Debug, PartialEq)]
pub struct Entity {
    key: u64,
    version: u64,
    /// The mesh.
    pub shape: ShapeId,
    /// The material.
    pub material: MaterialId,
    transforms: Vec<Mat4>,
    joints: Vec<Mat4>,
    phases: Vec<f32>,
    /// Draw-order override: entities with a `render_order` are drawn in increasing
    /// order of it, before (values below 128) or after (128 and above) the sky,
    /// instead of in their material's queue. `None`: the material's queue decides.
    pub render_order: Option<u8>,
    /// Drawn into the shadow maps of shadow-casting lights (default true).
    pub cast_shadows: bool,
    /// Darkened where shadow-casting lights are blocked (default true).
    pub receive_shadows: bool,
    tiles: Option<Tiles>,
    compact: bool,
    gpu_instances: Option<Aabb>,
    /// With tiles, the fraction of every tile drawn (0..=1, default 1): its
    /// first ⌈len × density⌉ instances, in every view and shadow view, with no
    /// upload. Without tiles, every instance is drawn.
    pub density: f32,
}

/// Source of entity identities: each entity (clones included) gets its own.
static NEXT_KEY: AtomicU64 = AtomicU64::new(1);

impl Clone for Entity {
    /// A copy with its own identity, so the renderer keeps it apart from the original.
    fn clone(&self) -> Self {
        Self {
            key: NEXT_KEY.fetch_add(1, Ordering::Relaxed),
            version: 0,
            shape: self.shape,
            material: self.material,
            transforms: self.transforms.clone(),
            joints: self.joints.clone(),
            phases: self.phases.clone(),
            render_order: self.render_order,
            cast_shadows: self.cast_shadows,
            receive_shadows: self.receive_shadows,
            tiles: self.tiles.clone(),
            compact: self.compact,
            gpu_instances: self.gpu_instances,
            density: self.density,
        }
    }
}

impl Entity {
    /// An entity with one instance at `transform`.
    pub fn new(shape: ShapeId, material: MaterialId, transform: Mat4) -> Self {
        Self::instanced(shape, material, vec![transform])
    }

    /// An entity with one instance per transform.
    pub fn instanced(shape: ShapeId, material: MaterialId, transforms: Vec<Mat4>) -> Self {
        Self {
            key: NEXT_KEY.fetch_add(1, Ordering::Relaxed),
            version: 0,
            shape,
            material,
            transforms,
            joints: Vec::new(),
            phases: Vec::new(),
            render_order: None,
            cast_shadows: true,
            receive_shadows: true,
            tiles: None,
            compact: false,
            gpu_instances: None,
            density: 1.0,
        }
    }

    /// The same entity with its draw-order override set (see [`Entity::render_order`]).
    pub fn with_render_order(mut self, order: Option<u8>) -> Self {
        self.render_order = order;
        self
    }

    /// The same entity casting and receiving shadows as given.
    pub fn with_shadows(mut self, cast: bool, receive: bool) -> Self {
        (self.cast_shadows, self.receive_shadows) = (cast, receive);
        self
    }

    /// The same entity with its instances grouped into tiles (see [`Tiles`]),
    /// each culled as a whole and drawn as one range.
    pub fn with_tiles(mut self, tiles: Tiles) -> Self {
        self.set_tiles(tiles);
        self
    }

    /// Group its instances into `tiles` (see [`with_tiles`](Self::with_tiles));
    /// marks the entity for re-upload.
    pub fn set_tiles(&mut self, tiles: Tiles) {
        self.version += 1;
        self.tiles = Some(tiles);
    }

    /// The tiles of its instances, if grouped.
    pub fn tiles(&self) -> Option<&Tiles> {
        self.tiles.as_ref()
    }

    /// The same entity with its instances stored in 16 bytes each on the GPU
    /// instead of 64 (vegetation): position (x and z exact, y as a half
    /// float), one scale (half float) and a turn about +Y (1/65536 of a turn);
    /// what else a transform holds (tilt, uneven scale) is lost. Takes effect
    /// for a tiled entity (see [`with_tiles`](Self::with_tiles)) without
    /// joints and with a material index below 32768; its tiles are then always
    /// culled on the CPU and drawn whole, blended or not. A half float holds
    /// at most [`MAX_COMPACT_HALF`] (y and scale): past it an instance draws
    /// wrongly (a `.scn` file is refused at its `instances` block).
    pub fn with_compact_instances(mut self) -> Self {
        self.set_compact_instances(true);
        self
    }

    /// Store its instances compactly or not (see
    /// [`with_compact_instances`](Self::with_compact_instances)); marks the
    /// entity for re-upload.
    pub fn set_compact_instances(&mut self, compact: bool) {
        self.version += 1;
        self.compact = compact;
    }

    /// Whether its instances are to be stored compactly (see
    /// [`with_compact_instances`](Self::with_compact_instances)).
    pub fn compact_instances(&self) -> bool {
        self.compact
    }

    /// The same entity with its instance records written on the GPU by a
    /// simulation ([`GpuSimulation::place`](crate::render::GpuSimulation::place))
    /// every frame: uploaded from its transforms only when the store writes
    /// them all again (its first frame, a new version, a compaction or a
    /// larger buffer), and then overwritten by the simulation in the same
    /// submission. Its transforms give the instance count and the start; the
    /// CPU, which does not see where the GPU puts them, culls every instance
    /// by `bounds` (a world box holding
    /// every instance whatever the simulation does) and chooses one level of
    /// detail for all of them, where GPU culling tests each instance's own
    /// box as the simulation writes it. Not stored compactly or in Morton
    /// order: record `k` of its range is instance `k`.
    pub fn with_gpu_instances(mut self, bounds: Aabb) -> Self {
        self.set_gpu_instances(Some(bounds));
        self
    }

    /// Have its instance records written on the GPU inside `bounds`, or
    /// (`None`) from its transforms again; marks the entity for re-upload.
    pub fn set_gpu_instances(&mut self, bounds: Option<Aabb>) {
        self.version += 1;
        self.gpu_instances = bounds;
    }

    /// The world box holding its instances where a GPU simulation writes
    /// them (see [`with_gpu_instances`](Self::with_gpu_instances)).
    pub fn gpu_instances(&self) -> Option<Aabb> {
        self.gpu_instances
    }

    /// The same entity with joint matrices, for a skinned shape (see
    /// [`Mesh::with_skin`](super::Mesh::with_skin)): vertex joint `j` moves by
    /// `joints[j]` (a joint's object-space pose times its inverse bind matrix)
    /// before the instance transform. Every instance shares the pose. Joint
    /// indices past the end use the last matrix.
    pub fn with_joints(mut self, joints: Vec<Mat4>) -> Self {
        self.joints = joints;
        self
    }

    /// The joint matrices (empty when the entity is not skinned).
    pub fn joints(&self) -> &[Mat4] {
        &self.joints
    }

    /// Change the joint matrices (a new pose); marks the entity for re-upload.
    pub fn joints_mut(&mut self) -> &mut Vec<Mat4> {
        self.version += 1;
        &mut self.joints
    }

    /// Each instance's motion phase, a fraction of a cycle, for materials whose
    /// motion follows it ([`Motion::Swim`](super::Motion::Swim)); missing
    /// entries are 0. Stored in 1/65536 steps.
    pub fn phases(&self) -> &[f32] {
        &self.phases
    }

    /// Change the phases; marks the instances for re-upload.
    pub fn phases_mut(&mut self) -> &mut Vec<f32> {
        self.version += 1;
        &mut self.phases
    }

    /// Object-to-world transform of each instance.
    pub fn transforms(&self) -> &[Mat4] {
        &self.transforms
    }

    /// Change the transforms; marks them for re-upload.
    pub fn transforms_mut(&mut self) -> &mut Vec<Mat4> {
        self.version += 1;
        &mut self.transforms
    }

    /// Replace instance `index`'s transform; marks the transforms for re-upload.
    ///
    /// Precondition: `index < self.transforms().len()` (panics otherwise, like slice indexing).
    pub fn set_transform(&mut self, index: usize, transform: Mat4) {
        self.transforms_mut()[index] = transform;
    }

    /// Its identity, the same across frames (clones get their own): what a
    /// GPU simulation finds its instances by
    /// ([`PlaceTargets::range`](crate::render::PlaceTargets::range)).
    pub fn key(&self) -> u64 {
        self.key
    }

    /// Bumped on every change to the transforms, joints or phases.
    pub(crate) fn version(&self) -> u64 {
        self.version
    }
}
