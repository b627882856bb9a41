//! Core layer: frustum culling on the GPU ([`Culling::Gpu`](crate::Culling::Gpu)).
//!
//! A draw list culled on the GPU is built from every valid instance of the
//! entities it draws (blended ones excepted: they are sorted far to near, so
//! culled on the CPU), as *cull ranges*: runs of consecutive store instances,
//! each with its batch, its frustum and where its batch's instances start in
//! the draw-index buffer. The CPU's work per frame is per entity, never per
//! instance, and what it uploads changes only when the entities do.
//!
//! Each frame the list's indirect commands are copied from the CPU's (whose
//! GPU-culled instance counts are 0) into [`GpuCull::args`], then one compute
//! pass (`shader/cull.wgsl`) tests every candidate's world box (uploaded with
//! the instances, [`BoundsGpu`](crate::render::resources::buffers::BoundsGpu)) against its frustum, writes the visible ones'
//! store indices into their batch's range and counts them into the command;
//! then copies each run's non-empty commands to the front of the run's range of
//! [`GpuCull::drawn_args`] with their count, which a
//! `multi_draw_indexed_indirect_count` call reads (where the adapter has
//! `MULTI_DRAW_INDIRECT_COUNT`; elsewhere the run draws all of
//! [`GpuCull::args`], empty commands included). Each frustum's instances drawn
//! come back to the CPU a frame or two late, without a stall.

use crate::render::cull::Frustum;
use crate::render::debug::readback::CountReadback;
use crate::render::debug::stats::DrawnCounts;
use crate::render::error::RenderError;
use crate::render::gpu_driven::commands::{Run, COMMAND_BYTES};
pub(crate) use crate::render::gpu_driven::cull_pipelines::CullPipelines;
use crate::render::gpu_driven::cull_pipelines::OcclusionPipelines;
use crate::render::gpu_driven::occlusion::{LateInput, LatePhase};
use crate::render::lod::LodView;
use crate::render::passes::shadow_views::MAX_SHADOW_VIEWS;
use crate::render::resources::gpu_array::GrowBuffer;
use crate::scene::levels::MAX_LEVELS;

/// Frames a view is culled by frustum alone after an occlusion-culled frame
/// that hid nothing.
pub const SKIP_UNPAID_OCCLUSION: u32 = 30;

/// Rows of the planes buffer per view: six frustum planes, then two of its
/// level-of-detail rule ([`LodView::to_gpu`]).
const VIEW_ROWS: usize = 8;

/// Words of each frustum's totals in the counts buffer: instances drawn
/// (fading instances' coarser copies among them), triangles drawn, the
/// GPU-culled instances drawn at each level of detail, then those copies.
pub(crate) const TOTAL_WORDS: usize = 3 + MAX_LEVELS;

/// Words read back at most: the totals of the most frustums a list has (the
/// camera, or every shadow view), and the hidden count.
const MAX_READBACK_WORDS: u32 = MAX_SHADOW_VIEWS as u32 * TOTAL_WORDS as u32 + 1;

/// Invocations per workgroup of both entry points.
const WORKGROUP: u32 = 64;
/// Candidates `start .. start + count` of a list: store instances `first ..`,
/// tested against frustum `frustum`, drawn by batch `batch`, whose instances
/// start at `out` in the draw-index buffer; with `levels` > 1, the levels of
/// detail the GPU picks from: level l is batch `batch + l`, its places a
/// region further on each, its error `error[l - 1]`.
#[repr(C)]
#[derive(Clone, Copy, Debug, PartialEq, bytemuck::Pod, bytemuck::Zeroable)]
pub(crate) struct CullRange {
    pub first: u32,
    pub count: u32,
    pub start: u32,
    pub batch: u32,
    pub frustum: u32,
    pub out: u32,
    pub levels: u32,
    pub pad: u32,
    pub error: [f32; 4],
}

/// `cull.wgsl`'s `Params`: one set for the early (or only) phase, one for the late.
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, bytemuck::Pod, bytemuck::Zeroable)]
struct Params {
    ranges: u32,
    candidates: u32,
    runs: u32,
    totals: u32,
    counts_first: u32,
    place_offset: u32,
    level_stride: u32,
    pad: u32,
}

/// What a list culled on the GPU holds there beside its draw indices.
pub(crate) struct GpuCull {
    label: &'static str,
    params: wgpu::Buffer,
    ranges: GrowBuffer,
    planes: GrowBuffer,
    /// The commands the cull pass counts instances into.
    pub args: GrowBuffer,
    /// Each run's non-empty commands, from the run's first batch on.
    pub drawn_args: GrowBuffer,
    runs: GrowBuffer,
    /// Each run's command count (the early phase's, then the late's), then
    /// each frustum's totals ([`TOTAL_WORDS`]), then the late phase's hidden count.
    pub counts: GrowBuffer,
    groups: Option<[wgpu::BindGroup; 2]>,
    uploaded: (Vec<CullRange>, Vec<Run>, Vec<[f32; 4]>, Params),
    params_now: Params,
    readback: CountReadback,
    /// The late phase, once the list has been occlusion-culled.
    late: Option<LatePhase>,
    /// Its bind groups: group 0 and 1 of the late dispatches, group 2 of both phases.
    late_groups: Option<[wgpu::BindGroup; 3]>,
    /// Whether this frame's list is occlusion-culled.
    pub occluding: bool,
    /// The late phase's `Params` as written.
    late_params: Option<Params>,
    /// Whether the newest occlusion-culled frame whose counts came back hid anything.
    occlusion_pays: bool,
    /// Frames left without occlusion culling, after one that hid nothing.
    skip_occlusion: u32,
}

/// What [`GpuCull::upload`] writes from.
pub(crate) struct CullInput<'a> {
    pub ranges: &'a [CullRange],
    pub runs: &'a [Run],
    /// Each view's frustum, and how it picks levels of detail.
    pub frustums: (&'a [Frustum], &'a [LodView]),
    /// Indirect commands in the list.
    pub commands: usize,
    /// How far apart in the draw-index buffer each level's places are.
    pub level_stride: u32,
}

/// The buffers the cull pass binds that the list does not own.
pub(crate) struct CullBindings<'a> {
    pub bounds: &'a wgpu::Buffer,
    pub draw_indices: &'a wgpu::Buffer,
}

impl GpuCull {
    pub(crate) fn new(device: &wgpu::Device, label: &'static str) -> Self {
        use wgpu::BufferUsages as U;
        let buffer = |usage, bytes| GrowBuffer::new(device, label, usage, bytes);
        Self {
            label,
            params: device.create_buffer(&wgpu::BufferDescriptor {
                label: Some(label),
                size: std::mem::size_of::<Params>() as u64,
                usage: U::UNIFORM | U::COPY_DST,
                mapped_at_creation: false,
            }),
            ranges: buffer(U::STORAGE, 1024),
            planes: buffer(U::STORAGE, 1024),
            args: buffer(U::STORAGE | U::INDIRECT | U::COPY_SRC, 1024),
            drawn_args: buffer(U::STORAGE | U::INDIRECT | U::COPY_SRC, 1024),
            runs: buffer(U::STORAGE, 1024),
            counts: buffer(U::STORAGE | U::INDIRECT | U::COPY_SRC, 1024),
            groups: None,
            uploaded: Default::default(),
            params_now: Params::default(),
            readback: CountReadback::new(device, MAX_READBACK_WORDS),
            late: None,
            late_groups: None,
            occluding: false,
            late_params: None,
            occlusion_pays: true,
            skip_occlusion: 0,
        }
    }

    /// Forget the bind groups (a buffer they hold was replaced).
    pub(crate) fn unbind(&mut self) {
        self.groups = None;
        self.late_groups = None;
    }

    /// Write what changed of `input` (and make room for it); returns bytes written.
    pub(crate) fn upload(
        &mut self,
        device: &wgpu::Device,
        queue: &wgpu::Queue,
        (input, late): (&CullInput, Option<&LateInput>),
        pipelines: &CullPipelines,
        bindings: CullBindings,
    ) -> Result<u64, RenderError> {
        // Per view: its six planes, then its level-of-detail rule.
        let (frustums, lods) = input.frustums;
        let planes: Vec<[f32; 4]> = (frustums.iter().zip(lods))
            .flat_map(|(f, lod)| f.planes().map(|p| p.to_array()).into_iter().chain(lod.to_gpu()))
            .collect();
        let candidates = input.ranges.last().map_or(0, |r| r.start + r.count);
        let runs = input.runs.len() as u32;
        // Counts: the early runs', the late runs', each frustum's total, then
        // how many instances the late phase found hidden.
        let frustums = frustums.len() as u32;
        let params = Params {
            ranges: input.ranges.len() as u32,
            candidates,
            runs,
            totals: 2 * runs,
            counts_first: 0,
            place_offset: 0,
            level_stride: input.level_stride,
            pad: 0,
        };
        let commands = input.commands as u64 * COMMAND_BYTES;
        let mut replaced = false;
        for (buffer, bytes) in [
            (&mut self.ranges, std::mem::size_of_val(input.ranges) as u64),
            (&mut self.planes, std::mem::size_of_val(planes.as_slice()) as u64),
            (&mut self.args, commands),
            (&mut self.drawn_args, commands),
            (&mut self.runs, std::mem::size_of_val(input.runs) as u64),
            (&mut self.counts, 4 * u64::from(2 * runs + frustums * TOTAL_WORDS as u32 + 1)),
        ] {
            replaced |= buffer.reserve(device, bytes)?;
        }
        if replaced {
            // Both phases' groups hold the ranges, planes, runs and counts.
            self.uploaded = Default::default();
            self.unbind();
        }
        let mut written = 0;
        if self.uploaded.0 != input.ranges {
            written += self.ranges.write(queue, 0, input.ranges);
            self.uploaded.0 = input.ranges.to_vec();
            // New candidates: last frame's flags say nothing of them.
            if let Some(late) = &mut self.late {
                late.reset_hidden = true;
            }
        }
        if self.uploaded.1 != input.runs {
            written += self.runs.write(queue, 0, input.runs);
            self.uploaded.1 = input.runs.to_vec();
        }
        if self.uploaded.2 != planes {
            written += self.planes.write(queue, 0, &planes);
            self.uploaded.2 = planes;
        }
        if self.uploaded.3 != params || replaced {
            queue.write_buffer(&self.params, 0, bytemuck::bytes_of(&params));
            written += std::mem::size_of::<Params>() as u64;
            self.uploaded.3 = params;
        }
        self.params_now = params;
        if self.groups.is_none() {
            self.groups = Some(self.bind(device, pipelines, &bindings, (&self.params, &self.args, &self.drawn_args)));
        }
        self.occluding = false;
        // Where occlusion culling hid nothing, frustum culling alone for a while.
        let probe = self.occlusion_pays || self.skip_occlusion == 0;
        self.skip_occlusion = self.skip_occlusion.saturating_sub(u32::from(!probe));
        if let (Some(input), Some(occlusion), true, true) = (late, &pipelines.occlusion, pipelines.occlusion_on, probe)
        {
            written += self.upload_late(device, queue, (input, params), (pipelines, occlusion), &bindings)?;
            self.occluding = true;
        }
        Ok(written)
    }

    /// The late phase's part of [`upload`](Self::upload).
    fn upload_late(
        &mut self,
        device: &wgpu::Device,
        queue: &wgpu::Queue,
        (input, early): (&LateInput, Params),
        (pipelines, occlusion): (&CullPipelines, &OcclusionPipelines),
        bindings: &CullBindings,
    ) -> Result<u64, RenderError> {
        let late = self.late.get_or_insert_with(|| LatePhase::new(device, self.label));
        let (mut written, replaced) = late.upload(device, queue, input, early.candidates)?;
        let params = Params { counts_first: early.runs, place_offset: input.place_offset, ..early };
        if replaced || self.late_params != Some(params) {
            queue.write_buffer(&late.params, 0, bytemuck::bytes_of(&params));
            written += std::mem::size_of::<Params>() as u64;
            self.late_params = Some(params);
        }
        if replaced {
            self.late_groups = None;
        }
        if self.late_groups.is_none() {
            let late = self.late.as_ref().expect("made above");
            let [cull, compact] = self.bind(device, pipelines, bindings, (&late.params, &late.args, &late.drawn_args));
            self.late_groups = Some([cull, compact, late.bind(device, &occlusion.layout)]);
        }
        Ok(written)
    }

    /// The cull and compact groups over `params` and the commands `args` (the
    /// early ones or the late) with their compacted `drawn_args`.
    fn bind(
        &self,
        device: &wgpu::Device,
        pipelines: &CullPipelines,
        bindings: &CullBindings,
        (params, args, drawn_args): (&wgpu::Buffer, &GrowBuffer, &GrowBuffer),
    ) -> [wgpu::BindGroup; 2] {
        fn whole(buffer: &wgpu::Buffer) -> wgpu::BindingResource<'_> {
            buffer.as_entire_binding()
        }
        let entries = [
            wgpu::BindGroupEntry { binding: 0, resource: whole(params) },
            wgpu::BindGroupEntry { binding: 1, resource: whole(bindings.bounds) },
            wgpu::BindGroupEntry { binding: 2, resource: whole(&self.ranges.buffer) },
            wgpu::BindGroupEntry { binding: 3, resource: whole(&self.planes.buffer) },
            wgpu::BindGroupEntry { binding: 4, resource: whole(bindings.draw_indices) },
            wgpu::BindGroupEntry { binding: 5, resource: whole(&args.buffer) },
            wgpu::BindGroupEntry { binding: 6, resource: whole(&self.counts.buffer) },
        ];
        let cull = device.create_bind_group(&wgpu::BindGroupDescriptor {
            label: Some(self.label),
            layout: &pipelines.cull_layout,
            entries: &entries,
        });
        let compact = device.create_bind_group(&wgpu::BindGroupDescriptor {
            label: Some(self.label),
            layout: &pipelines.compact_layout,
            entries: &[
                wgpu::BindGroupEntry { binding: 0, resource: whole(&self.runs.buffer) },
                wgpu::BindGroupEntry { binding: 1, resource: whole(&drawn_args.buffer) },
            ],
        });
        [cull, compact]
    }

    /// Record the (early) cull pass: the commands reset from `template` (the
    /// CPU's) and `late_template`'s, every candidate tested (occluding: only
    /// those seen last frame), the runs compacted; not occluding, the totals
    /// copied for reading back (`submits`: the queue's submissions so far).
    pub(crate) fn record(
        &mut self,
        encoder: &mut wgpu::CommandEncoder,
        pipelines: &CullPipelines,
        template: &wgpu::Buffer,
        submits: u64,
    ) {
        let Some([cull, compact]) = &self.groups else { return };
        let Params { candidates, runs, .. } = self.params_now;
        let frustums = self.uploaded.2.len() as u32 / VIEW_ROWS as u32;
        let commands = u64::from(self.uploaded.1.last().map_or(0, |r| r.first + r.len)) * COMMAND_BYTES;
        let occluding = self.occluding.then(|| self.late.as_ref().zip(self.late_groups.as_ref())).flatten();
        let occluding_now = occluding.is_some();
        if commands > 0 {
            encoder.copy_buffer_to_buffer(template, 0, &self.args.buffer, 0, commands);
            if let Some((late, _)) = occluding {
                encoder.copy_buffer_to_buffer(&late.template.buffer, 0, &late.args.buffer, 0, commands);
            }
        }
        let totals = frustums * TOTAL_WORDS as u32;
        encoder.clear_buffer(&self.counts.buffer, 0, Some(4 * u64::from(2 * runs + totals + 1)));
        if let Some((late, _)) = occluding {
            // All flags for new candidates; else only the hidden count after them.
            let from = if late.reset_hidden { 0 } else { 4 * u64::from(candidates) };
            encoder.clear_buffer(&late.hidden.buffer, from, Some(4 * u64::from(candidates) + 4 - from));
        }
        {
            let mut pass = encoder.begin_compute_pass(&wgpu::ComputePassDescriptor {
                label: Some("cull instances"),
                timestamp_writes: None,
            });
            pass.set_bind_group(0, cull, &[]);
            let pipeline = match (occluding, &pipelines.occlusion) {
                (Some((_, [.., occlusion])), Some(o)) => {
                    pass.set_bind_group(2, occlusion, &[]);
                    &o.early
                }
                _ => &pipelines.cull,
            };
            dispatch(&mut pass, (pipeline, candidates), (pipelines, compact, runs));
        }
        if let Some(late) = &mut self.late {
            late.reset_hidden &= !occluding_now;
        }
        if !occluding_now {
            self.readback.copy(encoder, &self.counts.buffer, u64::from(2 * runs) * 4, totals, submits);
        }
    }

    /// Record the late phase, between the early and the late forward pass:
    /// the pyramid from `depth` (its depth-only view), every candidate tested
    /// against it, the late runs compacted, the totals copied for reading back.
    pub(crate) fn record_late(
        &mut self,
        (device, encoder): (&wgpu::Device, &mut wgpu::CommandEncoder),
        pipelines: &CullPipelines,
        depth: &wgpu::TextureView,
        submits: u64,
    ) {
        let (Some(late), Some([cull, compact, occlusion]), Some(o)) =
            (&self.late, &self.late_groups, &pipelines.occlusion)
        else {
            return;
        };
        let Params { candidates, runs, .. } = self.params_now;
        if let Some(pyramid) = &late.pyramid {
            pyramid.record(device, encoder, &o.pyramid, depth);
        }
        {
            let mut pass = encoder.begin_compute_pass(&wgpu::ComputePassDescriptor {
                label: Some("cull instances: late"),
                timestamp_writes: None,
            });
            pass.set_bind_group(0, cull, &[]);
            pass.set_bind_group(2, occlusion, &[]);
            dispatch(&mut pass, (&o.late, candidates), (pipelines, compact, runs));
        }
        // The totals, and the hidden count after them.
        let totals = (self.uploaded.2.len() / VIEW_ROWS * TOTAL_WORDS) as u32;
        let hidden_at = 4 * u64::from(2 * runs + totals);
        encoder.copy_buffer_to_buffer(
            &late.hidden.buffer,
            4 * u64::from(candidates),
            &self.counts.buffer,
            hidden_at,
            4,
        );
        self.readback.copy(encoder, &self.counts.buffer, u64::from(2 * runs) * 4, totals + 1, submits);
    }

    /// Draw run `k` (`run`) of the list from the culled commands: the early
    /// phase's (or the only one's), or the late phase's when `late`.
    pub(crate) fn draw_run(
        &self,
        pipelines: &CullPipelines,
        pass: &mut wgpu::RenderPass<'_>,
        (k, late): (usize, bool),
        run: &Run,
    ) {
        let at = u64::from(run.first) * COMMAND_BYTES;
        let runs = self.params_now.runs as usize;
        match (late, &self.late, pipelines.draw_count) {
            (true, Some(l), count) => {
                crate::render::gpu_driven::occlusion::draw_late_run(l, &self.counts.buffer, count, pass, (k, runs), run)
            }
            (true, None, _) => {}
            (false, _, true) => pass.multi_draw_indexed_indirect_count(
                &self.drawn_args.buffer,
                at,
                &self.counts.buffer,
                k as u64 * 4,
                run.len,
            ),
            (false, _, false) => pass.multi_draw_indexed_indirect(&self.args.buffer, at, run.len),
        }
    }

    /// The late phase's commands, when this frame's list is occlusion-culled.
    pub(crate) fn late_args(&self) -> Option<&wgpu::Buffer> {
        self.late.as_ref().filter(|_| self.occluding).map(|l| &l.args.buffer)
    }

    /// What the last frame drew, every frustum's summed, waiting for the GPU.
    pub(crate) fn wait_drawn(&mut self, device: &wgpu::Device, submits: u64) -> Option<DrawnCounts> {
        let totals = self.uploaded.2.len() / VIEW_ROWS * TOTAL_WORDS;
        let latest = self.readback.wait_all(device, submits)?;
        Some(summed(&latest[..totals.min(latest.len())]))
    }

    /// What the newest frame whose counts came back drew, every frustum's
    /// summed (`None` before the first), without waiting for the GPU. An
    /// occlusion-culled frame's counts also say whether occlusion culling hid
    /// anything: where it hid nothing, the list is culled by frustum alone for
    /// [`SKIP_UNPAID_OCCLUSION`] frames, then tries again (on a CPU rasterizer
    /// the pyramid and the second pass cost more than frustum culling alone).
    pub(crate) fn drawn(&mut self, device: &wgpu::Device, submits: u64) -> Option<DrawnCounts> {
        let totals = self.uploaded.2.len() / VIEW_ROWS * TOTAL_WORDS;
        self.readback.collect(device, submits);
        let fresh = self.readback.take_fresh();
        let latest = self.readback.latest()?;
        if fresh {
            if let Some(&hidden) = latest.get(totals) {
                self.occlusion_pays = hidden > 0;
                if !self.occlusion_pays {
                    self.skip_occlusion = SKIP_UNPAID_OCCLUSION;
                }
            }
        }
        Some(summed(&latest[..totals.min(latest.len())]))
    }
}

/// The frustums' totals (each [`TOTAL_WORDS`] words) summed.
fn summed(totals: &[u32]) -> DrawnCounts {
    let mut drawn = DrawnCounts::default();
    for frustum in totals.chunks_exact(TOTAL_WORDS) {
        drawn.instances += u64::from(frustum[0].saturating_sub(frustum[2 + MAX_LEVELS]));
        drawn.triangles += u64::from(frustum[1]);
        for (level, &n) in drawn.per_level.iter_mut().zip(&frustum[2..2 + MAX_LEVELS]) {
            *level += u64::from(n);
        }
    }
    drawn
}

/// In `pass` (its group 0, and 2 where the cull pipeline reads it, bound):
/// `cull` over `candidates` invocations, then the compact pass over `runs`
/// with `compact` as its group 1.
fn dispatch(
    pass: &mut wgpu::ComputePass<'_>,
    (cull, candidates): (&wgpu::ComputePipeline, u32),
    (pipelines, compact, runs): (&CullPipelines, &wgpu::BindGroup, u32),
) {
    if candidates > 0 {
        pass.set_pipeline(cull);
        let (x, y) = grid(candidates);
        pass.dispatch_workgroups(x, y, 1);
    }
    if runs > 0 {
        pass.set_pipeline(&pipelines.compact);
        pass.set_bind_group(1, compact, &[]);
        let (x, y) = grid(runs);
        pass.dispatch_workgroups(x, y, 1);
    }
}

/// Workgroups for `n` invocations, in rows of at most 65,535.
fn grid(n: u32) -> (u32, u32) {
    let groups = n.div_ceil(WORKGROUP);
    let x = groups.min(65_535);
    (x, groups.div_ceil(x))
}

#[cfg(test)]
mod layout_tests {
    use super::*;
    use crate::shader::layout::{assert_layout, assert_mirrors};

    #[test]
    fn the_culling_records_mirror_their_wgsl_structs() {
        let wgsl = crate::shader::CULL;
        assert_mirrors!(CullRange, wgsl, "CullRange", [first, count, start, batch, frustum, out, levels, pad, error]);
        let fields = [
            ("ranges", std::mem::offset_of!(Params, ranges)),
            ("candidates", std::mem::offset_of!(Params, candidates)),
            ("runs", std::mem::offset_of!(Params, runs)),
            ("totals", std::mem::offset_of!(Params, totals)),
            ("counts_first", std::mem::offset_of!(Params, counts_first)),
            ("place_offset", std::mem::offset_of!(Params, place_offset)),
            ("level_stride", std::mem::offset_of!(Params, level_stride)),
            ("pad", std::mem::offset_of!(Params, pad)),
        ];
        assert_layout(wgsl, "Params", std::mem::size_of::<Params>(), &fields);
        let words = format!("const TOTAL_WORDS: u32 = {TOTAL_WORDS}u;");
        assert!(wgsl.contains(&words), "cull.wgsl must say {words}");
        let shift = format!("const FADE_SHIFT: u32 = {}u;", crate::render::lod::FADE_SHIFT);
        assert!(wgsl.contains(&shift), "cull.wgsl must say {shift}");
    }
}
