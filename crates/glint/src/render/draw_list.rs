//! Core layer: a [`DrawList`], the draws of one pass kind — the forward view, or
//! every shadow view of a frame — from sorted items to GPU commands: batches,
//! their instance indices in draw order, one indirect command per batch, and the
//! buffers those live in. Each list uploads only what differs from its last frame.

use super::batch::{self, Batch};
use super::gpu_array::GpuArray;
use super::mesh_pool::MeshRange;
use super::queue::DrawItem;
use super::resources::GrowBuffer;
use super::RenderError;

/// The draws of one pass kind and their GPU buffers.
pub(crate) struct DrawList {
    label: &'static str,
    /// Draw items of the frame, sorted before batching.
    pub items: Vec<DrawItem>,
    /// Instanced draws; a view's draws are one contiguous range.
    pub batches: Vec<Batch>,
    /// Visible instance indices in draw order (`@group(3) @binding(1)`).
    pub draw_indices: Vec<u32>,
    /// One command per batch, when the device draws indirect.
    pub indirect_args: Vec<wgpu::util::DrawIndexedIndirectArgs>,
    uploaded_draw_indices: Vec<u32>,
    uploaded_indirect_args: Vec<wgpu::util::DrawIndexedIndirectArgs>,
    draw_index_buffer: GpuArray,
    /// `None` where the device cannot draw indirect with a first instance.
    pub indirect: Option<GrowBuffer>,
    /// The Renderer block for this list: the instances and this list's draw indices.
    pub bind_group: wgpu::BindGroup,
}

/// Bytes written by [`DrawList::upload`].
pub(crate) struct ListUpload {
    pub draw_indices: u64,
    pub indirect: u64,
}

impl DrawList {
    pub(crate) fn new(
        device: &wgpu::Device,
        label: &'static str,
        layout: &wgpu::BindGroupLayout,
        instances: &GpuArray,
        (indirect, storage): (bool, bool),
    ) -> Self {
        let draw_index_buffer = GpuArray::new(device, label, 4, 1024, storage);
        let indirect = indirect.then(|| GrowBuffer::new(device, label, wgpu::BufferUsages::INDIRECT, 1024 * 20));
        let bind_group = bind(device, label, layout, instances, &draw_index_buffer);
        Self {
            label,
            items: Vec::new(),
            batches: Vec::new(),
            draw_indices: Vec::new(),
            indirect_args: Vec::new(),
            uploaded_draw_indices: Vec::new(),
            uploaded_indirect_args: Vec::new(),
            draw_index_buffer,
            indirect,
            bind_group,
        }
    }

    /// Forget this frame's draws.
    pub(crate) fn clear(&mut self) {
        self.items.clear();
        self.batches.clear();
        self.draw_indices.clear();
        self.indirect_args.clear();
    }

    /// Merge the items from `first_item` on (sorted) into batches appended to the
    /// list (their instance indices from `visible`), and make their indirect
    /// commands. Returns the range of batches they became.
    pub(crate) fn build(
        &mut self,
        first_item: usize,
        visible: &[u32],
        mesh: impl Fn(&Batch) -> MeshRange,
    ) -> std::ops::Range<usize> {
        let first_batch = self.batches.len();
        batch::merge(&self.items[first_item..], visible, &mut self.draw_indices, &mut self.batches);
        if self.indirect.is_some() {
            self.indirect_args.extend(self.batches[first_batch..].iter().map(|b| {
                let m = mesh(b);
                wgpu::util::DrawIndexedIndirectArgs {
                    index_count: m.index_count,
                    instance_count: b.instance_count,
                    first_index: m.first_index,
                    base_vertex: m.base_vertex,
                    first_instance: b.first_instance,
                }
            }));
        }
        first_batch..self.batches.len()
    }

    /// Point the bind group at a new instance buffer.
    pub(crate) fn rebind(&mut self, device: &wgpu::Device, layout: &wgpu::BindGroupLayout, instances: &GpuArray) {
        self.bind_group = bind(device, self.label, layout, instances, &self.draw_index_buffer);
    }

    /// Write the draw indices and indirect commands where they differ from what
    /// the GPU holds; `one_by_one` (the naive baseline) writes every draw index
    /// alone, every frame.
    pub(crate) fn upload(
        &mut self,
        device: &wgpu::Device,
        queue: &wgpu::Queue,
        (layout, instances): (&wgpu::BindGroupLayout, &GpuArray),
        one_by_one: bool,
    ) -> Result<ListUpload, RenderError> {
        let mut written = ListUpload { draw_indices: 0, indirect: 0 };
        if self.draw_index_buffer.reserve(device, 4, self.draw_indices.len())? {
            self.uploaded_draw_indices.clear();
            self.rebind(device, layout, instances);
        }
        if one_by_one {
            for k in 0..self.draw_indices.len() {
                written.draw_indices += self.draw_index_buffer.write(queue, k as u64, &self.draw_indices[k..=k]);
            }
            self.uploaded_draw_indices.clear();
        } else if self.draw_indices != self.uploaded_draw_indices {
            written.draw_indices = self.draw_index_buffer.write(queue, 0, &self.draw_indices);
            self.uploaded_draw_indices.clone_from(&self.draw_indices);
        }
        if let Some(indirect) = &mut self.indirect {
            if indirect.reserve(device, std::mem::size_of_val(self.indirect_args.as_slice()) as u64)? {
                self.uploaded_indirect_args.clear();
            }
            if bytemuck::cast_slice::<_, u8>(&self.indirect_args)
                != bytemuck::cast_slice::<_, u8>(&self.uploaded_indirect_args)
            {
                written.indirect = indirect.write(queue, 0, &self.indirect_args);
                self.uploaded_indirect_args.clone_from(&self.indirect_args);
            }
        }
        Ok(written)
    }
}

fn bind(
    device: &wgpu::Device,
    label: &str,
    layout: &wgpu::BindGroupLayout,
    instances: &GpuArray,
    draw_indices: &GpuArray,
) -> wgpu::BindGroup {
    device.create_bind_group(&wgpu::BindGroupDescriptor {
        label: Some(label),
        layout,
        entries: &[
            wgpu::BindGroupEntry { binding: 0, resource: instances.binding() },
            wgpu::BindGroupEntry { binding: 1, resource: draw_indices.binding() },
        ],
    })
}
