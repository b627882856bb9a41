//! Core layer: render queues and the 64-bit sort key.
//!
//! Every submitted entity becomes one [`DrawItem`] whose key orders the frame.
//! Opaque and alpha-test items are *binned*: grouped by the state that is costly
//! to rebind (pipeline, then material, then mesh), near to far only within equal
//! state. Transparent items are *sorted* far to near, because blending is only
//! right back to front.
//!
//! ```text
//! opaque / alpha-test
//!  63 62 | 61 ........ 50 | 49 ....... 34 | 33 ....... 18 | 17 ........ 0
//!  queue |  pipeline (12) | material (16) |   shape (16)  | depth (18) near→far
//!
//! transparent
//!  63 62 | 61 ........................ 32 | 31 ....... 16 | 15 ........ 0
//!  queue |      inverted depth (30) far→near    | material (16) |   shape (16)
//! ```
//!
//! Which bits are for correctness and which for speed: the queue bits decide pass
//! order and the transparent depth decides blending order; both are correctness.
//! Pipeline, material, shape and opaque depth only make equal state adjacent
//! (so runs merge into one draw) and let early depth testing reject hidden
//! fragments: ids larger than their field are masked, which costs merging, never
//! correctness, because batching compares the real ids.
//!
//! Worked example, two red cubes (near and far) and a glass sphere in front:
//! the cubes share pipeline, material and shape, so their keys differ only in the
//! depth bits, they sort next to each other and merge into one instanced draw;
//! the sphere's queue bits (transparent) put it after both, whatever its depth.

use crate::scene::{MaterialId, ShapeId};

/// Render queue, in drawing order (the sky is drawn between alpha-test and transparent).
#[derive(Clone, Copy, Debug, PartialEq, Eq, PartialOrd, Ord, Hash)]
pub enum Queue {
    /// Opaque surfaces, binned by state, near to far.
    Opaque = 0,
    /// Alpha-masked surfaces (discard), binned by state, near to far.
    AlphaTest = 1,
    /// Blended surfaces, far to near.
    Transparent = 2,
}

const QUEUE_SHIFT: u32 = 62;
const PIPELINE_SHIFT: u32 = 50;
const PIPELINE_BITS: u32 = 12;
const MATERIAL_BITS: u32 = 16;
const SHAPE_BITS: u32 = 16;
const OPAQUE_MATERIAL_SHIFT: u32 = 34;
const OPAQUE_SHAPE_SHIFT: u32 = 18;
const OPAQUE_DEPTH_BITS: u32 = 18;
const TRANSPARENT_DEPTH_SHIFT: u32 = 32;
const TRANSPARENT_DEPTH_BITS: u32 = 30;
const TRANSPARENT_MATERIAL_SHIFT: u32 = 16;

const fn mask(bits: u32) -> u64 {
    (1 << bits) - 1
}

/// Build the sort key of one draw item.
///
/// `depth` is the view distance divided by the far plane, clamped to 0..1.
pub fn sort_key(
    queue: Queue,
    pipeline: u16,
    material: MaterialId,
    shape: ShapeId,
    depth: f32,
) -> u64 {
    // f64: 2^30 − 1 is not representable in f32 and would round past the field.
    let depth = f64::from(depth.clamp(0.0, 1.0));
    let q = (queue as u64) << QUEUE_SHIFT;
    debug_assert!((queue as u64) < 4, "queue field is 2 bits");
    let material = u64::from(material.0) & mask(MATERIAL_BITS);
    let shape = u64::from(shape.0) & mask(SHAPE_BITS);
    match queue {
        Queue::Opaque | Queue::AlphaTest => {
            let d = (depth * mask(OPAQUE_DEPTH_BITS) as f64) as u64;
            q | (u64::from(pipeline) & mask(PIPELINE_BITS)) << PIPELINE_SHIFT
                | material << OPAQUE_MATERIAL_SHIFT
                | shape << OPAQUE_SHAPE_SHIFT
                | d
        }
        Queue::Transparent => {
            let d = ((1.0 - depth) * mask(TRANSPARENT_DEPTH_BITS) as f64) as u64;
            debug_assert!(d <= mask(TRANSPARENT_DEPTH_BITS));
            q | d << TRANSPARENT_DEPTH_SHIFT | material << TRANSPARENT_MATERIAL_SHIFT | shape
        }
    }
}

/// The queue a key belongs to.
pub fn queue_of(key: u64) -> Queue {
    match key >> QUEUE_SHIFT {
        0 => Queue::Opaque,
        1 => Queue::AlphaTest,
        _ => Queue::Transparent,
    }
}

/// One submitted entity, ready to sort: its key and what it draws.
#[derive(Clone, Copy, Debug, PartialEq)]
pub(crate) struct DrawItem {
    pub key: u64,
    pub pipeline: u16,
    pub material: MaterialId,
    pub shape: ShapeId,
    /// Range of the entity's transforms in the frame's submitted transforms.
    pub first: u32,
    pub count: u32,
}

/// Sort draw items by key (LSD radix sort, stable).
pub(crate) fn sort(items: &mut [DrawItem]) {
    radsort::sort_by_key(items, |item| item.key);
}

#[cfg(test)]
mod tests {
    use super::*;

    const M0: MaterialId = MaterialId(0);
    const M1: MaterialId = MaterialId(1);
    const S0: ShapeId = ShapeId(0);
    const S1: ShapeId = ShapeId(1);

    #[test]
    fn queues_come_in_pass_order_whatever_the_depth() {
        let opaque_far = sort_key(Queue::Opaque, 4095, MaterialId(u32::MAX), S1, 1.0);
        let mask_near = sort_key(Queue::AlphaTest, 0, M0, S0, 0.0);
        let glass_near = sort_key(Queue::Transparent, 0, M0, S0, 0.0);
        assert!(opaque_far < mask_near && mask_near < glass_near);
        assert_eq!(queue_of(opaque_far), Queue::Opaque);
        assert_eq!(queue_of(mask_near), Queue::AlphaTest);
        assert_eq!(queue_of(glass_near), Queue::Transparent);
    }

    #[test]
    fn opaque_bins_by_pipeline_then_material_then_shape_then_near_to_far() {
        let k = |p, m, s, d| sort_key(Queue::Opaque, p, m, s, d);
        assert!(
            k(0, M1, S1, 1.0) < k(1, M0, S0, 0.0),
            "pipeline dominates material"
        );
        assert!(
            k(0, M0, S1, 1.0) < k(0, M1, S0, 0.0),
            "material dominates shape"
        );
        assert!(
            k(0, M0, S0, 1.0) < k(0, M0, S1, 0.0),
            "shape dominates depth"
        );
        assert!(k(0, M0, S0, 0.1) < k(0, M0, S0, 0.9), "near before far");
    }

    #[test]
    fn transparent_sorts_far_to_near_before_state() {
        let k = |m, s, d| sort_key(Queue::Transparent, 0, m, s, d);
        assert!(
            k(M1, S1, 0.9) < k(M0, S0, 0.1),
            "far first, whatever the state"
        );
        assert!(
            k(M0, S0, 0.5) < k(M1, S0, 0.5),
            "equal depth: grouped by material"
        );
    }

    #[test]
    fn depth_is_clamped_and_ids_are_masked_into_their_fields() {
        assert_eq!(
            sort_key(Queue::Opaque, 0, M0, S0, -3.0),
            sort_key(Queue::Opaque, 0, M0, S0, 0.0)
        );
        assert_eq!(
            sort_key(Queue::Opaque, 0, M0, S0, 7.0),
            sort_key(Queue::Opaque, 0, M0, S0, 1.0)
        );
        // Material 65536 wraps to 0 in the key: same bin, still the opaque queue.
        let wrapped = sort_key(Queue::Opaque, 0, MaterialId(1 << 16), S0, 0.5);
        assert_eq!(wrapped, sort_key(Queue::Opaque, 0, M0, S0, 0.5));
    }

    #[test]
    fn radix_sort_orders_by_key_and_is_stable() {
        let item = |key, first| DrawItem {
            key,
            pipeline: 0,
            material: M0,
            shape: S0,
            first,
            count: 1,
        };
        let mut items = vec![
            item(5, 0),
            item(1, 1),
            item(5, 2),
            item(u64::MAX, 3),
            item(0, 4),
        ];
        sort(&mut items);
        let firsts: Vec<u32> = items.iter().map(|i| i.first).collect();
        assert_eq!(firsts, vec![4, 1, 0, 2, 3]);
    }
}
