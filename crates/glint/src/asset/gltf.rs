//! Core layer: glTF 2.0 (`.gltf` with embedded or separate buffers, and `.glb`)
//! through the `gltf` crate: the default scene's node hierarchy, every triangle
//! primitive with its material, cameras and `KHR_lights_punctual` lights. A mesh
//! used by several nodes becomes one part with a transform per node (one instanced
//! draw). Missing normals are made flat; tangents come from MikkTSpace.
//!
//! Materials use the metallic-roughness shading model: base colour, metallic,
//! roughness, emissive (and `KHR_materials_emissive_strength`), their maps, the
//! normal and occlusion maps, alpha modes, double-sidedness and the
//! `KHR_texture_transform` scale of the base colour map.
//! URIs resolve only inside the model's folder (`data:` URIs always work; see
//! [`LoadOptions`]).

use super::animation::{Animation, Channel, Interpolation, ModelNode, Property};
use super::model::{Model, ModelPart};
use super::texture::TextureCache;
use super::{AssetFolder, Diagnostic, LoadOptions, MaterialDesc, Texture, MAX_TEXTURE_SIDE};
use crate::scene::{AlphaMode, Camera, Light, Material, Mesh, ShadingModel};
use glam::{Mat4, Quat, Vec2, Vec3, Vec4};
use std::collections::HashMap;
use std::path::Path;

/// Parse glTF JSON or GLB bytes read from `path` (which names it in messages
/// and anchors the files it names).
pub(crate) fn parse_gltf(path: &Path, bytes: &[u8], options: LoadOptions) -> Result<Model, Diagnostic> {
    let fail = |m: String| Diagnostic::file(path, m);
    let invalid = |e: gltf::Error| fail(format!("invalid glTF: {e}"));
    let gltf::Gltf { document, blob } = gltf::Gltf::from_slice_without_validation(bytes).map_err(invalid)?;
    // Checks the gltf crate (1.4) panics on instead of reporting (found by fuzzing):
    // its validation indexes a primitive's POSITION accessor before checking it
    // exists, and reading an image unwraps its URI, or its MIME type when it
    // lives in a buffer view.
    let json = document.into_json();
    for (i, image) in json.images.iter().enumerate() {
        let ok = match (&image.uri, &image.buffer_view) {
            (Some(_), None) => true,
            (None, Some(_)) => image.mime_type.is_some(),
            _ => false,
        };
        if !ok {
            return Err(fail(format!("image {i}: expected a uri, or a bufferView with a mimeType")));
        }
    }
    for (m, mesh) in json.meshes.iter().enumerate() {
        for (p, primitive) in mesh.primitives.iter().enumerate() {
            if let Some(bad) = primitive.attributes.values().find(|a| a.value() >= json.accessors.len()) {
                let message = format!("mesh {m} primitive {p}: accessor {} does not exist", bad.value());
                return Err(fail(message));
            }
        }
    }
    let document = gltf::Document::from_json(json).map_err(invalid)?;
    let assets = AssetFolder::of(path, options);
    let folder = path.parent().unwrap_or(Path::new("")).to_path_buf();
    // Check every URI before anything reads it.
    let uris = document
        .buffers()
        .filter_map(|b| match b.source() {
            gltf::buffer::Source::Uri(uri) => Some(uri),
            gltf::buffer::Source::Bin => None,
        })
        .chain(document.images().filter_map(|i| match i.source() {
            gltf::image::Source::Uri { uri, .. } => Some(uri),
            gltf::image::Source::View { .. } => None,
        }));
    for uri in uris {
        if !uri.starts_with("data:") {
            assets.resolve(uri, path)?;
        }
    }
    let buffers = gltf::import_buffers(&document, Some(&folder), blob).map_err(|e| fail(format!("buffer: {e}")))?;
    let images = gltf::import_images(&document, Some(&folder), &buffers).map_err(|e| fail(format!("image: {e}")))?;
    let mut warnings = Vec::new();
    let mut textures = TextureCache::default();
    let mut texture = |info: Option<(usize, Option<String>)>, srgb: bool, warnings: &mut Vec<Diagnostic>| {
        let (image, name) = info?;
        let name = name.unwrap_or_else(|| format!("image {image}"));
        let decoded = textures.get_or_decode(image, srgb, || to_texture(&images[image], name, srgb));
        decoded.map_err(|e| warnings.push(fail(format!("image {image}: {e}; drawn without it")))).ok()
    };
    let image_of = |t: gltf::texture::Texture| (t.source().index(), t.source().name().map(str::to_string));
    let mut materials = Vec::new();
    for m in document.materials() {
        let pbr = m.pbr_metallic_roughness();
        let [r, g, b, a] = pbr.base_color_factor();
        let mut material = Material {
            name: m.name().map_or_else(|| format!("material {}", materials.len()), str::to_string),
            base_color: Vec4::new(r, g, b, a),
            shading: ShadingModel::MetallicRoughness,
            metallic: pbr.metallic_factor(),
            roughness: pbr.roughness_factor(),
            emissive: Vec3::from(m.emissive_factor()) * m.emissive_strength().unwrap_or(1.0),
            double_sided: m.double_sided(),
            alpha_mode: match m.alpha_mode() {
                gltf::material::AlphaMode::Opaque => AlphaMode::Opaque,
                gltf::material::AlphaMode::Mask => AlphaMode::Mask { cutoff: m.alpha_cutoff().unwrap_or(0.5) },
                gltf::material::AlphaMode::Blend => AlphaMode::Blend,
            },
            ..Material::default()
        };
        let base = pbr.base_color_texture();
        if let Some(transform) = base.as_ref().and_then(|info| info.texture_transform()) {
            material.uv_scale = Vec2::from(transform.scale());
            if transform.offset() != [0.0, 0.0] || transform.rotation() != 0.0 {
                let message =
                    format!("material '{}': texture offset and rotation are not supported yet", material.name);
                warnings.push(fail(message));
            }
        }
        let diffuse_map = texture(base.map(|i| image_of(i.texture())), true, &mut warnings);
        let normal_map = texture(m.normal_texture().map(|n| image_of(n.texture())), false, &mut warnings);
        let mr = pbr.metallic_roughness_texture().map(|i| image_of(i.texture()));
        let metallic_roughness_map = texture(mr, false, &mut warnings);
        let occlusion_map = texture(m.occlusion_texture().map(|i| image_of(i.texture())), false, &mut warnings);
        let emissive_map = texture(m.emissive_texture().map(|i| image_of(i.texture())), true, &mut warnings);
        materials.push(MaterialDesc {
            material,
            diffuse_map,
            normal_map,
            metallic_roughness_map,
            occlusion_map,
            emissive_map,
            ..MaterialDesc::default()
        });
    }
    let mut model = Model {
        path: path.to_path_buf(),
        parts: Vec::new(),
        materials,
        textures: Vec::new(),
        nodes: Vec::new(),
        animations: Vec::new(),
        cameras: Vec::new(),
        lights: Vec::new(),
        warnings: Vec::new(),
    };
    let scene = document.default_scene().or_else(|| document.scenes().next());
    let mut part_of: HashMap<(usize, usize), Option<usize>> = HashMap::new();
    // Depth-first over the hierarchy with world transforms; a node seen twice (a
    // cycle, which valid files do not have) is not entered again.
    // `glint_node[i]`: the model node of glTF node i, once visited.
    let mut glint_node: Vec<Option<usize>> = vec![None; document.nodes().len()];
    let mut stack: Vec<(gltf::Node, Option<usize>, Mat4)> =
        scene.iter().flat_map(|s| s.nodes()).map(|n| (n, None, Mat4::IDENTITY)).collect();
    while let Some((node, parent_node, parent)) = stack.pop() {
        if glint_node[node.index()].is_some() {
            continue;
        }
        let world = parent * Mat4::from_cols_array_2d(&node.transform().matrix());
        let (t, r, s) = node.transform().decomposed();
        let this = model.nodes.len();
        glint_node[node.index()] = Some(this);
        model.nodes.push(ModelNode {
            parent: parent_node,
            translation: Vec3::from(t),
            rotation: Quat::from_array(r).normalize(),
            scale: Vec3::from(s),
            placements: Vec::new(),
        });
        if let Some(mesh) = node.mesh() {
            for primitive in mesh.primitives() {
                let key = (mesh.index(), primitive.index());
                let part = match part_of.get(&key) {
                    Some(&p) => p,
                    None => {
                        let made = read_primitive(&primitive, &buffers)
                            .map_err(|e| fail(format!("mesh {} primitive {}: {e}", mesh.index(), primitive.index())))?;
                        let p = made.map(|mesh_data| {
                            let name = mesh.name().map_or_else(|| format!("mesh {}", mesh.index()), str::to_string);
                            let material = primitive.material().index();
                            model.parts.push(ModelPart { name, mesh: mesh_data, material, transforms: Vec::new() });
                            model.parts.len() - 1
                        });
                        if p.is_none() {
                            let message = format!(
                                "mesh {} primitive {}: not triangles; skipped",
                                mesh.index(),
                                primitive.index()
                            );
                            warnings.push(fail(message));
                        }
                        part_of.insert(key, p);
                        p
                    }
                };
                if let Some(p) = part {
                    model.nodes[this].placements.push((p, model.parts[p].transforms.len()));
                    model.parts[p].transforms.push(world);
                }
            }
        }
        if let Some(camera) = node.camera() {
            model.cameras.push(to_camera(&camera, world));
        }
        if let Some(light) = node.light() {
            let (light, note) = to_light(&light, world);
            model.lights.push(light);
            warnings.extend(note.map(fail));
        }
        stack.extend(node.children().map(|c| (c, Some(this), world)));
    }
    for animation in document.animations() {
        let name = animation.name().map_or_else(|| format!("animation {}", animation.index()), str::to_string);
        let mut channels = Vec::new();
        for channel in animation.channels() {
            let Some(node) = glint_node[channel.target().node().index()] else { continue };
            match read_channel(&channel, node, &buffers) {
                Ok(Some(c)) => channels.push(c),
                Ok(None) => warnings.push(fail(format!("{name}: morph-target weights are not supported yet"))),
                Err(e) => return Err(fail(format!("{name}, channel {}: {e}", channel.index()))),
            }
        }
        model.animations.push(Animation { name, channels });
    }
    if model.parts.is_empty() {
        return Err(fail("no triangle primitives in the default scene".into()));
    }
    model.textures = textures.into_textures();
    model.warnings = warnings;
    Ok(model)
}

/// Read one animation channel for model node `node`: `Ok(None)` for morph-target weights.
fn read_channel(
    channel: &gltf::animation::Channel,
    node: usize,
    buffers: &[gltf::buffer::Data],
) -> Result<Option<Channel>, String> {
    use gltf::animation::util::ReadOutputs;
    let reader = channel.reader(|b| buffers.get(b.index()).map(|d| &d.0[..]));
    let times: Vec<f32> = reader.read_inputs().ok_or("no key times")?.collect();
    let (property, values): (Property, Vec<Vec4>) = match reader.read_outputs().ok_or("no key values")? {
        ReadOutputs::Translations(v) => (Property::Translation, v.map(|t| Vec3::from(t).extend(0.0)).collect()),
        ReadOutputs::Rotations(v) => (Property::Rotation, v.into_f32().map(Vec4::from).collect()),
        ReadOutputs::Scales(v) => (Property::Scale, v.map(|s| Vec3::from(s).extend(0.0)).collect()),
        ReadOutputs::MorphTargetWeights(_) => return Ok(None),
    };
    let interpolation = match channel.sampler().interpolation() {
        gltf::animation::Interpolation::Step => Interpolation::Step,
        gltf::animation::Interpolation::Linear => Interpolation::Linear,
        gltf::animation::Interpolation::CubicSpline => Interpolation::CubicSpline,
    };
    let channel = Channel { node, property, interpolation, times, values };
    channel.validate()?;
    Ok(Some(channel))
}

/// Read one primitive: `Ok(None)` for a primitive that is not a triangle list.
fn read_primitive(primitive: &gltf::Primitive, buffers: &[gltf::buffer::Data]) -> Result<Option<Mesh>, String> {
    if primitive.mode() != gltf::mesh::Mode::Triangles {
        return Ok(None);
    }
    let reader = primitive.reader(|b| buffers.get(b.index()).map(|d| &d.0[..]));
    let positions: Vec<Vec3> = reader.read_positions().ok_or("no POSITION attribute")?.map(Vec3::from).collect();
    let count = positions.len();
    let indices: Vec<u32> = match reader.read_indices() {
        Some(i) => i.into_u32().collect(),
        None => (0..count as u32).collect(),
    };
    if let Some(&bad) = indices.iter().find(|&&i| i as usize >= count) {
        return Err(format!("index {bad} is past the {count} vertices"));
    }
    let uvs: Vec<Vec2> = match reader.read_tex_coords(0) {
        Some(t) => t.into_f32().map(Vec2::from).collect(),
        None => vec![Vec2::ZERO; count],
    };
    let colors: Option<Vec<[f32; 4]>> = reader.read_colors(0).map(|c| c.into_rgba_f32().collect());
    let attribute_error = |what: &str, n: usize| format!("{what} has {n} values for {count} positions");
    if uvs.len() != count {
        return Err(attribute_error("TEXCOORD_0", uvs.len()));
    }
    let mesh = match reader.read_normals() {
        Some(n) => {
            let normals: Vec<Vec3> = n.map(Vec3::from).collect();
            if normals.len() != count {
                return Err(attribute_error("NORMAL", normals.len()));
            }
            let mesh = Mesh::from_attributes(&positions, &normals, &uvs, indices).map_err(|e| e.to_string())?;
            match colors {
                Some(c) if c.len() == count => mesh.with_colors(c).map_err(|e| e.to_string())?,
                Some(c) => return Err(attribute_error("COLOR_0", c.len())),
                None => mesh,
            }
        }
        None => flat_mesh(&positions, &uvs, colors.as_deref(), &indices)?,
    };
    Ok(Some(mesh))
}

/// A mesh without normals, as the spec asks: flat shaded, each triangle its own
/// three vertices with the face normal.
fn flat_mesh(positions: &[Vec3], uvs: &[Vec2], colors: Option<&[[f32; 4]]>, indices: &[u32]) -> Result<Mesh, String> {
    let corners: Vec<usize> = indices.iter().map(|&i| i as usize).collect();
    let mut normals = Vec::with_capacity(corners.len());
    for tri in corners.chunks_exact(3) {
        let [a, b, c] = [positions[tri[0]], positions[tri[1]], positions[tri[2]]];
        normals.extend([(b - a).cross(c - a).normalize_or(Vec3::Y); 3]);
    }
    let p: Vec<Vec3> = corners.iter().map(|&i| positions[i]).collect();
    let t: Vec<Vec2> = corners.iter().map(|&i| uvs[i]).collect();
    let mesh =
        Mesh::from_attributes(&p, &normals, &t, (0..corners.len() as u32).collect()).map_err(|e| e.to_string())?;
    match colors {
        Some(c) if c.len() == positions.len() => {
            mesh.with_colors(corners.iter().map(|&i| c[i]).collect()).map_err(|e| e.to_string())
        }
        Some(c) => Err(format!("COLOR_0 has {} values for {} positions", c.len(), positions.len())),
        None => Ok(mesh),
    }
}

/// Convert decoded pixels to RGBA8, refusing images over [`MAX_TEXTURE_SIDE`].
fn to_texture(data: &gltf::image::Data, name: String, srgb: bool) -> Result<Texture, String> {
    use gltf::image::Format;
    let (w, h) = (data.width, data.height);
    if w > MAX_TEXTURE_SIDE || h > MAX_TEXTURE_SIDE {
        return Err(format!("{w}x{h} is larger than {MAX_TEXTURE_SIDE} pixels a side"));
    }
    let px = &data.pixels;
    let rgba: Vec<u8> = match data.format {
        Format::R8G8B8A8 => px.clone(),
        Format::R8G8B8 => px.chunks_exact(3).flat_map(|p| [p[0], p[1], p[2], 255]).collect(),
        Format::R8G8 => px.chunks_exact(2).flat_map(|p| [p[0], p[0], p[0], p[1]]).collect(),
        Format::R8 => px.iter().flat_map(|&v| [v, v, v, 255]).collect(),
        Format::R16G16B16A16 => px.chunks_exact(2).map(|c| c[1]).collect(),
        Format::R16G16B16 => px.chunks_exact(6).flat_map(|p| [p[1], p[3], p[5], 255]).collect(),
        other => return Err(format!("pixel format {other:?} is not supported yet")),
    };
    let image = image::RgbaImage::from_raw(w, h, rgba).ok_or("pixel data does not match its size")?;
    Ok(Texture::new(name, image, srgb))
}

/// A glTF camera at node transform `world` (looking down its local −Z).
fn to_camera(camera: &gltf::Camera, world: Mat4) -> Camera {
    let eye = world.transform_point3(Vec3::ZERO);
    let forward = world.transform_vector3(Vec3::NEG_Z).normalize_or(Vec3::NEG_Z);
    let base = match camera.projection() {
        gltf::camera::Projection::Perspective(p) => {
            Camera::perspective(p.yfov().to_degrees(), p.znear(), p.zfar().unwrap_or(p.znear() * 1e4))
        }
        gltf::camera::Projection::Orthographic(o) => Camera::orthographic(o.ymag() * 2.0, o.znear(), o.zfar()),
    };
    base.looking_at(eye, eye + forward)
}

/// A `KHR_lights_punctual` light at `world`, and a note when glint has to
/// approximate it.
fn to_light(light: &gltf::khr_lights_punctual::Light, world: Mat4) -> (Light, Option<String>) {
    use gltf::khr_lights_punctual::Kind;
    let color = Vec3::from(light.color());
    let position = world.transform_point3(Vec3::ZERO);
    // glTF point intensities are candela; glint's are unitless: scaled down to a usable range.
    let range = light.range().unwrap_or(100.0);
    match light.kind() {
        Kind::Directional => {
            let direction = world.transform_vector3(Vec3::NEG_Z);
            (Light::directional(direction, color, light.intensity()), None)
        }
        Kind::Point => (Light::point(position, color, light.intensity(), range), None),
        Kind::Spot { .. } => (
            Light::point(position, color, light.intensity(), range),
            Some("spot light drawn as a point light (spot cones are not supported yet)".into()),
        ),
    }
}
