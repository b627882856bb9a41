//! Core layer: materials on the GPU: their entries in the material table, their
//! texture sets (Material bind groups shared by materials with the same maps) and
//! their pipelines, made ready in stage 1 of the frame.

use crate::gpu::TargetFormat;
use crate::render::debug::stats::FrameStats;
use crate::render::error::RenderError;
use crate::render::frame_variant::FrameVariant;
use crate::render::resources::pipelines::{Pipelines, VertexLayout};
use crate::render::resources::registry::{Maps, MaterialGpuTwin, Registry, TextureSet};
use crate::scene::{Environment, MaterialId, TextureId};
use crate::shader::ShaderFeatures;

impl Registry {
    /// Make material `id` ready to draw meshes of `layout` into `target` under
    /// `environment` (its fog) in a frame of variant `frame`: its textures
    /// uploaded, its texture set, its table entry written if edited, its pipeline built.
    /// Returns its pipeline and texture set.
    pub(crate) fn prepare_material(
        &mut self,
        id: MaterialId,
        layout: VertexLayout,
        target: TargetFormat,
        (environment, frame): (&Environment, FrameVariant),
        stats: &mut FrameStats,
    ) -> Result<(u16, u16), RenderError> {
        let slot = self.materials.get(id.0 as usize).ok_or(RenderError::UnknownMaterial(id))?;
        let fog = environment.fog.is_some();
        let current =
            slot.gpu.as_ref().filter(|g| !slot.dirty && g.target == target && g.fog == fog && g.frame == frame);
        if let Some((pipeline, twin)) = current.and_then(|g| g.pipelines[layout.index()].zip(Some(g))) {
            return Ok((pipeline, twin.texture_set));
        }
        let material = slot.material.clone();
        if current.is_none() {
            let maps: Maps = material.maps();
            for texture in maps.into_iter().flatten() {
                stats.bytes_uploaded.textures += self.upload_texture(texture, &material.name)?;
            }
            let texture_set = match self.texture_sets.iter().position(|s| s.maps == maps) {
                Some(k) => k as u16,
                None => {
                    let bind_group = self.texture_set_group(maps);
                    self.texture_sets.push(TextureSet { maps, bind_group });
                    (self.texture_sets.len() - 1) as u16
                }
            };
            let slot = &mut self.materials[id.0 as usize];
            if slot.dirty {
                stats.bytes_uploaded.material += self.material_table.write(&self.queue, id.0, &material.to_gpu());
                slot.dirty = false;
            }
            slot.gpu = Some(MaterialGpuTwin {
                texture_set,
                pipelines: [None; VertexLayout::COUNT],
                shadow_pipelines: [[None; 2]; VertexLayout::COUNT],
                target,
                fog,
                frame,
            });
        }
        let mut features = ShaderFeatures::for_material(&material, environment);
        features.set(ShaderFeatures::SHADOWS, frame.shadows);
        features.set(ShaderFeatures::SHADOW_CUBES, frame.shadow_cubes);
        features.set(ShaderFeatures::SOFT_SHADOWS, frame.soft_shadows);
        let lit = !features.intersects(ShaderFeatures::UNLIT | ShaderFeatures::ALPHA_BLEND);
        features.set(ShaderFeatures::AMBIENT_OCCLUSION, frame.ambient_occlusion && lit);
        // Blended surfaces are lit too: every lit variant of a clustered frame
        // takes its point and spot lights from the clusters (its loop over
        // them has none).
        features.set(ShaderFeatures::CLUSTERED, frame.clustered && !features.contains(ShaderFeatures::UNLIT));
        let key = Pipelines::key(features, frame.lights, layout, material.render_states(), target);
        let (pipeline, built) = self.pipelines.forward_id(&self.device, key)?;
        stats.pipelines_compiled += u32::from(built);
        let twin = self.materials[id.0 as usize].gpu.as_mut().expect("made above");
        twin.pipelines[layout.index()] = Some(pipeline);
        Ok((pipeline, twin.texture_set))
    }

    /// Upload texture `id`'s pixels unless that was done already (a texture
    /// is uploaded on its first use, once, whoever uses it); returns the bytes
    /// uploaded. `owner` names the user in the error for an unknown id.
    pub(crate) fn upload_texture(&mut self, id: TextureId, owner: &str) -> Result<u64, RenderError> {
        let side = self.device.limits().max_texture_dimension_2d;
        let unknown = || RenderError::UnknownTexture { material: owner.to_string(), texture: id };
        let tex = self.textures.get_mut(id.0 as usize).ok_or_else(unknown)?;
        let Some(pending) = tex.pending.take() else { return Ok(0) };
        let (w, h) = pending.image.dimensions();
        if w.max(h) > side {
            return Err(RenderError::TextureTooLarge { name: pending.name.clone(), width: w, height: h, side });
        }
        let scope = crate::gpu::DriverErrors::watch(&self.device);
        let (view, bytes, blits) = self.uploader.upload(&self.device, &self.queue, &pending);
        self.mip_blits.extend(blits);
        if let Some(error) = scope.finish() {
            return Err(RenderError::Device { what: "a texture", message: error.to_string() });
        }
        tex.view = Some(view);
        Ok(bytes)
    }

    /// The Material block's bind group for a texture set: the table and the maps
    /// (1×1 defaults where a map is absent).
    pub(crate) fn texture_set_group(&self, maps: Maps) -> wgpu::BindGroup {
        let d = &self.defaults;
        let defaults =
            [&d.white_srgb, &d.flat_normal, &d.white_linear, &d.white_linear, &d.white_linear, &d.white_srgb];
        let views: Vec<&wgpu::TextureView> = maps
            .iter()
            .zip(defaults)
            .map(|(map, default)| map.and_then(|t| self.textures[t.0 as usize].view.as_ref()).unwrap_or(default))
            .collect();
        self.device.create_bind_group(&wgpu::BindGroupDescriptor {
            label: Some(&format!("material block: texture set {maps:?} (group 2)")),
            layout: &self.pipelines.material_layout,
            entries: &[
                wgpu::BindGroupEntry { binding: 0, resource: self.material_table.binding() },
                wgpu::BindGroupEntry { binding: 1, resource: wgpu::BindingResource::TextureView(views[0]) },
                wgpu::BindGroupEntry { binding: 2, resource: wgpu::BindingResource::TextureView(views[1]) },
                wgpu::BindGroupEntry { binding: 3, resource: wgpu::BindingResource::TextureView(views[2]) },
                wgpu::BindGroupEntry { binding: 4, resource: wgpu::BindingResource::Sampler(&self.sampler) },
                wgpu::BindGroupEntry { binding: 5, resource: wgpu::BindingResource::TextureView(views[3]) },
                wgpu::BindGroupEntry { binding: 6, resource: wgpu::BindingResource::TextureView(views[4]) },
                wgpu::BindGroupEntry { binding: 7, resource: wgpu::BindingResource::TextureView(views[5]) },
            ],
        })
    }
}
