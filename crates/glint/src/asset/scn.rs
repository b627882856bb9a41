//! Meaning of `.scn` files: classnames and keys (see `docs/scn.md` for the full
//! reference) turned into a [`SceneDesc`], checked without a GPU, and placed into
//! a [`Renderer`](crate::Renderer) with [`Renderer::place_scene`](crate::Renderer::place_scene).

use super::procedural::{blob_vertex_count, MAX_SCENE_BLOB_VERTICES};
use super::scene_desc::{CameraView, DrawOptions, EntityDesc, MaterialDesc, MeshRef, SceneDesc, TextureRef};
use super::scn_cloth::{self, ClothDesc};
use super::scn_emitter;
use super::scn_fields::{numbers, Fields};
use super::scn_lights;
use super::scn_material::material_fields;
use super::scn_school::SchoolDesc;
use super::scn_syntax::{decode_scene_text, parse_blocks, Block, Pair};
use super::scn_targets;
use super::texture::read_texture;
use super::texture::TextureCache;
use super::{decoded_bytes, read_environment};
use super::{AssetFolder, Diagnostic, LoadOptions, Model, ShapeKind, Texture, MAX_SCENE_BYTES, MAX_SCENE_TOTAL_BYTES};
use crate::scene::{
    AmbientOcclusion, Background, Camera, Culling, Environment, EnvironmentLight, EnvironmentSource, Fog, Light,
    Material, ShadowLayout, Transparency, MAX_CLUSTERED_LIGHTS, MAX_SHADOW_MAP_BYTES,
};
use crate::text::{list, quote};
use glam::{EulerRot, Mat4, Quat, Vec3};
use std::collections::HashMap;
use std::path::{Path, PathBuf};

/// Most instances one scene file may place, over all blocks: 2 million 64-byte
/// instance records fill 122 MiB, inside the 128 MiB storage binding every
/// adapter offers (wgpu's default limit), so any adapter can draw them.
pub const MAX_INSTANCES: u64 = 2_000_000;

/// Most tiles along each side of an `instances` block (`tiles`): 65,536 tiles.
pub const MAX_TILES: i64 = 256;

/// Most cameras (each a view of the frame) one scene may have: each is a pass
/// over the scene every frame.
pub const MAX_CAMERAS: usize = 16_384;

/// Read, parse and validate a `.scn` file, decoding the textures it names.
pub fn load_scene(path: &Path) -> Result<SceneDesc, Diagnostic> {
    load_scene_with(path, LoadOptions::default())
}

/// [`load_scene`] with options for the models it names.
pub fn load_scene_with(path: &Path, options: LoadOptions) -> Result<SceneDesc, Diagnostic> {
    let bytes = options.files.read(path, MAX_SCENE_BYTES)?;
    let text = decode_scene_text(path, &bytes)?;
    parse_scene_with(path, &text, options)
}

/// Parse and validate `.scn` text; `path` names it in messages and anchors
/// relative texture paths.
pub fn parse_scene(path: &Path, text: &str) -> Result<SceneDesc, Diagnostic> {
    parse_scene_with(path, text, LoadOptions::default())
}

/// [`parse_scene`] with options for the models it names.
pub fn parse_scene_with(path: &Path, text: &str, options: LoadOptions) -> Result<SceneDesc, Diagnostic> {
    let blocks = parse_blocks(path, text)?;
    let mut loader = Loader {
        path,
        assets: AssetFolder::for_scene(path, &options),
        scene: SceneDesc {
            path: path.to_path_buf(),
            environment: Environment::default(),
            cameras: Vec::new(),
            camera_views: Vec::new(),
            render_targets: Vec::new(),
            lights: Vec::new(),
            materials: Vec::new(),
            textures: Vec::new(),
            models: Vec::new(),
            entities: Vec::new(),
            cloths: Vec::new(),
            schools: Vec::new(),
            light_sways: Vec::new(),
            light_circles: Vec::new(),
            emitters: Vec::new(),
            warnings: Vec::new(),
            time_of_day: None,
            transparency: Default::default(),
            environment_image: None,
        },
        textures: TextureCache::new(options.texture_memory),
        model_index: HashMap::new(),
        material_names: HashMap::new(),
        blobs: std::collections::HashSet::new(),
        blob_vertices: 0,
        model_bytes: Vec::new(),
        bytes_read: 0,
        options,
        placements: Vec::new(),
        cloths: Vec::new(),
        schools: Vec::new(),
        instances: 0,
        camera_lines: Vec::new(),
        targets: scn_targets::Targets::default(),
        time_of_day: None,
        time_of_day_line: None,
        deferred: None,
    };
    loader.time_of_day = loader.options.time_of_day;
    // Render targets first, so cameras and materials may name one defined
    // anywhere in the file (as materials are named by entities).
    let is_target = |b: &&Block| b.pairs.iter().any(|p| p.key == "classname" && p.value.trim() == "render_target");
    for block in blocks.iter().filter(is_target).chain(blocks.iter().filter(|b| !is_target(b))) {
        let misses = loader.assets.files.misses();
        if let Err(error) = loader.block(block) {
            loader.defer(error, misses)?;
        }
    }
    loader.finish()
}

/// An `entity` or `instances` block before material names are resolved.
pub(super) struct Placement {
    pub(super) mesh: MeshRef,
    pub(super) material: Option<(String, usize)>,
    pub(super) draw: DrawOptions,
    pub(super) transforms: Vec<Mat4>,
    /// Tiles, density and compact instances: an entity of its own.
    pub(super) tiles: Option<(crate::scene::Tiles, f32, bool)>,
    /// An entity of its own without tiles (a school's fish, its predator).
    pub(super) alone: bool,
}

pub(super) struct Loader<'a> {
    pub(super) path: &'a Path,
    assets: AssetFolder,
    scene: SceneDesc,
    textures: TextureCache<PathBuf>,
    model_index: HashMap<PathBuf, usize>,
    /// Each material's index in `scene.materials`, by name: resolving a name
    /// and refusing a repeated one take constant time, so N blocks load in linear
    /// time (a linear search made 10⁶ material blocks take minutes).
    material_names: HashMap<String, usize>,
    /// The distinct blob meshes named so far, (detail, seed), and their vertices.
    blobs: std::collections::HashSet<(u32, u32)>,
    blob_vertices: u64,
    /// The file size of each of `scene.models` (an overridden copy counts as its
    /// original), and their total against [`MAX_SCENE_TOTAL_BYTES`].
    model_bytes: Vec<u64>,
    bytes_read: u64,
    pub(super) options: LoadOptions,
    pub(super) placements: Vec<Placement>,
    /// Cloths with their material names, resolved in [`Loader::finish`].
    cloths: Vec<(ClothDesc, Option<(String, usize)>)>,
    instances: u64,
    /// Schools, their entities' places in `placements` until resolved.
    pub(super) schools: Vec<SchoolDesc>,
    /// Each camera's block line, for errors found once the file is read.
    camera_lines: Vec<usize>,
    /// The `render_target` blocks so far, by name.
    targets: scn_targets::Targets,
    /// The world's `time_of_day` (or the caller's), applied once every light is read.
    time_of_day: Option<f32>,
    /// The line of the world's `time_of_day`, when it came from the file.
    time_of_day_line: Option<usize>,
    /// The first error that came of a file the memory set lacks ([`Loader::defer`]).
    deferred: Option<Diagnostic>,
}

/// A camera's `ssao`, `ssao_radius` and `ssao_intensity` (the last two read
/// either way, so they are never reported unknown).
fn ambient_occlusion(f: &mut Fields) -> Result<Option<AmbientOcclusion>, Diagnostic> {
    let on = f.flag("ssao")?;
    let radius = f.number("ssao_radius", 0.001..=AmbientOcclusion::MAX_RADIUS)?;
    let intensity = f.number("ssao_intensity", 0.0..=AmbientOcclusion::MAX_INTENSITY)?;
    let defaults = AmbientOcclusion::default();
    Ok((on == Some(true)).then(|| AmbientOcclusion {
        radius: radius.unwrap_or(defaults.radius),
        intensity: intensity.unwrap_or(defaults.intensity),
    }))
}

/// Rotation from Quake-style angles in degrees: pitch about X, yaw about Y, roll about Z.
pub(crate) fn rotation(angles: Vec3) -> Quat {
    let r = angles * (std::f32::consts::PI / 180.0);
    Quat::from_euler(EulerRot::YXZ, r.y, r.x, r.z)
}

impl Loader<'_> {
    fn block(&mut self, block: &Block) -> Result<(), Diagnostic> {
        let class_pair = block
            .pairs
            .iter()
            .find(|p| p.key == "classname")
            .ok_or_else(|| Diagnostic::at(self.path, block.line, "block has no \"classname\""))?;
        let class = class_pair.value.trim();
        let mut f = Fields { path: self.path, class, block, used: vec![false; block.pairs.len()] };
        match class {
            "world" => self.world(&mut f)?,
            "camera" => self.camera(&mut f)?,
            "render_target" => {
                self.targets.parse(&mut f)?;
            }
            "light_directional" | "light_point" | "light_spot" => {
                let light = scn_lights::light(class, &mut f, &mut self.scene.warnings)?;
                let index = self.scene.lights.len();
                match light.kind {
                    crate::scene::LightKind::Directional { direction } => {
                        self.scene.light_sways.extend(scn_lights::sway(&mut f, direction, index)?);
                    }
                    crate::scene::LightKind::Point { position, .. } | crate::scene::LightKind::Spot { position, .. } => {
                        self.scene.light_circles.extend(scn_lights::circle(&mut f, position, index)?);
                    }
                }
                self.add_light(&f, light)?
            }
            "material" => self.material(&mut f)?,
            "entity" => self.entity(&mut f)?,
            "instances" => self.instances(&mut f)?,
            "school" => self.school(&mut f)?,
            "emitter" => {
                let (params, looks, dt) = scn_emitter::parse(&mut f, block.line)?;
                scn_emitter::check_scene_room(&self.scene.emitters, &params).map_err(|m| Diagnostic::at(self.path, block.line, m))?;
                if f.get("texture").is_some_and(|p| self.targets.map(self.path, p.line, &p.value).is_some()) {
                    return Err(Diagnostic::at(self.path, block.line, "\"texture\": particles show an image file, not a render target"));
                }
                let texture = self.texture(&mut f, "texture", true)?;
                let (blend, soft, lit) = (looks.blend, looks.soft, looks.lit);
                let emitter = scn_emitter::EmitterDesc { line: block.line, params, blend, soft, lit, texture, dt };
                self.scene.emitters.push(emitter);
            }
            "cloth" => {
                let nodes: u64 = self.cloths.iter().map(|(c, _)| c.setup.mesh.nodes.len() as u64).sum();
                let mut cloth = scn_cloth::parse(&mut f, &self.assets, nodes)?;
                cloth.draw = Self::draw_options(&mut f)?;
                if let Some(solve) = self.options.cloth_solve {
                    cloth.setup.solve = solve;
                }
                let material = Self::material_ref(&mut f);
                self.cloths.push((cloth, material));
            }
            other => {
                return Err(Diagnostic::at(
                    self.path,
                    class_pair.line,
                    format!("unknown classname {}, expected one of: world, camera, light_directional, light_point, light_spot, material, entity, instances, school, emitter, cloth, render_target", quote(other)),
                ))
            }
        }
        self.scene.warnings.extend(f.leftovers());
        Ok(())
    }

    fn world(&mut self, f: &mut Fields) -> Result<(), Diagnostic> {
        if let Some((k, _)) = f.choice("transparency", &Transparency::NAMES)? {
            self.scene.transparency = Transparency::ALL[k];
        }
        let env = &mut self.scene.environment;
        if let Some(c) = f.color("background")? {
            env.background = Background::Color(c);
        }
        match (f.color("sky_top")?, f.color("sky_bottom")?) {
            (Some(top), Some(bottom)) => env.background = Background::Gradient { top, bottom },
            (None, None) => {}
            _ => {
                return Err(Diagnostic::at(
                    self.path,
                    f.block.line,
                    "\"sky_top\" and \"sky_bottom\" must be given together",
                ))
            }
        }
        if let Some(c) = f.color("ambient")? {
            env.ambient = c;
        }
        let density = f.number("fog_density", 0.0..=100.0)?;
        let color = f.color("fog_color")?;
        if density.is_some() || color.is_some() {
            let color = color.unwrap_or(match env.background {
                Background::Color(c) | Background::Gradient { bottom: c, .. } => c,
            });
            env.fog = Some(Fog { color, density: density.unwrap_or(0.02) });
        }
        if let Some(glare) = f.number("glare", 0.0..=4.0)? {
            env.glare = glare;
        }
        let hours = f.number("time_of_day", 0.0..=24.0)?;
        if self.time_of_day.is_none() && hours.is_some() {
            self.time_of_day = hours;
            self.time_of_day_line = f.get("time_of_day").map(|p| p.line);
        }
        if let Some(strength) = f.number("wind", 0.0..=crate::scene::MAX_WIND)? {
            env.wind.strength = strength;
        }
        if let Some(pair) = f.get("wind_direction") {
            let [x, z] = super::scn_fields::numbers::<2>(self.path, pair, "2 numbers (x z)")?;
            let direction = glam::Vec2::new(x, z);
            if direction.length() < 1e-6 {
                return Err(Diagnostic::at(self.path, pair.line, "\"wind_direction\" must not be 0 0"));
            }
            env.wind.direction = direction.normalize();
        }
        self.environment(f)
    }

    /// The world's image-based lighting: `environment` (`sky`, or a `.hdr` or
    /// OpenEXR file), `environment_intensity`, `environment_rotation` (degrees
    /// about +Y) and `sky_blur` (0..1).
    fn environment(&mut self, f: &mut Fields) -> Result<(), Diagnostic> {
        let intensity = f.number("environment_intensity", 0.0..=1000.0)?;
        let rotation = f.number("environment_rotation", -3600.0..=3600.0)?;
        let blur = f.number("sky_blur", 0.0..=1.0)?;
        let Some(pair) = f.get("environment") else {
            if let Some(key) =
                [(intensity, "environment_intensity"), (rotation, "environment_rotation"), (blur, "sky_blur")]
                    .iter()
                    .find_map(|(v, key)| v.map(|_| key))
            {
                return Err(Diagnostic::at(self.path, f.block.line, format!("\"{key}\" needs \"environment\"")));
            }
            return Ok(());
        };
        let source = match pair.value.trim() {
            "sky" => EnvironmentSource::Sky,
            file => {
                let at = |m: String| Diagnostic::at(self.path, pair.line, format!("\"environment\": {m}"));
                let path = self.assets.resolve(file, self.path).map_err(|e| at(e.message))?;
                let image =
                    read_environment(&path, self.textures.free(), &self.assets.files).map_err(|e| at(e.message))?;
                self.textures.charge(decoded_bytes(&image));
                let id = image.id();
                self.scene.environment_image = Some(image);
                EnvironmentSource::Image(id)
            }
        };
        let light = EnvironmentLight {
            intensity: intensity.unwrap_or(1.0),
            rotation: rotation.unwrap_or(0.0).to_radians(),
            sky_blur: blur.unwrap_or(0.0),
            ..EnvironmentLight::new(source)
        };
        self.scene.environment.light = Some(light);
        Ok(())
    }

    fn camera(&mut self, f: &mut Fields) -> Result<(), Diagnostic> {
        if self.scene.cameras.len() == MAX_CAMERAS {
            let message = format!("more than {MAX_CAMERAS} cameras: a scene may have at most that many views");
            return Err(Diagnostic::at(self.path, f.block.line, message));
        }
        let origin = f.vec3("origin")?.unwrap_or(Vec3::new(0.0, 2.0, 6.0));
        let near = f.number("near", 1e-4..=1e6)?.unwrap_or(0.1);
        let far = f.number("far", 1e-3..=1e9)?.unwrap_or(200.0);
        if far <= near {
            return Err(Diagnostic::at(
                self.path,
                f.block.line,
                format!("camera \"far\" ({far}) must be greater than \"near\" ({near})"),
            ));
        }
        let fov = f.number("fov", 1.0..=179.0)?.unwrap_or(60.0);
        let mut camera = match f.choice("projection", &["perspective", "orthographic"])? {
            Some((1, _)) => Camera::orthographic(f.number("size", 1e-4..=1e9)?.unwrap_or(10.0), near, far),
            _ => Camera::perspective(fov, near, far),
        };
        let (target, up) = match (f.vec3("target")?, f.vec3("angles")?) {
            (Some(t), _) => (t, None),
            // The angles give the whole orientation, roll and the up of a camera
            // looking straight down included.
            (None, Some(a)) => (origin + rotation(a) * Vec3::NEG_Z, Some(rotation(a) * Vec3::Y)),
            (None, None) => (Vec3::ZERO, None),
        };
        if target.distance_squared(origin) < 1e-12 {
            return Err(Diagnostic::at(
                self.path,
                f.block.line,
                "camera \"target\" is the same point as its \"origin\"",
            ));
        }
        camera = camera.looking_at(origin, target);
        camera.up = up.unwrap_or(camera.up);
        let viewport = f.viewport("viewport")?;
        let post = super::scn_post::chain(f)?;
        let output = self.targets.named(f, "output")?;
        let culling = f.choice("cull", &Culling::NAMES)?.map_or(Culling::default(), |(k, _)| Culling::ALL[k]);
        let ambient_occlusion = ambient_occlusion(f)?;
        let lod_error = f.number("lod_error", 0.0..=1e4)?;
        self.scene.camera_views.push(CameraView { viewport, post, output, culling, ambient_occlusion, lod_error });
        self.camera_lines.push(f.block.line);
        self.scene.cameras.push(camera);
        Ok(())
    }

    fn add_light(&mut self, f: &Fields, light: Light) -> Result<(), Diagnostic> {
        if self.scene.lights.len() == MAX_CLUSTERED_LIGHTS {
            return Err(Diagnostic::at(
                self.path,
                f.block.line,
                format!("more than {MAX_CLUSTERED_LIGHTS} lights: a frame can use at most {MAX_CLUSTERED_LIGHTS}"),
            ));
        }
        self.scene.lights.push(light);
        // Checked here as the renderer will (it refuses such maps): `glint check`
        // then says what `glint render` would.
        let bytes = ShadowLayout::plan(&self.scene.lights).bytes();
        if bytes > MAX_SHADOW_MAP_BYTES {
            let message = format!(
                "with this light the shadow maps need {} MiB, more than the {} MiB limit: lower \"shadow_map_size\" (2D maps share the largest size, as do point lights' cubes)",
                bytes >> 20,
                MAX_SHADOW_MAP_BYTES >> 20
            );
            return Err(Diagnostic::at(self.path, f.block.line, message));
        }
        Ok(())
    }

    fn texture(&mut self, f: &mut Fields, key: &str, srgb: bool) -> Result<Option<TextureRef>, Diagnostic> {
        let Some(pair) = f.get(key) else {
            return Ok(None);
        };
        if let Some(target) = self.targets.map(self.path, pair.line, &pair.value) {
            return target.map(Some);
        }
        let fail = |e: Diagnostic| Diagnostic::at(self.path, pair.line, format!("\"{key}\": {e}"));
        let file = self
            .assets
            .resolve(pair.value.trim(), self.path)
            .map_err(|e| Diagnostic::at(self.path, pair.line, format!("\"{key}\": {}", e.message)))?;
        let misses = self.assets.files.misses();
        let decoded =
            self.textures.get_or_decode(file.clone(), srgb, |free| read_texture(&file, srgb, free, &self.assets.files));
        match decoded {
            Ok(texture) => Ok(Some(texture)),
            Err(error) => self.defer(fail(error), misses).map(|()| None),
        }
    }

    /// Keep `error` for the end of the load when a read since the set's count
    /// was `misses` found the memory set lacking its file, and go on; otherwise
    /// it is the load's error. A page fetches what the set lacked and loads
    /// again, so going on finds every file a pass can name (a block's textures,
    /// every block's models) instead of one a pass.
    fn defer(&mut self, error: Diagnostic, misses: usize) -> Result<(), Diagnostic> {
        if self.assets.files.misses() == misses {
            return Err(error);
        }
        self.deferred.get_or_insert(error);
        Ok(())
    }

    fn material(&mut self, f: &mut Fields) -> Result<(), Diagnostic> {
        let name_pair = f.require("name")?;
        let name = name_pair.value.trim().to_string();
        if self.material_names.contains_key(&name) {
            return Err(Diagnostic::at(
                self.path,
                name_pair.line,
                format!("material {} is defined twice", quote(&name)),
            ));
        }
        let material = material_fields(f, Material { name, ..Material::default() })?;
        let desc = MaterialDesc {
            diffuse_map: self.texture(f, "diffuse_map", true)?,
            normal_map: self.texture(f, "normal_map", false)?,
            specular_map: self.texture(f, "specular_map", false)?,
            metallic_roughness_map: self.texture(f, "metallic_roughness_map", false)?,
            occlusion_map: self.texture(f, "occlusion_map", false)?,
            emissive_map: self.texture(f, "emissive_map", true)?,
            material,
        };
        self.material_names.insert(desc.material.name.clone(), self.scene.materials.len());
        self.scene.materials.push(desc);
        Ok(())
    }

    /// Count a model file of `size` bytes (or a copy of one) against the scene's
    /// [`MAX_SCENE_TOTAL_BYTES`], before it is loaded or copied.
    fn charge_model_bytes(&mut self, size: u64) -> Result<(), String> {
        self.bytes_read = self.bytes_read.saturating_add(size);
        if self.bytes_read > MAX_SCENE_TOTAL_BYTES {
            return Err(format!(
                "the scene's models (and their overridden copies) add up to more than the {MAX_SCENE_TOTAL_BYTES}-byte limit"
            ));
        }
        Ok(())
    }

    /// The `key` key (`mesh`, `predator_mesh`): a procedural shape, or a model file (`.obj`, `.gltf`, `.glb`, relative to the
    /// scene) whose materials `mtl.NAME.key` pairs may override for this block.
    pub(super) fn mesh(&mut self, f: &mut Fields, key: &str) -> Result<MeshRef, Diagnostic> {
        let pair = f.require(key)?;
        let value = pair.value.trim();
        if !Model::is_model_path(Path::new(value)) {
            let kind = f.mesh(key)?;
            if let ShapeKind::Blob { detail, seed } = kind {
                self.count_blob(detail, seed, pair.line)?;
            }
            return Ok(MeshRef::Shape(kind));
        }
        let at = |m: String| Diagnostic::at(self.path, pair.line, format!("\"{key}\": {m}"));
        let file = self.assets.resolve(value, self.path).map_err(|e| at(e.message))?;
        let index = match self.model_index.get(&file) {
            Some(&i) => i,
            None => {
                let size = self.assets.files.size(&file);
                self.charge_model_bytes(size).map_err(at)?;
                let options = LoadOptions { texture_memory: self.textures.free(), ..self.options.clone() };
                let model = Model::load_with(&file, options).map_err(|e| at(e.to_string()))?;
                self.textures.charge(model.textures.iter().map(Texture::bytes).sum());
                self.scene.warnings.extend(model.warnings.iter().cloned());
                self.model_bytes.push(size);
                self.scene.models.push(model);
                self.model_index.insert(file, self.scene.models.len() - 1);
                self.scene.models.len() - 1
            }
        };
        self.model_overrides(f, index, &format!("{}.", key.replace("mesh", "mtl"))).map(MeshRef::Model)
    }

    /// Apply this block's `mtl.NAME.key` pairs (`prefix` `mtl.`; a school's
    /// predator takes `predator_mtl.`) to a copy of model `index`; returns the
    /// copy's index, or `index` when there are none.
    fn model_overrides(&mut self, f: &mut Fields, index: usize, prefix: &str) -> Result<usize, Diagnostic> {
        // In first-mention order, found by name in constant time.
        let mut by_material: Vec<(String, Vec<Pair>)> = Vec::new();
        let mut slot: HashMap<&str, usize> = HashMap::new();
        for (i, pair) in f.block.pairs.iter().enumerate() {
            let Some(rest) = pair.key.strip_prefix(prefix) else { continue };
            f.used[i] = true;
            let (name, key) = rest.rsplit_once('.').ok_or_else(|| {
                Diagnostic::at(self.path, pair.line, format!("{}: expected {prefix}MATERIAL.key", quote(&pair.key)))
            })?;
            let stripped = Pair { key: key.to_string(), value: pair.value.clone(), line: pair.line };
            match slot.get(name) {
                Some(&k) => by_material[k].1.push(stripped),
                None => {
                    slot.insert(name, by_material.len());
                    by_material.push((name.to_string(), vec![stripped]));
                }
            }
        }
        if by_material.is_empty() {
            return Ok(index);
        }
        let size = self.model_bytes[index];
        self.charge_model_bytes(size).map_err(|m| Diagnostic::at(self.path, f.block.line, m))?;
        let mut model = self.scene.models[index].clone();
        let mut named: HashMap<String, usize> = HashMap::new();
        for (k, m) in model.materials.iter().enumerate() {
            named.entry(m.material.name.clone()).or_insert(k);
        }
        for (name, pairs) in by_material {
            let line = pairs[0].line;
            let Some(desc) = named.get(&name).map(|&k| &mut model.materials[k]) else {
                let names: Vec<&str> = model.materials.iter().map(|m| m.material.name.as_str()).collect();
                let message = format!("the model has no material {} (it has: {})", quote(&name), list(&names));
                return Err(Diagnostic::at(self.path, line, message));
            };
            let block = Block { line, pairs };
            let mut fields =
                Fields { path: self.path, class: "mtl override", block: &block, used: vec![false; block.pairs.len()] };
            desc.material = material_fields(&mut fields, desc.material.clone())?;
            self.scene.warnings.extend(fields.leftovers());
        }
        self.model_bytes.push(size);
        self.scene.models.push(model);
        Ok(self.scene.models.len() - 1)
    }

    /// The `render_order`, `cast_shadows` and `receive_shadows` keys.
    pub(super) fn draw_options(f: &mut Fields) -> Result<DrawOptions, Diagnostic> {
        Ok(DrawOptions {
            render_order: f.integer("render_order", 0..=255)?.map(|v| v as u8),
            cast_shadows: f.flag("cast_shadows")?.unwrap_or(DrawOptions::default().cast_shadows),
            receive_shadows: f.flag("receive_shadows")?.unwrap_or(DrawOptions::default().receive_shadows),
        })
    }

    pub(super) fn material_ref(f: &mut Fields) -> Option<(String, usize)> {
        f.get("material").map(|p| (p.value.trim().to_string(), p.line))
    }

    /// Count a `blob` mesh against [`MAX_SCENE_BLOB_VERTICES`] (each distinct
    /// detail and seed once: they share a mesh), before any is built.
    fn count_blob(&mut self, detail: u32, seed: u32, line: usize) -> Result<(), Diagnostic> {
        if !self.blobs.insert((detail, seed)) {
            return Ok(());
        }
        self.blob_vertices += blob_vertex_count(detail);
        if self.blob_vertices > MAX_SCENE_BLOB_VERTICES {
            let message = format!(
                "the scene's distinct blobs ({} so far: each detail and seed is its own mesh) have {} vertices, \
                 more than the {MAX_SCENE_BLOB_VERTICES} glint builds for one scene: lower \"detail\" or reuse a \"mesh_seed\"",
                self.blobs.len(),
                self.blob_vertices
            );
            return Err(Diagnostic::at(self.path, line, message));
        }
        Ok(())
    }

    /// Count `n` placements of `mesh` against [`MAX_INSTANCES`], each as
    /// many instances as the mesh makes (a model's parts and their nodes).
    pub(super) fn count_instances(&mut self, n: u64, mesh: &MeshRef, line: usize) -> Result<(), Diagnostic> {
        let each = self.scene.instances_per_placement(mesh) as u64;
        self.instances = self.instances.saturating_add(n.saturating_mul(each));
        if self.instances > MAX_INSTANCES {
            let parts = match each {
                1 => String::new(),
                _ => format!(" ({n} placements of a model that makes {each} instances each)"),
            };
            return Err(Diagnostic::at(
                self.path,
                line,
                format!(
                    "the scene places {} instances{parts}, more than glint allows in one file ({MAX_INSTANCES})",
                    self.instances
                ),
            ));
        }
        Ok(())
    }

    fn scale(f: &mut Fields) -> Result<Vec3, Diagnostic> {
        let Some(pair) = f.get("scale") else {
            return Ok(Vec3::ONE);
        };
        let s = if pair.value.split_whitespace().count() == 1 {
            Vec3::splat(numbers::<1>(f.path, pair, "1 or 3 numbers")?[0])
        } else {
            Vec3::from(numbers::<3>(f.path, pair, "1 or 3 numbers")?)
        };
        if s.min_element() <= 0.0 {
            return Err(Diagnostic::at(f.path, pair.line, "\"scale\" must be positive"));
        }
        Ok(s)
    }

    fn entity(&mut self, f: &mut Fields) -> Result<(), Diagnostic> {
        let mesh = self.mesh(f, "mesh")?;
        let material = Self::material_ref(f);
        let origin = f.vec3("origin")?.unwrap_or(Vec3::ZERO);
        let angles = f.vec3("angles")?.unwrap_or(Vec3::ZERO);
        let scale = Self::scale(f)?;
        self.count_instances(1, &mesh, f.block.line)?;
        let transform = Mat4::from_scale_rotation_translation(scale, rotation(angles), origin);
        let draw = Self::draw_options(f)?;
        self.placements.push(Placement {
            mesh,
            material,
            draw,
            transforms: vec![transform],
            tiles: None,
            alone: false,
        });
        Ok(())
    }

    /// A material name (and the line naming it) as an index into the scene's materials.
    fn material_index(&self, name: Option<(String, usize)>) -> Result<Option<usize>, Diagnostic> {
        let Some((name, line)) = name else { return Ok(None) };
        let index = self.material_names.get(&name).copied();
        let message = || format!("unknown material {} (define it in a material block)", quote(&name));
        index.map(Some).ok_or_else(|| Diagnostic::at(self.path, line, message()))
    }

    /// Resolve material names and gather placements into one task per (mesh, material, render order).
    fn finish(mut self) -> Result<SceneDesc, Diagnostic> {
        if let Some(error) = self.deferred {
            return Err(error);
        }
        if let Some(transparency) = self.options.transparency {
            self.scene.transparency = transparency;
        }
        if let Some(hours) = self.time_of_day {
            self.scene.set_time_of_day(hours).map_err(|e| match self.time_of_day_line {
                Some(line) => Diagnostic::at(self.path, line, e.message),
                None => e,
            })?;
        }
        self.scene.textures = std::mem::replace(&mut self.textures, TextureCache::new(0)).into_textures();
        // Tiled blocks are entities of their own (keyed by their place).
        let mut tasks: HashMap<(MeshRef, Option<usize>, DrawOptions, Option<usize>), usize> = HashMap::new();
        let mut task_of = Vec::with_capacity(self.placements.len());
        for (k, placement) in std::mem::take(&mut self.placements).into_iter().enumerate() {
            let material = self.material_index(placement.material)?;
            let own = (placement.tiles.is_some() || placement.alone).then_some(k);
            let task = *tasks.entry((placement.mesh, material, placement.draw, own)).or_insert_with(|| {
                let (tiles, density, compact) = placement.tiles.map_or((None, 1.0, false), |(t, d, c)| (Some(t), d, c));
                self.scene.entities.push(EntityDesc {
                    mesh: placement.mesh,
                    material,
                    draw: placement.draw,
                    transforms: Vec::new(),
                    tiles,
                    density,
                    compact,
                });
                self.scene.entities.len() - 1
            });
            self.scene.entities[task].transforms.extend(placement.transforms);
            task_of.push(task);
        }
        for mut school in std::mem::take(&mut self.schools) {
            school.fish_entity = task_of[school.fish_entity];
            school.predator_entity = school.predator_entity.map(|k| task_of[k]);
            self.scene.schools.push(school);
        }
        for (mut cloth, material) in std::mem::take(&mut self.cloths) {
            cloth.material = self.material_index(material)?;
            self.scene.cloths.push(cloth);
        }
        if self.scene.cameras.is_empty() {
            self.scene
                .cameras
                .push(Camera::perspective(60.0, 0.1, 200.0).looking_at(Vec3::new(0.0, 2.0, 6.0), Vec3::ZERO));
            self.scene.camera_views.push(CameraView::default());
            self.camera_lines.push(0);
        }
        let files = self.scene.textures.len();
        scn_targets::finish_maps(&mut self.scene.materials, files);
        self.scene.render_targets = std::mem::take(&mut self.targets.list);
        let scene = &self.scene;
        let targets = scene.render_targets.len();
        scn_targets::check_order(self.path, &scene.camera_views, &self.camera_lines, &scene.materials, files, targets)?;
        Ok(self.scene)
    }
}

#[cfg(test)]
#[path = "scn_tests.rs"]
mod tests;

#[cfg(test)]
#[path = "scn_hostile_tests.rs"]
mod hostile_tests;
