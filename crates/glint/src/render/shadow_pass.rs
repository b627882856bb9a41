//! Core layer: [`Renderer::shadow_pass`], the shadow maps of a frame.
//!
//! Each shadow view (a cascade, a spot light, a cube face) is culled on its own
//! from the submitted entities that cast shadows — so a caster outside the
//! camera's view still casts — and its draws are sorted and batched like the
//! forward view's, into one [`DrawList`](super::draw_list::DrawList) for all
//! views. Each view is one depth-only render pass into its layer of the shadow
//! maps, recorded into the frame's one encoder before the forward pass, and
//! sent in the frame's one submission.

use super::blocks::CameraGpu;
use super::cull::Frustum;
use super::encode::Bound;
use super::explain::PassType;
use super::pipelines::PassKind;
use super::prepare::Prepared;
use super::queue::{self, DrawItem, Queue};
use super::shadow_maps::{ShadowGpu, ShadowMaps};
use super::shadow_views::{self, ShadowView, ViewTarget};
use super::timer::Timed;
use super::view::ViewFrame;
use super::views::{ViewBlocks, MAX_SHADOW_VIEWS};
use super::visible::VisibleRun;
use super::{ms_since, FrameStats, PassStats, RenderError, Renderer};
use crate::gpu::OffscreenTarget;
use crate::scene::{Aabb, AlphaMode, Culling, Light, LightKind, Lighting, ShadowLayout, View, MAX_LIGHTS};
use glam::Vec3;
use web_time::Instant;

/// The shadow maps a view's shadow pass drew this frame: what the forward pass
/// of the same view ([`Renderer::flush`]) samples. [`Shadows::none`] draws
/// without shadows.
#[derive(Clone, Debug, Default)]
pub struct Shadows {
    pub(super) drawn: Option<ShadowsDrawn>,
}

impl Shadows {
    /// No shadow maps: every light is drawn without shadows.
    pub fn none() -> Self {
        Self::default()
    }
}

/// What a shadow pass drew.
#[derive(Clone, Debug)]
pub(super) struct ShadowsDrawn {
    /// The renderer's frame it was drawn for (the maps are redrawn every frame).
    pub frame_index: u64,
    /// The view it was drawn for (cascades follow the camera and its aspect).
    pub view: View,
    /// The lights the maps were drawn for.
    pub lights: Vec<Light>,
    /// Per light, its first shadow view (2D layer, or cube for point lights).
    pub first_view: Vec<Option<u32>>,
    /// Shadow views drawn.
    pub views: u32,
    /// Draws and time of the pass.
    pub cost: PassStats,
    /// Bytes it uploaded and pipelines it compiled, added to the frame's.
    pub prepared: FrameStats,
}

impl ShadowsDrawn {
    /// Per light, its first shadow view, when these maps were drawn this frame
    /// for `view` and exactly `lights`.
    pub fn first_views(&self, frame_index: u64, view: &View, lights: &[Light]) -> Result<&[Option<u32>], RenderError> {
        if self.frame_index != frame_index {
            return Err(RenderError::StaleShadows);
        }
        // The maps follow the camera and the rectangle's shape, not the post chain.
        let same = self.view.camera == view.camera && self.view.viewport == view.viewport;
        if !same || self.lights != lights {
            return Err(RenderError::ShadowsForOtherView);
        }
        Ok(&self.first_view)
    }
}

/// A frame's shadow views, their names, and each light's first view.
struct ShadowPlan {
    views: Vec<ShadowView>,
    names: Vec<String>,
    first: Vec<Option<u32>>,
}

impl Renderer {
    /// Draw the shadow maps of every light in `lighting` that casts shadows (see
    /// [`Light::with_shadows`]), from the entities submitted so far, for `view`
    /// of `target` (a camera is a view of the whole target). Call it between the
    /// frame's [`submit`](Self::submit)s and its [`flush`](Self::flush), and give
    /// what it returns to that flush, with the same view and lights: it darkens
    /// what they cannot reach.
    ///
    /// Lights past the shadow maps' room (16 two-dimensional views: four per
    /// directional light, one per spot light; 4 point lights) are drawn without
    /// shadows, with a warning in the log. A bad id submitted this frame is
    /// reported by `flush`.
    pub fn shadow_pass<'l>(
        &mut self,
        view: impl Into<View>,
        lighting: impl Into<Lighting<'l>>,
        target: &OffscreenTarget,
    ) -> Result<Shadows, RenderError> {
        let start = Instant::now();
        let (view, lighting) = (view.into(), lighting.into());
        let lights = lighting.lights;
        if lights.len() > MAX_LIGHTS {
            return Err(RenderError::TooManyLights(lights.len()));
        }
        if self.submit_error.is_some() {
            return Ok(Shadows::none());
        }
        let mut prepared = FrameStats::default();
        // The flush after this pass samples the maps it draws: choose its pipelines now.
        self.frame_variant = super::FrameVariant::expected(lights, self.occludes(view.ambient_occlusion));
        let draws_with = self.prepare(self.scene_format(&view, target), &lighting.environment, &mut prepared)?;
        let [_, _, width, height] = view.viewport.pixels(target.width(), target.height());
        let frame = ViewFrame::new(&view, width, height, self.cull_pipelines.is_some());
        let ShadowPlan { views, names, first: first_view } = self.plan_shadow_views(&frame, lights)?;
        let mut drawn = ShadowsDrawn {
            frame_index: self.frame_index,
            view,
            lights: lights.to_vec(),
            first_view,
            views: views.len() as u32,
            cost: PassStats::default(),
            prepared,
        };
        if !views.is_empty() {
            let ranges = self.batch_shadow_views((&views, &draws_with), frame.culling, &mut drawn.prepared)?;
            self.upload_shadow_views(&views, &lighting.environment, &mut drawn.prepared)?;
            let mut encoder = self.take_encoder();
            self.outline.enter(&mut encoder, "shadows");
            self.encode_shadow_views(&mut encoder, (&views, &names), &ranges, &mut drawn.cost);
            self.outline.leave(&mut encoder);
            self.encoder = Some(encoder);
        }
        drawn.cost.cpu_ms = ms_since(start);
        Ok(Shadows { drawn: Some(drawn) })
    }

    /// Every shadow view of `lights`, its name ("light 0 cascade 2", "light 1
    /// face 3") and each light's first view. Sizes the shadow maps for them
    /// (rebuilding the Scene bind group when they change).
    fn plan_shadow_views(&mut self, frame: &ViewFrame, lights: &[Light]) -> Result<ShadowPlan, RenderError> {
        let layout = ShadowLayout::plan(lights);
        let casters = self.caster_bounds();
        let (mut views, mut names) = (Vec::new(), Vec::new());
        for (k, (light, first)) in lights.iter().zip(&layout.first).enumerate() {
            let Some(settings) = light.shadows else { continue };
            let Some(first) = *first else {
                log::warn!("light {k}: no room left in the shadow maps; drawn without shadows");
                continue;
            };
            let shared = |size| crate::scene::ShadowSettings { map_size: size, ..settings };
            match light.kind {
                LightKind::Directional { direction } => views.extend(shadow_views::cascades(
                    &frame.camera,
                    frame.aspect,
                    direction,
                    &shared(layout.size_2d),
                    casters,
                    first,
                )),
                LightKind::Spot { .. } => views.extend(shadow_views::spot(light, &shared(layout.size_2d), first)),
                LightKind::Point { .. } => {
                    views.extend(shadow_views::cube(light, &shared(layout.size_cube), first).into_iter().flatten())
                }
            }
            let name = |j| match light.kind {
                LightKind::Directional { .. } => format!("light {k} cascade {j}"),
                LightKind::Spot { .. } => format!("light {k}"),
                LightKind::Point { .. } => format!("light {k} face {j}"),
            };
            names.extend((0..views.len() - names.len()).map(name));
        }
        let ShadowLayout { size_2d, size_cube, layers, cubes, first } = layout;
        debug_assert!(views.len() <= MAX_SHADOW_VIEWS);
        if !views.is_empty() && !self.shadow_maps.fits(size_2d, layers, size_cube, cubes) {
            let (layers, cubes) = (layers.max(self.shadow_maps.layers), cubes.max(self.shadow_maps.cubes));
            self.shadow_maps =
                ShadowMaps::checked(&self.device, self.shadow_maps.support, size_2d, layers, size_cube, cubes)?;
            self.shadow_maps_generation += 1;
            self.refresh_view();
        }
        Ok(ShadowPlan { views, names, first })
    }

    /// The world box around every submitted entity that casts shadows.
    fn caster_bounds(&self) -> Option<Aabb> {
        let boxes = self.submitted.iter().filter(|s| s.cast_shadows).filter_map(|s| self.store.slot(s.slot).bounds);
        Aabb::from_points(boxes.flat_map(|(c, e)| [Vec3::from(c - e), Vec3::from(c + e)]))
    }

    /// Cull, queue, sort and batch every view's casters into the shadow list
    /// (culled on the GPU: every valid instance a candidate), each submitted
    /// entity drawing as `prepared` says; returns each view's range of runs.
    fn batch_shadow_views(
        &mut self,
        (views, prepared): (&[ShadowView], &[Prepared]),
        culling: Culling,
        stats: &mut FrameStats,
    ) -> Result<Vec<std::ops::Range<usize>>, RenderError> {
        self.view.shadows.clear();
        let mut visible = std::mem::take(&mut self.visible);
        let mut ranges = Vec::with_capacity(views.len());
        // Blended materials cast no shadow.
        let blended: Vec<bool> =
            self.registry.materials.iter().map(|m| m.material.alpha_mode == AlphaMode::Blend).collect();
        for view in views {
            let view_proj = view.view_proj();
            let casts = |s: &super::Submitted| s.cast_shadows && !blended[s.material.0 as usize];
            let frustum = Frustum::from_view_proj(view_proj);
            self.collect_visible(&frustum, culling, casts, &mut visible);
            let pass = match view.target {
                ViewTarget::Layer(_) => PassKind::ShadowDepth,
                ViewTarget::CubeFace { .. } => PassKind::ShadowDistance,
            };
            let first_item = self.view.shadows.items.len();
            for &VisibleRun { entry, start, len } in visible.runs.iter().chain(&visible.ranges) {
                let material = self.submitted[entry].material;
                let pipeline = match self.registry.shadow_pipeline(material, &prepared[entry], pass, stats) {
                    Ok(pipeline) => pipeline,
                    Err(e) => {
                        self.visible = visible;
                        return Err(e);
                    }
                };
                let s = &self.submitted[entry];
                let (material, shape) = (s.material, s.shape);
                let slot = &self.registry.materials[material.0 as usize];
                let queue = match slot.material.alpha_mode {
                    AlphaMode::Mask { .. } => Queue::AlphaTest,
                    _ => Queue::Opaque,
                };
                let texture_set = prepared[entry].draw.texture_set;
                // Near to far from the light, so nearer casters hide the rest early.
                let center = self.store.slot(s.slot).bounds.map_or(Vec3::ZERO, |(c, _)| Vec3::from(c));
                let depth = view_proj.project_point3(center).z.clamp(0.0, 1.0);
                self.view.shadows.items.push(DrawItem {
                    key: queue::sort_key(queue.stage(), false, pipeline, texture_set, material, shape, depth),
                    pipeline,
                    material,
                    shape,
                    first: start,
                    count: len,
                    entry: entry as u32,
                });
            }
            queue::sort(&mut self.view.shadows.items[first_item..]);
            let draw_of = |item: &DrawItem| prepared[item.entry as usize].draw;
            let placed = |item: &DrawItem| visible.placed[item.entry as usize];
            ranges.push(self.view.shadows.build(first_item, &visible.instances, frustum, draw_of, placed));
        }
        self.visible = visible;
        Ok(ranges)
    }

    /// Write the instances that changed, each view's Camera record, the Shadow
    /// block, and the shadow list's indices and commands.
    fn upload_shadow_views(
        &mut self,
        views: &[ShadowView],
        environment: &crate::scene::Environment,
        stats: &mut FrameStats,
    ) -> Result<(), RenderError> {
        let bytes = &mut stats.bytes_uploaded;
        self.upload_instances(bytes)?;
        for (k, view) in views.iter().enumerate() {
            let record = CameraGpu::for_shadow(view).with_motion(environment);
            bytes.camera += self.view.blocks.update(&self.queue, 1 + k, record);
        }
        let block = ShadowGpu::new(views, self.shadow_maps.size_2d, self.shadow_maps.size_cube);
        bytes.scene += self.view.shadow_block.update(&self.queue, block);
        let layout = &self.registry.pipelines.instance_layout;
        let gpu = self.cull_pipelines.as_ref().zip(self.instances.bounds());
        let written =
            self.view.shadows.upload(&self.device, &self.queue, (layout, self.instances.array()), gpu, None)?;
        bytes.draw_indices += written.draw_indices;
        bytes.indirect += written.indirect;
        Ok(())
    }

    /// One depth pass per view (named in `names`) into its layer of the shadow
    /// maps, after the cull pass where the list is culled on the GPU.
    fn encode_shadow_views(
        &mut self,
        encoder: &mut wgpu::CommandEncoder,
        (views, names): (&[ShadowView], &[String]),
        ranges: &[std::ops::Range<usize>],
        cost: &mut PassStats,
    ) {
        if let Some(pipelines) = &self.cull_pipelines {
            if self.view.shadows.culled_on_gpu() {
                self.outline.pass("cull instances", PassType::Compute, &[]);
            }
            self.view.shadows.record_cull(encoder, pipelines, self.queue.submits());
        }
        let mut stats = FrameStats::default();
        for (k, (view, range)) in views.iter().zip(ranges).enumerate() {
            let attachment = match view.target {
                ViewTarget::Layer(layer) => &self.shadow_maps.layer_views[layer as usize],
                ViewTarget::CubeFace { cube, face } => &self.shadow_maps.face_views[(6 * cube + face) as usize],
            };
            let mut pass = encoder.begin_render_pass(&wgpu::RenderPassDescriptor {
                label: Some(&names[k]),
                color_attachments: &[],
                depth_stencil_attachment: Some(wgpu::RenderPassDepthStencilAttachment {
                    view: attachment,
                    depth_ops: Some(wgpu::Operations { load: wgpu::LoadOp::Clear(1.0), store: wgpu::StoreOp::Store }),
                    stencil_ops: None,
                }),
                timestamp_writes: self
                    .gpu_timer
                    .as_ref()
                    .and_then(|t| t.pass_writes(Timed::Shadow, k == 0, k + 1 == views.len())),
                ..Default::default()
            });
            pass.set_bind_group(1, &self.view.blocks.bind_group, &[ViewBlocks::offset(1 + k)]);
            pass.set_bind_group(3, &self.view.shadows.bind_group, &[]);
            stats.bind_groups_set += 2;
            let bound = ["bind group 1 (the light's camera)", "bind group 3 (instances, draw indices)"];
            self.outline.pass(&names[k], PassType::Render, &bound);
            self.draw_stages(
                &self.view.shadows,
                &mut pass,
                (range.clone(), &[false]),
                &mut Bound::default(),
                &mut stats,
            );
        }
        if let Some(timer) = &mut self.gpu_timer {
            timer.resolve(encoder, Timed::Shadow, self.frame_index);
        }
        cost.draw_calls = stats.draw_calls;
        cost.draws = stats.draws;
        cost.instances = self.view.shadows.cpu_instances();
        if self.view.shadows.culled_on_gpu() {
            // Counted on the GPU, a frame or two late (0 before the first count comes back).
            let submits = self.queue.submits();
            let drawn = self.view.shadows.gpu.as_mut().and_then(|g| g.drawn(&self.device, submits));
            cost.instances = drawn.map_or(0, |d| d.iter().map(|&n| u64::from(n)).sum());
        }
    }
}
