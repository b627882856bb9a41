//! Core layer: [`Renderer::drawn_instances`], what the last frame's lists drew,
//! read back from the GPU: how tests tell that culling on the GPU keeps exactly
//! the instances culling on the CPU keeps.

use crate::render::gpu_driven::draw_list::DrawList;
use crate::render::{RenderError, Renderer};

impl Renderer {
    /// The instances the last frame's first view (that of `render` or
    /// `flush`) drew, as instance-store indices, sorted: the camera's, then
    /// each shadow view's. Culled on the GPU, read back from what the cull pass wrote
    /// (waiting for the GPU); culled on the CPU, from the lists. Store indices
    /// are the renderer's own business, but two renderers given the same
    /// entities in the same order number them alike. Compact instances are
    /// left out.
    #[doc(hidden)]
    pub fn drawn_instances(&self) -> Result<Vec<Vec<u32>>, RenderError> {
        let Some((view, _)) = self.last_keys.first().and_then(|key| self.views.get(key)) else {
            return Ok(Vec::new());
        };
        let mut views = self.read_list(&view.forward)?;
        views.extend(self.read_list(&view.shadows)?);
        Ok(views)
    }

    /// Each frustum's instances drawn by `list`, sorted.
    fn read_list(&self, list: &DrawList) -> Result<Vec<Vec<u32>>, RenderError> {
        let mut views = vec![Vec::new(); list.frustums.len()];
        // Each batch's (first place, instances) in the draw indices, per phase.
        let (indices, phases): (Vec<u32>, Vec<Vec<(u32, u32)>>) = match (&list.gpu, list.culled_on_gpu()) {
            (Some(gpu), true) => {
                let indices = self.read_words(list.draw_index_buffer().expect("a storage buffer"))?;
                let mut phases = Vec::new();
                for args in [Some(&gpu.args.buffer), gpu.late_args()].into_iter().flatten() {
                    let words = self.read_words(args)?;
                    phases.push((0..list.batches.len()).map(|b| (words[5 * b + 4], words[5 * b + 1])).collect());
                }
                (indices, phases)
            }
            _ => {
                (list.cpu_indices(), vec![list.batches.iter().map(|b| (b.first_instance, b.instance_count)).collect()])
            }
        };
        for run in &list.runs {
            // Compact instances are numbered apart from the store's: left out.
            for b in run.batches().filter(|&b| list.placed[b] != crate::render::frame::visible::Placed::Compact) {
                for phase in &phases {
                    let (first, count) = (phase[b].0 as usize, phase[b].1 as usize);
                    views[run.frustum as usize].extend_from_slice(&indices[first..first + count]);
                }
            }
        }
        views.iter_mut().for_each(|v| v.sort_unstable());
        Ok(views)
    }

    /// The words of `buffer`, waiting for the GPU.
    fn read_words(&self, buffer: &wgpu::Buffer) -> Result<Vec<u32>, RenderError> {
        let bytes = crate::gpu::read_buffer(&self.device, &self.queue, buffer)
            .map_err(|e| RenderError::Device { what: "an inspection readback", message: e.to_string() })?;
        Ok(bytemuck::pod_collect_to_vec(&bytes))
    }
}
