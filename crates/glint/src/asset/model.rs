//! Beginner layer: [`Model`], a mesh file loaded as parts (a mesh drawn with one
//! of the model's materials), ready to place in a renderer, and its materials
//! overridable by name without editing the file.

use super::animation::{Animation, ModelNode};
use super::{Diagnostic, EntityDesc, LoadOptions, MaterialDesc, MeshRef, SceneDesc, Texture};
use crate::scene::{Aabb, Background, Camera, Environment, Light, Material, Mesh};
use glam::{Mat4, Vec3};
use std::path::{Path, PathBuf};

/// One drawable piece of a model: a mesh, its material and its place in the model.
#[derive(Clone, Debug)]
pub struct ModelPart {
    /// Object or group name from the file (for diagnostics).
    pub name: String,
    /// The triangles.
    pub mesh: Mesh,
    /// Index into [`Model::materials`]; `None` for the renderer's default material.
    pub material: Option<usize>,
    /// Part-to-model transforms: one per place the part appears (a glTF mesh used
    /// by several nodes is one part drawn as one instanced draw). Identity for a
    /// skinned part: its joints place it.
    pub transforms: Vec<Mat4>,
    /// The skin ([`Model::skins`] index) moving a skinned part's vertices.
    pub skin: Option<usize>,
    /// A skinned part's joint matrices in the current pose (model space, inverse
    /// bind matrices applied), for [`Entity::with_joints`](crate::Entity::with_joints).
    pub joints: Vec<Mat4>,
    /// Morph targets, when the mesh has them; `mesh` holds them blended.
    pub morph: Option<Morph>,
}

/// A skeleton: the nodes whose poses move a skinned mesh.
#[derive(Clone, Debug, PartialEq)]
pub struct Skin {
    /// Name from the file.
    pub name: String,
    /// The joint nodes ([`Model::nodes`] indices), in the order vertices name them.
    pub joints: Vec<usize>,
    /// Per joint, the inverse of its model-space transform in the bind pose.
    pub inverse_bind: Vec<Mat4>,
}

/// A mesh's morph targets: position and normal offsets per vertex, blended by
/// weights ([`Morph::apply`], on the CPU; the blended mesh is uploaded again).
#[derive(Clone, Debug, PartialEq)]
pub struct Morph {
    /// Unmorphed positions, one per mesh vertex.
    pub positions: Vec<Vec3>,
    /// Unmorphed normals.
    pub normals: Vec<Vec3>,
    /// Per target, (position offsets, normal offsets), each one per vertex.
    pub targets: Vec<(Vec<Vec3>, Vec<Vec3>)>,
    /// The weights `mesh` was last blended with.
    pub weights: Vec<f32>,
}

impl Morph {
    /// Blend the targets into `mesh` with `weights` (missing weights are 0).
    /// Returns whether anything changed.
    pub fn apply(&mut self, mesh: &mut Mesh, weights: &[f32]) -> bool {
        let w: Vec<f32> = (0..self.targets.len()).map(|i| weights.get(i).copied().unwrap_or(0.0)).collect();
        if w == self.weights {
            return false;
        }
        let (mut p, mut n) = (self.positions.clone(), self.normals.clone());
        for (&wt, (dp, dn)) in w.iter().zip(&self.targets).filter(|(w, _)| **w != 0.0) {
            p.iter_mut().zip(dp).for_each(|(p, d)| *p += *d * wt);
            n.iter_mut().zip(dn).for_each(|(n, d)| *n += *d * wt);
        }
        self.weights = w;
        mesh.set_positions_normals(&p, &n)
    }
}

impl ModelPart {
    /// A rigid part (no skin, no morph targets).
    pub fn new(name: String, mesh: Mesh, material: Option<usize>, transforms: Vec<Mat4>) -> Self {
        Self { name, mesh, material, transforms, skin: None, joints: Vec::new(), morph: None }
    }

    /// The part's world transforms when its model is placed at each of `placements`.
    pub fn placed(&self, placements: &[Mat4]) -> Vec<Mat4> {
        placements.iter().flat_map(|p| self.transforms.iter().map(move |t| *p * *t)).collect()
    }
}

/// A model loaded from a file.
#[derive(Clone, Debug)]
pub struct Model {
    /// The file it came from.
    pub path: PathBuf,
    /// Its drawable parts.
    pub parts: Vec<ModelPart>,
    /// Its materials, in file order.
    pub materials: Vec<MaterialDesc>,
    /// Decoded textures the materials use, each file once.
    pub textures: Vec<Texture>,
    /// The node hierarchy (glTF; empty for OBJ), parents before children.
    pub nodes: Vec<ModelNode>,
    /// Keyframe animations of the nodes; [`Model::pose`] plays the first.
    pub animations: Vec<Animation>,
    /// Skeletons of the skinned parts.
    pub skins: Vec<Skin>,
    /// Cameras the file defines, placed in the model.
    pub cameras: Vec<Camera>,
    /// Lights the file defines, placed in the model.
    pub lights: Vec<Light>,
    /// What was wrong but not fatal (a missing `.mtl` or texture, an option
    /// ignored), each with a visible default in place.
    pub warnings: Vec<Diagnostic>,
}

impl Model {
    /// Instances one placement of the model makes: one per transform of each
    /// part (a glTF mesh used by several nodes is one part placed at each).
    pub fn instances_per_placement(&self) -> usize {
        self.parts.iter().map(|p| p.transforms.len()).sum()
    }

    /// Load a model file: Wavefront `.obj` (with its `.mtl` libraries), or glTF
    /// 2.0 `.gltf` / `.glb`.
    pub fn load(path: &Path) -> Result<Self, Diagnostic> {
        Self::load_with(path, LoadOptions::default())
    }

    /// [`Model::load`] with explicit options (e.g. letting files name assets
    /// outside their folder).
    pub fn load_with(path: &Path, options: LoadOptions) -> Result<Self, Diagnostic> {
        if !Self::is_model_path(path) {
            return Self::parse(path, &[], options); // the "not a model file" error, without reading it
        }
        let bytes = options.files.read(path, super::MAX_MODEL_BYTES)?;
        Self::parse(path, &bytes, options)
    }

    /// Move the parts to where the first animation puts them at `time` seconds
    /// (the rest pose for a model without animations; nothing for one without
    /// nodes): part transforms, skinned parts' joint matrices and morphed meshes.
    /// Returns the indices of the parts whose mesh changed (morph targets).
    pub fn pose(&mut self, time: f32) -> Vec<usize> {
        let pose = super::animation::pose_nodes(&self.nodes, self.animations.first(), time);
        self.apply_pose(&pose)
    }

    /// Move the parts to the rest pose (no animation).
    pub(crate) fn rest_pose(&mut self) {
        let pose = super::animation::pose_nodes(&self.nodes, None, 0.0);
        self.apply_pose(&pose);
    }

    fn apply_pose(&mut self, pose: &super::animation::Pose) -> Vec<usize> {
        let mut morphed = Vec::new();
        for (node, (transform, weights)) in self.nodes.iter().zip(pose.world.iter().zip(&pose.weights)) {
            for &(p, k) in &node.placements {
                let part = &mut self.parts[p];
                part.transforms[k] = if part.skin.is_some() { Mat4::IDENTITY } else { *transform };
                // A mesh placed by several nodes takes its first node's weights.
                if let (0, Some(morph)) = (k, part.morph.as_mut()) {
                    if morph.apply(&mut part.mesh, weights) {
                        morphed.push(p);
                    }
                }
            }
        }
        for part in &mut self.parts {
            if let Some(skin) = part.skin.and_then(|s| self.skins.get(s)) {
                part.joints = skin
                    .joints
                    .iter()
                    .zip(&skin.inverse_bind)
                    .map(|(&node, ibm)| pose.world.get(node).copied().unwrap_or(Mat4::IDENTITY) * *ibm)
                    .collect();
            }
        }
        morphed
    }

    /// Parse a model from `bytes` as if read from `path`: its extension picks the
    /// format, its folder anchors the files it names. For files already in memory
    /// (and fuzzing).
    pub fn parse(path: &Path, bytes: &[u8], options: LoadOptions) -> Result<Self, Diagnostic> {
        match path.extension().and_then(|e| e.to_str()).map(str::to_ascii_lowercase).as_deref() {
            Some("obj") => super::obj::parse_obj(path, bytes, options),
            Some("gltf" | "glb") => super::gltf::parse_gltf(path, bytes, options),
            _ => Err(Diagnostic::file(path, "not a model file: expected the extension .obj, .gltf or .glb")),
        }
    }

    /// Whether `path` names a model file (by extension).
    pub fn is_model_path(path: &Path) -> bool {
        path.extension()
            .and_then(|e| e.to_str())
            .is_some_and(|e| ["obj", "gltf", "glb"].contains(&e.to_ascii_lowercase().as_str()))
    }

    /// Change the material called `name` (as the file names it) before the model
    /// is placed, e.g. `model.override_material("Wood", |m| m.base_color.x = 1.0)`.
    /// Returns whether the model has such a material.
    pub fn override_material(&mut self, name: &str, edit: impl FnOnce(&mut Material)) -> bool {
        match self.materials.iter_mut().find(|m| m.material.name == name) {
            Some(m) => {
                edit(&mut m.material);
                true
            }
            None => false,
        }
    }

    /// The model-space box around every part; `None` for a model without parts.
    /// Skinned parts count as posed by each of their joints.
    pub fn bounds(&self) -> Option<Aabb> {
        let corners = self.parts.iter().flat_map(|p| {
            let b = p.mesh.aabb();
            let places = if p.joints.is_empty() { &p.transforms } else { &p.joints };
            places.iter().flat_map(move |t| {
                (0..8).map(move |i| {
                    let pick = |bit: u32, lo: f32, hi: f32| if i & bit == 0 { lo } else { hi };
                    let corner =
                        Vec3::new(pick(1, b.min.x, b.max.x), pick(2, b.min.y, b.max.y), pick(4, b.min.z, b.max.z));
                    t.transform_point3(corner)
                })
            })
        });
        Aabb::from_points(corners)
    }
}

impl Model {
    /// A scene showing this model alone: one placement at the origin; camera 0
    /// frames its bounds from above and to the side, the file's own cameras follow;
    /// the file's lights, or a sun and a fill light when it has none; ambient light
    /// and a sky.
    pub fn into_scene(self) -> SceneDesc {
        self.scene()
    }

    /// [`into_scene`](Self::into_scene) as `glint view`, `glint render` and the
    /// web page show a model file: a glTF model also lit by a studio
    /// environment ([`SceneDesc::with_studio_environment`]), as the glTF sample
    /// viewer lights one, so metals have something to reflect.
    pub fn into_shown_scene(self) -> SceneDesc {
        let gltf = (self.path.extension().and_then(|e| e.to_str()))
            .is_some_and(|e| e.eq_ignore_ascii_case("gltf") || e.eq_ignore_ascii_case("glb"));
        match gltf {
            true => self.scene().with_studio_environment(),
            false => self.scene(),
        }
    }

    fn scene(self) -> SceneDesc {
        let bounds = self.bounds().unwrap_or(Aabb { min: Vec3::splat(-1.0), max: Vec3::splat(1.0) });
        let (center, radius) = (bounds.center(), (bounds.half_extent().length()).max(1e-3));
        let fov = 45.0_f32;
        // Far enough that the bounding sphere fits the vertical field of view.
        let distance = radius / (fov.to_radians() * 0.5).sin() * 1.05;
        let eye = center + Vec3::new(0.8, 0.6, 1.2).normalize() * distance;
        let camera = Camera::perspective(fov, distance * 0.01, distance + radius * 4.0).looking_at(eye, center);
        let environment = Environment {
            background: Background::Gradient { top: Vec3::new(0.25, 0.35, 0.55), bottom: Vec3::new(0.75, 0.78, 0.8) },
            ambient: Vec3::splat(0.3),
            ..Environment::default()
        };
        let sun = Light::directional(Vec3::new(-0.4, -1.0, -0.6), Vec3::ONE, 1.0);
        let fill = Light::directional(Vec3::new(0.6, -0.3, 0.8), Vec3::ONE, 0.35);
        SceneDesc {
            path: self.path.clone(),
            environment,
            cameras: std::iter::once(camera).chain(self.cameras.iter().copied()).collect(),
            camera_views: vec![Default::default(); 1 + self.cameras.len()],
            render_targets: Vec::new(),
            lights: if self.lights.is_empty() { vec![sun, fill] } else { self.lights.clone() },
            materials: Vec::new(),
            textures: Vec::new(),
            warnings: self.warnings.clone(),
            entities: vec![EntityDesc {
                mesh: MeshRef::Model(0),
                material: None,
                draw: Default::default(),
                transforms: vec![Mat4::IDENTITY],
                tiles: None,
                density: 1.0,
                compact: false,
            }],
            cloths: Vec::new(),
            schools: Vec::new(),
            light_sways: Vec::new(),
            light_circles: Vec::new(),
            emitters: Vec::new(),
            time_of_day: None,
            transparency: Default::default(),
            environment_image: None,
            models: vec![self],
        }
    }
}
