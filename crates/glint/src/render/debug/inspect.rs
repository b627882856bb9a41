//! Core layer: [`Renderer::drawn_instances`](crate::Renderer::drawn_instances), what the last frame's lists drew,
//! read back from the GPU: how tests tell that culling on the GPU keeps exactly
//! the instances culling on the CPU keeps.

use crate::render::error::RenderError;
use crate::render::gpu_driven::draw_list::DrawList;

/// Each frustum's instances drawn by `list`, sorted.
pub(crate) fn read_list(
    (device, queue): (&wgpu::Device, &wgpu::Queue),
    list: &DrawList,
) -> Result<Vec<Vec<u32>>, RenderError> {
    let mut views = vec![Vec::new(); list.frustums.len()];
    // Each batch's (first place, instances) in the draw indices, per phase.
    let (indices, phases): (Vec<u32>, Vec<Vec<(u32, u32)>>) = match (&list.gpu, list.culled_on_gpu()) {
        (Some(gpu), true) => {
            let indices = read_words((device, queue), list.draw_index_buffer().expect("a storage buffer"))?;
            let mut phases = Vec::new();
            for args in [Some(&gpu.args.buffer), gpu.late_args()].into_iter().flatten() {
                let words = read_words((device, queue), args)?;
                phases.push((0..list.batches.len()).map(|b| (words[5 * b + 4], words[5 * b + 1])).collect());
            }
            (indices, phases)
        }
        _ => (list.cpu_indices(), vec![list.batches.iter().map(|b| (b.first_instance, b.instance_count)).collect()]),
    };
    for run in &list.runs {
        // Compact instances are numbered apart from the store's: left out.
        for b in run.batches().filter(|&b| list.placed[b] != crate::render::gpu_driven::commands::Placed::Compact) {
            for phase in &phases {
                let (first, count) = (phase[b].0 as usize, phase[b].1 as usize);
                views[run.frustum as usize].extend_from_slice(&indices[first..first + count]);
            }
        }
    }
    // A fading instance is drawn at two levels: its store index once.
    for v in &mut views {
        v.iter_mut().for_each(|i| *i &= crate::render::lod::INDEX_MASK);
        v.sort_unstable();
        v.dedup();
    }
    Ok(views)
}

/// The words of `buffer`, waiting for the GPU.
fn read_words((device, queue): (&wgpu::Device, &wgpu::Queue), buffer: &wgpu::Buffer) -> Result<Vec<u32>, RenderError> {
    let bytes = crate::gpu::read_buffer(device, queue, buffer)
        .map_err(|e| RenderError::Device { what: "an inspection readback", message: e.to_string() })?;
    Ok(bytemuck::pod_collect_to_vec(&bytes))
}
