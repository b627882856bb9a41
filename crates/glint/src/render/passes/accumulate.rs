//! Core layer: accumulated stills ([`SubFrame`]). Each sub-frame, a view into
//! the output is drawn jittered into its HDR target and folded into its
//! running mean, `mean + (x − mean) / (k + 1)`, kept in 32-bit float (16-bit
//! halves would stop moving once a sub-frame's share fell under their
//! precision) in two images the fold ping-pongs between: as the floats'
//! bits in 32-bit unsigned integers, which every backend renders into (wgpu's
//! GL backend, and so WebGL2, cannot render into 32-bit floats). The last sub-frame
//! copies the mean into a 16-bit HDR image for the view's post chain, so the
//! average is taken before tonemapping (`shader/accumulate.wgsl`).

use crate::gpu::HDR_FORMAT;
use crate::render::debug::explain::{DrawCall, PassType};
use crate::render::debug::outline::Outline;
use crate::render::error::RenderError;
use crate::render::frame::input::SubFrame;

/// Format of a view's running mean: the bits of 32-bit floats.
const MEAN_FORMAT: wgpu::TextureFormat = wgpu::TextureFormat::Rgba32Uint;

/// The fold's uniform (`Fold` in `accumulate.wgsl`): x, the sub-frame's weight.
#[repr(C)]
#[derive(Clone, Copy, Debug, PartialEq, bytemuck::Pod, bytemuck::Zeroable)]
struct Fold {
    weight: [f32; 4],
}

/// The fold's and the copy's pipelines, made with the first still.
pub(crate) struct AccumulatePipelines {
    layout: wgpu::BindGroupLayout,
    fold: wgpu::RenderPipeline,
    copy: wgpu::RenderPipeline,
}

impl AccumulatePipelines {
    /// Both pipelines on `device`.
    pub(crate) fn new(device: &wgpu::Device) -> Result<Self, RenderError> {
        let scope = crate::gpu::DriverErrors::watch(device);
        let texture = |binding, sample_type| wgpu::BindGroupLayoutEntry {
            binding,
            visibility: wgpu::ShaderStages::FRAGMENT,
            ty: wgpu::BindingType::Texture {
                sample_type,
                view_dimension: wgpu::TextureViewDimension::D2,
                multisampled: false,
            },
            count: None,
        };
        let weight = wgpu::BindGroupLayoutEntry {
            binding: 2,
            visibility: wgpu::ShaderStages::FRAGMENT,
            ty: wgpu::BindingType::Buffer {
                ty: wgpu::BufferBindingType::Uniform,
                has_dynamic_offset: false,
                min_binding_size: wgpu::BufferSize::new(std::mem::size_of::<Fold>() as u64),
            },
            count: None,
        };
        let layout = device.create_bind_group_layout(&wgpu::BindGroupLayoutDescriptor {
            label: Some("accumulate: layout"),
            entries: &[
                texture(0, wgpu::TextureSampleType::Uint),
                texture(1, wgpu::TextureSampleType::Float { filterable: false }),
                weight,
            ],
        });
        let pipeline_layout = device.create_pipeline_layout(&wgpu::PipelineLayoutDescriptor {
            label: Some("accumulate: pipeline layout"),
            bind_group_layouts: &[Some(&layout)],
            immediate_size: 0,
        });
        let module = device.create_shader_module(wgpu::ShaderModuleDescriptor {
            label: Some("accumulate: shader"),
            source: wgpu::ShaderSource::Wgsl(crate::shader::ACCUMULATE.into()),
        });
        let shader = (&pipeline_layout, &module);
        let pipeline = |label, entry, format| {
            crate::gpu::full_screen_pipeline(device, label, shader, ("vs_accumulate", entry), format)
        };
        let pipelines = Self {
            fold: pipeline("accumulate: fold", "fs_fold", MEAN_FORMAT),
            copy: pipeline("accumulate: copy", "fs_copy", HDR_FORMAT),
            layout,
        };
        match scope.finish() {
            Some(error) => Err(driver_error(error)),
            None => Ok(pipelines),
        }
    }
}

fn driver_error(error: wgpu::Error) -> RenderError {
    RenderError::Device { what: "the accumulated still's passes", message: error.to_string() }
}

/// A view's running mean: two 32-bit float images the fold ping-pongs
/// between, the HDR image its post chain reads, and the fold's weight.
pub(crate) struct Accumulation {
    size: (u32, u32),
    means: [wgpu::TextureView; 2],
    image: wgpu::TextureView,
    weight: wgpu::Buffer,
    /// The sub-frame it takes next.
    next: SubFrame,
    /// Which of `means` holds the mean so far.
    current: usize,
}

impl Accumulation {
    fn new(device: &wgpu::Device, (width, height): (u32, u32)) -> Result<Self, RenderError> {
        let scope = crate::gpu::DriverErrors::watch(device);
        let image = |label, format| {
            let texture = device.create_texture(&wgpu::TextureDescriptor {
                label: Some(label),
                size: wgpu::Extent3d { width, height, depth_or_array_layers: 1 },
                mip_level_count: 1,
                sample_count: 1,
                dimension: wgpu::TextureDimension::D2,
                format,
                usage: wgpu::TextureUsages::RENDER_ATTACHMENT | wgpu::TextureUsages::TEXTURE_BINDING,
                view_formats: &[],
            });
            texture.create_view(&Default::default())
        };
        let accumulation = Self {
            size: (width, height),
            means: [image("accumulate: mean 0", MEAN_FORMAT), image("accumulate: mean 1", MEAN_FORMAT)],
            image: image("accumulate: image", HDR_FORMAT),
            weight: device.create_buffer(&wgpu::BufferDescriptor {
                label: Some("accumulate: weight"),
                size: std::mem::size_of::<Fold>() as u64,
                usage: wgpu::BufferUsages::UNIFORM | wgpu::BufferUsages::COPY_DST,
                mapped_at_creation: false,
            }),
            next: SubFrame { index: 0, count: 0 },
            current: 0,
        };
        match scope.finish() {
            Some(error) => Err(driver_error(error)),
            None => Ok(accumulation),
        }
    }

    /// The view's accumulation for `sample` of a still `size` pixels: `kept`,
    /// which must have taken the sub-frame before, or at sub-frame 0 new
    /// where `kept` is missing or of another size.
    pub(crate) fn for_sample(
        device: &wgpu::Device,
        kept: Option<Self>,
        sample: SubFrame,
        size: (u32, u32),
    ) -> Result<Self, RenderError> {
        let out_of_order =
            |why: String| RenderError::SubFrameOutOfOrder { index: sample.index, count: sample.count, why };
        match kept {
            Some(a) if sample.index == 0 && a.size == size => Ok(a),
            _ if sample.index == 0 => Self::new(device, size),
            None => Err(out_of_order("this view drew no sub-frame 0 before it".into())),
            Some(a) if a.next != sample => {
                let (k, n) = (a.next.index, a.next.count);
                Err(out_of_order(format!("this view expected sub-frame {k} of {n} next")))
            }
            Some(a) if a.size != size => {
                let (w, h) = a.size;
                Err(out_of_order(format!("this view's earlier sub-frames were {w}x{h}")))
            }
            Some(a) => Ok(a),
        }
    }

    /// Record `sample`, drawn into `scene`, folded into the mean, and at the
    /// still's last sub-frame (returns true) the mean copied into
    /// [`mean`](Self::mean)'s image.
    pub(crate) fn fold(
        &mut self,
        (device, queue, pipelines): (&wgpu::Device, &wgpu::Queue, &AccumulatePipelines),
        (encoder, outline): (&mut wgpu::CommandEncoder, &Outline),
        scene: &wgpu::TextureView,
        sample: SubFrame,
    ) -> bool {
        let fold = Fold { weight: [1.0 / (sample.index + 1) as f32, 0.0, 0.0, 0.0] };
        queue.write_buffer(&self.weight, 0, bytemuck::bytes_of(&fold));
        let (from, to) = (self.current, 1 - self.current);
        let read = [&self.means[from], scene];
        let fold = (pipelines, &pipelines.fold);
        full_screen(device, fold, (encoder, outline), (read, &self.weight), (&self.means[to], "fold"));
        self.current = to;
        self.next = SubFrame { index: sample.index + 1, ..sample };
        if !sample.is_last() {
            return false;
        }
        let read = [&self.means[to], scene]; // the copy reads only the mean
        let copy = (pipelines, &pipelines.copy);
        full_screen(device, copy, (encoder, outline), (read, &self.weight), (&self.image, "copy"));
        true
    }

    /// The HDR image the last sub-frame copied the mean into.
    pub(crate) fn mean(&self) -> &wgpu::TextureView {
        &self.image
    }
}

/// One full-screen pass of `pipeline` reading `read` and `weight`, writing
/// `target`, as `outline` lists it ("accumulate: fold", "accumulate: copy").
fn full_screen(
    device: &wgpu::Device,
    (pipelines, pipeline): (&AccumulatePipelines, &wgpu::RenderPipeline),
    (encoder, outline): (&mut wgpu::CommandEncoder, &Outline),
    (read, weight): ([&wgpu::TextureView; 2], &wgpu::Buffer),
    (target, what): (&wgpu::TextureView, &str),
) {
    let bind_group = device.create_bind_group(&wgpu::BindGroupDescriptor {
        label: Some("accumulate: inputs"),
        layout: &pipelines.layout,
        entries: &[
            wgpu::BindGroupEntry { binding: 0, resource: wgpu::BindingResource::TextureView(read[0]) },
            wgpu::BindGroupEntry { binding: 1, resource: wgpu::BindingResource::TextureView(read[1]) },
            wgpu::BindGroupEntry { binding: 2, resource: weight.as_entire_binding() },
        ],
    });
    let label = format!("accumulate: {what}");
    let mut pass = encoder.begin_render_pass(&wgpu::RenderPassDescriptor {
        label: Some(&label),
        color_attachments: &[Some(wgpu::RenderPassColorAttachment {
            view: target,
            depth_slice: None,
            resolve_target: None,
            ops: wgpu::Operations { load: wgpu::LoadOp::Load, store: wgpu::StoreOp::Store },
        })],
        ..Default::default()
    });
    pass.set_pipeline(pipeline);
    pass.set_bind_group(0, &bind_group, &[]);
    pass.draw(0..3, 0..1);
    drop(pass);
    outline.pass(&label, PassType::Render, &[]);
    let changed = ["pipeline", "bind group 0 (the mean, the sub-frame and the weight)"];
    outline.call(|| DrawCall::single(&label, "draw", (1, 1), &changed));
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn jitter_covers_the_pixel_and_is_none_for_a_frame_of_its_own() {
        assert_eq!(SubFrame::ONE.jitter(), glam::Vec2::ZERO);
        let offsets: Vec<glam::Vec2> = (0..16).map(|index| SubFrame { index, count: 16 }.jitter()).collect();
        assert!(offsets.iter().all(|o| o.abs().max_element() <= 0.5), "{offsets:?}");
        // Halton (2, 3): 1 → (1/2, 1/3), 2 → (1/4, 2/3).
        assert!((offsets[0] - glam::Vec2::new(0.0, 1.0 / 3.0 - 0.5)).length() < 1e-6);
        assert!((offsets[1] - glam::Vec2::new(-0.25, 2.0 / 3.0 - 0.5)).length() < 1e-6);
        // Every quarter of the pixel gets about four of sixteen.
        for quarter in 0..4 {
            let inside = |o: &&glam::Vec2| (o.x >= 0.0) == (quarter & 1 == 1) && (o.y >= 0.0) == (quarter & 2 == 2);
            let count = offsets.iter().filter(inside).count();
            assert!((3..=5).contains(&count), "quarter {quarter}: {count} of {offsets:?}");
        }
        // And no two of 256 fall within a 64th of a pixel of each other.
        let many: Vec<glam::Vec2> = (0..256).map(|index| SubFrame { index, count: 256 }.jitter()).collect();
        let closest = (0..256).flat_map(|a| (0..a).map(move |b| (a, b))).map(|(a, b)| many[a].distance(many[b]));
        assert!(closest.fold(f32::MAX, f32::min) > 1.0 / 64.0);
        let mean = offsets.iter().sum::<glam::Vec2>() / 16.0;
        assert!(mean.length() < 0.05, "centred: {mean}");
    }

    #[test]
    fn the_fold_weight_mirrors_its_wgsl_struct() {
        crate::shader::layout::assert_mirrors!(Fold, crate::shader::ACCUMULATE, "Fold", [weight]);
    }
}
