//! Core layer: stage 2 of the frame, which instances each view sees. An entity
//! whose world box is wholly inside or outside the frustum is decided at once;
//! tiles of a crossing entity's instances likewise; only crossing tiles have their
//! instances tested one by one.

use crate::render::cull::{self, Containment, Frustum};
use crate::render::debug::stats::FrameStats;
use crate::render::gpu_driven::commands::Placed;
use crate::render::resources::instances::{InstanceStore, Slot};
use crate::render::resources::Resources;
use crate::render::view::ViewFrame;
use crate::scene::{Culling, FarField, MaterialId, ShapeId};
use glam::Vec3;
use p3_maybe_rayon::prelude::*;

/// An entity as submitted this frame: its store slot and what it draws with.
pub(crate) struct Submitted {
    pub slot: usize,
    pub shape: ShapeId,
    pub material: MaterialId,
    pub render_order: Option<u8>,
    pub cast_shadows: bool,
    /// Its instances.
    pub instances: u64,
    /// The fraction of each tile drawn: the entity's density times the renderer's.
    pub density: f32,
    /// Its material's far field, which draws less of its far tiles.
    pub far_field: Option<FarField>,
}

impl Submitted {
    /// How much of each of its tiles a view whose far fields are measured
    /// from `far_eye` draws.
    pub(crate) fn share(&self, far_eye: Option<Vec3>) -> TileShare {
        TileShare { density: self.density, far: self.far_field.zip(far_eye) }
    }
}

/// How much of each tile of a tiled entity is drawn: the first `density` of
/// it, and no more than a far field (`far`: it and the eye it is measured
/// from) draws where the box of the tile's placed positions comes nearest.
#[derive(Clone, Copy, Debug)]
pub(crate) struct TileShare {
    pub density: f32,
    pub far: Option<(FarField, Vec3)>,
}

impl TileShare {
    /// Every tile's first `density`, no far field.
    #[cfg(test)]
    pub(crate) fn density(density: f32) -> Self {
        Self { density, far: None }
    }

    /// The instances drawn of a tile of `len` whose instances are placed in
    /// the box `center ± extent`.
    fn drawn(self, len: u32, (center, extent): (glam::Vec3A, glam::Vec3A)) -> u32 {
        let drawn = crate::scene::Tiles::drawn(len, self.density);
        let Some((field, eye)) = self.far else { return drawn };
        let nearest = (glam::Vec3A::from(eye) - center).abs() - extent;
        drawn.min(field.drawn(len, nearest.max(glam::Vec3A::ZERO).length()))
    }
}

/// Submitted instances above which entities are culled on all cores. Tiles make
/// culling cheap enough that threads rarely pay: on many.scn (100,000 instances in
/// 100 entities, 2 cores) tiled culling took 0.32 ms serial and 0.45 ms on rayon.
const PARALLEL_ENTITY_CULL_THRESHOLD: u64 = 1 << 20;

/// A submitted entity's visible instances: a range of [`Visible::instances`].
pub(crate) struct VisibleRun {
    /// The entity's index among the frame's submitted entities.
    pub entry: usize,
    /// Its first instance in the list.
    pub start: u32,
    /// How many.
    pub len: u32,
}

/// What one view (or shadow view) sees: the visible instances of the submitted
/// entities in submission order, and each entity's run of them; culled on the
/// GPU, each entity's valid instances, which the GPU tests. Kept by the
/// renderer between frames only to reuse its allocations.
#[derive(Default)]
pub(crate) struct Visible {
    /// Instance slots in the instance store.
    pub instances: Vec<u32>,
    /// One run per entity with any instance visible.
    pub runs: Vec<VisibleRun>,
    /// Runs of store instances, `start` the first in the store: culled on the
    /// GPU, one per entity with any valid instance, or per tile the frustum
    /// sees of a tiled entity ([`Placed::OnGpu`]); culled on the CPU, the
    /// visible tiles of tiled entities, each drawn whole ([`Placed::Whole`]).
    pub ranges: Vec<VisibleRun>,
    /// How each submitted entity's instances reach the draw list, by entry.
    pub placed: Vec<Placed>,
    /// Tiles tested and drawn.
    pub tiles: TileCounts,
}

impl Visible {
    /// Instances kept: listed, and in whole tiles.
    pub(crate) fn kept(&self) -> u64 {
        let whole = self.ranges.iter().filter(|r| matches!(self.placed[r.entry], Placed::Whole | Placed::Compact));
        self.instances.len() as u64 + whole.map(|r| u64::from(r.len)).sum::<u64>()
    }
}

/// Tiles tested against a frustum, and tiles with any instance kept.
#[derive(Clone, Copy, Debug, Default)]
pub(crate) struct TileCounts {
    pub tested: u64,
    pub drawn: u64,
}

impl std::ops::AddAssign for TileCounts {
    fn add_assign(&mut self, other: Self) {
        (self.tested, self.drawn) = (self.tested + other.tested, self.drawn + other.drawn);
    }
}

/// The submitted entities a view may draw: all but those whose materials
/// show `hides`, the view's own render target, which it is drawing. A plain
/// list of materials, so that the test crosses rayon's threads (the renderer
/// is not `Sync` on the WebGPU page).
pub(crate) struct Shown(Vec<bool>);

impl Shown {
    /// Whether the view may draw `s`.
    pub(crate) fn contains(&self, s: &Submitted) -> bool {
        !self.0.get(s.material.0 as usize).copied().unwrap_or(false)
    }
}

/// What a view that draws into the render target shown by `hides` may draw.
pub(crate) fn shown(res: &Resources, hides: Option<crate::scene::TextureId>) -> Shown {
    let Some(texture) = hides else { return Shown(Vec::new()) };
    let materials = 0..res.registry.materials.len() as u32;
    Shown(materials.map(|m| res.registry.shows(crate::scene::MaterialId(m), texture)).collect())
}

/// Stage 3 of a view: each of the `submitted` entities' instances that
/// `view` sees (not those whose materials show its own target), into
/// `visible`. An entity whose world box is wholly inside or outside the
/// frustum is decided at once; only boxes crossing a plane have their
/// instances tested one by one.
pub(crate) fn cull(
    res: &Resources,
    (submitted, visible): (&[Submitted], &mut Visible),
    view: &ViewFrame,
    stats: &mut FrameStats,
) {
    let shown = shown(res, view.hides);
    collect_visible(res, (&view.frustum, view.culling, view.far_eye), (submitted, |s| shown.contains(s)), visible);
    let store = &res.store;
    let drawn = submitted.iter().filter(|s| shown.contains(s));
    stats.instances_invalid = drawn.map(|s| u64::from(store.slot(s.slot).invalid)).sum();
    stats.instances_culled = stats.instances_submitted - stats.instances_invalid - visible.kept();
    (stats.tiles_tested, stats.tiles_drawn) = (visible.tiles.tested, visible.tiles.drawn);
    stats.culling = view.culling;
}

/// Fill `out` with the instances of the submitted entities `wanted` keeps
/// that `frustum` sees (every valid one when `culling` is off): listed, or
/// as runs of instances (whole tiles, compact ones whatever the culling;
/// culling on the GPU, the candidates of the entities not blended), as
/// `out.placed` says.
pub(crate) fn collect_visible(
    res: &Resources,
    (frustum, culling, far_eye): (&Frustum, Culling, Option<Vec3>),
    (submitted, wanted): (&[Submitted], impl Fn(&Submitted) -> bool + Sync),
    out: &mut Visible,
) {
    out.instances.clear();
    out.runs.clear();
    out.ranges.clear();
    out.tiles = TileCounts::default();
    let store = &res.store;
    let blended: Vec<bool> =
        (0..res.registry.materials.len() as u32).map(|m| res.registry.blended(crate::scene::MaterialId(m))).collect();
    out.placed.clear();
    out.placed.extend(submitted.iter().map(|s| match blended[s.material.0 as usize] {
        _ if store.slot(s.slot).compact => Placed::Compact,
        true => Placed::Listed,
        false if culling == Culling::Gpu => Placed::OnGpu,
        false if store.slot(s.slot).tiled => Placed::Whole,
        false => Placed::Listed,
    }));
    let frustum_on = culling != Culling::Off;
    for (entry, s) in submitted.iter().enumerate().filter(|&(k, s)| out.placed[k] != Placed::Listed && wanted(s)) {
        let slot = store.slot(s.slot);
        let ranges = &mut out.ranges;
        if slot.tiled {
            // The GPU culls by the same boxes: every instance carries its
            // tile's (compact ones are culled here alone).
            out.tiles += visible_tiles(frustum, frustum_on, slot, s.share(far_eye), |r| {
                ranges.push(VisibleRun { entry, start: r.start, len: r.end - r.start });
            });
        } else if slot.count > slot.invalid {
            ranges.push(VisibleRun { entry, start: slot.first, len: slot.count - slot.invalid });
        }
    }
    let placed = &out.placed;
    let listed = |entry: usize, s: &Submitted| placed[entry] == Placed::Listed && wanted(s);
    let culling = frustum_on;
    let (visible, runs, tiles) = (&mut out.instances, &mut out.runs, &mut out.tiles);
    let mut push_run = |entry: usize, visible: &mut Vec<u32>, start: usize| {
        let len = (visible.len() - start) as u32;
        if len > 0 {
            runs.push(VisibleRun { entry, start: start as u32, len });
        }
    };
    if submitted.len() > 1 && submitted.iter().map(|s| s.instances).sum::<u64>() >= PARALLEL_ENTITY_CULL_THRESHOLD {
        // Many instances: entities culled on all cores, results kept in submission order.
        let lists: Vec<(Vec<u32>, TileCounts)> = submitted
            .par_iter()
            .enumerate()
            .map(|(entry, s)| {
                let mut list = Vec::new();
                let mut counts = TileCounts::default();
                if listed(entry, s) {
                    counts =
                        visible_instances(frustum, culling, store.slot(s.slot), s.share(far_eye), (store, &mut list));
                }
                (list, counts)
            })
            .collect();
        for (entry, (list, counts)) in lists.into_iter().enumerate() {
            let start = visible.len();
            visible.extend_from_slice(&list);
            push_run(entry, visible, start);
            *tiles += counts;
        }
    } else {
        for (entry, s) in submitted.iter().enumerate() {
            let start = visible.len();
            if listed(entry, s) {
                *tiles += visible_instances(frustum, culling, store.slot(s.slot), s.share(far_eye), (store, visible));
            }
            push_run(entry, visible, start);
        }
    }
}

/// Append the instances of `slot` (an entity's range) that `frustum` sees to
/// `out`, as store indices; with `culling` off, every valid one. An entity box
/// wholly inside or outside decides at once, else its clusters are tested, and
/// only the instances of clusters crossing a plane one by one. A tiled entity's
/// tiles are culled whole, `share` of each drawn ([`visible_tiles`]).
/// Invalid instances are never appended.
pub(crate) fn visible_instances(
    frustum: &Frustum,
    culling: bool,
    slot: &Slot,
    share: TileShare,
    (store, out): (&InstanceStore, &mut Vec<u32>),
) -> TileCounts {
    if slot.tiled {
        return visible_tiles(frustum, culling, slot, share, |range| out.extend(range));
    }
    let valid = slot.first..slot.first + slot.count - slot.invalid;
    let test = |range: std::ops::Range<u32>, out: &mut Vec<u32>| {
        cull::cull_boxes(frustum, &store.bounds, range.start as usize..range.end as usize, out);
    };
    match containment(frustum, culling, slot) {
        Containment::Outside => {}
        Containment::Inside => out.extend(valid),
        Containment::Intersecting if slot.clusters.is_empty() => test(valid, out),
        Containment::Intersecting => {
            for cluster in &slot.clusters {
                let start = slot.first + cluster.first;
                let run = start..start + cluster.valid;
                match frustum.classify(cluster.center, cluster.extent) {
                    Containment::Outside => {}
                    Containment::Inside => out.extend(run),
                    Containment::Intersecting => test(run, out),
                }
            }
        }
    }
    TileCounts::default()
}

/// Give `keep` the store range of each tile of tiled `slot` that `frustum`
/// sees (every tile with `culling` off), cut to its first instances as
/// `share` says; empty ones are not given. Returns the tiles tested and kept.
fn visible_tiles(
    frustum: &Frustum,
    culling: bool,
    slot: &Slot,
    share: TileShare,
    mut keep: impl FnMut(std::ops::Range<u32>),
) -> TileCounts {
    let mut counts = TileCounts::default();
    let whole = match containment(frustum, culling, slot) {
        Containment::Outside => return counts,
        Containment::Inside => true,
        Containment::Intersecting => false,
    };
    for tile in &slot.clusters {
        let drawn = share.drawn(tile.valid, tile.origins);
        if drawn == 0 {
            continue;
        }
        if !whole {
            counts.tested += 1;
            if frustum.classify(tile.center, tile.extent) == Containment::Outside {
                continue;
            }
        }
        counts.drawn += 1;
        let start = slot.instance_base() + tile.first;
        keep(start..start + drawn);
    }
    counts
}

/// Where `slot`'s entity box lies (inside with `culling` off; outside when it
/// has no valid instance).
fn containment(frustum: &Frustum, culling: bool, slot: &Slot) -> Containment {
    match slot.bounds {
        None => Containment::Outside,
        Some(_) if !culling => Containment::Inside,
        Some((c, e)) => frustum.classify(c, e),
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::scene::{Camera, Entity, MaterialId, ShapeId};
    use glam::{Mat4, Vec3};

    #[test]
    fn tiled_culling_keeps_exactly_the_instances_a_per_instance_test_keeps() {
        use rand::{Rng, SeedableRng};
        let mut rng = rand_pcg::Pcg32::seed_from_u64(3);
        let mut transforms: Vec<Mat4> = (0..5000)
            .map(|_| {
                let p = Vec3::new(
                    rng.random_range(-60.0..60.0),
                    rng.random_range(-5.0..5.0),
                    rng.random_range(-60.0..60.0),
                );
                Mat4::from_scale_rotation_translation(Vec3::splat(rng.random_range(0.1..3.0)), glam::Quat::IDENTITY, p)
            })
            .collect();
        for k in (0..5000).step_by(97) {
            transforms[k] = Mat4::from_translation(Vec3::new(f32::NAN, 0.0, 0.0));
        }
        let e = Entity::instanced(ShapeId(0), MaterialId(0), transforms);
        let cube = crate::scene::Aabb { min: Vec3::splat(-0.5), max: Vec3::splat(0.5) };
        let mut store = InstanceStore::default();
        let slot = store.submit(&e, cube, 0);
        assert!(!store.slot(slot).clusters.is_empty());
        for (eye, target) in
            [(Vec3::new(0.0, 3.0, -70.0), Vec3::ZERO), (Vec3::new(10.0, 2.0, 5.0), Vec3::new(40.0, 0.0, 30.0))]
        {
            let camera = Camera::perspective(60.0, 0.5, 80.0).looking_at(eye, target);
            let frustum = Frustum::from_view_proj(camera.projection(1.5) * camera.view());
            let mut tiled = Vec::new();
            visible_instances(&frustum, true, store.slot(slot), TileShare::density(1.0), (&store, &mut tiled));
            tiled.sort_unstable();
            let each: Vec<u32> = (0..5000u32)
                .filter(|&i| store.bounds.is_valid(i as usize))
                .filter(|&i| frustum.intersects(store.bounds.center(i as usize), store.bounds.extent(i as usize)))
                .collect();
            assert!(!each.is_empty() && each.len() < 4900, "a partial view: {}", each.len());
            assert_eq!(tiled, each);
        }
    }

    /// A box: centre and half extent.
    type Box3 = (glam::Vec3A, glam::Vec3A);

    /// 20,000 unit cubes at random over 200 × 200 (one in 97 invalid), sorted
    /// into 8 × 8 tiles in random order inside each: the entity and each
    /// instance's own box.
    fn tiled_field(padding: f32) -> (Entity, Vec<Option<Box3>>, Vec<u32>) {
        use rand::{Rng, SeedableRng};
        let mut rng = rand_pcg::Pcg32::seed_from_u64(11);
        let mut placed: Vec<(u32, Vec3)> = (0..20_000)
            .map(|_| {
                let p = Vec3::new(rng.random_range(-100.0..100.0), 0.0, rng.random_range(-100.0..100.0));
                let cell = |v: f32| (((v + 100.0) / 25.0) as u32).min(7);
                (cell(p.x) + 8 * cell(p.z), p)
            })
            .collect();
        placed.sort_by_key(|&(tile, _)| tile);
        let mut sizes = vec![0u32; 64];
        placed.iter().for_each(|&(tile, _)| sizes[tile as usize] += 1);
        let mut transforms: Vec<Mat4> = placed.iter().map(|&(_, p)| Mat4::from_translation(p)).collect();
        for k in (0..transforms.len()).step_by(97) {
            transforms[k] = Mat4::from_translation(Vec3::NAN);
        }
        let own = transforms
            .iter()
            .map(|m| m.is_finite().then(|| (glam::Vec3A::from(m.w_axis.truncate()), glam::Vec3A::splat(0.5))))
            .collect();
        let tiles = crate::scene::Tiles::from_sizes(sizes.iter().copied(), padding);
        (Entity::instanced(ShapeId(0), MaterialId(0), transforms).with_tiles(tiles), own, sizes)
    }

    #[test]
    fn tiles_keep_what_each_instance_keeps_plus_their_padding_whole() {
        let padding = 1.0;
        let (e, own, sizes) = tiled_field(padding);
        let cube = crate::scene::Aabb { min: Vec3::splat(-0.5), max: Vec3::splat(0.5) };
        let mut store = InstanceStore::default();
        let slot = store.submit(&e, cube, 0);
        let first = store.slot(slot).first;
        // Which tile each stored instance is in (the store keeps the given order
        // inside a tile, moving invalid ones last: same tile either way).
        let tile_of: Vec<usize> =
            (sizes.iter().enumerate()).flat_map(|(t, &n)| std::iter::repeat_n(t, n as usize)).collect();
        let camera =
            Camera::perspective(50.0, 0.5, 90.0).looking_at(Vec3::new(-30.0, 20.0, -60.0), Vec3::new(10.0, 0.0, 0.0));
        let frustum = Frustum::from_view_proj(camera.projection(1.5) * camera.view());
        let mut kept = Vec::new();
        let counts = visible_instances(&frustum, true, store.slot(slot), TileShare::density(1.0), (&store, &mut kept));
        let kept: std::collections::BTreeSet<u32> = kept.into_iter().map(|i| i - first).collect();
        // Each tile's box from the instances' own boxes, grown by the padding.
        let mut boxes = vec![(glam::Vec3A::splat(f32::INFINITY), glam::Vec3A::splat(f32::NEG_INFINITY)); 64];
        for (i, b) in own.iter().enumerate() {
            if let Some((c, e)) = b {
                let t = &mut boxes[tile_of[i]];
                (t.0, t.1) = (t.0.min(c - e), t.1.max(c + e));
            }
        }
        let seen: Vec<bool> =
            boxes.iter().map(|(lo, hi)| frustum.intersects((lo + hi) * 0.5, (hi - lo) * 0.5 + padding)).collect();
        let store_index = |i: usize| -> u32 {
            // Stored position of given instance i: its tile's start, then valid first.
            let start: u32 = sizes[..tile_of[i]].iter().sum();
            let before = (start as usize..i).filter(|&k| own[k].is_some()).count() as u32;
            start + before
        };
        let mut expected = std::collections::BTreeSet::new();
        let mut each = 0;
        for (i, b) in own.iter().enumerate() {
            let Some((c, e)) = *b else { continue };
            if frustum.intersects(c, e) {
                each += 1;
                assert!(seen[tile_of[i]], "instance {i} seen alone, its tile too");
            }
            if seen[tile_of[i]] {
                expected.insert(store_index(i));
            }
        }
        assert!(each > 500 && each < 15_000, "a partial view: {each}");
        assert_eq!(kept, expected, "whole tiles: every valid instance of each tile seen");
        let drawn = seen.iter().filter(|&&s| s).count() as u64;
        assert_eq!((counts.tested, counts.drawn), (64, drawn));
        assert!(drawn < 64, "some tiles culled whole");
    }

    #[test]
    fn density_keeps_the_first_fraction_of_every_tile() {
        let (e, own, sizes) = tiled_field(0.0);
        let cube = crate::scene::Aabb { min: Vec3::splat(-0.5), max: Vec3::splat(0.5) };
        let mut store = InstanceStore::default();
        let slot = store.submit(&e, cube, 0);
        let frustum = Frustum::from_view_proj(Mat4::IDENTITY);
        let valid = own.iter().filter(|b| b.is_some()).count() as f64;
        for density in [1.0, 0.5, 0.25, 0.0] {
            let mut kept = Vec::new();
            let counts =
                visible_instances(&frustum, false, store.slot(slot), TileShare::density(density), (&store, &mut kept));
            let mut start = 0;
            let mut expected = Vec::new();
            for (tile, &n) in store.slot(slot).clusters.iter().zip(&sizes) {
                assert_eq!(tile.first, start);
                let drawn = (f64::from(tile.valid) * f64::from(density)).ceil() as u32;
                expected.extend(tile.first..tile.first + drawn);
                start += n;
            }
            let kept: Vec<u32> = kept.into_iter().map(|i| i - store.slot(slot).first).collect();
            assert_eq!(kept, expected, "density {density}");
            let wanted = valid * f64::from(density);
            assert!((kept.len() as f64 - wanted).abs() <= 64.0, "{} for {wanted}", kept.len());
            assert_eq!(counts.tested, 0, "culling off tests no tile");
            assert_eq!(counts.drawn, if density > 0.0 { 64 } else { 0 });
        }
    }
}
