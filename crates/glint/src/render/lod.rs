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
//!
//! A camera view cross-fades: where the next coarser level's error is within
//! [`FADE_BAND`] of being allowed, the instance is drawn at both levels, the
//! coarser on q of every 16 pixels of a 4 × 4 ordered-dither pattern and the
//! finer on the others (q growing from 0 to 15 across the band), so a level
//! never pops in and no pixel shows both. The fade rides in the draw index's
//! top bits ([`FADE_SHIFT`]); the fragment shader (`LOD_FADE`) drops the
//! other level's pixels. Shadow views, blended instances and whole tiles pick
//! one level.

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

/// How far below being allowed a coarser level starts fading in, as a
/// fraction of the error allowed: from an allowed error of its own over
/// 1 + `FADE_BAND`. A fading instance is drawn twice, and its pipeline drops
/// pixels (no early depth test): on the underwater scene (24,000 fish) a band
/// of 0.1 drew 6 % more triangles and cost 4–6 % of the frame, 0.25 drew 14 %
/// more.
pub(crate) const FADE_BAND: f32 = 0.1;

/// A draw index's store index is its low `FADE_SHIFT` bits; above them, its
/// fade: bit 0 set on the coarser copy, bits 1..=4 the q of 16 pixels the
/// coarser draws (0: not fading).
pub(crate) const FADE_SHIFT: u32 = 27;

/// The store index of a draw index (its fade bits dropped).
pub(crate) const INDEX_MASK: u32 = (1 << FADE_SHIFT) - 1;

/// How one view picks levels.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub(crate) struct LodView {
    /// Row 3 of the view-projection matrix: a world point's clip w.
    pub w_row: Vec4,
    /// Pixels a world unit covers at w = 1, over the pixels of error allowed;
    /// 0 draws every instance at full detail.
    pub scale: f32,
    /// The band its instances cross-fade over ([`FADE_BAND`]; 0: none).
    pub fade_band: f32,
}

/// An instance's level in a view, and how far it has faded into the next
/// coarser: that level draws `fade` of every 16 pixels (0: not fading).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub(crate) struct Pick {
    pub level: u8,
    pub fade: u8,
}

impl Pick {
    /// The draw index of store instance `index` drawn at the picked level
    /// (`coarser` false) or at the next (true): the fade above the index.
    pub(crate) fn draw_index(self, index: u32, coarser: bool) -> u32 {
        match self.fade {
            0 => index,
            q => index | (u32::from(q) << (FADE_SHIFT + 1)) | (u32::from(coarser) << FADE_SHIFT),
        }
    }
}

/// Whether the pixel at `(x, y)` is the coarser level's in a fade of `q` of
/// 16: its place in the 4 × 4 ordered-dither (Bayer) matrix is under `q`
/// (forward.wgsl `lod_dithered_out` reads the same).
#[cfg(test)]
fn coarser_pixel(x: u32, y: u32, q: u32) -> bool {
    let bayer2 = |x: u32, y: u32| ((x ^ y) << 1) | y;
    let order = (bayer2(x & 1, y & 1) << 2) | bayer2((x >> 1) & 1, (y >> 1) & 1);
    order < q
}

impl LodView {
    /// A view through `view_proj` drawn `height` pixels high that allows
    /// `error_px` pixels of error (0 or less: full detail everywhere).
    pub(crate) fn new(view_proj: Mat4, height: u32, error_px: f32) -> Self {
        let scale = match error_px > 0.0 {
            true => 0.5 * height as f32 * view_proj.row(1).truncate().length() / error_px,
            false => 0.0,
        };
        Self { w_row: view_proj.row(3), scale, fade_band: FADE_BAND }
    }

    /// A view through `view_proj` whose pixels (a shadow map's texels) are
    /// `texel` world units across at w = 1, allowing `error_px` of them.
    pub(crate) fn texels(view_proj: Mat4, texel: f32, error_px: f32) -> Self {
        let scale = if error_px > 0.0 && texel > 0.0 { 1.0 / (texel * error_px) } else { 0.0 };
        Self { w_row: view_proj.row(3), scale, fade_band: 0.0 }
    }

    /// The level a box `center ± extent` of a shape with `levels` draws at,
    /// not fading.
    pub(crate) fn level(&self, levels: &Levels, center: Vec3A, extent: Vec3A) -> u8 {
        self.pick(levels, center, extent).level
    }

    /// The level a box `center ± extent` of a shape with `levels` draws at,
    /// and its fade into the next coarser (`cull.wgsl` `pick_of`, term for term).
    pub(crate) fn pick(&self, levels: &Levels, center: Vec3A, extent: Vec3A) -> Pick {
        if levels.count <= 1 || self.scale <= 0.0 {
            return Pick::default();
        }
        let radius = extent.length();
        let w = self.w_row.dot(center.extend(1.0)) - radius * self.w_row.truncate().length();
        // The error, in world units, a level may make here.
        let allowed = w / (radius * self.scale);
        if allowed.is_nan() || allowed <= 0.0 {
            return Pick::default();
        }
        let level = (1..levels.count).rev().find(|&l| levels.error[usize::from(l)] <= allowed).unwrap_or(0);
        let next = usize::from(level) + 1;
        if self.fade_band <= 0.0 || next >= usize::from(levels.count) {
            return Pick { level, fade: 0 };
        }
        let band = self.fade_band;
        let coarser = (allowed / levels.error[next] * (1.0 + band) - 1.0) / band;
        Pick { level, fade: ((coarser.clamp(0.0, 1.0) * 16.0) as u8).min(15) }
    }

    /// The GPU's copy: `w_row`, then `scale`, the fade band and padding.
    pub(crate) fn to_gpu(self) -> [[f32; 4]; 2] {
        [self.w_row.to_array(), [self.scale, self.fade_band, 0.0, 0.0]]
    }
}

/// The draw items of one visible run of a shape with `levels`, `count`
/// instances from `first`, as `(level, first, count, copies)` given to
/// `item`: placed `Listed`, entries `first ..` of the view's visible list
/// `visible`, reordered so that each level's are adjacent, finest first, an
/// item per level used, and after each level's own the coarser copies of the
/// instances fading into it (`copies` true; the run then moves to the list's
/// end, its entries with their fade bits: [`Pick::draw_index`]); a whole tile
/// at its box's level; GPU-culled candidates at [`LEVEL_ON_GPU`] where the
/// shape has levels; compact instances at full detail.
pub(crate) fn level_items(
    lod: &LodView,
    levels: &Levels,
    (placed, first, count): (Placed, u32, u32),
    (visible, bounds): (&mut Vec<u32>, &Boxes),
    mut item: impl FnMut(u8, u32, u32, bool),
) {
    let pick = |i: u32| lod.pick(levels, bounds.center(i as usize), bounds.extent(i as usize));
    match placed {
        _ if levels.count <= 1 || lod.scale <= 0.0 => item(0, first, count, false),
        Placed::OnGpu => item(LEVEL_ON_GPU, first, count, false),
        Placed::Compact => item(0, first, count, false),
        // A tile's instances all carry its box.
        Placed::Whole => item(pick(first).level, first, count, false),
        Placed::Listed => {
            let run = first as usize..(first + count) as usize;
            let picks: Vec<Pick> = visible[run.clone()].iter().map(|&i| pick(i)).collect();
            // Group 2l holds level l's own instances, 2l + 1 the copies fading into it.
            let mut per_group = [0u32; 2 * MAX_LEVELS];
            for p in &picks {
                per_group[2 * usize::from(p.level)] += 1;
                if p.fade > 0 {
                    per_group[2 * usize::from(p.level) + 3] += 1;
                }
            }
            let copies = per_group.iter().skip(1).step_by(2).sum::<u32>();
            if copies == 0 && per_group[2 * usize::from(picks[0].level)] == count {
                return item(picks[0].level, first, count, false);
            }
            // A counting sort: each group's place starts after the ones before.
            let mut at = [0u32; 2 * MAX_LEVELS];
            for g in 1..at.len() {
                at[g] = at[g - 1] + per_group[g - 1];
            }
            let mut sorted = vec![0u32; (count + copies) as usize];
            for (&i, p) in visible[run.clone()].iter().zip(&picks) {
                let g = 2 * usize::from(p.level);
                sorted[at[g] as usize] = p.draw_index(i, false);
                at[g] += 1;
                if p.fade > 0 {
                    sorted[at[g + 3] as usize] = p.draw_index(i, true);
                    at[g + 3] += 1;
                }
            }
            let mut start = match copies {
                0 => {
                    visible[run].copy_from_slice(&sorted);
                    first
                }
                _ => {
                    visible.extend_from_slice(&sorted);
                    (visible.len() - sorted.len()) as u32
                }
            };
            for (g, &n) in per_group.iter().enumerate().filter(|(_, &n)| n > 0) {
                item((g / 2) as u8, start, n, g % 2 == 1);
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
        let off = LodView::new(camera.projection(1.0) * camera.view(), 256, 0.0);
        assert_eq!(off.level(&levels(), Vec3A::new(0.0, 0.0, -1000.0), Vec3A::splat(0.5)), 0);
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
    fn a_fade_gives_the_coarser_level_q_of_every_16_pixels_and_the_finer_the_rest() {
        for q in 0..16u32 {
            for (bx, by) in [(0u32, 0u32), (4, 8), (12, 4)] {
                let block = (0..16).map(|k| (bx + k % 4, by + k / 4));
                let coarser = block.filter(|&(x, y)| coarser_pixel(x, y, q)).count() as u32;
                assert_eq!(coarser, q, "fade {q}, block at ({bx}, {by})");
            }
        }
        // Each step adds pixels, never moves them: a growing fade shows no flicker.
        assert!((0..15).all(|q| (0..16).all(|k| !coarser_pixel(k % 4, k / 4, q) || coarser_pixel(k % 4, k / 4, q + 1))));
        let wgsl = include_str!("../shader/forward.wgsl");
        assert!(wgsl.contains(&format!("const FADE_SHIFT: u32 = {FADE_SHIFT}u;")));
    }

    #[test]
    fn an_instance_fades_into_the_coarser_level_across_the_band_before_it_switches() {
        let camera = Camera::perspective(60.0, 0.1, 5000.0).looking_at(Vec3::ZERO, -Vec3::Z);
        let lod = LodView::new(camera.projection(1.0) * camera.view(), 256, 1.0);
        let picks: Vec<Pick> = (20..100_000)
            .map(|z| lod.pick(&levels(), Vec3A::new(0.0, 0.0, -(z as f32) * 0.01), Vec3A::splat(0.5)))
            .collect();
        // Further on, a level's fade only grows, then the next level takes over.
        for w in picks.windows(2) {
            let (a, b) = (w[0], w[1]);
            assert!(b.level > a.level || (b.level == a.level && b.fade >= a.fade), "{a:?} then {b:?}");
            if b.level > a.level {
                assert!(a.fade >= 14 && b.fade == 0 || b.level == 2, "{a:?} then {b:?}: no pop");
            }
        }
        assert!(picks.iter().any(|p| p.level == 0 && (4..12).contains(&p.fade)), "a fade half way");
        assert_eq!(picks.last().map(|p| (p.level, p.fade)), Some((2, 0)), "the coarsest fades into nothing");
        // Shadow views, and views without levels, never fade.
        let shadow = LodView::texels(camera.projection(1.0) * camera.view(), 0.01, 1.0);
        assert!(
            (1..400).all(|z| shadow.pick(&levels(), Vec3A::new(0.0, 0.0, -(z as f32)), Vec3A::splat(0.5)).fade == 0)
        );
        assert_eq!(Pick { level: 1, fade: 5 }.draw_index(7, true), 7 | (5 << 28) | (1 << 27));
        assert_eq!(Pick { level: 1, fade: 0 }.draw_index(7, true), 7);
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
        level_items(&lod, &levels(), (Placed::Listed, 10, 4), (&mut visible, &bounds), |l, f, n, _| {
            items.push((l, f, n))
        });
        let instances = &visible[10..];
        assert_eq!(instances, vec![1, 3, 0, 2]);
        assert_eq!(items, vec![(0, 10, 2), (2, 12, 2)]);
    }
}
