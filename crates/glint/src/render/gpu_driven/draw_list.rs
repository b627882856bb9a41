//! Core layer: a [`DrawList`], the draws of one pass kind — the forward view, or
//! every shadow view of a frame — from sorted items to GPU commands: batches,
//! what each draws with, the runs of batches one call draws, their instance
//! indices in draw order, one indirect command per batch, and the buffers those
//! live in. Each list uploads only what differs from its last frame.
//!
//! Draw-index buffer layout: a ramp `0, 1, 2, …` over the instance store
//! (once a list draws whole tiles, which index it by their store range, so
//! the CPU writes nothing per instance for them), then the instances of
//! batches culled on the CPU, in draw order, then (lists culled on the GPU,
//! `gpu_cull.rs`) a region the cull pass fills, one stretch per GPU-culled
//! batch as long as its candidates. The ramp is written when it grows.

use crate::render::batch::{self, Batch};
use crate::render::cull::Frustum;
use crate::render::debug::stats::DrawnCounts;
use crate::render::error::RenderError;
use crate::render::gpu_driven::commands::{Placed, Run};
use crate::render::gpu_driven::gpu_cull::{CullBindings, CullInput, CullPipelines, CullRange, GpuCull};
use crate::render::gpu_driven::occlusion::{late_commands, LateInput};
use crate::render::lod::{LodView, LEVEL_ON_GPU};
use crate::render::queue::DrawItem;
use crate::render::resources::gpu_array::GpuArray;
use crate::render::resources::gpu_array::GrowBuffer;
use crate::render::resources::mesh_pool::MeshRange;
use crate::scene::levels::MAX_LEVELS;

/// What a list may rely on: indirect drawing, storage buffers, GPU culling.
#[derive(Clone, Copy, Debug)]
pub(crate) struct ListPaths {
    pub indirect: bool,
    pub storage: bool,
    pub gpu_cull: bool,
}

/// What a batch draws with, found when it was made: its mesh and texture set.
#[derive(Clone, Copy, Debug)]
pub(crate) struct BatchDraw {
    pub mesh: MeshRange,
    pub texture_set: u16,
}

/// The draws of one pass kind and their GPU buffers.
pub(crate) struct DrawList {
    label: &'static str,
    /// Draw items of the frame, sorted before batching.
    pub items: Vec<DrawItem>,
    /// Instanced draws; a view's draws are one contiguous range. A GPU-culled
    /// batch's instance count is its candidates', of which the GPU draws the visible.
    pub batches: Vec<Batch>,
    /// What each batch draws with.
    pub draws: Vec<BatchDraw>,
    /// Runs of adjacent batches of one stage with one pipeline, texture set and
    /// mesh page: one draw call each where the device draws indirect.
    pub runs: Vec<Run>,
    /// Instance indices of the CPU-culled batches in draw order (`@group(3) @binding(1)`).
    pub draw_indices: Vec<u32>,
    /// The GPU-culled batches' candidates, in batch order.
    pub cull_ranges: Vec<CullRange>,
    /// Length of the GPU-culled region of the draw-index buffer, for one level.
    gpu_region: u32,
    /// Copies of that region, one per level of detail the GPU may pick (at least 1).
    level_regions: u32,
    /// How each batch's instances are placed: listed, culled on the GPU, or
    /// whole tiles (through the ramp, or compact instances by their number).
    pub placed: Vec<Placed>,
    /// The ramp's length this frame needs: the end of the last whole tile drawn.
    ramp_needed: u32,
    /// The ramp's length, a power of two (it never shrinks, so the regions
    /// after it stay put).
    ramp: u32,
    /// How much of the ramp the GPU holds.
    ramp_uploaded: u32,
    /// Each view's frustum (the ranges' and runs' `frustum` index it).
    pub frustums: Vec<Frustum>,
    /// How each of those views picks levels of detail.
    pub lods: Vec<LodView>,
    /// One command per batch, when the device draws indirect.
    pub indirect_args: Vec<wgpu::util::DrawIndexedIndirectArgs>,
    uploaded_draw_indices: Vec<u32>,
    uploaded_indirect_args: Vec<wgpu::util::DrawIndexedIndirectArgs>,
    draw_index_buffer: GpuArray,
    /// `None` where the device cannot draw indirect with a first instance.
    pub indirect: Option<GrowBuffer>,
    /// The list's GPU culling state, where the device can cull on the GPU.
    pub gpu: Option<GpuCull>,
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
        paths: ListPaths,
    ) -> Self {
        let draw_index_buffer = GpuArray::new(device, label, 4, 1024, paths.storage);
        let usage = wgpu::BufferUsages::INDIRECT | wgpu::BufferUsages::COPY_SRC;
        let indirect = paths.indirect.then(|| GrowBuffer::new(device, label, usage, 1024 * 20));
        let bind_group = bind(device, label, layout, instances, &draw_index_buffer);
        Self {
            label,
            items: Vec::new(),
            batches: Vec::new(),
            draws: Vec::new(),
            runs: Vec::new(),
            draw_indices: Vec::new(),
            cull_ranges: Vec::new(),
            gpu_region: 0,
            level_regions: 1,
            placed: Vec::new(),
            ramp_needed: 0,
            ramp: 0,
            ramp_uploaded: 0,
            frustums: Vec::new(),
            lods: Vec::new(),
            indirect_args: Vec::new(),
            uploaded_draw_indices: Vec::new(),
            uploaded_indirect_args: Vec::new(),
            draw_index_buffer,
            indirect,
            gpu: paths.gpu_cull.then(|| GpuCull::new(device, label)),
            bind_group,
        }
    }

    /// Forget this frame's draws.
    pub(crate) fn clear(&mut self) {
        self.items.clear();
        self.batches.clear();
        self.draws.clear();
        self.runs.clear();
        self.draw_indices.clear();
        self.cull_ranges.clear();
        self.gpu_region = 0;
        self.level_regions = 1;
        self.placed.clear();
        self.ramp_needed = 0;
        self.frustums.clear();
        self.lods.clear();
        self.indirect_args.clear();
    }

    /// The draw indices as the CPU wrote them, from the start of the buffer:
    /// the ramp, then the CPU-culled instances.
    pub(crate) fn cpu_indices(&self) -> Vec<u32> {
        (0..self.ramp).chain(self.draw_indices.iter().copied()).collect()
    }

    /// What the batches not culled on the GPU draw (listed and whole tiles):
    /// fading instances' coarser copies add their triangles, not instances.
    pub(crate) fn cpu_drawn(&self) -> DrawnCounts {
        let mut drawn = DrawnCounts::default();
        let batches = self.batches.iter().zip(&self.draws).zip(&self.placed);
        for ((b, d), _) in batches.filter(|(_, &p)| p != Placed::OnGpu) {
            let n = u64::from(b.instance_count);
            drawn.triangles += n * u64::from(d.mesh.index_count / 3);
            if !b.copies {
                drawn.instances += n;
                drawn.per_level[usize::from(b.level).min(MAX_LEVELS - 1)] += n;
            }
        }
        drawn
    }

    /// What the list drew, counted on the GPU (the batches culled on the CPU
    /// counted there too, and in their levels here), from the newest frame
    /// whose counts came back, waiting for the last frame's when `wait`;
    /// `None` where it is not culled on the GPU or no count came back yet.
    pub(crate) fn gpu_drawn(&mut self, device: &wgpu::Device, submits: u64, wait: bool) -> Option<DrawnCounts> {
        let cpu = self.cpu_drawn();
        let gpu = self.gpu.as_mut().filter(|_| !self.cull_ranges.is_empty())?;
        let mut drawn = match wait {
            true => gpu.wait_drawn(device, submits)?,
            false => gpu.drawn(device, submits)?,
        };
        for (level, n) in drawn.per_level.iter_mut().zip(cpu.per_level) {
            *level += n;
        }
        Some(drawn)
    }

    /// Whether this frame's list is culled on the GPU (it has candidates there).
    pub(crate) fn culled_on_gpu(&self) -> bool {
        !self.cull_ranges.is_empty()
    }

    /// Merge the items from `first_item` on (sorted), seen by a view whose
    /// frustum is `frustum`, into batches appended to the list, and those into
    /// runs. Where `placed` says an item is culled on the GPU, it names store
    /// instances (`first ..`), which all become its batch's candidates; where
    /// it is a whole tile, store instances drawn as they are (joining a batch
    /// only right after the store instances before it); else entries of
    /// `visible`. `draw_of` says what the batch an item begins draws with
    /// (at full detail: a batch draws its items' level). Items whose level the
    /// GPU picks (`lod` says how) become a batch per level of their shape.
    /// Returns the range of runs they became.
    pub(crate) fn build(
        &mut self,
        first_item: usize,
        visible: &[u32],
        (frustum, lod): (Frustum, LodView),
        draw_of: impl Fn(&DrawItem) -> BatchDraw,
        placed: impl Fn(&DrawItem) -> Placed,
    ) -> std::ops::Range<usize> {
        let (first_batch, first_run, first_range) = (self.batches.len(), self.runs.len(), self.cull_ranges.len());
        let view = self.frustums.len() as u32;
        self.frustums.push(frustum);
        self.lods.push(lod);
        let Self { items, batches, draws, draw_indices, cull_ranges, gpu_region, placed: kinds, ramp_needed, .. } =
            self;
        let follows = |before: &DrawItem, item: &DrawItem| match (placed(before), placed(item)) {
            (a @ (Placed::Whole | Placed::Compact), b) if a == b => before.first + before.count == item.first,
            (a, b) => a == b,
        };
        let place = |item: &DrawItem, batch: usize, begins: bool| {
            if begins {
                let draw = draw_of(item);
                let level = if item.level == LEVEL_ON_GPU { 0 } else { item.level };
                draws.push(BatchDraw { mesh: draw.mesh.level(level.into()), ..draw });
            }
            let kind = placed(item);
            kinds.resize(batch + 1, Placed::Listed);
            kinds[batch] = kind;
            match kind {
                Placed::Listed => {
                    let at = draw_indices.len() as u32;
                    draw_indices.extend_from_slice(&visible[item.first as usize..(item.first + item.count) as usize]);
                    return at;
                }
                Placed::Whole => {
                    *ramp_needed = (*ramp_needed).max(item.first + item.count);
                    return item.first;
                }
                // The COMPACT variant draws its instances by their number.
                Placed::Compact => return item.first,
                Placed::OnGpu => {}
            }
            // The pass places each visible instance after its batch's others:
            // every range of a batch writes from the batch's first place.
            let last = cull_ranges.last();
            let start = last.map_or(0, |r| r.start + r.count);
            let at = *gpu_region;
            let out = last.filter(|r| r.batch == batch as u32).map_or(at, |r| r.out);
            cull_ranges.push(CullRange {
                first: item.first,
                count: item.count,
                start,
                batch: batch as u32,
                frustum: view,
                out,
                levels: 1,
                pad: 0,
                error: [0.0; 4],
            });
            *gpu_region += item.count;
            at
        };
        batch::merge_placed(&items[first_item..], batches, place, follows);
        self.placed.resize(self.batches.len(), Placed::Listed);
        self.expand_levels(first_batch, first_range);
        let key = |k: usize| {
            let (b, d) = (&self.batches[k], &self.draws[k]);
            (b.stage, b.pipeline, d.texture_set, d.mesh.page)
        };
        let mut start = first_batch;
        for k in first_batch + 1..=self.batches.len() {
            if k == self.batches.len() || key(k) != key(start) {
                self.runs.push(Run::new(start, k - start, view));
                start = k;
            }
        }
        first_run..self.runs.len()
    }

    /// Make each batch from `first_batch` on whose levels the GPU picks one
    /// batch per level of its shape, adjacent (so in one run), and tell its
    /// cull ranges (from `first_range` on) their shape's levels.
    fn expand_levels(&mut self, first_batch: usize, first_range: usize) {
        if !self.batches[first_batch..].iter().any(|b| b.level == LEVEL_ON_GPU) {
            return;
        }
        let batches = self.batches.split_off(first_batch);
        let draws = self.draws.split_off(first_batch);
        let placed = self.placed.split_off(first_batch);
        let mut moved_to = Vec::with_capacity(batches.len());
        for ((batch, draw), placed) in batches.into_iter().zip(draws).zip(placed) {
            let levels = match batch.level {
                LEVEL_ON_GPU => draw.mesh.levels.count.max(1),
                _ => 1,
            };
            moved_to.push((self.batches.len() as u32, levels));
            for l in 0..levels {
                let level = if batch.level == LEVEL_ON_GPU { l } else { batch.level };
                self.batches.push(Batch { level, ..batch });
                self.draws.push(BatchDraw { mesh: draw.mesh.level(level.into()), ..draw });
                self.placed.push(placed);
            }
            self.level_regions = self.level_regions.max(levels.into());
        }
        for r in &mut self.cull_ranges[first_range..] {
            let (batch, levels) = moved_to[r.batch as usize - first_batch];
            let errors = self.draws[batch as usize].mesh.levels.error;
            (r.batch, r.levels, r.error) = (batch, levels.into(), [errors[1], errors[2], errors[3], errors[4]]);
        }
    }

    /// Append one batch of one instance drawn alone (the naive baseline's):
    /// store instance `listed`, named through the draw-index list, or with
    /// `None` a compact instance the batch names by its number.
    pub(crate) fn push_alone(&mut self, batch: Batch, draw: BatchDraw, listed: Option<u32>) {
        self.runs.push(Run::new(self.batches.len(), 1, 0));
        self.batches.push(batch);
        self.draws.push(draw);
        match listed {
            Some(instance) => {
                self.placed.push(Placed::Listed);
                self.draw_indices.push(instance);
            }
            None => self.placed.push(Placed::Compact),
        }
    }

    /// Write every draw index alone (the naive baseline's way, every frame);
    /// returns bytes written.
    pub(crate) fn write_indices_one_by_one(
        &mut self,
        device: &wgpu::Device,
        queue: &wgpu::Queue,
        (layout, instances): (&wgpu::BindGroupLayout, &GpuArray),
    ) -> Result<u64, RenderError> {
        if self.draw_index_buffer.reserve(device, 4, self.draw_indices.len())? {
            self.rebind(device, layout, instances);
        }
        // Written over the ramp's place.
        self.uploaded_draw_indices.clear();
        (self.ramp, self.ramp_uploaded) = (0, 0);
        let each = (0..self.draw_indices.len())
            .map(|k| self.draw_index_buffer.write(queue, k as u64, &self.draw_indices[k..=k]));
        Ok(each.sum())
    }

    /// Point the bind groups at a new instance buffer.
    pub(crate) fn rebind(&mut self, device: &wgpu::Device, layout: &wgpu::BindGroupLayout, instances: &GpuArray) {
        self.bind_group = bind(device, self.label, layout, instances, &self.draw_index_buffer);
        if let Some(gpu) = &mut self.gpu {
            gpu.unbind();
        }
    }

    /// Place the CPU-culled indices after the ramp and the GPU-culled region
    /// after them, and make one indirect command per batch (a GPU-culled one
    /// counting no instance: the cull pass counts them).
    fn finish(&mut self) {
        if self.ramp_needed > self.ramp {
            // Grown to a power of two, so a moving view rarely grows it again.
            self.ramp = self.ramp_needed.next_power_of_two();
        }
        let base = self.ramp + self.draw_indices.len() as u32;
        for r in &mut self.cull_ranges {
            r.out += base;
        }
        for (b, &placed) in self.batches.iter_mut().zip(&self.placed) {
            match placed {
                // Level l's places are l regions on.
                Placed::OnGpu => b.first_instance += base + u32::from(b.level) * self.gpu_region,
                Placed::Listed => b.first_instance += self.ramp,
                Placed::Whole | Placed::Compact => {}
            }
        }
        if self.indirect.is_some() {
            let on_gpu = self.placed.iter().map(|&p| p == Placed::OnGpu);
            let commands = self.batches.iter().zip(&self.draws).zip(on_gpu);
            self.indirect_args.extend(commands.map(|((b, d), gpu)| wgpu::util::DrawIndexedIndirectArgs {
                index_count: d.mesh.index_count,
                instance_count: if gpu { 0 } else { b.instance_count },
                first_index: d.mesh.first_index,
                base_vertex: d.mesh.base_vertex,
                first_instance: b.first_instance,
            }));
        }
    }

    /// Write the draw indices and indirect commands where they differ from what
    /// the GPU holds, and the GPU culling state of a GPU-culled list; `occlusion`
    /// (the view's view-projection and its depth buffer's width, height and
    /// samples) occlusion-culls it where the device can.
    pub(crate) fn upload(
        &mut self,
        device: &wgpu::Device,
        queue: &wgpu::Queue,
        (layout, instances): (&wgpu::BindGroupLayout, &GpuArray),
        gpu: Option<(&CullPipelines, &wgpu::Buffer)>,
        occlusion: Option<(glam::Mat4, (u32, u32, u32))>,
    ) -> Result<ListUpload, RenderError> {
        self.finish();
        let mut written = ListUpload { draw_indices: 0, indirect: 0 };
        let occlusion = occlusion.filter(|_| gpu.is_some_and(|(p, _)| p.occlusion()) && self.culled_on_gpu());
        // Occlusion culling places the late phase's instances after the early ones'.
        let regions = if occlusion.is_some() { 2 } else { 1 };
        let region = (self.level_regions * self.gpu_region) as usize;
        let capacity = self.ramp as usize + self.draw_indices.len() + regions * region;
        if self.draw_index_buffer.reserve(device, 4, capacity)? {
            self.uploaded_draw_indices.clear();
            self.ramp_uploaded = 0;
            self.rebind(device, layout, instances);
        }
        if self.ramp_uploaded < self.ramp {
            let rest: Vec<u32> = (self.ramp_uploaded..self.ramp).collect();
            written.draw_indices += self.draw_index_buffer.write(queue, self.ramp_uploaded.into(), &rest);
            self.ramp_uploaded = self.ramp;
            // The indices after it moved.
            self.uploaded_draw_indices.clear();
        }
        if self.draw_indices != self.uploaded_draw_indices {
            written.draw_indices += self.draw_index_buffer.write(queue, self.ramp.into(), &self.draw_indices);
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
        if let (Some(state), Some((pipelines, bounds)), Some(draw_indices), true) =
            (&mut self.gpu, gpu, self.draw_index_buffer.buffer(), !self.cull_ranges.is_empty())
        {
            let input = CullInput {
                ranges: &self.cull_ranges,
                runs: &self.runs,
                frustums: (&self.frustums, &self.lods),
                commands: self.batches.len(),
                level_stride: self.gpu_region,
            };
            let region = self.level_regions * self.gpu_region;
            let template = occlusion.map(|_| late_commands(&self.indirect_args, &self.placed, region));
            let late = occlusion.zip(template.as_deref()).map(|((view_proj, depth), template)| LateInput {
                view_proj,
                depth,
                template,
                place_offset: region,
            });
            let bindings = CullBindings { bounds, draw_indices };
            written.indirect += state.upload(device, queue, (&input, late.as_ref()), pipelines, bindings)?;
        }
        Ok(written)
    }

    /// The draw-index buffer, where it is a storage buffer.
    pub(crate) fn draw_index_buffer(&self) -> Option<&wgpu::Buffer> {
        self.draw_index_buffer.buffer()
    }

    /// Record this frame's cull pass, when the list is culled on the GPU.
    pub(crate) fn record_cull(&mut self, encoder: &mut wgpu::CommandEncoder, pipelines: &CullPipelines, submits: u64) {
        let culled_on_gpu = self.culled_on_gpu();
        if let (Some(gpu), Some(template), true) = (&mut self.gpu, &self.indirect, culled_on_gpu) {
            gpu.record(encoder, pipelines, &template.buffer, submits);
        }
    }
}

/// The stage of run `run`'s batches in `list`.
pub(crate) fn run_stage(list: &DrawList, run: &Run) -> u8 {
    list.batches[run.first as usize].stage
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
