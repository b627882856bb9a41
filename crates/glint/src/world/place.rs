//! World layer: placing loaded assets into a renderer. A [`Model`] or a
//! [`SceneDesc`] is plain data read from a file; placing it adds its textures,
//! render targets, materials and shapes to the renderer's [`Registry`] and
//! returns the entities that draw them ([`PlacedScene`]).
//! [`World::pose`](crate::World::pose) moves them along as the scene's
//! animations and cloths advance.

use super::cloth::ClothSim;
use super::school::SchoolSim;
use crate::asset::{MeshRef, Model, SceneDesc, ShapeKind, Texture};
use crate::render::{Registry, Renderer};
use crate::scene::{Entity, Material, MaterialId, RenderTargetId, ShadingModel, ShapeId, TextureId};
use crate::sim::cloth::ClothView;
use glam::{Mat4, Quat, Vec3};
use std::collections::HashMap;

/// A scene placed into a renderer by [`Renderer::place_scene`].
#[derive(Clone, Debug)]
pub struct PlacedScene {
    /// One entity per render task (per part for model meshes), then each
    /// cloth's surface (with the debug view, its edge ribbons and pin markers),
    /// ready to submit.
    pub entities: Vec<Entity>,
    /// The renderer's id of each of the scene's render targets, in file order
    /// (for [`SceneDesc::views`]).
    pub render_targets: Vec<RenderTargetId>,
    /// The renderer's id of each of the scene's textures
    /// ([`SceneDesc::textures`], then each render target's), for what
    /// shows them besides its materials (an emitter's sprite).
    pub textures: Vec<TextureId>,
}

/// A model's ids in one registry: shape and material per part.
struct ModelIds {
    parts: Vec<(ShapeId, MaterialId)>,
}

impl Renderer {
    /// Add `model`'s shapes, textures and materials, and return one entity per
    /// part, instanced at every transform of `placements` (model to world).
    pub fn place_model(&mut self, model: &Model, placements: &[Mat4]) -> Vec<Entity> {
        let ids = self.registry_mut().add_model(model);
        model_entities(model, &ids, placements)
    }

    /// Add the scene's textures, render targets, materials, shapes and models,
    /// and return its entities with the ids of its render targets, every
    /// school at its seeded start. Its lights and environment are not the
    /// renderer's: give [`SceneDesc::lighting`] to each frame.
    pub fn place_scene(&mut self, desc: &SceneDesc) -> PlacedScene {
        self.place_scene_and_runs(desc).0
    }

    /// [`place_scene`](Self::place_scene), with each cloth's and school's run at its start.
    pub(crate) fn place_scene_and_runs(&mut self, desc: &SceneDesc) -> (PlacedScene, Vec<ClothSim>, Vec<SchoolSim>) {
        let registry = self.registry_mut();
        if let Some(image) = &desc.environment_image {
            registry.add_environment(image);
        }
        let mut textures: Vec<TextureId> = desc.textures.iter().map(|t| registry.add_texture(t.clone())).collect();
        // Render target k's texture follows the file textures (see `SceneDesc::render_targets`).
        let mut render_targets = Vec::new();
        for t in &desc.render_targets {
            match registry.add_render_target(t.size.0, t.size.1, t.hdr) {
                Ok((id, texture)) => {
                    render_targets.push(id);
                    textures.push(texture);
                }
                Err(e) => {
                    // The maps that show it keep their places: a white pixel stands in.
                    log::warn!("render target '{}': {e}; shown as white", t.name);
                    let white = image::RgbaImage::from_pixel(1, 1, image::Rgba([255; 4]));
                    textures.push(registry.add_texture(Texture::new(&t.name, white, true)));
                }
            }
        }
        let materials: Vec<MaterialId> =
            desc.materials.iter().map(|m| registry.add_material(m.resolve(&textures))).collect();
        // Added on first use, so scenes that name every material do not get one.
        let mut default_material = None;
        let mut shapes = HashMap::new();
        let mut models: Vec<Option<ModelIds>> = (0..desc.models.len()).map(|_| None).collect();
        let mut entities = Vec::new();
        for e in &desc.entities {
            let first = entities.len();
            match e.mesh {
                MeshRef::Shape(kind) => {
                    let shape = *shapes
                        .entry(kind)
                        .or_insert_with(|| registry.add_named_shape(kind.mesh(), kind.name().into()));
                    let material = match e.material {
                        Some(i) => materials[i],
                        None => *default_material.get_or_insert_with(|| registry.add_material(Material::default())),
                    };
                    entities.push(Entity::instanced(shape, material, e.transforms.clone()));
                }
                MeshRef::Model(i) => {
                    let model = &desc.models[i];
                    let ids = models[i].get_or_insert_with(|| registry.add_model(model));
                    entities.extend(model_entities(model, ids, &e.transforms));
                }
            }
            for entity in &mut entities[first..] {
                e.draw.apply(entity);
                if let Some(tiles) = &e.tiles {
                    entity.set_tiles(tiles.clone());
                    entity.density = e.density;
                    entity.set_compact_instances(e.compact);
                }
            }
        }
        let cloths: Vec<ClothSim> = desc.cloths.iter().map(ClothSim::new).collect();
        for (cloth, sim) in desc.cloths.iter().zip(&cloths) {
            // A cloth that cannot be simulated shows nothing.
            let Some(view) = &sim.view else { continue };
            let first = entities.len();
            // Cloth is thin: both sides show, whatever the named material says.
            let look = cloth.material.map_or_else(Material::default, |i| desc.materials[i].resolve(&textures));
            let material = registry.add_material(Material { double_sided: true, ..look });
            let surface = registry.add_deforming_shape(view.surface.clone(), "cloth".into());
            entities.push(Entity::new(surface, material, Mat4::IDENTITY));
            if let Some(edges) = &view.edges {
                let ink = Material {
                    shading: ShadingModel::Unlit,
                    double_sided: true,
                    ..Material::color("cloth edges", 0.02, 0.02, 0.03)
                };
                let edges = registry.add_deforming_shape(edges.clone(), "cloth edges".into());
                let ink = registry.add_material(ink);
                entities.push(Entity::new(edges, ink, Mat4::IDENTITY));
                if !view.pins.is_empty() {
                    let red =
                        Material { shading: ShadingModel::Unlit, ..Material::color("cloth pins", 1.0, 0.1, 0.05) };
                    let red = registry.add_material(red);
                    let ball = *shapes
                        .entry(ShapeKind::Sphere)
                        .or_insert_with(|| registry.add_named_shape(ShapeKind::Sphere.mesh(), "sphere".into()));
                    entities.push(Entity::instanced(ball, red, pin_transforms(view)));
                }
            }
            for entity in &mut entities[first..] {
                cloth.draw.apply(entity);
            }
        }
        let ranges = super::school::entity_ranges(desc);
        let schools: Vec<SchoolSim> = desc.schools.iter().map(SchoolSim::new).collect();
        for (sim, school) in schools.iter().zip(&desc.schools) {
            // Each fish at its start, with its own tail beat from the first frame.
            sim.show(school, desc, &ranges, &mut entities);
        }
        (PlacedScene { entities, render_targets, textures }, cloths, schools)
    }
}

impl Registry {
    /// Add a model's textures, materials and one shape per part.
    fn add_model(&mut self, model: &Model) -> ModelIds {
        let textures: Vec<_> = model.textures.iter().map(|t| self.add_texture(t.clone())).collect();
        let materials: Vec<MaterialId> =
            model.materials.iter().map(|m| self.add_material(m.resolve(&textures))).collect();
        // Added on first use; also stands in for a material index the model lacks.
        let mut default_material = None;
        let parts = (model.parts.iter())
            .map(|part| {
                let material = match part.material.and_then(|i| materials.get(i)) {
                    Some(&m) => m,
                    None => *default_material.get_or_insert_with(|| self.add_material(Material::default())),
                };
                let file = model
                    .path
                    .file_name()
                    .map_or_else(|| model.path.display().to_string(), |f| f.to_string_lossy().into());
                let name = format!("{file}: {}", part.name);
                let shape = match part.morph {
                    Some(_) => self.add_deforming_shape(part.mesh.clone(), name),
                    None => self.add_named_shape(part.mesh.clone(), name),
                };
                (shape, material)
            })
            .collect();
        ModelIds { parts }
    }
}

/// One entity per part of a model added as `ids`, instanced at every transform of `placements`.
fn model_entities(model: &Model, ids: &ModelIds, placements: &[Mat4]) -> Vec<Entity> {
    (model.parts.iter().zip(&ids.parts))
        .map(|(part, &(shape, material))| {
            Entity::instanced(shape, material, part.placed(placements)).with_joints(part.joints.clone())
        })
        .collect()
}

/// Entities [`Renderer::place_scene`] makes for a cloth showing `view`: its
/// surface, and with the debug view its edge ribbons and (when it has pins)
/// its pin markers; none for a cloth that cannot be simulated.
pub(crate) fn cloth_entity_count(view: Option<&ClothView>) -> usize {
    match view.map(|v| (&v.edges, v.pins.is_empty())) {
        None => 0,
        Some((None, _)) => 1,
        Some((Some(_), true)) => 2,
        Some((Some(_), false)) => 3,
    }
}

/// One sphere per pinned node, as big as the view's pin markers.
pub(crate) fn pin_transforms(view: &ClothView) -> Vec<Mat4> {
    view.pins
        .iter()
        .map(|&p| Mat4::from_scale_rotation_translation(Vec3::splat(view.pin_size), Quat::IDENTITY, p))
        .collect()
}
