//! Core layer: merging sorted draw items into instanced draws.

use crate::render::queue::{stage_of, DrawItem};
use crate::scene::{MaterialId, ShapeId};

/// One instanced draw: a run of adjacent items with equal stage, pipeline,
/// material, shape, level of detail and fade copies.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Batch {
    /// The sort key of its first item.
    pub key: u64,
    /// Draw stage (top byte of the sort key).
    pub stage: u8,
    /// Forward pipeline id.
    pub pipeline: u16,
    /// Material.
    pub material: MaterialId,
    /// Shape.
    pub shape: ShapeId,
    /// First instance of the run in the frame's draw-index buffer.
    pub first_instance: u32,
    /// Instances drawn.
    pub instance_count: u32,
    /// Its level of detail (0: full detail).
    pub level: u8,
    /// Whether it draws fading instances' coarser copies ([`DrawItem::copies`]).
    pub copies: bool,
}

/// Merge adjacent equal items of a sorted list into batches appended to
/// `batches`, and append their instance indices (from `visible`) to
/// `draw_indices` in draw order, so each batch is one contiguous range.
pub fn merge(items: &[DrawItem], visible: &[u32], draw_indices: &mut Vec<u32>, batches: &mut Vec<Batch>) {
    let place = |item: &DrawItem, _, _| {
        let at = draw_indices.len() as u32;
        draw_indices.extend_from_slice(&visible[item.first as usize..(item.first + item.count) as usize]);
        at
    };
    merge_placed(items, batches, place, |_, _| true);
}

/// [`merge`], with `place` putting each item's instances where its batch
/// (given by index, and whether the item begins it) draws them: it returns
/// where the item's first goes, right after the batch's earlier items' when
/// the item joins a batch. An equal item joins the batch of the one before
/// it only where `follows(before, item)` allows.
pub(crate) fn merge_placed(
    items: &[DrawItem],
    batches: &mut Vec<Batch>,
    mut place: impl FnMut(&DrawItem, usize, bool) -> u32,
    follows: impl Fn(&DrawItem, &DrawItem) -> bool,
) {
    let first_batch = batches.len();
    let mut before: Option<&DrawItem> = None;
    for item in items {
        let stage = stage_of(item.key);
        let joins = batches[first_batch..].last().is_some_and(|b| {
            b.stage == stage
                && b.pipeline == item.pipeline
                && b.material == item.material
                && b.shape == item.shape
                && b.level == item.level
                && b.copies == item.copies
        }) && before.is_some_and(|b| follows(b, item));
        before = Some(item);
        if !joins {
            batches.push(Batch {
                key: item.key,
                stage,
                pipeline: item.pipeline,
                material: item.material,
                shape: item.shape,
                first_instance: 0,
                instance_count: 0,
                level: item.level,
                copies: item.copies,
            });
        }
        let k = batches.len() - 1;
        let at = place(item, k, !joins);
        let b = &mut batches[k];
        if !joins {
            b.first_instance = at;
        }
        b.instance_count += item.count;
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::render::queue::{sort, sort_key, Queue};

    fn item(material: u32, shape: u32, first: u32, count: u32, depth: f32) -> DrawItem {
        let (m, s) = (MaterialId(material), ShapeId(shape));
        DrawItem {
            key: sort_key(Queue::Opaque.stage(), false, 0, 0, m, s, depth),
            pipeline: 0,
            material: m,
            shape: s,
            first,
            count,
            entry: 0,
            level: 0,
            copies: false,
        }
    }

    #[test]
    fn equal_state_merges_and_indices_are_packed_per_batch() {
        // Visible instances 10..16; items: (m0,s0) ×2, (m1,s0) ×1, (m0,s0) ×3.
        let visible: Vec<u32> = (10..16).collect();
        let mut items = vec![item(0, 0, 0, 2, 0.5), item(1, 0, 2, 1, 0.1), item(0, 0, 3, 3, 0.2)];
        sort(&mut items);
        let (mut indices, mut batches) = (Vec::new(), Vec::new());
        merge(&items, &visible, &mut indices, &mut batches);
        assert_eq!(batches.len(), 2);
        assert_eq!((batches[0].material, batches[0].first_instance, batches[0].instance_count), (MaterialId(0), 0, 5));
        assert_eq!((batches[1].material, batches[1].first_instance, batches[1].instance_count), (MaterialId(1), 5, 1));
        // Near item (depth 0.2: visible 13..16) first, then the far one (10..12), then m1.
        assert_eq!(indices, vec![13, 14, 15, 10, 11, 12]);
    }

    #[test]
    fn three_materials_by_two_shapes_make_six_batches() {
        let mut items: Vec<DrawItem> = (0..60u32).map(|i| item(i % 3, (i / 3) % 2, i, 1, i as f32 / 60.0)).collect();
        let visible: Vec<u32> = (0..60).collect();
        sort(&mut items);
        let (mut indices, mut batches) = (Vec::new(), Vec::new());
        merge(&items, &visible, &mut indices, &mut batches);
        assert_eq!(batches.len(), 6);
        assert_eq!(indices.len(), 60);
        assert!(batches.iter().all(|b| b.instance_count == 10));
    }
}
