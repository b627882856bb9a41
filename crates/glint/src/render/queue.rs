//! Core layer: render queues and the 64-bit sort key.
//!
//! Every visible run of an entity becomes one [`DrawItem`] (every visible
//! *instance*, for blended entities) whose key orders the frame. Opaque and
//! alpha-test items are *binned*: grouped by the state that is costly to rebind
//! (pipeline, then texture set, then material, then mesh), near to far only within
//! equal state. Adjacent items with one pipeline and texture set become one
//! multi-draw-indirect call; equal material and mesh merge into one instanced draw.
//! Blended items are *sorted* far to near, because blending is only right back
//! to front.
//!
//! ```text
//! binned (opaque, alpha-test)
//!  63 .... 56 | 55 ..... 44 | 43 ....... 34 | 33 ..... 22 | 21 .... 12 | 11 ...... 0
//!  stage (8)  | pipeline(12)| texture set(10)| material(12)| shape (10) | depth (12) near→far
//!
//! sorted (blended)
//!  63 ...... 56 | 55 .......................... 32 | 31 ...... 16 | 15 ...... 0
//!   stage (8)   |   inverted depth (24) far→near   | material (16)|  shape (16)
//! ```
//!
//! The *stage* is the queue's ([`Queue::stage`]: opaque 64, alpha-test 96,
//! transparent 192), or an entity's `render_order` when it has one, which is how a
//! scene forces a deliberate draw order (the vegetation demo draws near, large
//! objects first and the ground after the sky). The sky is drawn before the first
//! item whose stage is [`SKY_STAGE`] (128) or more.
//!
//! Correctness bits: the stage (pass order) and, for blended items, the depth.
//! Speed bits: pipeline, texture set, material, shape and the binned depth only make equal
//! state adjacent (so runs merge into one draw) and let early depth testing reject
//! hidden fragments. Ids wider than their field are masked, which can cost merging
//! but never correctness, because batching compares the real ids.
//!
//! Worked example, two red cubes (near and far) and a glass sphere in front: the
//! cubes share pipeline, material and shape, so their keys differ only in the
//! depth bits, they sort next to each other and merge into one instanced draw; the
//! sphere's stage (192, transparent) puts it after both, whatever its depth.

use crate::scene::{MaterialId, ShapeId};

/// Render queue of a material, in drawing order.
#[derive(Clone, Copy, Debug, PartialEq, Eq, PartialOrd, Ord, Hash)]
pub enum Queue {
    /// Opaque surfaces, binned by state, near to far.
    Opaque,
    /// Alpha-masked surfaces (discard), binned by state, near to far.
    AlphaTest,
    /// Blended surfaces, far to near.
    Transparent,
}

impl Queue {
    /// The queue's stage, the top byte of its keys.
    pub const fn stage(self) -> u8 {
        match self {
            Queue::Opaque => 64,
            Queue::AlphaTest => 96,
            Queue::Transparent => 192,
        }
    }
}

/// Items at this stage or later are drawn after the sky.
pub const SKY_STAGE: u8 = 128;

const STAGE_SHIFT: u32 = 56;
const PIPELINE_SHIFT: u32 = 44;
const PIPELINE_BITS: u32 = 12;
const TEXTURE_SET_SHIFT: u32 = 34;
const TEXTURE_SET_BITS: u32 = 10;
const MATERIAL_BITS: u32 = 16;
const SHAPE_BITS: u32 = 16;
const BINNED_MATERIAL_SHIFT: u32 = 22;
const BINNED_MATERIAL_BITS: u32 = 12;
const BINNED_SHAPE_SHIFT: u32 = 12;
const BINNED_SHAPE_BITS: u32 = 10;
const BINNED_DEPTH_BITS: u32 = 12;
const SORTED_DEPTH_SHIFT: u32 = 32;
const SORTED_DEPTH_BITS: u32 = 24;
const SORTED_MATERIAL_SHIFT: u32 = 16;

const fn mask(bits: u32) -> u64 {
    (1 << bits) - 1
}

/// Build the sort key of one draw item.
///
/// `blended` picks the far-to-near layout; `depth` is the view distance over the
/// far plane, clamped to 0..1.
pub fn sort_key(
    stage: u8,
    blended: bool,
    pipeline: u16,
    texture_set: u16,
    material: MaterialId,
    shape: ShapeId,
    depth: f32,
) -> u64 {
    // f64: 2^24 − 1 steps are not all representable in f32.
    let depth = f64::from(depth.clamp(0.0, 1.0));
    let stage = u64::from(stage) << STAGE_SHIFT;
    let (material, shape) = (u64::from(material.0), u64::from(shape.0));
    if blended {
        let (material, shape) = (material & mask(MATERIAL_BITS), shape & mask(SHAPE_BITS));
        let d = ((1.0 - depth) * mask(SORTED_DEPTH_BITS) as f64) as u64;
        debug_assert!(d <= mask(SORTED_DEPTH_BITS));
        stage | d << SORTED_DEPTH_SHIFT | material << SORTED_MATERIAL_SHIFT | shape
    } else {
        let d = (depth * mask(BINNED_DEPTH_BITS) as f64) as u64;
        debug_assert!(d <= mask(BINNED_DEPTH_BITS));
        stage
            | (u64::from(pipeline) & mask(PIPELINE_BITS)) << PIPELINE_SHIFT
            | (u64::from(texture_set) & mask(TEXTURE_SET_BITS)) << TEXTURE_SET_SHIFT
            | (material & mask(BINNED_MATERIAL_BITS)) << BINNED_MATERIAL_SHIFT
            | (shape & mask(BINNED_SHAPE_BITS)) << BINNED_SHAPE_SHIFT
            | d
    }
}

/// The fields of a sort key ([`decode_key`]).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct KeyFields {
    /// The stage.
    pub stage: u8,
    /// The pipeline id (binned keys only).
    pub pipeline: Option<u16>,
    /// The texture set (binned keys only).
    pub texture_set: Option<u16>,
    /// The material id, masked to its field.
    pub material: u32,
    /// The shape id, masked to its field.
    pub shape: u32,
    /// The depth over the far plane, to the field's precision.
    pub depth: f32,
}

/// The fields of `key`, built by [`sort_key`] with `blended` as given.
pub fn decode_key(key: u64, blended: bool) -> KeyFields {
    let field = |shift: u32, bits: u32| (key >> shift) & mask(bits);
    if blended {
        let d = field(SORTED_DEPTH_SHIFT, SORTED_DEPTH_BITS) as f64 / mask(SORTED_DEPTH_BITS) as f64;
        KeyFields {
            stage: stage_of(key),
            pipeline: None,
            texture_set: None,
            material: field(SORTED_MATERIAL_SHIFT, MATERIAL_BITS) as u32,
            shape: field(0, SHAPE_BITS) as u32,
            depth: (1.0 - d) as f32,
        }
    } else {
        KeyFields {
            stage: stage_of(key),
            pipeline: Some(field(PIPELINE_SHIFT, PIPELINE_BITS) as u16),
            texture_set: Some(field(TEXTURE_SET_SHIFT, TEXTURE_SET_BITS) as u16),
            material: field(BINNED_MATERIAL_SHIFT, BINNED_MATERIAL_BITS) as u32,
            shape: field(BINNED_SHAPE_SHIFT, BINNED_SHAPE_BITS) as u32,
            depth: (field(0, BINNED_DEPTH_BITS) as f64 / mask(BINNED_DEPTH_BITS) as f64) as f32,
        }
    }
}

/// The stage of a key.
pub fn stage_of(key: u64) -> u8 {
    (key >> STAGE_SHIFT) as u8
}

/// One draw request, ready to sort: its key, what it draws, and which of the
/// frame's visible instance indices it covers.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct DrawItem {
    /// The sort key ([`sort_key`]).
    pub key: u64,
    /// Forward pipeline id.
    pub pipeline: u16,
    /// Material.
    pub material: MaterialId,
    /// Shape.
    pub shape: ShapeId,
    /// First entry in the frame's visible-instance list.
    pub first: u32,
    /// Number of entries.
    pub count: u32,
    /// The submitted entity it draws, by its place among the frame's submissions.
    pub entry: u32,
    /// Its level of detail (0: full detail), or `u8::MAX` where the GPU's
    /// cull pass picks each instance's.
    pub level: u8,
    /// Whether its entries are the coarser copies of instances fading into
    /// `level` (their triangles are drawn, their instances counted at the
    /// finer level: see `render/lod.rs`).
    pub copies: bool,
}

/// Below this many items a comparison sort beats the radix sort's eight fixed passes.
const RADIX_THRESHOLD: usize = 256;

/// Sort draw items by key, stably: LSD radix sort, or merge sort for short lists.
pub fn sort(items: &mut [DrawItem]) {
    if items.len() < RADIX_THRESHOLD {
        items.sort_by_key(|item| item.key);
    } else {
        radsort::sort_by_key(items, |item| item.key);
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    const M0: MaterialId = MaterialId(0);
    const M1: MaterialId = MaterialId(1);
    const S0: ShapeId = ShapeId(0);
    const S1: ShapeId = ShapeId(1);
    const OPAQUE: u8 = Queue::Opaque.stage();

    #[test]
    fn queues_come_in_pass_order_whatever_the_depth_and_state() {
        let opaque_far = sort_key(OPAQUE, false, 4095, 0, MaterialId(u32::MAX), S1, 1.0);
        let mask_near = sort_key(Queue::AlphaTest.stage(), false, 0, 0, M0, S0, 0.0);
        let glass_near = sort_key(Queue::Transparent.stage(), true, 0, 0, M0, S0, 0.0);
        assert!(opaque_far < mask_near && mask_near < glass_near);
        assert!(stage_of(mask_near) < SKY_STAGE && stage_of(glass_near) >= SKY_STAGE);
        assert_eq!(stage_of(glass_near), 192);
    }

    #[test]
    fn render_order_overrides_the_queue() {
        // Ground forced after the sky, a near bush forced before everything.
        let ground = sort_key(200, false, 0, 0, M0, S0, 0.0);
        let glass = sort_key(Queue::Transparent.stage(), true, 0, 0, M1, S1, 0.0);
        let bush = sort_key(1, false, 4095, 0, M1, S1, 1.0);
        let opaque = sort_key(OPAQUE, false, 0, 0, M0, S0, 0.0);
        assert!(bush < opaque && glass < ground);
        assert!(stage_of(ground) >= SKY_STAGE);
    }

    #[test]
    fn binned_order_is_pipeline_then_texture_set_then_material_then_shape_then_near_to_far() {
        let k = |p, m, s, d| sort_key(OPAQUE, false, p, 0, m, s, d);
        assert!(k(0, M1, S1, 1.0) < k(1, M0, S0, 0.0), "pipeline dominates material");
        let t = |p, set, m| sort_key(OPAQUE, false, p, set, m, S0, 0.0);
        assert!(t(0, 9, M0) < t(1, 0, M0), "pipeline dominates texture set");
        assert!(t(0, 0, M1) < t(0, 1, M0), "texture set dominates material");
        assert!(k(0, M0, S1, 1.0) < k(0, M1, S0, 0.0), "material dominates shape");
        assert!(k(0, M0, S0, 1.0) < k(0, M0, S1, 0.0), "shape dominates depth");
        assert!(k(0, M0, S0, 0.1) < k(0, M0, S0, 0.9), "near before far");
    }

    #[test]
    fn blended_sorts_far_to_near_before_state() {
        let k = |m, s, d| sort_key(Queue::Transparent.stage(), true, 0, 0, m, s, d);
        assert!(k(M1, S1, 0.9) < k(M0, S0, 0.1), "far first, whatever the state");
        assert!(k(M0, S0, 0.5) < k(M1, S0, 0.5), "equal depth: grouped by material");
        assert!(k(M0, S0, 0.500_001) < k(M0, S0, 0.5), "24 bits tell close depths apart");
    }

    #[test]
    fn depth_is_clamped_and_ids_are_masked_into_their_fields() {
        let k = |m, d| sort_key(OPAQUE, false, 0, 0, m, S0, d);
        assert_eq!(k(M0, -3.0), k(M0, 0.0));
        assert_eq!(k(M0, 7.0), k(M0, 1.0));
        assert_eq!(k(M0, f32::NAN), k(M0, 0.0), "NaN depth clamps, never spills into other fields");
        // Material 4096 wraps to 0 in the binned key: same bin, still the same stage.
        assert_eq!(k(MaterialId(1 << 12), 0.5), k(M0, 0.5));
        assert_eq!(stage_of(sort_key(255, true, u16::MAX, 0, MaterialId(u32::MAX), ShapeId(u32::MAX), 0.0)), 255);
    }

    #[test]
    fn decoding_a_key_gives_back_every_field() {
        let binned = decode_key(sort_key(96, false, 1234, 567, MaterialId(890), ShapeId(321), 0.25), false);
        assert_eq!((binned.stage, binned.pipeline, binned.texture_set), (96, Some(1234), Some(567)));
        assert_eq!((binned.material, binned.shape), (890, 321));
        assert!((binned.depth - 0.25).abs() < 1.0 / 4095.0, "{}", binned.depth);
        let sorted = decode_key(sort_key(192, true, 9, 9, MaterialId(40_000), ShapeId(65_000), 0.75), true);
        assert_eq!((sorted.stage, sorted.pipeline, sorted.texture_set), (192, None, None));
        assert_eq!((sorted.material, sorted.shape), (40_000, 65_000));
        assert!((sorted.depth - 0.75).abs() < 1e-6, "{}", sorted.depth);
        // Wider ids are masked, as in the key.
        assert_eq!(decode_key(sort_key(64, false, 0, 0, MaterialId(4096 + 5), S0, 0.0), false).material, 5);
    }

    #[test]
    fn sort_orders_by_key_and_is_stable_on_both_paths() {
        let item = |key, first| DrawItem {
            key,
            pipeline: 0,
            material: M0,
            shape: S0,
            first,
            count: 1,
            entry: 0,
            level: 0,
            copies: false,
        };
        let mut items = vec![item(5, 0), item(1, 1), item(5, 2), item(u64::MAX, 3), item(0, 4)];
        sort(&mut items);
        let firsts: Vec<u32> = items.iter().map(|i| i.first).collect();
        assert_eq!(firsts, vec![4, 1, 0, 2, 3]);
        // The radix path: many items, keys with ties, against a stable comparison sort.
        let mut many: Vec<DrawItem> =
            (0..5000u32).map(|i| item(u64::from(i.wrapping_mul(2_654_435_761) % 97) << 40, i)).collect();
        let mut expected = many.clone();
        expected.sort_by_key(|i| i.key);
        sort(&mut many);
        assert_eq!(many, expected);
    }
}
