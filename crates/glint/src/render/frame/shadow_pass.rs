//! Core layer: the frame's shadow maps. [`plan_shadows`] plans
//! every shadow view once a frame: a spot light's view and a point light's six
//! cube faces are the same for every camera view, so they are planned once and
//! drawn once, by the frame's first view; a directional light's cascades follow
//! each view's camera, so each view plans and draws its own (into the same
//! layers, after the earlier views' forward passes have read them).
//!
//! Each shadow view (a cascade, a spot light, a cube face) is culled on its own
//! from every submitted entity that casts shadows — so a caster outside the
//! camera's view still casts — and its draws are sorted and batched like the
//! forward view's, into one [`DrawList`](crate::render::gpu_driven::draw_list::DrawList) for all
//! the view's shadow views ([`draw_shadows`]). Each is one
//! depth-only render pass into its layer of the shadow maps, recorded into the
//! frame's one encoder before the view's forward pass.

use crate::gpu::OffscreenTarget;
use crate::render::cull::Frustum;
use crate::render::debug::explain::PassType;
use crate::render::debug::stats::{ms_since, FrameStats, PassStats};
use crate::render::debug::timer::Timed;
use crate::render::error::RenderError;
use crate::render::frame::draw::{draw_stages, Bound};
use crate::render::frame::forward::upload_instances;
use crate::render::frame::input::ViewKey;
use crate::render::frame::prepared::Prepared;
use crate::render::frame::state::Frame;
use crate::render::frame::visible::VisibleRun;
use crate::render::frame::visible::{collect_visible, Submitted};
use crate::render::lod::{level_items, LodView, SHADOW_ERROR_FACTOR};
use crate::render::passes::shadow_maps::{ShadowGpu, ShadowMaps};
use crate::render::passes::shadow_views::MAX_SHADOW_VIEWS;
use crate::render::passes::shadow_views::{self, ShadowView, ViewTarget};
use crate::render::queue::{self, DrawItem, Queue};
use crate::render::resources::blocks::CameraGpu;
use crate::render::resources::pipelines::PassKind;
use crate::render::resources::Resources;
use crate::render::view::ViewFrame;
use crate::render::views::{ViewBlocks, ViewGpu};
use crate::scene::{Aabb, AlphaMode, Environment, LightKind, Lighting, ShadowLayout, View};
use glam::Vec3;
use web_time::Instant;

/// One shadow view of the frame's plan.
#[derive(Clone, Debug)]
pub(crate) struct PlannedShadow {
    pub view: ShadowView,
    /// Its pass's name: "light 0 cascade 2", "light 1", "light 2 face 3".
    pub name: String,
    /// A spot or point light's: the same for every camera view.
    pub shared: bool,
}

/// The frame's shadow views.
pub(crate) struct ShadowPlan {
    /// Per light, its first shadow view (2D layer, or cube for point lights);
    /// empty when the frame draws no shadows.
    first: Vec<Option<u32>>,
    /// Per view of the frame, its shadow views in the lights' order.
    views: Vec<Vec<PlannedShadow>>,
}

/// One camera view's share of the plan.
pub(crate) struct ViewShadows<'a> {
    /// Per light, its first shadow view (empty: no shadows).
    pub first: &'a [Option<u32>],
    /// Its shadow views, which its Shadow block holds.
    pub views: &'a [PlannedShadow],
    /// Whether it draws the shared ones too (the frame's first view does).
    pub draws_shared: bool,
}

impl ShadowPlan {
    /// View `k`'s shadows; `first` when it is the first view drawn.
    pub(crate) fn of_view(&self, k: usize, first: bool) -> ViewShadows<'_> {
        ViewShadows { first: &self.first, views: &self.views[k], draws_shared: first }
    }
}

impl ViewShadows<'_> {
    /// Per light, its first shadow view, for the Scene block.
    pub(crate) fn shadowed(&self) -> &[Option<u32>] {
        self.first
    }

    /// The shadow views it draws.
    fn drawn(&self) -> impl Iterator<Item = &PlannedShadow> {
        self.views.iter().filter(|p| self.draws_shared || !p.shared)
    }
}

/// Stage 2 of the frame: every shadow view of `lighting`'s lights that cast
/// shadows (see [`Light::with_shadows`](crate::Light::with_shadows)) for
/// `views` (drawn into `output` or their render targets), unless `on` is
/// false. Sizes the shadow maps for them once. Lights past the maps' room
/// (16 two-dimensional views: four per directional light, one per spot
/// light; 4 point lights) are drawn without shadows, with a warning in the log.
pub(crate) fn plan_shadows(
    res: &mut Resources,
    frame: &Frame,
    (views, output): (&[(ViewKey, &View)], &OffscreenTarget),
    lighting: &Lighting,
    on: bool,
) -> Result<ShadowPlan, RenderError> {
    let lights = lighting.lights;
    if !on || lights.iter().all(|l| l.shadows.is_none()) {
        return Ok(ShadowPlan { first: Vec::new(), views: vec![Vec::new(); views.len()] });
    }
    let layout = ShadowLayout::plan(lights);
    let casters = caster_bounds(res, &frame.submitted);
    // Each view's shadow views, in the lights' order.
    let mut planned: Vec<Vec<PlannedShadow>> = vec![Vec::new(); views.len()];
    for (k, (light, first)) in lights.iter().zip(&layout.first).enumerate() {
        let Some(settings) = light.shadows else { continue };
        let Some(first) = *first else {
            log::warn!("light {k}: no room left in the shadow maps; drawn without shadows");
            continue;
        };
        let sized = |size| crate::scene::ShadowSettings { map_size: size, ..settings };
        let name = |j| match light.kind {
            LightKind::Directional { .. } => format!("light {k} cascade {j}"),
            LightKind::Spot { .. } => format!("light {k}"),
            LightKind::Point { .. } => format!("light {k} face {j}"),
        };
        let shared: Vec<ShadowView> = match light.kind {
            LightKind::Directional { direction } => {
                let settings = sized(layout.size_2d);
                for (list, (_, view)) in planned.iter_mut().zip(views) {
                    let [.., width, height] = view_rectangle(res, view, output);
                    let aspect = width as f32 / height.max(1) as f32;
                    let cascades = shadow_views::cascades(&view.camera, aspect, direction, &settings, casters, first);
                    let named = cascades.into_iter().enumerate();
                    list.extend(named.map(|(j, view)| PlannedShadow { view, name: name(j), shared: false }));
                }
                continue;
            }
            LightKind::Spot { .. } => shadow_views::spot(light, &sized(layout.size_2d), first).into_iter().collect(),
            LightKind::Point { .. } => {
                shadow_views::cube(light, &sized(layout.size_cube), first).into_iter().flatten().collect()
            }
        };
        for list in &mut planned {
            let named = shared.iter().enumerate();
            list.extend(named.map(|(j, &view)| PlannedShadow { view, name: name(j), shared: true }));
        }
    }
    let ShadowLayout { size_2d, size_cube, layers, cubes, first } = layout;
    debug_assert!(planned.iter().all(|v| v.len() <= MAX_SHADOW_VIEWS));
    let any = planned.iter().any(|v| !v.is_empty());
    if any && !res.shadow_maps.fits(size_2d, layers, size_cube, cubes) {
        let (layers, cubes) = (layers.max(res.shadow_maps.layers), cubes.max(res.shadow_maps.cubes));
        res.shadow_maps = ShadowMaps::checked(&res.device, res.shadow_maps.support, size_2d, layers, size_cube, cubes)?;
        res.shadow_maps_generation += 1;
    }
    Ok(ShadowPlan { first, views: planned })
}

/// The pixel rectangle `view` draws into: of its render target, or of `output`.
fn view_rectangle(res: &Resources, view: &View, output: &OffscreenTarget) -> [u32; 4] {
    let target = res.registry.render_target_of(view).map_or(output, |t| &t.0);
    view.viewport.pixels(target.width(), target.height())
}

/// The world box around every entity of `submitted` that casts shadows.
fn caster_bounds(res: &Resources, submitted: &[Submitted]) -> Option<Aabb> {
    let boxes = submitted.iter().filter(|s| s.cast_shadows).filter_map(|s| res.store.slot(s.slot).bounds);
    Aabb::from_points(boxes.flat_map(|(c, e)| [Vec3::from(c - e), Vec3::from(c + e)]))
}

/// Stage 2 of a view: the shadow views it draws of `shadows`, culled (as
/// `culling` says) from every submitted caster, batched into its shadow
/// list, uploaded and drawn, each entity drawing as `prepared` says; its
/// Shadow block holds all of `shadows`' views. Counted in `stats` (shadow
/// views, the shadow pass's cost).
pub(crate) fn draw_shadows(
    res: &mut Resources,
    frame: &mut Frame,
    gpu: &mut ViewGpu,
    (view, shadows): (&ViewFrame, &ViewShadows),
    (prepared, environment): (&[Prepared], &Environment),
    stats: &mut FrameStats,
) -> Result<(), RenderError> {
    if shadows.views.is_empty() {
        return Ok(());
    }
    let start = Instant::now();
    let drawn: Vec<&PlannedShadow> = shadows.drawn().collect();
    let ranges = batch_shadow_views(res, frame, gpu, (&drawn, prepared), view, stats)?;
    upload_shadow_views(res, gpu, (&drawn, shadows.views), (environment, view.far_eye), stats)?;
    let mut cost = PassStats::default();
    if !drawn.is_empty() {
        frame.outline.enter(&mut frame.encoder, "shadows");
        encode_shadow_views(res, frame, gpu, &drawn, &ranges, &mut cost);
        frame.outline.leave(&mut frame.encoder);
    }
    stats.shadow_views = drawn.len() as u32;
    cost.cpu_ms = ms_since(start);
    stats.passes.shadow = cost;
    Ok(())
}

/// Cull, queue, sort and batch each shadow view's casters into the view's
/// shadow list (culled on the GPU: every valid instance a candidate), each
/// submitted entity drawing as `prepared` says, at the levels of detail the
/// light's view allows (`camera`'s error times [`SHADOW_ERROR_FACTOR`] in
/// texels); returns each shadow view's range of runs.
fn batch_shadow_views(
    res: &mut Resources,
    frame: &mut Frame,
    gpu: &mut ViewGpu,
    (views, prepared): (&[&PlannedShadow], &[Prepared]),
    camera: &ViewFrame,
    stats: &mut FrameStats,
) -> Result<Vec<std::ops::Range<usize>>, RenderError> {
    gpu.shadows.clear();
    let mut visible = std::mem::take(&mut frame.visible);
    let mut ranges = Vec::with_capacity(views.len());
    // Blended materials cast no shadow.
    let blended: Vec<bool> = res.registry.materials.iter().map(|m| m.material.alpha_mode == AlphaMode::Blend).collect();
    let culling = camera.culling;
    for planned in views {
        let view = &planned.view;
        let view_proj = view.view_proj();
        let lod = LodView::texels(view_proj, view.texel, camera.lod_error * SHADOW_ERROR_FACTOR);
        let casts = |s: &Submitted| s.cast_shadows && !blended[s.material.0 as usize];
        let frustum = Frustum::from_view_proj(view_proj);
        collect_visible(res, (&frustum, culling, camera.far_eye), (&frame.submitted, casts), &mut visible);
        let pass = match view.target {
            ViewTarget::Layer(_) => PassKind::ShadowDepth,
            ViewTarget::CubeFace { .. } => PassKind::ShadowDistance,
        };
        let first_item = gpu.shadows.items.len();
        for &VisibleRun { entry, start, len } in visible.runs.iter().chain(&visible.ranges) {
            let material = frame.submitted[entry].material;
            let pipeline = match res.registry.shadow_pipeline(material, &prepared[entry], pass, stats) {
                Ok(pipeline) => pipeline,
                Err(e) => {
                    frame.visible = visible;
                    return Err(e);
                }
            };
            let s = &frame.submitted[entry];
            let (material, shape) = (s.material, s.shape);
            let slot = &res.registry.materials[material.0 as usize];
            let queue = match slot.material.alpha_mode {
                AlphaMode::Mask { .. } => Queue::AlphaTest,
                _ => Queue::Opaque,
            };
            let texture_set = prepared[entry].draw.texture_set;
            // Near to far from the light, so nearer casters hide the rest early.
            let center = res.store.slot(s.slot).bounds.map_or(Vec3::ZERO, |(c, _)| Vec3::from(c));
            let depth = view_proj.project_point3(center).z.clamp(0.0, 1.0);
            let key = queue::sort_key(queue.stage(), false, pipeline, texture_set, material, shape, depth);
            let item = |level, first, count, copies| DrawItem {
                key,
                pipeline,
                material,
                shape,
                first,
                count,
                entry: entry as u32,
                level,
                copies,
            };
            let (levels, items) = (&prepared[entry].draw.mesh.levels, &mut gpu.shadows.items);
            let run = (visible.placed[entry], start, len);
            level_items(
                &lod,
                levels,
                run,
                (&mut visible.instances, &res.store.bounds),
                |level, first, count, copies| {
                    items.push(item(level, first, count, copies));
                },
            );
        }
        queue::sort(&mut gpu.shadows.items[first_item..]);
        let draw_of = |item: &DrawItem| prepared[item.entry as usize].draw;
        let placed = |item: &DrawItem| visible.placed[item.entry as usize];
        ranges.push(gpu.shadows.build(first_item, &visible.instances, (frustum, lod), draw_of, placed));
    }
    frame.visible = visible;
    Ok(ranges)
}

/// Write the instances that changed, each view's Camera record (far fields
/// measured from `far_eye`, the camera view's), the Shadow block, and the
/// shadow list's indices and commands.
fn upload_shadow_views(
    res: &mut Resources,
    gpu: &mut ViewGpu,
    (drawn, all): (&[&PlannedShadow], &[PlannedShadow]),
    (environment, far_eye): (&Environment, Option<Vec3>),
    stats: &mut FrameStats,
) -> Result<(), RenderError> {
    let bytes = &mut stats.bytes_uploaded;
    upload_instances(res, bytes);
    for (k, planned) in drawn.iter().enumerate() {
        let record = CameraGpu::for_shadow(&planned.view).with_motion(environment).with_far_eye(far_eye);
        bytes.camera += gpu.blocks.update(&res.queue, 1 + k, record);
    }
    let views: Vec<ShadowView> = all.iter().map(|p| p.view).collect();
    let block = ShadowGpu::new(&views, res.shadow_maps.size_2d, res.shadow_maps.size_cube);
    bytes.scene += gpu.shadow_block.update(&res.queue, block);
    let layout = &res.registry.pipelines.instance_layout;
    let culls = res.cull_pipelines.as_ref().zip(res.instances.bounds());
    let written = gpu.shadows.upload(&res.device, &res.queue, (layout, res.instances.array()), culls, None)?;
    bytes.draw_indices += written.draw_indices;
    bytes.indirect += written.indirect;
    Ok(())
}

/// One depth pass per shadow view (named as planned) into its layer of
/// the shadow maps, after the cull pass where the list is culled on the GPU.
fn encode_shadow_views(
    res: &mut Resources,
    frame: &mut Frame,
    gpu: &mut ViewGpu,
    views: &[&PlannedShadow],
    ranges: &[std::ops::Range<usize>],
    cost: &mut PassStats,
) {
    if let Some(pipelines) = &res.cull_pipelines {
        if gpu.shadows.culled_on_gpu() {
            frame.outline.pass("cull instances", PassType::Compute, &[]);
        }
        gpu.shadows.record_cull(&mut frame.encoder, pipelines, res.queue.submits());
    }
    let mut stats = FrameStats::default();
    for (k, (planned, range)) in views.iter().zip(ranges).enumerate() {
        let name = &planned.name;
        let attachment = match planned.view.target {
            ViewTarget::Layer(layer) => &res.shadow_maps.layer_views[layer as usize],
            ViewTarget::CubeFace { cube, face } => &res.shadow_maps.face_views[(6 * cube + face) as usize],
        };
        let mut pass = frame.encoder.begin_render_pass(&wgpu::RenderPassDescriptor {
            label: Some(name),
            color_attachments: &[],
            depth_stencil_attachment: Some(wgpu::RenderPassDepthStencilAttachment {
                view: attachment,
                depth_ops: Some(wgpu::Operations { load: wgpu::LoadOp::Clear(1.0), store: wgpu::StoreOp::Store }),
                stencil_ops: None,
            }),
            timestamp_writes: res
                .gpu_timer
                .as_ref()
                .and_then(|t| t.pass_writes(Timed::Shadow, k == 0, k + 1 == views.len())),
            ..Default::default()
        });
        pass.set_bind_group(1, &gpu.blocks.bind_group, &[ViewBlocks::offset(1 + k)]);
        pass.set_bind_group(3, &gpu.shadows.bind_group, &[]);
        stats.bind_groups_set += 2;
        let bound = ["bind group 1 (the light's camera)", "bind group 3 (instances, draw indices)"];
        frame.outline.pass(name, PassType::Render, &bound);
        draw_stages(
            res,
            &frame.outline,
            &gpu.shadows,
            &mut pass,
            (range.clone(), &[false]),
            &mut Bound::default(),
            &mut stats,
        );
    }
    if let Some(timer) = &mut res.gpu_timer {
        timer.resolve(&mut frame.encoder, Timed::Shadow, frame.index);
    }
    cost.draw_calls = stats.draw_calls;
    cost.draws = stats.draws;
    let mut drawn = gpu.shadows.cpu_drawn();
    if gpu.shadows.culled_on_gpu() {
        // Counted on the GPU, a frame or two late (0 before the first count comes back).
        let submits = res.queue.submits();
        drawn = gpu.shadows.gpu_drawn(&res.device, submits, false).unwrap_or_default();
    }
    (cost.instances, cost.triangles) = (drawn.instances, drawn.triangles);
}
