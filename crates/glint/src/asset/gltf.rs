//! Core layer: glTF 2.0 (`.gltf` with embedded or separate buffers, and `.glb`)
//! through the `gltf` crate: the default scene's node hierarchy, every triangle
//! primitive with its material, cameras and `KHR_lights_punctual` lights. A mesh
//! used by several nodes becomes one part with a transform per node (one instanced
//! draw). Missing normals are made flat; tangents come from MikkTSpace. A
//! node's `MSFT_lod` levels become its mesh's levels of detail (`gltf_lod`).
//!
//! Materials use the metallic-roughness shading model: base colour, metallic,
//! roughness, emissive (and `KHR_materials_emissive_strength`), their maps, the
//! normal and occlusion maps, alpha modes, double-sidedness and the
//! `KHR_texture_transform` scale of the base colour map.
//!
//! Nothing reaches the crate's readers unchecked: the JSON is validated first
//! (`gltf_check`: indices, byte ranges, accessor types, values the specification
//! bounds), and buffers and images are read by `gltf_data` rather than the
//! crate's importers, with size limits, and images only when a material uses
//! them. URIs resolve only inside the model's folder (`data:` URIs always work;
//! see [`LoadOptions`]).

use super::animation::{Animation, Channel, Interpolation, ModelNode, Property};
use super::gltf_check::{check_buffers, check_json, MAX_MODEL_VERTICES};
use super::gltf_data::{read_buffers, read_image, UriBase};
use super::gltf_lod::{with_node_levels, NodeLevels};
use super::model::{Model, ModelPart};
use super::model::{Morph, Skin};
use super::texture::{decode_texture, TextureCache};
use super::{AssetFolder, Diagnostic, LoadOptions, MaterialDesc};
use crate::scene::{AlphaMode, Camera, Light, MapSlots, Material, Mesh, ShadingModel, SkinVertex};
use glam::{Mat4, Quat, Vec2, Vec3, Vec4};
use std::collections::HashMap;
use std::path::Path;

/// A GLB's header must give the file's own length (the gltf crate reads the
/// chunks without comparing it).
fn check_glb_length(bytes: &[u8]) -> Result<(), String> {
    let Some(header) = bytes.strip_prefix(b"glTF") else { return Ok(()) };
    let Some(length) = header.get(4..8).map(|b| u32::from_le_bytes([b[0], b[1], b[2], b[3]])) else {
        return Err("GLB header is cut short: expected 12 bytes".into());
    };
    if u64::from(length) != bytes.len() as u64 {
        return Err(format!("GLB header says the file is {length} bytes, but it is {}", bytes.len()));
    }
    Ok(())
}

/// Parse glTF JSON or GLB bytes read from `path` (which names it in messages
/// and anchors the files it names).
pub(crate) fn parse_gltf(path: &Path, bytes: &[u8], options: LoadOptions) -> Result<Model, Diagnostic> {
    let fail = |m: String| Diagnostic::file(path, m);
    let invalid = |e: gltf::Error| fail(format!("invalid glTF: {e}"));
    check_glb_length(bytes).map_err(fail)?;
    let gltf::Gltf { document, blob } = gltf::Gltf::from_slice_without_validation(bytes).map_err(invalid)?;
    // Checks the gltf crate (1.4) panics on instead of reporting (found by fuzzing):
    // reading an image unwraps its URI, or its MIME type when it lives in a
    // buffer view. The rest of what its readers assume is checked in gltf_check.
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
    let mut notes = Vec::new();
    check_json(&json, &mut notes).map_err(fail)?;
    let document = gltf::Document::from_json(json).map_err(invalid)?;
    let json = document.as_json();
    let assets = AssetFolder::of(path, &options);
    let uris = UriBase { path, assets: &assets };
    // Every URI is checked before anything is read.
    uris.check_uris(json)?;
    let buffers = read_buffers(json, blob, &uris)?;
    check_buffers(json, &buffers).map_err(fail)?;
    let mut warnings: Vec<Diagnostic> = notes.into_iter().map(fail).collect();
    let mut textures = TextureCache::new(options.texture_memory);
    let mut texture = |info: Option<(usize, Option<String>)>, srgb: bool, warnings: &mut Vec<Diagnostic>| {
        let (image, name) = info?;
        let name = name.unwrap_or_else(|| format!("image {image}"));
        // Only images a material uses are read and decoded.
        let decoded = textures.get_or_decode(image, srgb, |free| {
            let bytes = read_image(json, image, &buffers, &uris)?;
            decode_texture(&bytes, name, srgb, free, &assets.files)
        });
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
        // One uv transform per material: the base colour map's (else the first
        // map's); maps with another transform are noted.
        let transforms: Vec<(&str, Option<[f32; 5]>)> = [
            ("baseColorTexture", base.as_ref().map(transform_of)),
            ("metallicRoughnessTexture", pbr.metallic_roughness_texture().as_ref().map(transform_of)),
            ("emissiveTexture", m.emissive_texture().as_ref().map(transform_of)),
        ]
        .into_iter()
        .filter(|(_, t)| t.is_some())
        .collect();
        if let Some(&(_, Some([ox, oy, rotation, sx, sy]))) = transforms.first() {
            (material.uv_offset, material.uv_rotation, material.uv_scale) =
                (Vec2::new(ox, oy), rotation, Vec2::new(sx, sy));
            if let Some((other, _)) = transforms.iter().find(|(_, t)| *t != transforms[0].1) {
                let message = format!(
                    "material {}: {other} has its own texture transform; the {} one is used for every map",
                    crate::text::quote(&material.name),
                    transforms[0].0
                );
                warnings.push(fail(message));
            }
        }
        let mut sets = Vec::new();
        if let Some(i) = &base {
            sets.push((i.tex_coord(), MapSlots::DIFFUSE));
        }
        if let Some(i) = &pbr.metallic_roughness_texture() {
            sets.push((i.tex_coord(), MapSlots::METALLIC_ROUGHNESS));
        }
        if let Some(i) = &m.emissive_texture() {
            sets.push((i.tex_coord(), MapSlots::EMISSIVE));
        }
        if let Some(n) = m.normal_texture() {
            sets.push((n.tex_coord(), MapSlots::NORMAL));
        }
        if let Some(o) = m.occlusion_texture() {
            sets.push((o.tex_coord(), MapSlots::OCCLUSION));
        }
        for (set, slot) in sets {
            material.uv1_maps.set(slot, set >= 1);
            if set > 1 {
                warnings.push(fail(format!(
                    "material {}: TEXCOORD_{set} is read as TEXCOORD_1",
                    crate::text::quote(&material.name)
                )));
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
        skins: Vec::new(),
        cameras: Vec::new(),
        lights: Vec::new(),
        warnings: Vec::new(),
    };
    let scene = document.default_scene().or_else(|| document.scenes().next());
    // Parts by (mesh, primitive, skin, levels): one mesh under two skins is two parts.
    type PartKey = (usize, usize, Option<usize>, Vec<usize>);
    let mut part_of: HashMap<PartKey, Option<usize>> = HashMap::new();
    let mut built: u64 = 0;
    let node_levels = NodeLevels::read(bytes, document.nodes().len()).map_err(fail)?;
    // Nodes that are another's coarser level are drawn only as that level.
    let levels_only = node_levels.level_nodes();
    let read = |p: &gltf::Primitive| read_primitive(p, &buffers);
    // Depth-first over the hierarchy with world transforms; a node seen twice (a
    // cycle, which valid files do not have) is not entered again.
    // `glint_node[i]`: the model node of glTF node i, once visited.
    let mut glint_node: Vec<Option<usize>> = vec![None; document.nodes().len()];
    let mut stack: Vec<(gltf::Node, Option<usize>, Mat4)> =
        scene.iter().flat_map(|s| s.nodes()).map(|n| (n, None, Mat4::IDENTITY)).collect();
    while let Some((node, parent_node, parent)) = stack.pop() {
        if glint_node[node.index()].is_some() || levels_only.contains(&node.index()) {
            continue;
        }
        let world = parent * Mat4::from_cols_array_2d(&node.transform().matrix());
        let (t, r, s) = node.transform().decomposed();
        let this = model.nodes.len();
        glint_node[node.index()] = Some(this);
        model.nodes.push(ModelNode {
            parent: parent_node,
            translation: Vec3::from(t),
            // A matrix with a zero scale decomposes to no rotation at all.
            rotation: Some(Quat::from_array(r))
                .filter(|q| q.is_finite() && q.length() > 0.0)
                .map_or(Quat::IDENTITY, Quat::normalize),
            scale: Vec3::from(s),
            placements: Vec::new(),
            weights: Vec::new(),
        });
        if let Some(mesh) = node.mesh() {
            let skin = node.skin().map(|s| s.index());
            let weights = node.weights().or(mesh.weights()).unwrap_or(&[]);
            model.nodes[this].weights = weights.to_vec();
            for primitive in mesh.primitives() {
                let key = (mesh.index(), primitive.index(), skin, node_levels.of(node.index()).to_vec());
                let part = match part_of.get(&key) {
                    Some(&p) => p,
                    None => {
                        let where_ = format!("mesh {} primitive {}", mesh.index(), primitive.index());
                        let made = read(&primitive).map_err(|e| fail(format!("{where_}: {e}")))?;
                        let made = match made {
                            Some((full, None)) => {
                                let (at, lod) = ((&document, &node_levels), (&node, &primitive));
                                let mut notes = Vec::new();
                                let full = with_node_levels(at, lod, full, &read, &mut notes).map_err(&fail)?;
                                warnings.extend(notes.into_iter().map(&fail));
                                Some((full, None))
                            }
                            other => other,
                        };
                        // The JSON's count (check_work) takes each mesh once a skin;
                        // levels may add copies, so what is built is counted too.
                        built += made.as_ref().map_or(0, |(m, _)| m.vertices().len() as u64);
                        if built > MAX_MODEL_VERTICES {
                            return Err(fail(format!(
                                "the meshes and their MSFT_lod levels build more than {MAX_MODEL_VERTICES} vertices"
                            )));
                        }
                        let p = made.map(|(mesh_data, morph)| {
                            let name = mesh.name().map_or_else(|| format!("mesh {}", mesh.index()), str::to_string);
                            let material = primitive.material().index();
                            let mut part = ModelPart::new(name, mesh_data, material, Vec::new());
                            // A skinned mesh without skin weights is drawn rigid.
                            part.skin = skin.filter(|_| part.mesh.skin().is_some());
                            part.morph = morph;
                            model.parts.push(part);
                            model.parts.len() - 1
                        });
                        if p.is_none() {
                            warnings.push(fail(format!("{where_}: not triangles; skipped")));
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
            model.lights.push(to_light(&light, world));
        }
        stack.extend(node.children().map(|c| (c, Some(this), world)));
    }
    for animation in document.animations() {
        let name = animation.name().map_or_else(|| format!("animation {}", animation.index()), str::to_string);
        let mut channels = Vec::new();
        for channel in animation.channels() {
            let Some(node) = glint_node[channel.target().node().index()] else { continue };
            let c = read_channel(&channel, node, &buffers)
                .map_err(|e| fail(format!("{name}, channel {}: {e}", channel.index())))?;
            channels.push(c);
        }
        model.animations.push(Animation { name, channels });
    }
    if model.parts.is_empty() {
        return Err(fail("no triangle primitives in the default scene".into()));
    }
    read_skins(&document, &buffers, &glint_node, &mut model).map_err(fail)?;
    model.rest_pose();
    model.textures = textures.into_textures();
    model.warnings = warnings;
    Ok(model)
}

/// Read one animation channel for model node `node`.
fn read_channel(channel: &gltf::animation::Channel, node: usize, buffers: &[Vec<u8>]) -> Result<Channel, String> {
    use gltf::animation::util::ReadOutputs;
    let reader = channel.reader(|b| buffers.get(b.index()).map(Vec::as_slice));
    let times: Vec<f32> = reader.read_inputs().ok_or("no key times")?.collect();
    // The crate's reader panics on unsigned-int rotations and weights (not allowed by the spec).
    if channel.sampler().output().data_type() == gltf::accessor::DataType::U32 {
        return Err("key values: component type U32 is not allowed".into());
    }
    let (property, values): (Property, Vec<Vec4>) = match reader.read_outputs().ok_or("no key values")? {
        ReadOutputs::Translations(v) => (Property::Translation, v.map(|t| Vec3::from(t).extend(0.0)).collect()),
        ReadOutputs::Rotations(v) => (Property::Rotation, v.into_f32().map(Vec4::from).collect()),
        ReadOutputs::Scales(v) => (Property::Scale, v.map(|s| Vec3::from(s).extend(0.0)).collect()),
        ReadOutputs::MorphTargetWeights(w) => {
            // Keys × targets weights (× 3 for cubic splines), regrouped four to a Vec4 per value.
            let weights: Vec<f32> = w.into_f32().collect();
            let per_key =
                if channel.sampler().interpolation() == gltf::animation::Interpolation::CubicSpline { 3 } else { 1 };
            let values = times.len() * per_key;
            if values == 0 || weights.is_empty() || weights.len() % values != 0 {
                return Err(format!("{} weights for {} keys", weights.len(), times.len()));
            }
            let targets = weights.len() / values;
            let vec4s = weights
                .chunks(targets)
                .flat_map(|value| value.chunks(4).map(|c| Vec4::from_slice(&[c, &[0.0; 4][c.len()..]].concat())));
            (Property::Weights, vec4s.collect())
        }
    };
    let interpolation = match channel.sampler().interpolation() {
        gltf::animation::Interpolation::Step => Interpolation::Step,
        gltf::animation::Interpolation::Linear => Interpolation::Linear,
        gltf::animation::Interpolation::CubicSpline => Interpolation::CubicSpline,
    };
    let channel = Channel { node, property, interpolation, times, values };
    channel.validate()?;
    Ok(channel)
}

/// The skins the parts use, with their joints as model nodes. A part's vertices
/// must name joints its skin has.
fn read_skins(
    document: &gltf::Document,
    buffers: &[Vec<u8>],
    glint_node: &[Option<usize>],
    model: &mut Model,
) -> Result<(), String> {
    let mut skin_of: HashMap<usize, usize> = HashMap::new();
    for part in &mut model.parts {
        let Some(index) = part.skin else { continue };
        let skin = document.skins().nth(index).ok_or_else(|| format!("skin {index} does not exist"))?;
        let joint_count = skin.joints().len();
        if usize::from(part.mesh.max_joint()) >= joint_count {
            return Err(format!(
                "part {}: a vertex names joint {} but skin {index} has {joint_count}",
                crate::text::quote(&part.name),
                part.mesh.max_joint()
            ));
        }
        if let Some(&s) = skin_of.get(&index) {
            part.skin = Some(s);
            continue;
        }
        let joints = skin
            .joints()
            .map(|j| {
                glint_node[j.index()]
                    .ok_or_else(|| format!("skin {index}: joint node {} is not in the scene", j.index()))
            })
            .collect::<Result<Vec<usize>, String>>()?;
        let reader = skin.reader(|b| buffers.get(b.index()).map(Vec::as_slice));
        let inverse_bind: Vec<Mat4> = match reader.read_inverse_bind_matrices() {
            Some(m) => m.map(|m| Mat4::from_cols_array_2d(&m)).collect(),
            None => vec![Mat4::IDENTITY; joint_count],
        };
        if inverse_bind.len() != joint_count || inverse_bind.iter().any(|m| !m.is_finite()) {
            return Err(format!("skin {index}: expected {joint_count} finite inverse bind matrices"));
        }
        let name = skin.name().map_or_else(|| format!("skin {index}"), str::to_string);
        model.skins.push(Skin { name, joints, inverse_bind });
        skin_of.insert(index, model.skins.len() - 1);
        part.skin = Some(model.skins.len() - 1);
    }
    Ok(())
}

/// Read one primitive, with its morph targets: `Ok(None)` for a primitive that is
/// not a triangle list. Every attribute must have one value per position.
fn read_primitive(primitive: &gltf::Primitive, buffers: &[Vec<u8>]) -> Result<Option<(Mesh, Option<Morph>)>, String> {
    if primitive.mode() != gltf::mesh::Mode::Triangles {
        return Ok(None);
    }
    let reader = primitive.reader(|b| buffers.get(b.index()).map(Vec::as_slice));
    let positions: Vec<Vec3> = reader.read_positions().ok_or("no POSITION attribute")?.map(Vec3::from).collect();
    let count = positions.len();
    let check = |what: &str, n: usize| {
        if n == count {
            Ok(())
        } else {
            Err(format!("{what} has {n} values for {count} positions"))
        }
    };
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
    check("TEXCOORD_0", uvs.len())?;
    let uv1: Option<Vec<[f32; 2]>> = reader.read_tex_coords(1).map(|t| t.into_f32().collect());
    let colors: Option<Vec<[f32; 4]>> = reader.read_colors(0).map(|c| c.into_rgba_f32().collect());
    let skin: Option<Vec<SkinVertex>> = match (reader.read_joints(0), reader.read_weights(0)) {
        (Some(j), Some(w)) => {
            let skin: Vec<SkinVertex> =
                j.into_u16().zip(w.into_f32()).map(|(joints, weights)| SkinVertex { joints, weights }).collect();
            // The specification's weights are 0 or more (and sum to 1, which glint does not need).
            if let Some(v) = skin.iter().position(|s| s.weights.iter().any(|w| !w.is_finite() || *w < 0.0)) {
                return Err(format!("WEIGHTS_0: vertex {v} has a weight that is negative, NaN or infinite"));
            }
            Some(skin)
        }
        (None, None) => None,
        _ => return Err("JOINTS_0 and WEIGHTS_0 must come together".into()),
    };
    let normals: Option<Vec<Vec3>> = reader.read_normals().map(|n| n.map(Vec3::from).collect());
    let mut targets = Vec::new();
    for (t, (p, n, _)) in reader.read_morph_targets().enumerate() {
        let p: Vec<Vec3> = p.map_or_else(|| vec![Vec3::ZERO; count], |p| p.map(Vec3::from).collect());
        let n: Vec<Vec3> = n.map_or_else(|| vec![Vec3::ZERO; count], |n| n.map(Vec3::from).collect());
        check(&format!("morph target {t} POSITION"), p.len())?;
        check(&format!("morph target {t} NORMAL"), n.len())?;
        targets.push((p, n));
    }
    for (what, n) in [
        ("NORMAL", normals.as_ref().map(Vec::len)),
        ("TEXCOORD_1", uv1.as_ref().map(Vec::len)),
        ("COLOR_0", colors.as_ref().map(Vec::len)),
        ("JOINTS_0/WEIGHTS_0", skin.as_ref().map(Vec::len)),
    ] {
        check(what, n.unwrap_or(count))?;
    }
    // Without normals the spec asks for flat shading: each triangle gets its own
    // three vertices (every stream follows) with the face normal.
    let (corners, normals, indices): (Option<Vec<usize>>, Vec<Vec3>, Vec<u32>) = match normals {
        Some(n) => (None, n, indices),
        None => {
            let corners: Vec<usize> = indices.iter().map(|&i| i as usize).collect();
            let mut normals = Vec::with_capacity(corners.len());
            for tri in corners.chunks_exact(3) {
                let [a, b, c] = [positions[tri[0]], positions[tri[1]], positions[tri[2]]];
                normals.extend([(b - a).cross(c - a).normalize_or(Vec3::Y); 3]);
            }
            let n = corners.len() as u32;
            (Some(corners), normals, (0..n).collect())
        }
    };
    let positions: Vec<Vec3> = pick(positions, corners.as_deref());
    let corners = corners.as_deref();
    let e = |e: crate::scene::MeshError| e.to_string();
    let mut mesh = Mesh::from_attributes(&positions, &normals, &pick(uvs, corners), indices).map_err(e)?;
    if let Some(c) = colors {
        mesh = mesh.with_colors(pick(c, corners)).map_err(e)?;
    }
    if let Some(uv) = uv1 {
        mesh = mesh.with_uv1(pick(uv, corners)).map_err(e)?;
    }
    if let Some(s) = skin {
        mesh = mesh.with_skin(pick(s, corners)).map_err(e)?;
    }
    let morph = (!targets.is_empty()).then(|| Morph {
        positions: mesh.vertices().iter().map(|v| Vec3::from(v.position)).collect(),
        normals: mesh.vertices().iter().map(|v| Vec3::from(v.normal)).collect(),
        targets: targets.into_iter().map(|(p, n)| (pick(p, corners), pick(n, corners))).collect(),
        weights: Vec::new(),
    });
    Ok(Some((mesh, morph)))
}

/// `v` in the order of `corners` (when the vertices were split), else as it is.
fn pick<T: Copy>(v: Vec<T>, corners: Option<&[usize]>) -> Vec<T> {
    match corners {
        Some(c) => c.iter().map(|&i| v[i]).collect(),
        None => v,
    }
}

/// A texture's `KHR_texture_transform` as offset x, y, rotation, scale x, y.
fn transform_of(info: &gltf::texture::Info) -> [f32; 5] {
    info.texture_transform().map_or([0.0, 0.0, 0.0, 1.0, 1.0], |t| {
        let ([ox, oy], [sx, sy]) = (t.offset(), t.scale());
        [ox, oy, t.rotation(), sx, sy]
    })
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

/// A `KHR_lights_punctual` light at `world` (lights shine down their local −Z).
fn to_light(light: &gltf::khr_lights_punctual::Light, world: Mat4) -> Light {
    use gltf::khr_lights_punctual::Kind;
    let color = Vec3::from(light.color());
    let position = world.transform_point3(Vec3::ZERO);
    // glTF intensities (candela, lux) are taken as glint's unitless intensities.
    let range = light.range().unwrap_or(100.0);
    match light.kind() {
        Kind::Directional => {
            let direction = world.transform_vector3(Vec3::NEG_Z);
            Light::directional(direction, color, light.intensity())
        }
        Kind::Point => Light::point(position, color, light.intensity(), range),
        Kind::Spot { inner_cone_angle, outer_cone_angle } => {
            let direction = world.transform_vector3(Vec3::NEG_Z);
            let cone = (inner_cone_angle, outer_cone_angle);
            Light::spot(position, direction, color, light.intensity(), range, cone)
        }
    }
}
