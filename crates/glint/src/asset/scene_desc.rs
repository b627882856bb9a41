//! What a loaded scene is: [`SceneDesc`] and the descriptions it holds
//! (materials, render tasks, cameras' views), checked and ready to place into a
//! renderer ([`Renderer::place_scene`](crate::Renderer::place_scene)). The `.scn`
//! loader (`scn.rs`) and the model loaders make them.

use super::scn_cloth::ClothDesc;
use super::scn_targets::RenderTargetDesc;
use super::{Diagnostic, Model, ShapeKind, Texture};
use crate::scene::{
    Camera, Culling, Entity, Environment, Light, Lighting, Material, PostEffect, RenderTargetId, TextureId, View,
    Viewport,
};
use glam::Mat4;
use std::path::PathBuf;

/// A texture a material uses: index into [`SceneDesc::textures`].
pub type TextureRef = usize;

/// A material from a `material` block, its maps as indices into [`SceneDesc::textures`].
#[derive(Clone, Debug, Default)]
pub struct MaterialDesc {
    /// Everything but the texture ids.
    pub material: Material,
    /// `diffuse_map` (sRGB).
    pub diffuse_map: Option<TextureRef>,
    /// `normal_map` (linear).
    pub normal_map: Option<TextureRef>,
    /// `specular_map` (linear).
    pub specular_map: Option<TextureRef>,
    /// Metallic-roughness map (linear).
    pub metallic_roughness_map: Option<TextureRef>,
    /// Occlusion map (linear).
    pub occlusion_map: Option<TextureRef>,
    /// Emissive map (sRGB).
    pub emissive_map: Option<TextureRef>,
}

impl MaterialDesc {
    /// The material with its texture references turned into `textures`' ids
    /// (`textures[i]` is the renderer's id of texture `i`).
    pub fn resolve(&self, textures: &[TextureId]) -> Material {
        Material {
            diffuse_map: self.diffuse_map.map(|i| textures[i]),
            normal_map: self.normal_map.map(|i| textures[i]),
            specular_map: self.specular_map.map(|i| textures[i]),
            metallic_roughness_map: self.metallic_roughness_map.map(|i| textures[i]),
            occlusion_map: self.occlusion_map.map(|i| textures[i]),
            emissive_map: self.emissive_map.map(|i| textures[i]),
            ..self.material.clone()
        }
    }

    /// Its maps, in [`Material::maps`]' order.
    pub fn maps(&self) -> [Option<TextureRef>; 6] {
        [
            self.diffuse_map,
            self.normal_map,
            self.specular_map,
            self.metallic_roughness_map,
            self.occlusion_map,
            self.emissive_map,
        ]
    }

    /// The same, to change.
    pub fn maps_mut(&mut self) -> [&mut Option<TextureRef>; 6] {
        [
            &mut self.diffuse_map,
            &mut self.normal_map,
            &mut self.specular_map,
            &mut self.metallic_roughness_map,
            &mut self.occlusion_map,
            &mut self.emissive_map,
        ]
    }
}

/// One render task: every instance of one mesh with one material, gathered from
/// all `entity` and `instances` blocks that use that pair.
#[derive(Clone, Debug)]
pub struct EntityDesc {
    /// The shape or model.
    pub mesh: MeshRef,
    /// Index into [`SceneDesc::materials`]; `None` for the default material.
    pub material: Option<usize>,
    /// Draw order and shadow flags.
    pub draw: DrawOptions,
    /// One transform per instance.
    pub transforms: Vec<Mat4>,
    /// The instances' tiles (an `instances` block with `tiles`).
    pub tiles: Option<crate::scene::Tiles>,
    /// With tiles, the fraction of each tile drawn (see [`Entity::density`]).
    pub density: f32,
    /// With tiles, 16-byte instances (see [`Entity::with_compact_instances`]).
    pub compact: bool,
}

/// How an `entity` or `instances` block's instances draw: keys `render_order`,
/// `cast_shadows` and `receive_shadows` (see the same fields of [`Entity`]).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub struct DrawOptions {
    /// Draw-order override (see [`Entity::render_order`]).
    pub render_order: Option<u8>,
    /// Whether the instances cast shadows (default true).
    pub cast_shadows: bool,
    /// Whether shadows fall on the instances (default true).
    pub receive_shadows: bool,
}

impl Default for DrawOptions {
    fn default() -> Self {
        Self { render_order: None, cast_shadows: true, receive_shadows: true }
    }
}

impl DrawOptions {
    /// Set these options on `entity`.
    pub fn apply(self, entity: &mut Entity) {
        entity.render_order = self.render_order;
        entity.cast_shadows = self.cast_shadows;
        entity.receive_shadows = self.receive_shadows;
    }
}

/// What an entity draws: a procedural shape, or a model file (every part of it).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum MeshRef {
    /// A procedural shape.
    Shape(ShapeKind),
    /// Index into [`SceneDesc::models`].
    Model(usize),
}

/// A parsed and validated scene file, ready to place into a renderer.
#[derive(Clone, Debug)]
pub struct SceneDesc {
    /// The file it came from.
    pub path: PathBuf,
    /// Background and ambient light.
    pub environment: Environment,
    /// Cameras in file order (a default one when the file has none).
    pub cameras: Vec<Camera>,
    /// Each camera's `viewport`, post chain and `output` (the same order).
    pub camera_views: Vec<CameraView>,
    /// `render_target` blocks in file order: render target k's texture comes
    /// after the file textures in material maps, and placing the scene gives
    /// its id ([`PlacedScene::render_targets`](crate::world::PlacedScene::render_targets)).
    pub render_targets: Vec<RenderTargetDesc>,
    /// Lights in file order.
    pub lights: Vec<Light>,
    /// Materials in file order.
    pub materials: Vec<MaterialDesc>,
    /// Decoded textures, each file once.
    pub textures: Vec<Texture>,
    /// Models named by `mesh` keys, each file once, plus a copy per entity that
    /// overrides its materials (`mtl.NAME.key`).
    pub models: Vec<Model>,
    /// Render tasks, one per (mesh, material, draw options), in first-use order.
    pub entities: Vec<EntityDesc>,
    /// Simulated cloths in file order; their entities follow the render tasks'.
    pub cloths: Vec<ClothDesc>,
    /// Fish schools in file order; each draws with entities of its own.
    pub schools: Vec<super::SchoolDesc>,
    /// Particle emitters in file order; each draws in a particle layer of its own.
    pub emitters: Vec<super::EmitterDesc>,
    /// Directional lights whose direction sways with the scene time.
    pub light_sways: Vec<LightSway>,
    /// Point and spot lights that circle with the scene time.
    pub light_circles: Vec<LightCircle>,
    /// Non-fatal problems (unknown keys, repeated keys), `path:line: message`.
    pub warnings: Vec<Diagnostic>,
    /// The hour its sun and sky were last set to ([`SceneDesc::set_time_of_day`]).
    pub time_of_day: Option<f32>,
    /// The image its environment lights it with, when that is a file's
    /// ([`EnvironmentSource::Image`](crate::scene::EnvironmentSource::Image) of its id).
    pub environment_image: Option<super::EnvironmentImage>,
    /// The world key `transparency`: how every camera's view blends
    /// transparent surfaces ([`View::transparency`]).
    pub transparency: crate::scene::Transparency,
}

/// A directional light whose direction sways with time (`sway` in `.scn`).
#[derive(Clone, Debug, PartialEq)]
pub struct LightSway {
    /// The light, an index into [`SceneDesc::lights`].
    pub light: usize,
    /// Its direction at rest.
    pub base: glam::Vec3,
    /// How far it swings either way, degrees.
    pub degrees: f32,
    /// Seconds a swing.
    pub period: f32,
}

/// A point or spot light circling its `origin` in a level circle with time
/// (`circle` in `.scn`).
#[derive(Clone, Debug, PartialEq)]
pub struct LightCircle {
    /// The light, an index into [`SceneDesc::lights`].
    pub light: usize,
    /// The circle's centre (the light's `origin`).
    pub centre: glam::Vec3,
    /// Its radius.
    pub radius: f32,
    /// Seconds a turn (counter-clockwise seen from above).
    pub period: f32,
    /// Where on the circle it is at time 0, degrees from +x towards −z.
    pub phase: f32,
}

/// How a camera of a scene draws: where in the image, and its post chain.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct CameraView {
    /// `viewport`: its rectangle of the image (`None`: drawn only alone).
    pub viewport: Option<Viewport>,
    /// `post`: its effects, in order.
    pub post: Vec<PostEffect>,
    /// `output`: the render target it draws into (an index of
    /// [`SceneDesc::render_targets`]), rather than the image.
    pub output: Option<usize>,
    /// `cull`: how it culls (`off`, `cpu` or `gpu`, the default).
    pub culling: Culling,
    /// `ssao`, `ssao_radius`, `ssao_intensity`: its screen-space ambient occlusion.
    pub ambient_occlusion: Option<crate::scene::AmbientOcclusion>,
    /// `lod_error`: the pixels of error its levels of detail may make
    /// ([`View::lod_error`]; `None`: the default).
    pub lod_error: Option<f32>,
}

impl SceneDesc {
    /// This scene lit by a neutral studio environment
    /// ([`EnvironmentImage::studio`](super::EnvironmentImage::studio)), its sky
    /// drawn blurred: how glTF viewers show a model without a scene of its own.
    pub fn with_studio_environment(mut self) -> Self {
        let studio = super::EnvironmentImage::studio();
        let source = crate::scene::EnvironmentSource::Image(studio.id());
        self.environment.light =
            Some(crate::scene::EnvironmentLight { sky_blur: 0.6, ..crate::scene::EnvironmentLight::new(source) });
        self.environment_image = Some(studio);
        self
    }

    /// The views `glint render` draws: the cameras that draw into render
    /// targets ([`SceneDesc::target_views`]), then every other camera that has a
    /// viewport, in file order, or else the first other camera alone over the image.
    pub fn views(&self, targets: &[RenderTargetId]) -> Vec<View> {
        let into_image: Vec<usize> =
            (0..self.cameras.len()).filter(|&k| self.camera_views[k].output.is_none()).collect();
        let placed: Vec<View> = (into_image.iter())
            .filter_map(|&k| self.camera_views[k].viewport.map(|v| self.camera_view(k).with_viewport(v)))
            .collect();
        let image = match (placed.is_empty(), into_image.first()) {
            (true, Some(&first)) => vec![self.camera_view(first)],
            _ => placed,
        };
        self.target_views(targets).into_iter().chain(image).collect()
    }

    /// The cameras that draw into render targets, as views into them;
    /// `targets` is each render target's id in the renderer the scene was
    /// placed into (a camera whose target has none is left out).
    pub fn target_views(&self, targets: &[RenderTargetId]) -> Vec<View> {
        (0..self.cameras.len())
            .filter_map(|k| {
                let c = &self.camera_views[k];
                let view = self.camera_view(k).with_viewport(c.viewport.unwrap_or_default());
                c.output.and_then(|t| targets.get(t)).map(|&id| view.with_output(id))
            })
            .collect()
    }

    /// The scene's lights under its environment, for each frame.
    pub fn lighting(&self) -> Lighting<'_> {
        Lighting::new(&self.lights, self.environment)
    }

    /// Whether it draws anything its [`transparency`](Self::transparency)
    /// decides: a blended material (of the scene or a model) or an
    /// alpha-blended emitter.
    pub fn has_transparency(&self) -> bool {
        let blended = |m: &MaterialDesc| m.material.alpha_mode == crate::scene::AlphaMode::Blend;
        self.materials.iter().chain(self.models.iter().flat_map(|m| &m.materials)).any(blended)
            || self.emitters.iter().any(|e| e.blend == crate::scene::ParticleBlend::Alpha)
    }

    /// Camera `index` over the whole image, with its post chain.
    pub fn camera_view(&self, index: usize) -> View {
        let c = &self.camera_views[index];
        let view = View::new(self.cameras[index]).with_post(c.post.clone()).with_culling(c.culling);
        let view = view.with_ambient_occlusion(c.ambient_occlusion).with_transparency(self.transparency);
        match c.lod_error {
            Some(pixels) => view.with_lod_error(pixels),
            None => view,
        }
    }

    /// Draw every cloth's debug view (edge ribbons, pin markers) or not;
    /// whether any cloth changed (place the scene again to show it).
    pub fn set_cloth_debug(&mut self, debug: bool) -> bool {
        let mut changed = false;
        for cloth in self.cloths.iter_mut().filter(|c| c.debug != debug) {
            cloth.debug = debug;
            changed = true;
        }
        changed
    }

    /// Total instances over all render tasks: a model's placements count once
    /// per instance of each of its parts ([`Model::instances_per_placement`]).
    pub fn instance_count(&self) -> usize {
        self.entities.iter().map(|e| e.transforms.len() * self.instances_per_placement(&e.mesh)).sum()
    }

    /// Instances one placement of `mesh` makes: one for a shape, a model's
    /// [`Model::instances_per_placement`].
    pub fn instances_per_placement(&self, mesh: &MeshRef) -> usize {
        match *mesh {
            MeshRef::Shape(_) => 1,
            MeshRef::Model(i) => self.models.get(i).map_or(1, Model::instances_per_placement),
        }
    }

    /// Check, without stepping, that posing at `time` stays within the cloth
    /// limits ([`MAX_POSE_STEPS`](super::MAX_POSE_STEPS) per cloth, 10⁹
    /// node²-steps over all of them; see `docs/limits.md`) and the schools'
    /// ([`MAX_POSE_SCHOOL_TESTS`](super::MAX_POSE_SCHOOL_TESTS)) and emitters'
    /// ([`MAX_POSE_PARTICLE_STEPS`](super::MAX_POSE_PARTICLE_STEPS)), each at most
    /// [`MAX_POSE_STEPS`](super::MAX_POSE_STEPS) steps too: the error names
    /// the block that goes over. Posing at an earlier time takes no more work.
    /// A cloth's, school's or emitter's description changed since loading is
    /// checked again ([`ClothSetup::check`](crate::scene::cloth::ClothSetup::check),
    /// [`SchoolParams::check`](crate::scene::school::SchoolParams::check),
    /// [`EmitterParams::check`](crate::scene::emitter::EmitterParams::check)).
    pub fn check_pose(&self, time: f32) -> Result<(), Diagnostic> {
        self.check_pose_from(None, time)
    }

    /// [`check_pose`](Self::check_pose) for posing at `time` with every
    /// simulation at its state at `from` (`None`: at its start): the work of
    /// the steps between (all of them where `from` is later than `time`, as
    /// the simulations start again). A sequence posed frame by frame is
    /// checked one frame at a time.
    pub fn check_pose_from(&self, from: Option<f32>, time: f32) -> Result<(), Diagnostic> {
        self.check_simulations()?;
        self.check_pose_work(from, time)
    }

    /// Check its cloths', schools' and emitters' descriptions again (one
    /// changed since loading cannot run).
    pub fn check_simulations(&self) -> Result<(), Diagnostic> {
        for cloth in &self.cloths {
            let at =
                |e: crate::scene::cloth::ClothMeshError| Diagnostic::at(&self.path, cloth.line, format!("cloth: {e}"));
            cloth.setup.check().map_err(at)?;
        }
        for s in &self.schools {
            s.params.check().map_err(|m| Diagnostic::at(&self.path, s.line, format!("school: {m}")))?;
        }
        for e in &self.emitters {
            let dt = (e.dt.is_finite() && e.dt > 0.0)
                .then_some(())
                .ok_or_else(|| format!("dt must be above 0, got {}", e.dt));
            e.params.check().and(dt).map_err(|m| Diagnostic::at(&self.path, e.line, format!("emitter: {m}")))?;
        }
        Ok(())
    }

    /// The posing limits of [`check_pose_from`](Self::check_pose_from)
    /// alone, its descriptions already checked ([`check_simulations`](Self::check_simulations)):
    /// cheap, for checking each frame of a long sequence.
    pub fn check_pose_work(&self, from: Option<f32>, time: f32) -> Result<(), Diagnostic> {
        let mut work = 0u64;
        for cloth in &self.cloths {
            cloth.check_pose((from, time), work, &self.path)?;
            work = work.saturating_add(cloth.pose_work(from, time));
        }
        let fish = super::scn_school::pose_work(&self.schools, (from, time));
        within(&self.path, (super::MAX_POSE_SCHOOL_TESTS, "neighbour tests"), fish)?;
        let particles = super::scn_emitter::pose_work(&self.emitters, (from, time));
        within(&self.path, (super::MAX_POSE_PARTICLE_STEPS, "particle-steps"), particles)
    }
}

/// "time 4 s", or "time 2 s to 4 s" from a simulation state at 2 s (a
/// later one counts as the start).
pub(crate) fn span(from: Option<f32>, time: f32) -> String {
    match from.filter(|&f| f > 0.0 && f <= time) {
        None => format!("time {time} s"),
        Some(f) => format!("time {f} s to {time} s"),
    }
}

/// An error at the first of `blocks` (line, steps, work, what it is) that
/// takes more than [`MAX_POSE_STEPS`](super::MAX_POSE_STEPS) steps, or where
/// the work so far passes `limit` (of `unit`); else `Ok`.
fn within(
    scene: &std::path::Path,
    (limit, unit): (u64, &str),
    blocks: impl Iterator<Item = (usize, u64, u64, String)>,
) -> Result<(), Diagnostic> {
    let mut work = 0u64;
    for (line, steps, more, what) in blocks {
        let most = super::MAX_POSE_STEPS;
        if steps > most {
            return Err(Diagnostic::at(scene, line, format!("{what}, more than the {most} steps one pose may take")));
        }
        work = work.saturating_add(more);
        if work > limit {
            return Err(Diagnostic::at(scene, line, format!("{what}, more than the {limit} {unit} a pose may take")));
        }
    }
    Ok(())
}
