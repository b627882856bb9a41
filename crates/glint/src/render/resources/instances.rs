//! Core layer: the persistent instance store. Every submitted entity owns a range
//! of one instance array (transform + material index) that lives on the GPU between
//! frames; a range is written again only when its entity's version (dirty flag),
//! shape or material changes. Beside it, the world
//! bounds of every instance as structure-of-arrays (centres, half extents) for culling.
//!
//! Tiles: an entity's instances are stored in Morton (Z-curve) order of their world
//! positions, so every run of [`CLUSTER`] consecutive instances is a compact patch
//! of space with one bounding box. The culler tests those boxes first and tests
//! instances one by one only in patches that cross a frustum plane (the vegetation
//! demo's tiled instancing). The order inside an entity's range is the store's
//! business: nothing outside it names instances by position.
//!
//! An entity with [`Tiles`] keeps its own order instead: each of its tiles is
//! a cluster, its valid instances first, and every instance's box is its tile's
//! (grown by the padding), so every test of an instance, on the CPU or the GPU,
//! is its tile's test: a tile is culled as a whole.
//!
//! A skinned entity's range holds its instances, then its joint matrices in the
//! same record format; each instance records how far ahead its joints start, so
//! the range can move (compaction) without rewriting it.

use crate::render::cull::{transform_aabb, Boxes};
use crate::render::resources::blocks::{CompactGpu, InstanceGpu, COMPACT_MATERIALS};
use crate::scene::{Aabb, Entity, MaterialId, ShapeId, Tiles};
use glam::{Mat4, Vec3A};
use std::collections::HashMap;
use std::ops::Range;

/// One entity's place in the store.
#[derive(Clone, Debug)]
pub(crate) struct Slot {
    key: u64,
    version: u64,
    shape: ShapeId,
    material: MaterialId,
    /// Whether the records say the entity receives shadows.
    receive_shadows: bool,
    /// How far the instances reached when the range was written.
    reach: Reach,
    /// First instance in the store.
    pub first: u32,
    /// Instance count.
    pub count: u32,
    /// Joint matrices stored after the instances.
    joints: u32,
    /// Union of the valid instances' world boxes (centre, half extent); `None` when
    /// no instance is valid.
    pub bounds: Option<(Vec3A, Vec3A)>,
    /// Instances whose transform has NaN or infinity: stored as zero matrices (after
    /// the valid ones), never drawn.
    pub invalid: u32,
    /// The range's clusters: its runs of [`CLUSTER`] instances (none when the
    /// entity has no more than one run), or its tiles.
    pub clusters: Vec<Cluster>,
    /// Whether the clusters are the entity's tiles.
    pub tiled: bool,
    /// Whether its instances are stored compactly, four to a record
    /// ([`CompactGpu`]): then `first` counts records and each instance is
    /// numbered `4 · first + k` (see [`Slot::instance_base`]).
    pub compact: bool,
    /// Whether a GPU simulation writes its records ([`Entity::with_gpu_instances`]).
    gpu: bool,
    /// Frame in which the entity was last submitted.
    last_frame: u64,
}

impl Slot {
    /// Records the entity occupies: instances, then joints; compact, a quarter
    /// record each.
    pub(crate) fn len(&self) -> usize {
        match self.compact {
            true => self.count.div_ceil(4) as usize,
            false => (self.count + self.joints) as usize,
        }
    }

    /// The number of its first instance as draws name it: its first record,
    /// or compact, its first quarter record.
    pub(crate) fn instance_base(&self) -> u32 {
        if self.compact {
            4 * self.first
        } else {
            self.first
        }
    }
}

/// All instances of all entities submitted recently.
#[derive(Default)]
pub(crate) struct InstanceStore {
    slots: Vec<Slot>,
    by_key: HashMap<u64, usize>,
    /// Instances as uploaded: transform and material (invalid transforms zeroed).
    pub instances: Vec<InstanceGpu>,
    /// World boxes, one per instance (never visible for invalid instances).
    pub bounds: Boxes,
    /// Instances left behind by entities that moved or shrank.
    garbage: usize,
    /// Ranges written since the last upload.
    dirty: Vec<Range<u32>>,
    /// The whole store must be uploaded (after compaction or growth).
    all_dirty: bool,
}

impl InstanceStore {
    /// The slot for `index`.
    pub(crate) fn slot(&self, index: usize) -> &Slot {
        &self.slots[index]
    }

    /// Where the instances of the entity keyed `entity` are written on the GPU
    /// ([`Entity::with_gpu_instances`]): its range, with what each record holds
    /// besides its transform; `None` for an entity not submitted in `frame`,
    /// or whose records the store writes.
    pub(crate) fn gpu_range(&self, entity: u64, frame: u64) -> Option<crate::gpu::InstanceRange> {
        let slot = &self.slots[*self.by_key.get(&entity)?];
        let written = slot.gpu && !slot.compact && slot.joints == 0 && slot.last_frame == frame;
        written.then_some(crate::gpu::InstanceRange {
            first: slot.first,
            count: slot.count,
            material: slot.material.0,
            receive_shadows: slot.receive_shadows,
            local: slot.reach.local,
            walk: slot.reach.walk,
        })
    }

    /// Number of instances stored, garbage included.
    pub(crate) fn len(&self) -> usize {
        self.instances.len()
    }

    /// Record `entity` as submitted in `frame`, writing its transforms and bounds if
    /// they changed (or it is new, or its shape, the shape's box or its material changed). Returns its slot index.
    pub(crate) fn submit(&mut self, entity: &Entity, reach: impl Into<Reach>, frame: u64) -> usize {
        let reach = reach.into();
        let count = entity.transforms().len() as u32;
        let joints = entity.joints().len() as u32;
        let index = match self.by_key.get(&entity.key()) {
            Some(&i) => i,
            None => {
                self.slots.push(Slot {
                    key: entity.key(),
                    version: entity.version().wrapping_sub(1),
                    shape: entity.shape,
                    material: entity.material,
                    receive_shadows: entity.receive_shadows,
                    reach,
                    first: self.instances.len() as u32,
                    count: 0,
                    joints: 0,
                    bounds: None,
                    invalid: 0,
                    clusters: Vec::new(),
                    tiled: false,
                    compact: false,
                    gpu: false,
                    last_frame: frame,
                });
                self.by_key.insert(entity.key(), self.slots.len() - 1);
                self.slots.len() - 1
            }
        };
        let compact = stored_compactly(entity);
        let slot = &mut self.slots[index];
        slot.last_frame = frame;
        if (slot.count, slot.joints, slot.compact) != (count, joints, compact) {
            // A new size needs a new range at the end; the old one becomes garbage.
            self.garbage += slot.len();
            slot.first = self.instances.len() as u32;
            slot.count = count;
            slot.joints = joints;
            slot.compact = compact;
            let new_len = self.instances.len() + slot.len();
            self.instances.resize(new_len, InstanceGpu::default());
            self.bounds.resize(new_len);
            slot.version = entity.version().wrapping_sub(1);
        }
        if slot.version != entity.version()
            || slot.shape != entity.shape
            || slot.material != entity.material
            || slot.receive_shadows != entity.receive_shadows
            || slot.reach != reach
        {
            slot.receive_shadows = entity.receive_shadows;
            slot.version = entity.version();
            slot.reach = reach;
            slot.shape = entity.shape;
            slot.material = entity.material;
            let range = slot.first as usize..slot.first as usize + slot.len();
            let records = &mut self.instances[range.clone()];
            let written = write_range(entity, (reach, compact), records, &mut self.bounds, range.start);
            slot.bounds = written.bounds;
            slot.invalid = written.invalid;
            slot.clusters = written.clusters;
            slot.tiled = entity.tiles().is_some() && entity.gpu_instances().is_none();
            slot.gpu = entity.gpu_instances().is_some();
            self.dirty.push(range.start as u32..range.end as u32);
        }
        index
    }

    /// When waste (ranges left behind, plus entities not submitted in `frame`)
    /// outweighs live data, rebuild the store from the entities submitted in
    /// `frame` and mark everything for upload. Returns the slot indices remapped:
    /// `remap[old] = new` (`usize::MAX` if dropped).
    pub(crate) fn compact_if_wasteful(&mut self, frame: u64) -> Option<Vec<usize>> {
        let stale: usize = self.slots.iter().filter(|s| s.last_frame != frame).map(Slot::len).sum();
        let waste = self.garbage + stale;
        if waste < 4096 || waste < self.instances.len() / 2 {
            return None;
        }
        let mut remap = vec![usize::MAX; self.slots.len()];
        let (mut instances, mut bounds) = (Vec::new(), Boxes::default());
        let mut slots = Vec::new();
        for (old, slot) in self.slots.iter().enumerate().filter(|(_, s)| s.last_frame == frame) {
            let range = slot.first as usize..slot.first as usize + slot.len();
            let mut moved = slot.clone();
            moved.first = instances.len() as u32;
            instances.extend_from_slice(&self.instances[range.clone()]);
            bounds.extend_from(&self.bounds, range);
            remap[old] = slots.len();
            slots.push(moved);
        }
        self.by_key = slots.iter().enumerate().map(|(i, s)| (s.key, i)).collect();
        self.slots = slots;
        self.instances = instances;
        self.bounds = bounds;
        self.garbage = 0;
        self.all_dirty = true;
        Some(remap)
    }

    /// Take the ranges to upload: everything after compaction, else the merged dirty ranges.
    pub(crate) fn take_dirty(&mut self) -> Vec<Range<u32>> {
        let mut ranges = std::mem::take(&mut self.dirty);
        if std::mem::take(&mut self.all_dirty) {
            let everything = 0..self.instances.len() as u32;
            return vec![everything];
        }
        ranges.sort_by_key(|r| r.start);
        let mut merged: Vec<Range<u32>> = Vec::with_capacity(ranges.len());
        for r in ranges.into_iter().filter(|r| !r.is_empty()) {
            match merged.last_mut() {
                Some(last) if r.start <= last.end => last.end = last.end.max(r.end),
                _ => merged.push(r),
            }
        }
        merged
    }

    /// Mark the whole store for upload (the GPU buffer was recreated).
    pub(crate) fn mark_all_dirty(&mut self) {
        self.all_dirty = true;
    }
}

/// Instances per tile: the culler's unit above single instances.
pub(crate) const CLUSTER: usize = 64;

/// How far an entity's instances reach: the shape's local box (grown by its
/// material's [`Motion`](crate::scene::Motion)), and the radius each walks
/// around its placed position in world units (0: none).
#[derive(Clone, Copy, Debug, PartialEq)]
pub(crate) struct Reach {
    pub local: Aabb,
    pub walk: f32,
}

impl From<Aabb> for Reach {
    fn from(local: Aabb) -> Self {
        Self { local, walk: 0.0 }
    }
}

impl Reach {
    /// The world box `(c, e)` of an instance placed by `m`, grown to hold it
    /// anywhere on its walk facing any way: around its placed position, out to
    /// the walk's radius plus the box's own reach from there in x and z.
    fn walked(self, m: &Mat4, (c, e): (Vec3A, Vec3A)) -> (Vec3A, Vec3A) {
        if self.walk <= 0.0 {
            return (c, e);
        }
        let o = Vec3A::from(m.w_axis.truncate());
        let side = self.walk + (e.x * e.x + e.z * e.z).sqrt() + (c - o).truncate().length();
        (Vec3A::new(o.x, c.y, o.z), Vec3A::new(side, e.y, side))
    }
}

/// A run of an entity's instances culled by one box: a Morton run of
/// [`CLUSTER`], or one of the entity's [`Tiles`].
#[derive(Clone, Copy, Debug, PartialEq)]
pub(crate) struct Cluster {
    /// Its first instance, counted from the entity's first.
    pub first: u32,
    /// Its valid instances, which come first (a cluster without any is never visible).
    pub valid: u32,
    /// Its box: centre and half extent.
    pub center: Vec3A,
    pub extent: Vec3A,
    /// The box (centre, half extent) of its valid instances' placed
    /// positions, which a far field measures its distances from.
    pub origins: (Vec3A, Vec3A),
}

/// Whether `entity`'s instances are stored compactly: asked for, tiled, not
/// skinned, and its material one a compact record can name.
pub(crate) fn stored_compactly(entity: &Entity) -> bool {
    entity.compact_instances()
        && entity.tiles().is_some()
        && entity.gpu_instances().is_none()
        && entity.joints().is_empty()
        && entity.material.0 < COMPACT_MATERIALS
}

/// What [`write_range`] found.
struct Written {
    bounds: Option<(Vec3A, Vec3A)>,
    invalid: u32,
    clusters: Vec<Cluster>,
}

/// Copy an entity's transforms into the store with its material, and compute
/// each instance's world box (boxes from `first` on) and each cluster's: in
/// Morton order of their world positions with the invalid ones last, or, with
/// tiles, tile by tile with each tile's invalid ones last and every box its
/// tile's; then its joint matrices. Invalid (non-finite) transforms and joints
/// become zero matrices with a never-visible box, so NaN never reaches the GPU
/// or the culler.
///
/// A skinned entity's local box is the union of the shape's box moved by each
/// joint: every skinned vertex is a weighted average of points in those boxes.
fn write_range(
    entity: &Entity,
    (reach, compact): (Reach, bool),
    records: &mut [InstanceGpu],
    boxes: &mut Boxes,
    first: usize,
) -> Written {
    let (src, material, receive) = (entity.transforms(), entity.material, entity.receive_shadows);
    let (lc, le) = skinned_box(entity.joints(), reach.local);
    // Where a GPU simulation writes the records, every instance's box is the
    // one that holds them all (the CPU does not see where each is).
    let held = entity.gpu_instances().map(|b| (Vec3A::from(b.center()), Vec3A::from(b.half_extent())));
    let world: Vec<Option<(Vec3A, Vec3A)>> = src
        .iter()
        .map(|m| m.is_finite().then(|| held.unwrap_or_else(|| reach.walked(m, transform_aabb(m, lc, le)))))
        .collect();
    // A GPU simulation's instances keep their order, not their tiles'.
    let tiles = entity.tiles().filter(|_| held.is_none());
    let (lo, hi) = world
        .iter()
        .flatten()
        .fold((Vec3A::splat(f32::INFINITY), Vec3A::splat(f32::NEG_INFINITY)), |(lo, hi), &(c, e)| {
            (lo.min(c - e), hi.max(c + e))
        });
    let invalid = world.iter().filter(|w| w.is_none()).count() as u32;
    let mut bounds = (invalid < src.len() as u32).then(|| ((lo + hi) * 0.5, (hi - lo) * 0.5));
    let (order, groups) = match (held, tiles) {
        // Record k is instance k, where the simulation writes it.
        (Some(_), _) => ((0..src.len() as u32).collect(), std::iter::once(0..src.len() as u32).collect()),
        (None, Some(tiles)) => tile_order(tiles, &world),
        (None, None) => morton_order(&world, (lo, hi)),
    };
    let padding = Vec3A::splat(tiles.map_or(0.0, Tiles::padding));
    let mut clusters = Vec::with_capacity(groups.len());
    if compact {
        // Four to a record; the tiles are culled on the CPU only, so no record
        // has a box of its own.
        let compacts: Vec<CompactGpu> =
            order.iter().map(|&i| CompactGpu::new(&src[i as usize], material, receive)).collect();
        for (k, (record, four)) in records.iter_mut().zip(compacts.chunks(4)).enumerate() {
            let mut lanes = [CompactGpu::default(); 4];
            lanes[..four.len()].copy_from_slice(four);
            *record = CompactGpu::record(lanes);
            boxes.set_never_visible(first + k);
        }
    }
    let (instances, joint_records) = records.split_at_mut(if compact { 0 } else { src.len() });
    for group in groups {
        let run = &order[group.start as usize..group.end as usize];
        let valid = run.iter().filter(|&&i| world[i as usize].is_some()).count() as u32;
        let (lo, hi) = run
            .iter()
            .filter_map(|&i| world[i as usize])
            .fold((Vec3A::splat(f32::INFINITY), Vec3A::splat(f32::NEG_INFINITY)), |(lo, hi), (c, e)| {
                (lo.min(c - e), hi.max(c + e))
            });
        let (center, extent) = match valid {
            0 => (Vec3A::ZERO, Vec3A::splat(crate::render::cull::NEVER_VISIBLE_EXTENT)),
            _ => ((lo + hi) * 0.5, (hi - lo) * 0.5 + padding),
        };
        let placed = run
            .iter()
            .filter(|&&i| world[i as usize].is_some())
            .map(|&i| Vec3A::from(src[i as usize].w_axis.truncate()));
        let (olo, ohi) = placed
            .fold((Vec3A::splat(f32::INFINITY), Vec3A::splat(f32::NEG_INFINITY)), |(lo, hi), p| (lo.min(p), hi.max(p)));
        let origins = if valid == 0 { (Vec3A::ZERO, Vec3A::ZERO) } else { ((olo + ohi) * 0.5, (ohi - olo) * 0.5) };
        for (k, &i) in run.iter().enumerate().filter(|_| !compact) {
            let at = group.start as usize + k;
            match world[i as usize] {
                Some((c, e)) => {
                    let joints = joint_records.len() as u32;
                    let offset = if joints > 0 { (src.len() - at) as u32 } else { 0 };
                    let phase = entity.phases().get(i as usize).copied().unwrap_or(0.0);
                    instances[at] = InstanceGpu::new(&src[i as usize], material, receive)
                        .with_joints(offset, joints)
                        .with_phase(phase);
                    match tiles {
                        Some(_) => boxes.set(first + at, center, extent),
                        None => boxes.set(first + at, c, e),
                    }
                }
                None => {
                    instances[at] = InstanceGpu::new(&Mat4::ZERO, material, receive);
                    boxes.set_never_visible(first + at);
                }
            }
        }
        clusters.push(Cluster { first: group.start, valid, center, extent, origins });
    }
    if tiles.is_some() {
        // The entity's box holds its tiles' padding too.
        bounds = bounds.map(|(c, e)| (c, e + padding));
    } else if clusters.len() < 2 {
        clusters.clear();
    }
    for (k, (record, joint)) in joint_records.iter_mut().zip(entity.joints()).enumerate() {
        let joint = if joint.is_finite() { *joint } else { Mat4::ZERO };
        *record = InstanceGpu::new(&joint, material, receive);
        boxes.set_never_visible(first + src.len() + k);
    }
    Written { bounds, invalid, clusters }
}

/// The order to store instances in (indices into `world`) and its runs of
/// [`CLUSTER`]: Morton order of their positions in the box `lo ..= hi`, the
/// invalid ones (no box) last.
fn morton_order(world: &[Option<(Vec3A, Vec3A)>], (lo, hi): (Vec3A, Vec3A)) -> (Vec<u32>, Vec<Range<u32>>) {
    let n = world.len() as u32;
    let mut order: Vec<u32> = (0..n).collect();
    // Sorted when there are runs to make or invalid instances to move last.
    if world.len() > CLUSTER || world.iter().any(Option::is_none) {
        let scale = 1023.0 / (hi - lo).max(Vec3A::splat(1e-6));
        let key = |i: &u32| match world[*i as usize] {
            Some((c, _)) => morton3(((c - lo) * scale).as_uvec3().min(glam::UVec3::splat(1023))),
            None => u32::MAX,
        };
        radsort::sort_by_key(&mut order, key);
    }
    let runs = (0..n).step_by(CLUSTER).map(|s| s..(s + CLUSTER as u32).min(n)).collect();
    (order, runs)
}

/// The order to store a tiled entity's instances in and its tiles: the given
/// order, each tile's invalid instances (no box) after its valid ones.
fn tile_order(tiles: &Tiles, world: &[Option<(Vec3A, Vec3A)>]) -> (Vec<u32>, Vec<Range<u32>>) {
    let ranges: Vec<Range<u32>> = tiles.ranges(world.len() as u32).collect();
    let mut order: Vec<u32> = (0..world.len() as u32).collect();
    for range in &ranges {
        order[range.start as usize..range.end as usize].sort_by_key(|&i| world[i as usize].is_none());
    }
    (order, ranges)
}

/// Centre and half extent of the local box `local` as skinned by `joints` (the
/// box itself for an entity without joints).
fn skinned_box(joints: &[Mat4], local: Aabb) -> (Vec3A, Vec3A) {
    let (c, e) = (Vec3A::from(local.center()), Vec3A::from(local.half_extent()));
    let moved = joints.iter().filter(|j| j.is_finite()).map(|j| transform_aabb(j, c, e));
    let Some((lo, hi)) = moved.fold(None, |acc: Option<(Vec3A, Vec3A)>, (c, e)| {
        let (lo, hi) = acc.unwrap_or((c - e, c + e));
        Some((lo.min(c - e), hi.max(c + e)))
    }) else {
        return (c, e);
    };
    ((lo + hi) * 0.5, (hi - lo) * 0.5)
}

/// Interleave the low 10 bits of x, y and z into a 30-bit Morton code.
fn morton3(v: glam::UVec3) -> u32 {
    fn spread(mut x: u32) -> u32 {
        x &= 0x3ff;
        x = (x | (x << 16)) & 0x0300_00ff;
        x = (x | (x << 8)) & 0x0300_f00f;
        x = (x | (x << 4)) & 0x030c_30c3;
        (x | (x << 2)) & 0x0924_9249
    }
    spread(v.x) | spread(v.y) << 1 | spread(v.z) << 2
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::scene::MaterialId;
    use glam::Vec3;

    fn unit() -> Aabb {
        Aabb { min: Vec3::splat(-0.5), max: Vec3::splat(0.5) }
    }

    fn entity(n: usize) -> Entity {
        Entity::instanced(
            ShapeId(0),
            MaterialId(0),
            (0..n).map(|i| Mat4::from_translation(Vec3::X * i as f32)).collect(),
        )
    }

    #[test]
    fn unchanged_entities_are_not_rewritten_and_moved_ones_are() {
        let mut store = InstanceStore::default();
        let (mut a, b) = (entity(3), entity(2));
        store.submit(&a, unit(), 0);
        store.submit(&b, unit(), 0);
        assert_eq!(store.take_dirty(), vec![0..5], "first frame: both, merged into one range");
        store.submit(&a, unit(), 1);
        store.submit(&b, unit(), 1);
        assert!(store.take_dirty().is_empty(), "nothing changed");
        a.set_transform(1, Mat4::from_translation(Vec3::Y * 9.0));
        let slot = store.submit(&a, unit(), 2);
        store.submit(&b, unit(), 2);
        assert_eq!(store.take_dirty(), vec![0..3], "only the moved entity's range");
        assert_eq!(store.slot(slot).bounds.unwrap().0.y, 4.5, "union of y 0..9 has centre 4.5");
    }

    #[test]
    fn a_resized_entity_moves_and_compaction_drops_what_was_not_submitted() {
        let mut store = InstanceStore::default();
        let mut a = entity(3000);
        let gone = entity(3000);
        store.submit(&a, unit(), 0);
        store.submit(&gone, unit(), 0);
        a.transforms_mut().push(Mat4::IDENTITY);
        let slot = store.submit(&a, unit(), 1);
        assert_eq!(store.slot(slot).first, 6000, "grown entity moved to the end");
        assert_eq!(store.len(), 9001);
        let remap = store.compact_if_wasteful(1).expect("3000 garbage + 3000 stale ≥ half");
        assert_eq!(remap[slot], 0);
        assert_eq!(store.len(), 3001);
        assert_eq!(store.slot(0).first, 0);
        assert_eq!(store.take_dirty(), vec![0..3001]);
        // Instance 0 (at the origin) and the pushed identity, wherever the tiles put them.
        assert_eq!(store.instances.iter().filter(|i| i.transform() == Mat4::IDENTITY).count(), 2);
    }

    #[test]
    fn nan_transforms_are_zeroed_counted_and_never_visible() {
        let mut store = InstanceStore::default();
        let mut e = entity(3);
        e.set_transform(1, Mat4::from_translation(Vec3::new(f32::NAN, 0.0, 0.0)));
        let slot = store.submit(&e, unit(), 0);
        assert_eq!(store.slot(slot).invalid, 1);
        assert_eq!(store.instances[2], InstanceGpu::new(&Mat4::ZERO, MaterialId(0), true), "invalid ones go last");
        assert!(store.instances.iter().all(|i| i.transform().is_finite()));
        assert!(!store.bounds.is_valid(2) && store.bounds.is_valid(0) && store.bounds.is_valid(1));
        let bounds = store.slot(slot).bounds.unwrap();
        assert!(bounds.0.is_finite() && bounds.1.is_finite(), "the union skips the invalid instance");
    }

    #[test]
    fn tiles_are_compact_and_hold_every_instance_once() {
        use rand::{Rng, SeedableRng};
        let mut rng = rand_pcg::Pcg32::seed_from_u64(7);
        let transforms: Vec<Mat4> = (0..1000)
            .map(|_| {
                Mat4::from_translation(Vec3::new(rng.random_range(-100.0..100.0), 0.0, rng.random_range(-100.0..100.0)))
            })
            .collect();
        let e = Entity::instanced(ShapeId(0), MaterialId(0), transforms.clone());
        let mut store = InstanceStore::default();
        let slot = store.submit(&e, unit(), 0);
        let clusters = &store.slot(slot).clusters;
        assert_eq!(clusters.len(), 1000usize.div_ceil(CLUSTER));
        // A permutation: every submitted translation stored exactly once.
        let key = |m: Mat4| (m.w_axis.x.to_bits(), m.w_axis.z.to_bits());
        let mut stored: Vec<_> = store.instances.iter().map(|i| key(i.transform())).collect();
        let mut submitted: Vec<_> = transforms.iter().map(|&m| key(m)).collect();
        stored.sort_unstable();
        submitted.sort_unstable();
        assert_eq!(stored, submitted);
        // Each tile's box holds its instances, and Morton order keeps tiles small:
        // 16 tiles over a 200 × 200 field average far less than the whole field.
        let mut area = 0.0;
        for (k, &Cluster { first, valid, center: c, extent: e, .. }) in clusters.iter().enumerate() {
            assert_eq!((first as usize, valid as usize), (k * CLUSTER, CLUSTER.min(1000 - k * CLUSTER)));
            for i in k * CLUSTER..((k + 1) * CLUSTER).min(1000) {
                let (bc, be) = (store.bounds.center(i), store.bounds.extent(i));
                assert!((bc - be).cmpge(c - e - 1e-3).all() && (bc + be).cmple(c + e + 1e-3).all());
            }
            area += 4.0 * e.x * e.z;
        }
        assert!(area / (clusters.len() as f32) < 0.2 * 200.0 * 200.0, "mean tile area {area}");
    }

    #[test]
    fn tiles_keep_their_order_and_give_every_instance_the_tile_box() {
        // Two tiles of three: x = 0, NaN, 2 and x = 10, 11, 12; padding 0.25.
        let mut e = entity(6);
        e.set_transform(1, Mat4::from_translation(Vec3::NAN));
        for (k, x) in [(3, 10.0), (4, 11.0), (5, 12.0)] {
            e.set_transform(k, Mat4::from_translation(Vec3::X * x));
        }
        let e = e.with_tiles(Tiles::from_sizes([3, 3], 0.25));
        let mut store = InstanceStore::default();
        let index = store.submit(&e, unit(), 0);
        let slot = store.slot(index).clone();
        assert!(slot.tiled);
        let xs: Vec<f32> = store.instances.iter().map(|i| i.transform().w_axis.x).collect();
        assert_eq!(xs, [0.0, 2.0, 0.0, 10.0, 11.0, 12.0], "given order, the invalid one last in its tile (zeroed)");
        let tiles: Vec<(u32, u32)> = slot.clusters.iter().map(|c| (c.first, c.valid)).collect();
        assert_eq!(tiles, [(0, 2), (3, 3)]);
        let pad = 0.25;
        assert_eq!(slot.clusters[0].center, Vec3A::new(1.0, 0.0, 0.0));
        assert_eq!(slot.clusters[0].extent, Vec3A::new(1.5 + pad, 0.5 + pad, 0.5 + pad), "x -0.5..2.5, grown");
        for i in [0, 1, 3, 4, 5] {
            let tile = &slot.clusters[usize::from(i >= 3)];
            assert_eq!((store.bounds.center(i), store.bounds.extent(i)), (tile.center, tile.extent), "instance {i}");
        }
        assert!(!store.bounds.is_valid(2));
        let (c, ext) = slot.bounds.expect("valid instances");
        assert!((c.x - 6.0).abs() < 1e-5 && (ext.x - (6.5 + pad)).abs() < 1e-5, "padded union {c} ± {ext}");
    }

    #[test]
    fn compact_instances_take_a_quarter_record_each_in_tile_order() {
        let e = entity(10).with_tiles(Tiles::from_sizes([6, 4], 0.0)).with_compact_instances();
        let mut store = InstanceStore::default();
        store.submit(&entity(2), unit(), 0);
        let index = store.submit(&e, unit(), 0);
        let slot = store.slot(index).clone();
        assert!(slot.compact && slot.tiled);
        assert_eq!((slot.first, slot.len(), store.len()), (2, 3, 5), "ten in three records after two full ones");
        assert_eq!(slot.instance_base(), 8, "numbered by quarter records");
        let tiles: Vec<(u32, u32)> = slot.clusters.iter().map(|c| (c.first, c.valid)).collect();
        assert_eq!(tiles, [(0, 6), (6, 4)]);
        // Instance 5 (x = 5) is the second record's second quarter.
        let record: [CompactGpu; 4] = bytemuck::cast(store.instances[3]);
        assert_eq!(f32::from_bits(record[1].0[0]), 5.0);
        assert!((2..5).all(|k| !store.bounds.is_valid(k)), "compact records have no box of their own");
        // Not tiled, the request is not taken.
        let index = store.submit(&entity(10).with_compact_instances(), unit(), 0);
        assert!(!store.slot(index).compact);
    }

    #[test]
    fn joint_matrices_follow_their_instances_and_widen_the_bounds() {
        let mut store = InstanceStore::default();
        let lift = Mat4::from_translation(Vec3::Y * 10.0);
        let e = entity(2).with_joints(vec![Mat4::IDENTITY, lift, Mat4::IDENTITY]);
        let other = entity(1);
        store.submit(&other, unit(), 0);
        let slot = store.submit(&e, unit(), 0);
        assert_eq!(store.len(), 1 + 2 + 3, "two instances then three joints");
        let first = store.slot(slot).first as usize;
        for at in first..first + 2 {
            let record = store.instances[at];
            assert_eq!((at as u32 + record.joints, record.joint_count), (first as u32 + 2, 3), "points at joint 0");
        }
        assert_eq!(store.instances[first + 3].transform(), lift, "joints stored in order");
        assert!(!store.bounds.is_valid(first + 2), "joint records are never culled as instances");
        let (c, e) = store.slot(slot).bounds.unwrap();
        assert!((c.y + e.y - 10.5).abs() < 1e-5, "the lifted joint's box counts: top {}", c.y + e.y);
    }

    #[test]
    fn clones_are_separate_entities() {
        let mut store = InstanceStore::default();
        let a = entity(2);
        let b = a.clone();
        assert_ne!(store.submit(&a, unit(), 0), store.submit(&b, unit(), 0));
        assert_eq!(store.len(), 4);
    }
}
