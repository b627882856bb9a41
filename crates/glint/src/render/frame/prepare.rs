//! Core layer: stage 1 of the frame, making sure everything the submitted
//! entities use exists on the GPU (mesh buffers, textures, material blocks,
//! pipelines), and [`Renderer::precompile`], which does it before the first frame.

use crate::gpu::TargetFormat;
use crate::render::frame::Frame;
use crate::render::gpu_driven::draw_list::BatchDraw;
use crate::render::resources::pipelines::{SkyPass, VertexLayout};
use crate::render::{FrameStats, FrameVariant, Registry, RenderError, Renderer};
use crate::scene::{Background, Entity, Environment, Lighting, MaterialId, ShapeId, MAX_LIGHTS};

/// What a prepared table was made for: the frame, its submissions, the
/// target, the view's variant and the environment's fog and sky.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(crate) struct PrepareKey {
    frame: u64,
    entities: usize,
    target: TargetFormat,
    variant: FrameVariant,
    fog: bool,
    sky: Option<SkyPass>,
    glare: bool,
}

/// What a submitted entity draws with, as stage 1 made it: its forward
/// pipeline, its mesh's vertex layout, and what its batches draw with.
#[derive(Clone, Copy, Debug)]
pub(crate) struct Prepared {
    pub pipeline: u16,
    pub layout: VertexLayout,
    pub draw: BatchDraw,
}

impl Renderer {
    /// Build, before the first frame, everything drawing `entities` under `lighting`
    /// into a glint target (not a post-processed view) of `samples` samples needs: mesh buffers, textures, material
    /// blocks and every pipeline variant (with shadow lookups where a light casts
    /// shadows), so that the first frame compiles nothing. Returns the number of
    /// pipelines compiled.
    pub fn precompile<'l>(
        &mut self,
        entities: &[&Entity],
        lighting: impl Into<Lighting<'l>>,
        samples: u32,
    ) -> Result<u32, RenderError> {
        let lighting = lighting.into();
        if lighting.lights.len() > MAX_LIGHTS {
            return Err(RenderError::TooManyLights(lighting.lights.len()));
        }
        let variant = FrameVariant::expected(lighting.lights, false);
        self.prepare_environment(&lighting)?;
        let mut stats = FrameStats::default();
        let uses: Vec<_> = entities
            .iter()
            .map(|e| (e.shape, e.material, crate::render::resources::instances::stored_compactly(e)))
            .collect();
        let target = TargetFormat { color: crate::gpu::COLOR_FORMAT, samples };
        self.registry.prepare_uses(&uses, target, (&lighting.environment, variant), &mut stats)?;
        Ok(stats.pipelines_compiled)
    }

    /// Prefilter `lighting`'s environment (image-based lighting) now, in a
    /// submission of its own, unless that was done already (a frame does it
    /// otherwise: at load time, so the first frame does not). Returns whether it
    /// prefiltered.
    pub fn prefilter_environment(&mut self, lighting: &Lighting) -> Result<bool, RenderError> {
        let done = self.prepare_environment(lighting)?;
        self.queue.submit(std::mem::take(&mut self.registry.mip_blits));
        Ok(done)
    }

    /// Prefilter `lighting`'s environment (image-based lighting) unless that
    /// was done already, its passes to run first in the next submission (views
    /// bind the new maps when drawn next). Returns whether it prefiltered.
    pub(crate) fn prepare_environment(&mut self, lighting: &Lighting) -> Result<bool, RenderError> {
        let commands = self.environment.update(&mut self.registry, &lighting.environment, lighting.lights)?;
        let done = commands.is_some();
        self.registry.mip_blits.extend(commands);
        Ok(done)
    }

    /// Stage 1 of a view: make sure everything the submitted entities use
    /// exists on the GPU (for `target`, with the forward variant `variant`,
    /// under `environment`). Returns what each submitted entity draws with, in
    /// submission order. The views of one frame that draw into the same
    /// format with the same variant share one table: prepare runs once per
    /// frame for each (counted in `frame`).
    pub(crate) fn prepare(
        &mut self,
        frame: &mut Frame,
        target: TargetFormat,
        variant: FrameVariant,
        environment: &Environment,
        stats: &mut FrameStats,
    ) -> Result<Vec<Prepared>, RenderError> {
        let key = PrepareKey {
            frame: frame.index,
            entities: self.submitted.len(),
            target,
            variant,
            fog: environment.fog.is_some(),
            sky: sky_pass(environment),
            glare: environment.glare > 0.0,
        };
        if let Some((_, table)) = self.last_prepared.as_ref().filter(|(k, _)| *k == key) {
            return Ok(table.clone());
        }
        let uses: Vec<_> =
            self.submitted.iter().map(|s| (s.shape, s.material, self.store.slot(s.slot).compact)).collect();
        let table = self.registry.prepare_uses(&uses, target, (environment, variant), stats)?;
        frame.prepares += 1;
        self.last_prepared = Some((key, table.clone()));
        Ok(table)
    }
}

impl Registry {
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
            let slot = self.shapes.get_mut(shape.0 as usize).ok_or(RenderError::UnknownShape(shape))?;
            let mesh = match slot.gpu {
                Some(range) => range,
                None => {
                    let scope = crate::gpu::DriverErrors::watch(&self.device);
                    let added = self.mesh_pool.add(&self.device, &self.queue, &slot.mesh);
                    if let Some(error) = scope.finish() {
                        return Err(RenderError::Device { what: "the mesh pool", message: error.to_string() });
                    }
                    let (range, bytes) = added.map_err(|source| RenderError::MeshTooLarge { shape, source })?;
                    slot.gpu = Some(range);
                    stats.bytes_uploaded.meshes += bytes;
                    range
                }
            };
            if std::mem::take(&mut slot.rewrite) {
                stats.bytes_uploaded.meshes += self.mesh_pool.rewrite_vertices(&self.queue, mesh, &slot.mesh);
            }
            let layout = VertexLayout { compact, ..slot.layout };
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

/// The sky a frame under `environment` draws: the environment's where it
/// lights the scene, else the gradient's, else none (a plain clear colour).
pub(crate) fn sky_pass(environment: &Environment) -> Option<SkyPass> {
    match (environment.light, environment.background) {
        (Some(_), _) => Some(SkyPass::Environment),
        (None, Background::Gradient { .. }) => Some(SkyPass::Gradient),
        (None, Background::Color(_)) => None,
    }
}
