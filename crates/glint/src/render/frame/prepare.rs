//! Core layer: stage 1 of the frame, making sure everything the submitted
//! entities use exists on the GPU (mesh buffers, textures, material blocks,
//! pipelines), also for [`Renderer::precompile`](crate::Renderer::precompile), which does it before the first frame.

use crate::gpu::TargetFormat;
use crate::render::debug::stats::FrameStats;
use crate::render::error::RenderError;
use crate::render::frame::prepared::{sky_pass, PrepareKey, Prepared};
use crate::render::frame::state::Frame;
use crate::render::frame_variant::FrameVariant;
use crate::render::gpu_driven::draw_list::BatchDraw;
use crate::render::resources::mesh_pool::MeshRange;
use crate::render::resources::pipelines::{SkyPass, VertexLayout};
use crate::render::resources::registry::Registry;
use crate::render::resources::Resources;
use crate::scene::{Environment, Lighting, MaterialId, ShapeId};

/// Prefilter `lighting`'s environment (image-based lighting) unless that
/// was done already, its passes to run first in the next submission (views
/// bind the new maps when drawn next). Returns whether it prefiltered.
pub(crate) fn prepare_environment(res: &mut Resources, lighting: &Lighting) -> Result<bool, RenderError> {
    let sources = |id| res.registry.environment(id);
    let commands =
        res.environment.update((&res.device, &res.queue), sources, &lighting.environment, lighting.lights)?;
    let done = commands.is_some();
    res.registry.mip_blits.extend(commands);
    Ok(done)
}

/// Stage 1 of a view: make sure everything the submitted entities use
/// exists on the GPU (for `target`, with the forward variant `variant`,
/// under `environment`). Returns what each submitted entity draws with, in
/// submission order. The views of one frame that draw into the same
/// format with the same variant share one table: prepare runs once per
/// frame for each (counted in `frame`).
pub(crate) fn prepare(
    res: &mut Resources,
    frame: &mut Frame,
    target: TargetFormat,
    variant: FrameVariant,
    environment: &Environment,
    stats: &mut FrameStats,
) -> Result<Vec<Prepared>, RenderError> {
    let key = PrepareKey {
        entities: frame.submitted.len(),
        target,
        variant,
        fog: environment.fog.is_some(),
        sky: sky_pass(environment),
        glare: environment.glare > 0.0,
    };
    if let Some((_, table)) = frame.prepared.as_ref().filter(|(k, _)| *k == key) {
        return Ok(table.clone());
    }
    let uses: Vec<_> = frame.submitted.iter().map(|s| (s.shape, s.material, res.store.slot(s.slot).compact)).collect();
    let table = res.registry.prepare_uses(&uses, target, (environment, variant), stats)?;
    frame.prepares += 1;
    frame.prepared = Some((key, table.clone()));
    Ok(table)
}

impl Registry {
    /// Where `shape` is in the mesh pool, copying it there (with its levels of
    /// detail, unless it deforms) the first time; and the bytes that took.
    pub(crate) fn mesh_range(&mut self, shape: ShapeId) -> Result<(MeshRange, u64), RenderError> {
        let slot = self.shapes.get_mut(shape.0 as usize).ok_or(RenderError::UnknownShape(shape))?;
        if let Some(range) = slot.gpu {
            return Ok((range, 0));
        }
        let scope = crate::gpu::DriverErrors::watch(&self.device);
        let levels = match (slot.deforms, &self.level_cache) {
            (true, _) => Vec::new(),
            (false, Some(cache)) => cache.levels(&slot.mesh).0,
            (false, None) => crate::scene::levels::detail_levels(&slot.mesh),
        };
        let added = self.mesh_pool.add(&self.device, &self.queue, (&slot.mesh, &levels));
        if let Some(error) = scope.finish() {
            return Err(RenderError::Device { what: "the mesh pool", message: error.to_string() });
        }
        let (range, bytes) = added.map_err(|source| RenderError::MeshTooLarge { shape, source })?;
        slot.gpu = Some(range);
        Ok((range, bytes))
    }

    /// Where a GPU simulation writes `shape`'s vertices this frame, once
    /// [`mesh_range`](Self::mesh_range) put it in the pool; `None` before, or
    /// where the pool's vertices are not storage buffers.
    pub(crate) fn vertex_target(&self, shape: ShapeId) -> Option<crate::gpu::VertexTarget<'_>> {
        let slot = self.shapes.get(shape.0 as usize)?;
        let vertices = slot.mesh.vertices().len() as u32;
        slot.gpu.and_then(|range| self.mesh_pool.vertex_target(range, vertices))
    }

    /// Stage 1 for the registry: mesh buffers, textures, material blocks and
    /// pipelines for each (shape, material) in `uses`, drawn into `target` under
    /// `environment` in a frame of variant `frame`. Returns what each use draws with.
    pub(crate) fn prepare_uses(
        &mut self,
        uses: &[(ShapeId, MaterialId, bool)],
        target: TargetFormat,
        (environment, frame): (&Environment, FrameVariant),
        stats: &mut FrameStats,
    ) -> Result<Vec<Prepared>, RenderError> {
        if self.material_table.reserve(&self.device, self.materials.len())? {
            // A new table: every entry is written again, every texture set rebound to it.
            for slot in &mut self.materials {
                slot.dirty = true;
            }
            for k in 0..self.texture_sets.len() {
                self.texture_sets[k].bind_group = self.texture_set_group(self.texture_sets[k].maps);
            }
        }
        let mut prepared = Vec::with_capacity(uses.len());
        for &(shape, material, compact) in uses {
            let (mesh, bytes) = self.mesh_range(shape)?;
            stats.bytes_uploaded.meshes += bytes;
            let slot = &mut self.shapes[shape.0 as usize];
            if std::mem::take(&mut slot.rewrite) {
                stats.bytes_uploaded.meshes += self.mesh_pool.rewrite_vertices(&self.queue, mesh, &slot.mesh);
            }
            // Levels matter to the pipeline only where the frame cross-fades them.
            let levels = frame.lod_fade && mesh.levels.count > 1;
            let layout = VertexLayout { compact, levels, ..slot.layout };
            let (pipeline, texture_set) =
                self.prepare_material(material, layout, target, (environment, frame), stats)?;
            prepared.push(Prepared { pipeline, layout, draw: BatchDraw { mesh, texture_set } });
        }
        if let Some(sky) = sky_pass(environment) {
            stats.pipelines_compiled += u32::from(self.pipelines.build_sky(&self.device, target, sky)?);
        }
        if environment.glare > 0.0 {
            stats.pipelines_compiled += u32::from(self.pipelines.build_sky(&self.device, target, SkyPass::Glare)?);
        }
        Ok(prepared)
    }
}
