//! Core layer: the forward view's stages 3 (queue) and 6 (upload).

use crate::gpu::OffscreenTarget;
use crate::render::debug::stats::{FrameStats, UploadStats};
use crate::render::error::RenderError;
use crate::render::frame::lights::upload_clusters;
use crate::render::frame::prepared::Prepared;
use crate::render::frame::state::Frame;
use crate::render::lod::level_items;
use crate::render::queue::{self, DrawItem, Queue};
use crate::render::resources::blocks::{CameraGpu, SceneGpu};
use crate::render::resources::Resources;
use crate::render::view::ViewFrame;
use crate::render::views::ViewGpu;
use crate::scene::{Culling, Lighting};
use glam::Vec3A;

/// Stage 3: one draw item per visible run and level of detail (its
/// instances reordered by level, [`level_items`]), or per visible instance for
/// blended materials so that they can be sorted far to near one by one; one
/// per run of store instances (an entity's candidates culled on the GPU, a
/// whole tile). Depth is the view distance of the run's (or instance's, or
/// entity's) box centre over the far plane.
pub(crate) fn build_queue(
    res: &Resources,
    frame: &mut Frame,
    gpu: &mut ViewGpu,
    view: &ViewFrame,
    prepared: &[Prepared],
) {
    let Frame { visible, submitted, .. } = frame;
    let far = view.camera.far();
    let depth = |center: Vec3A| -view.view.transform_point3a(center).z / far;
    let runs = visible.runs.iter().map(|r| (r, false)).chain(visible.ranges.iter().map(|r| (r, true)));
    for (run, of_store) in runs {
        let s = &submitted[run.entry];
        let material = &res.registry.materials[s.material.0 as usize];
        let Prepared { pipeline, draw, .. } = prepared[run.entry];
        let texture_set = draw.texture_set;
        let queue = match material.material.alpha_mode {
            crate::scene::AlphaMode::Opaque => Queue::Opaque,
            crate::scene::AlphaMode::Mask { .. } => Queue::AlphaTest,
            crate::scene::AlphaMode::Blend => Queue::Transparent,
        };
        let stage = s.render_order.unwrap_or(queue.stage());
        let blended = queue == Queue::Transparent;
        let item = |level, first, count, copies, depth| DrawItem {
            key: queue::sort_key(stage, blended, pipeline, texture_set, s.material, s.shape, depth),
            pipeline,
            material: s.material,
            shape: s.shape,
            first,
            count,
            entry: run.entry as u32,
            level,
            copies,
        };
        let (levels, bounds) = (&draw.mesh.levels, &res.store.bounds);
        if blended && !of_store {
            for k in run.start..run.start + run.len {
                let instance = visible.instances[k as usize] as usize;
                let level = view.lod.level(levels, bounds.center(instance), bounds.extent(instance));
                gpu.forward.items.push(item(level, k, 1, false, depth(bounds.center(instance))));
            }
        } else {
            let depth = depth(res.store.slot(s.slot).bounds.map_or(Vec3A::ZERO, |(c, _)| c));
            let (items, run_of) = (&mut gpu.forward.items, (visible.placed[run.entry], run.start, run.len));
            level_items(&view.lod, levels, run_of, (&mut visible.instances, bounds), |level, first, count, copies| {
                items.push(item(level, first, count, copies, depth));
            });
        }
    }
}

/// Stage 6: write the blocks that changed, the instances that changed, and this
/// frame's draw indices and indirect commands where they differ from the last frame's.
/// `shadowed` is each light's first shadow view (empty: no shadows).
/// Culled on the GPU, the view is occlusion-culled against its depth in `target`.
pub(crate) fn upload(
    res: &mut Resources,
    gpu: &mut ViewGpu,
    frame: &ViewFrame,
    (lighting, shadowed): (&Lighting, &[Option<u32>]),
    target: &OffscreenTarget,
    stats: &mut FrameStats,
) -> Result<(), RenderError> {
    upload_view_blocks(res, gpu, frame, lighting, shadowed, &mut stats.bytes_uploaded)?;
    let bytes = &mut stats.bytes_uploaded;
    let layout = &res.registry.pipelines.instance_layout;
    let culls = res.cull_pipelines.as_ref().zip(res.instances.bounds());
    let view_proj = frame.projection * frame.view;
    let depth = (target.width(), target.height(), target.samples());
    let occlusion = (frame.culling == Culling::Gpu).then_some((view_proj, depth));
    let list = &mut gpu.forward;
    let written = list.upload(&res.device, &res.queue, (layout, res.instances.array()), culls, occlusion)?;
    stats.occlusion = list.gpu.as_ref().is_some_and(|g| g.occluding);
    bytes.draw_indices += written.draw_indices;
    bytes.indirect += written.indirect;
    stats.set_drawn(gpu.forward.cpu_drawn());
    if gpu.forward.culled_on_gpu() {
        // Counted on the GPU (blended instances included), a frame or two late.
        let submits = res.queue.submits();
        let drawn = gpu.forward.gpu_drawn(&res.device, submits, false);
        let valid = stats.instances_submitted - stats.instances_invalid;
        stats.set_drawn(drawn.unwrap_or_default());
        stats.instances_culled = drawn.map_or(0, |d| valid.saturating_sub(d.instances));
    }
    Ok(())
}

/// The view's Scene and Camera blocks where they changed, its light
/// clusters where it clusters, and the instances that changed.
pub(crate) fn upload_view_blocks(
    res: &mut Resources,
    gpu: &mut ViewGpu,
    frame: &ViewFrame,
    lighting: &Lighting,
    shadowed: &[Option<u32>],
    bytes: &mut UploadStats,
) -> Result<(), RenderError> {
    let scene = SceneGpu::new(&lighting.environment, lighting.lights, shadowed)
        .with_specular_levels(res.environment.last_level())
        .with_sub_frame(frame.sample);
    let scene = upload_clusters(res, gpu, (scene, lighting.lights, shadowed), bytes)?;
    bytes.scene += gpu.scene_block.update(&res.queue, scene);
    let camera =
        CameraGpu::new(frame.camera, frame.projection).with_motion(&lighting.environment).with_far_eye(frame.far_eye);
    bytes.camera += gpu.blocks.update(&res.queue, 0, camera);
    upload_instances(res, bytes);
    Ok(())
}

/// Write the instances that changed (all of them when the frame's start
/// replaced the buffer: [`compact_store`](super::stages::compact_store)).
pub(crate) fn upload_instances(res: &mut Resources, bytes: &mut UploadStats) {
    for range in res.store.take_dirty() {
        let data = &res.store.instances[range.start as usize..range.end as usize];
        let (instances, bounds) = res.instances.write(&res.queue, range.start, data, &res.store.bounds);
        (bytes.instances, bytes.bounds) = (bytes.instances + instances, bytes.bounds + bounds);
    }
}

#[cfg(test)]
mod tests {
    use crate::gpu::OffscreenTarget;
    use crate::render::Renderer;
    use crate::render::Shadows;
    use crate::scene::ShapeKind;
    use crate::scene::{Background, Camera, Entity, Environment, Lighting, Material};
    use glam::{Mat4, Vec3};

    use crate::gpu::test_gpu as gpu;

    #[test]
    fn errors_while_pipelines_are_made_are_caught_not_left_to_panic() {
        let Some(gpu) = gpu() else { return };
        let scope = crate::gpu::DriverErrors::watch(&gpu.device);
        // Invalid on every adapter: anisotropy must be at least 1.
        let _sampler =
            gpu.device.create_sampler(&wgpu::SamplerDescriptor { anisotropy_clamp: 0, ..Default::default() });
        let error = scope.finish().expect("the error is caught");
        assert!(matches!(error, wgpu::Error::Validation { .. }), "{error}");
        let clean = crate::gpu::DriverErrors::watch(&gpu.device);
        let _sampler = gpu.device.create_sampler(&wgpu::SamplerDescriptor::default());
        assert!(clean.finish().is_none(), "nothing to catch");
    }

    #[test]
    fn blended_instances_are_drawn_far_to_near_and_render_order_overrides_queues() {
        let Some(gpu) = gpu() else { return };
        let mut r = Renderer::new(&gpu);
        // Each instance at its own level of detail would split the draws this counts.
        r.set_levels_of_detail(false);
        let sphere = r.add_shape(ShapeKind::Sphere.mesh());
        let glass = r.add_material(Material { alpha_mode: crate::AlphaMode::Blend, ..Material::default() });
        let solid = r.add_material(Material::default());
        // Instances at view distances 4, 10, 7, 12, 5 (camera at z = 10 looking down −z), scrambled.
        let zs = [6.0, 0.0, 3.0, -2.0, 5.0];
        let glass_entity =
            Entity::instanced(sphere, glass, zs.iter().map(|&z| Mat4::from_translation(Vec3::Z * z)).collect());
        let ground = Entity::new(sphere, solid, Mat4::from_translation(Vec3::Y * -2.0)).with_render_order(Some(200));
        let front = Entity::new(sphere, solid, Mat4::from_translation(Vec3::X * 2.0));
        let camera = Camera::perspective(60.0, 0.1, 100.0).looking_at(Vec3::Z * 10.0, Vec3::ZERO);
        let mut target = OffscreenTarget::new(&gpu, 32, 32, 1).expect("target");
        r.submit(&ground);
        r.submit(&glass_entity);
        r.submit(&front);
        let sky = Environment {
            background: Background::Gradient { top: Vec3::Z, bottom: Vec3::ONE },
            ..Environment::default()
        };
        let stats = r.flush(camera, Lighting::new(&[], sky), &Shadows::none(), &mut target).expect("frame");
        // Drawn order: `front` (opaque), sky, the five glass instances far to near, then the ground (200).
        let forward = &r.views.last(0).expect("drawn").forward;
        let stages: Vec<u8> = forward.batches.iter().map(|b| b.stage).collect();
        assert_eq!(stages, vec![64, 192, 200]);
        let glass_batch = forward.batches[1];
        assert_eq!(glass_batch.instance_count, 5, "one entity's instances merge into one draw once sorted");
        let order: Vec<f32> = forward.draw_indices[glass_batch.first_instance as usize..][..5]
            .iter()
            .map(|&i| r.res.store.instances[i as usize].transform().w_axis.z)
            .collect();
        assert_eq!(order, vec![-2.0, 0.0, 3.0, 5.0, 6.0], "far (low z) to near");
        assert_eq!(stats.draws, 4, "front, sky, glass, ground");
    }
}
