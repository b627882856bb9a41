//! Placing a [`SceneDesc`] into a [`Renderer`]: its textures, render targets,
//! materials, shapes and models become the renderer's, and its render tasks and
//! cloths entities ([`SceneDesc::instantiate`]); posing moves them at a time
//! ([`SceneDesc::pose`]).

use super::model::AddedModel;
use super::scn::SceneDesc;
use super::scn_cloth::ClothDesc;
use super::{MeshRef, ShapeKind};
use crate::scene::{Entity, Material, MaterialId, ShadingModel};
use crate::sim::cloth::ClothView;
use crate::Renderer;
use glam::{Mat4, Quat, Vec3};
use std::collections::HashMap;

impl SceneDesc {
    /// Pose every model at `time` seconds (see [`Model::pose`]), advance every
    /// cloth to `time` (see [`ClothDesc::pose`]), and move the matching `entities`
    /// (as [`SceneDesc::instantiate`] returned them into `renderer`) along: only
    /// entities of animated models and moved cloths change, so only they are
    /// uploaded again; morphed meshes and cloth surfaces replace their shapes in
    /// `renderer` (one vertex-buffer write each). Fails when a cloth cannot reach
    /// `time` (too many steps, or a step that does not converge).
    pub fn pose(&mut self, time: f32, entities: &mut [Entity], renderer: &mut Renderer) -> Result<(), crate::Error> {
        self.check_pose(time)?;
        let mut moved = vec![false; self.models.len()];
        let mut morphed = vec![Vec::new(); self.models.len()];
        for ((model, moved), morphed) in self.models.iter_mut().zip(&mut moved).zip(&mut morphed) {
            *moved = !model.animations.is_empty();
            *morphed = model.pose(time);
        }
        let mut next = 0;
        for e in &self.entities {
            match e.mesh {
                MeshRef::Shape(_) => next += 1,
                MeshRef::Model(i) => {
                    let model = &self.models[i];
                    for (k, (part, entity)) in model.parts.iter().zip(entities[next..].iter_mut()).enumerate() {
                        if moved[i] {
                            *entity.transforms_mut() = part.placed(&e.transforms);
                            entity.joints_mut().clone_from(&part.joints);
                        }
                        if morphed[i].contains(&k) {
                            renderer.update_shape(entity.shape, part.mesh.clone());
                        }
                    }
                    next += model.parts.len();
                }
            }
        }
        for cloth in &mut self.cloths {
            let count = cloth_entity_count(cloth);
            if cloth.pose(time, &self.path)? {
                let view = &cloth.view;
                let meshes = std::iter::once(&view.surface).chain(&view.edges);
                for (entity, mesh) in entities[next..].iter().zip(meshes) {
                    renderer.update_shape(entity.shape, mesh.clone());
                }
                // Pins that did not move are not uploaded again.
                if count == 3 {
                    let (moved, pins) = (pin_transforms(view), &mut entities[next + 2]);
                    if pins.transforms() != moved {
                        *pins.transforms_mut() = moved;
                    }
                }
            }
            next += count;
        }
        Ok(())
    }

    /// Add this scene's shapes, textures and materials to `renderer`, set its
    /// environment, and return one entity per render task (per model part for
    /// model meshes), ready to submit.
    pub fn instantiate(&self, renderer: &mut Renderer) -> Vec<Entity> {
        renderer.set_environment(self.environment);
        let mut textures: Vec<_> = self.textures.iter().map(|t| renderer.add_texture(t.clone())).collect();
        // Render target k's texture follows the file textures (see `render_targets`).
        for t in &self.render_targets {
            match renderer.add_render_target(t.size.0, t.size.1, t.hdr) {
                Ok((_, texture)) => textures.push(texture),
                Err(e) => {
                    // The maps that show it keep their places: a white pixel stands in.
                    log::warn!("render target '{}': {e}; shown as white", t.name);
                    let white = image::RgbaImage::from_pixel(1, 1, image::Rgba([255; 4]));
                    textures.push(renderer.add_texture(super::Texture::new(&t.name, white, true)));
                }
            }
        }
        let materials: Vec<MaterialId> =
            self.materials.iter().map(|m| renderer.add_material(m.resolve(&textures))).collect();
        // Added on first use, so scenes that name every material do not get one.
        let mut default_material = None;
        let mut shapes = HashMap::new();
        let mut models = vec![None; self.models.len()];
        let mut entities = Vec::new();
        for e in &self.entities {
            let first = entities.len();
            match e.mesh {
                MeshRef::Shape(kind) => {
                    let shape = *shapes.entry(kind).or_insert_with(|| renderer.add_shape(kind.mesh()));
                    let material = match e.material {
                        Some(i) => materials[i],
                        None => *default_material.get_or_insert_with(|| renderer.add_material(Material::default())),
                    };
                    entities.push(Entity::instanced(shape, material, e.transforms.clone()));
                }
                MeshRef::Model(i) => {
                    let model = &self.models[i];
                    let added: &AddedModel = models[i].get_or_insert_with(|| model.add_to(renderer));
                    entities.extend(model.entities(added, &e.transforms));
                }
            }
            for entity in &mut entities[first..] {
                e.draw.apply(entity);
            }
        }
        for cloth in &self.cloths {
            let first = entities.len();
            // Cloth is thin: both sides show, whatever the named material says.
            let look = cloth.material.map_or_else(Material::default, |i| self.materials[i].resolve(&textures));
            let material = renderer.add_material(Material { double_sided: true, ..look });
            let surface = renderer.add_shape(cloth.view.surface.clone());
            entities.push(Entity::new(surface, material, Mat4::IDENTITY));
            if let Some(edges) = &cloth.view.edges {
                let ink = Material {
                    shading: ShadingModel::Unlit,
                    double_sided: true,
                    ..Material::color("cloth edges", 0.02, 0.02, 0.03)
                };
                let (ink, edges) = (renderer.add_material(ink), renderer.add_shape(edges.clone()));
                entities.push(Entity::new(edges, ink, Mat4::IDENTITY));
                if !cloth.view.pins.is_empty() {
                    let red =
                        Material { shading: ShadingModel::Unlit, ..Material::color("cloth pins", 1.0, 0.1, 0.05) };
                    let red = renderer.add_material(red);
                    let ball = *shapes
                        .entry(ShapeKind::Sphere)
                        .or_insert_with(|| renderer.add_shape(ShapeKind::Sphere.mesh()));
                    entities.push(Entity::instanced(ball, red, pin_transforms(&cloth.view)));
                }
            }
            for entity in &mut entities[first..] {
                cloth.draw.apply(entity);
            }
        }
        entities
    }
}

/// Entities [`SceneDesc::instantiate`] makes for a cloth: its surface, and with
/// the debug view its edge ribbons and (when it has pins) its pin markers.
fn cloth_entity_count(cloth: &ClothDesc) -> usize {
    match (&cloth.view.edges, cloth.view.pins.is_empty()) {
        (None, _) => 1,
        (Some(_), true) => 2,
        (Some(_), false) => 3,
    }
}

/// One sphere per pinned node, as big as the view's pin markers.
fn pin_transforms(view: &ClothView) -> Vec<Mat4> {
    view.pins
        .iter()
        .map(|&p| Mat4::from_scale_rotation_translation(Vec3::splat(view.pin_size), Quat::IDENTITY, p))
        .collect()
}
