//! Core layer: merging sorted draw items into instanced draws.

use super::blocks::InstanceGpu;
use super::queue::{queue_of, DrawItem, Queue};
use crate::scene::{MaterialId, ShapeId};
use glam::Mat4;

/// One instanced draw: a run of equal (queue, pipeline, material, shape) items.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(crate) struct Batch {
    pub queue: Queue,
    pub pipeline: u16,
    pub material: MaterialId,
    pub shape: ShapeId,
    /// First instance of the run in the frame's instance buffer.
    pub first_instance: u32,
    pub instance_count: u32,
}

/// Merge adjacent equal items of a sorted list into batches, and pack their
/// transforms into `instances` in draw order (so each batch is one contiguous range).
pub(crate) fn merge(
    items: &[DrawItem],
    transforms: &[Mat4],
    instances: &mut Vec<InstanceGpu>,
    batches: &mut Vec<Batch>,
) {
    instances.clear();
    batches.clear();
    for item in items {
        let queue = queue_of(item.key);
        let first = instances.len() as u32;
        instances.extend_from_slice(
            &transforms[item.first as usize..(item.first + item.count) as usize],
        );
        match batches.last_mut() {
            Some(b)
                if b.queue == queue
                    && b.pipeline == item.pipeline
                    && b.material == item.material
                    && b.shape == item.shape =>
            {
                b.instance_count += item.count;
            }
            _ => batches.push(Batch {
                queue,
                pipeline: item.pipeline,
                material: item.material,
                shape: item.shape,
                first_instance: first,
                instance_count: item.count,
            }),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::super::queue::{sort, sort_key};
    use super::*;

    fn item(material: u32, shape: u32, first: u32, count: u32, depth: f32) -> DrawItem {
        let (m, s) = (MaterialId(material), ShapeId(shape));
        DrawItem {
            key: sort_key(Queue::Opaque, 0, m, s, depth),
            pipeline: 0,
            material: m,
            shape: s,
            first,
            count,
        }
    }

    #[test]
    fn equal_state_merges_and_instances_are_packed_per_batch() {
        // Submitted: (m0,s0) ×2, (m1,s0) ×1, (m0,s0) ×3 — interleaved.
        let transforms: Vec<Mat4> = (0..6)
            .map(|i| Mat4::from_translation(glam::Vec3::splat(i as f32)))
            .collect();
        let mut items = vec![
            item(0, 0, 0, 2, 0.5),
            item(1, 0, 2, 1, 0.1),
            item(0, 0, 3, 3, 0.2),
        ];
        sort(&mut items);
        let (mut instances, mut batches) = (Vec::new(), Vec::new());
        merge(&items, &transforms, &mut instances, &mut batches);
        assert_eq!(batches.len(), 2);
        assert_eq!(
            (
                batches[0].material,
                batches[0].first_instance,
                batches[0].instance_count
            ),
            (MaterialId(0), 0, 5)
        );
        assert_eq!(
            (
                batches[1].material,
                batches[1].first_instance,
                batches[1].instance_count
            ),
            (MaterialId(1), 5, 1)
        );
        // Near item (depth 0.2, transforms 3..6) first, then the far one (0..2), then m1.
        let order: Vec<f32> = instances.iter().map(|m| m.w_axis.x).collect();
        assert_eq!(order, vec![3.0, 4.0, 5.0, 0.0, 1.0, 2.0]);
    }

    #[test]
    fn three_materials_by_two_shapes_make_six_batches() {
        let mut items = Vec::new();
        for i in 0..60u32 {
            items.push(item(i % 3, (i / 3) % 2, i, 1, (i as f32) / 60.0));
        }
        let transforms = vec![Mat4::IDENTITY; 60];
        sort(&mut items);
        let (mut instances, mut batches) = (Vec::new(), Vec::new());
        merge(&items, &transforms, &mut instances, &mut batches);
        assert_eq!(batches.len(), 6);
        assert_eq!(instances.len(), 60);
        assert!(batches.iter().all(|b| b.instance_count == 10));
    }
}
