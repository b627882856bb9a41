//! Core layer: choosing levels of detail ([`crate::scene::levels`]) per
//! instance and view. The rule, here and in `shader/cull.wgsl` term for term:
//! an instance whose world box has centre `c` and half-extent `e` (radius
//! `r = |e|`) is drawn at the coarsest level whose error, `error × r` world
//! units, projects to at most the view's allowed pixels at the box's nearest
//! depth. The projected size of a world length at a point is
//! `length × scale / w`, with `w` the point's clip w (row 3 of the
//! view-projection, which is 1 everywhere for an orthographic view) and
//! `scale` half the viewport's height in pixels times the length of row 1's
//! xyz (the projection's y scale). A box reaching the eye plane draws at full
//! detail.

use crate::render::cull::Boxes;
use crate::render::gpu_driven::commands::Placed;
use crate::render::resources::mesh_pool::Levels;
use crate::scene::levels::MAX_LEVELS;
use glam::{Mat4, Vec3A, Vec4};

/// A draw item's level when the GPU picks each instance's in its cull pass.
pub(crate) const LEVEL_ON_GPU: u8 = u8::MAX;

/// Shadow views allow this many times the view's error, in their map's
/// texels: filtering blurs a shadow's edge over several.
pub(crate) const SHADOW_ERROR_FACTOR: f32 = 2.0;

/// How one view picks levels.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub(crate) struct LodView {
    /// Row 3 of the view-projection matrix: a world point's clip w.
    pub w_row: Vec4,
    /// Pixels a world unit covers at w = 1, over the pixels of error allowed;
    /// 0 draws every instance at full detail.
    pub scale: f32,
}

impl LodView {
    /// A view through `view_proj` drawn `height` pixels high that allows
    /// `error_px` pixels of error (0 or less: full detail everywhere).
    pub(crate) fn new(view_proj: Mat4, height: u32, error_px: f32) -> Self {
        let scale = match error_px > 0.0 {
            true => 0.5 * height as f32 * view_proj.row(1).truncate().length() / error_px,
            false => 0.0,
        };
        Self { w_row: view_proj.row(3), scale }
    }

    /// A view through `view_proj` whose pixels (a shadow map's texels) are
    /// `texel` world units across at w = 1, allowing `error_px` of them.
    pub(crate) fn texels(view_proj: Mat4, texel: f32, error_px: f32) -> Self {
        let scale = if error_px > 0.0 && texel > 0.0 { 1.0 / (texel * error_px) } else { 0.0 };
        Self { w_row: view_proj.row(3), scale }
    }

    /// Full detail everywhere.
    pub(crate) fn full_detail() -> Self {
        Self::default()
    }

    /// The level a box `center ± extent` of a shape with `levels` draws at.
    pub(crate) fn level(&self, levels: &Levels, center: Vec3A, extent: Vec3A) -> u8 {
        if levels.count <= 1 || self.scale <= 0.0 {
            return 0;
        }
        let radius = extent.length();
        let w = self.w_row.dot(center.extend(1.0)) - radius * self.w_row.truncate().length();
        // The error, in world units, a level may make here.
        let allowed = w / (radius * self.scale);
        if allowed.is_nan() || allowed <= 0.0 {
            return 0;
        }
        (1..levels.count).rev().find(|&l| levels.error[usize::from(l)] <= allowed).unwrap_or(0)
    }

    /// The GPU's copy: `w_row`, then `scale` and padding.
    pub(crate) fn to_gpu(self) -> [[f32; 4]; 2] {
        [self.w_row.to_array(), [self.scale, 0.0, 0.0, 0.0]]
    }
}

/// The draw items of one visible run of a shape with `levels`, `count`
/// instances from `first`, as `(level, first, count)` given to `item`:
/// placed `Listed`, entries `first ..` of the view's visible list `visible`,
/// reordered so that each level's are adjacent, finest first, an item per
/// level used; a whole tile at its box's level; GPU-culled candidates at
/// [`LEVEL_ON_GPU`] where the shape has levels; compact instances at full detail.
pub(crate) fn level_items(
    lod: &LodView,
    levels: &Levels,
    (placed, first, count): (Placed, u32, u32),
    (visible, bounds): (&mut [u32], &Boxes),
    mut item: impl FnMut(u8, u32, u32),
) {
    let chosen = |i: u32| lod.level(levels, bounds.center(i as usize), bounds.extent(i as usize));
    match placed {
        _ if levels.count <= 1 || lod.scale <= 0.0 => item(0, first, count),
        Placed::OnGpu => item(LEVEL_ON_GPU, first, count),
        Placed::Compact => item(0, first, count),
        // A tile's instances all carry its box.
        Placed::Whole => item(chosen(first), first, count),
        Placed::Listed => {
            let instances = &mut visible[first as usize..(first + count) as usize];
            let chosen: Vec<u8> = instances.iter().map(|&i| chosen(i)).collect();
            let mut per_level = [0u32; MAX_LEVELS];
            for &l in &chosen {
                per_level[usize::from(l)] += 1;
            }
            if per_level[usize::from(chosen[0])] == count {
                return item(chosen[0], first, count);
            }
            // A counting sort: each level's place starts after the finer levels'.
            let mut at = [0u32; MAX_LEVELS];
            for l in 1..MAX_LEVELS {
                at[l] = at[l - 1] + per_level[l - 1];
            }
            let mut sorted = vec![0u32; instances.len()];
            for (&i, &l) in instances.iter().zip(&chosen) {
                sorted[at[usize::from(l)] as usize] = i;
                at[usize::from(l)] += 1;
            }
            instances.copy_from_slice(&sorted);
            let mut start = first;
            for (l, &n) in per_level.iter().enumerate().filter(|(_, &n)| n > 0) {
                item(l as u8, start, n);
                start += n;
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::scene::Camera;
    use glam::Vec3;

    fn levels() -> Levels {
        Levels { count: 3, error: [0.0, 0.01, 0.1, 0.0, 0.0], ..Levels::default() }
    }

    #[test]
    fn near_boxes_draw_full_detail_and_far_ones_coarser() {
        let camera = Camera::perspective(60.0, 0.1, 5000.0).looking_at(Vec3::ZERO, -Vec3::Z);
        let view_proj = camera.projection(1.0) * camera.view();
        let lod = LodView::new(view_proj, 256, 1.0);
        let at = |z: f32| lod.level(&levels(), Vec3A::new(0.0, 0.0, -z), Vec3A::splat(0.5));
        let chosen: Vec<u8> = [1.0, 10.0, 100.0, 1000.0].map(at).to_vec();
        assert_eq!(chosen[0], 0);
        assert!(chosen.windows(2).all(|w| w[0] <= w[1]), "{chosen:?}");
        assert_eq!(chosen[3], 2, "{chosen:?}");
        // A box around the eye, and LOD off, draw full detail.
        assert_eq!(lod.level(&levels(), Vec3A::ZERO, Vec3A::splat(0.5)), 0);
        assert_eq!(LodView::full_detail().level(&levels(), Vec3A::new(0.0, 0.0, -1000.0), Vec3A::splat(0.5)), 0);
    }

    #[test]
    fn an_orthographic_view_picks_by_size_alone() {
        let camera = Camera::orthographic(100.0, 0.1, 100.0).looking_at(Vec3::ZERO, -Vec3::Z);
        let lod = LodView::new(camera.projection(1.0) * camera.view(), 1024, 1.0);
        // 1024 px over 100 units: a radius-0.87 box at level 2 is off 0.087 units, 0.9 px.
        assert_eq!(lod.level(&levels(), Vec3A::new(0.0, 0.0, -10.0), Vec3A::splat(0.5)), 2);
        // A radius-86.6 box: level 1 is off 0.87 units, 8.9 px.
        assert_eq!(lod.level(&levels(), Vec3A::new(0.0, 0.0, -90.0), Vec3A::splat(50.0)), 0);
    }

    #[test]
    fn a_listed_run_is_split_by_level_keeping_order_within_each() {
        let camera = Camera::perspective(60.0, 0.1, 5000.0).looking_at(Vec3::ZERO, -Vec3::Z);
        let lod = LodView::new(camera.projection(1.0) * camera.view(), 256, 1.0);
        let mut bounds = Boxes::default();
        bounds.resize(4);
        for (i, z) in [1000.0, 1.0, 1000.0, 1.0].into_iter().enumerate() {
            bounds.set(i, Vec3A::new(0.0, 0.0, -z), Vec3A::splat(0.5));
        }
        // Entries 10 .. 14 of the visible list.
        let mut visible: Vec<u32> = [9; 10].into_iter().chain([0, 1, 2, 3]).collect();
        let mut items = Vec::new();
        level_items(&lod, &levels(), (Placed::Listed, 10, 4), (&mut visible, &bounds), |l, f, n| items.push((l, f, n)));
        let instances = &visible[10..];
        assert_eq!(instances, vec![1, 3, 0, 2]);
        assert_eq!(items, vec![(0, 10, 2), (2, 12, 2)]);
    }
}
