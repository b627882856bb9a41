//! Core layer: glTF 2.0 validation before the gltf crate's readers see the data.
//!
//! The crate's readers index, slice and unwrap on the assumption that a file is
//! valid (a `byteStride` smaller than an element fails an assert, a channel's
//! target node past the end an `unwrap`), and its own validation skips some of
//! what they rely on. So every index in the JSON, every byte range an accessor or
//! buffer view covers, and every accessor type a reader depends on is checked
//! here first, with the values the specification bounds (node transforms,
//! cameras, lights, material factors, texture transforms).
//!
//! What the specification forbids is an error naming the element ("accessor 3:
//! ..."); what is odd but drawable is a warning.

use super::MAX_BUFFER_BYTES;
use gltf::json;
use json::accessor::{ComponentType, Type};
use json::validation::Checked;
use json::Index;
use std::f32::consts::{FRAC_PI_2, PI};
use ComponentType::{F32, I16, I8, U16, U32, U8};

/// Check everything that needs only the JSON: `Err` with the first thing the
/// specification forbids, warnings pushed to `warnings`.
pub(super) fn check_json(root: &json::Root, warnings: &mut Vec<String>) -> Result<(), String> {
    check_version(&root.asset)?;
    check_indices(root)?;
    // Types first: an accessor of the wrong type usually does not fit its view
    // either, and the type is the clearer message.
    check_meshes(root)?;
    check_animations(root)?;
    check_skins(root)?;
    check_views(root)?;
    for (i, accessor) in root.accessors.iter().enumerate() {
        check_accessor(root, accessor).map_err(|e| format!("accessor {i}: {e}"))?;
    }
    check_work(root)?;
    check_nodes(root, warnings)?;
    check_cameras(root, warnings)?;
    check_lights(root, warnings)?;
    check_materials(root, warnings)
}

/// glTF 2.x only: a file of another major version (`"version": "3.0"`, or a
/// `minVersion` above 2.0) may mean something else by the same fields.
fn check_version(asset: &json::Asset) -> Result<(), String> {
    let major = |v: &str| v.split('.').next().and_then(|m| m.parse::<u32>().ok());
    if major(&asset.version) != Some(2) {
        return Err("asset: version must be 2.x".into());
    }
    if let Some(min) = &asset.min_version {
        if major(min) != Some(2) || min.split('.').nth(1).and_then(|m| m.parse::<u32>().ok()) != Some(0) {
            return Err("asset: minVersion must be 2.0, the version glint reads".into());
        }
    }
    Ok(())
}

/// Check what needs the buffers' bytes, once read (`buffers[i]` is buffer i):
/// each buffer holds its `byteLength`, and sparse indices lie inside their
/// accessor and strictly increase.
pub(super) fn check_buffers(root: &json::Root, buffers: &[Vec<u8>]) -> Result<(), String> {
    for (i, buffer) in root.buffers.iter().enumerate() {
        let have = buffers.get(i).map_or(0, Vec::len) as u64;
        if have < buffer.byte_length.0 {
            return Err(format!("buffer {i}: {have} bytes, fewer than its byteLength {}", buffer.byte_length.0));
        }
    }
    for (i, accessor) in root.accessors.iter().enumerate() {
        if let Some(sparse) = &accessor.sparse {
            check_sparse_indices(root, buffers, accessor.count.0, sparse).map_err(|e| format!("accessor {i}: {e}"))?;
        }
    }
    Ok(())
}

/// Most vertices one model builds, each morph target's copy counted: 16.7 M,
/// about 800 MB of vertex data. Accessors may be shared, so one buffer's data can
/// be read many times over (by many meshes, skins and morph targets); this bounds
/// what is built, not what is stored.
pub(super) const MAX_MODEL_VERTICES: u64 = 1 << 24;

/// Most animation keys one model reads (key times plus values, over every
/// channel): 16.7 M, about 270 MB once stored.
pub(super) const MAX_ANIMATION_KEYS: u64 = 1 << 24;

/// The vertices and animation keys the loader will build, against
/// [`MAX_MODEL_VERTICES`] and [`MAX_ANIMATION_KEYS`], before any is read.
fn check_work(root: &json::Root) -> Result<(), String> {
    use json::mesh::{Mode, Semantic};
    let count = |a: Index<json::Accessor>| root.accessors.get(a.value()).map_or(0, |a| a.count.0);
    // A mesh is built once per skin it is drawn with.
    let mut uses: Vec<(usize, Option<usize>)> =
        root.nodes.iter().filter_map(|n| n.mesh.map(|m| (m.value(), n.skin.map(|s| s.value())))).collect();
    uses.sort_unstable();
    uses.dedup();
    let mut vertices: u128 = 0;
    for (m, _) in uses {
        for primitive in root.meshes.get(m).map_or(&[][..], |mesh| &mesh.primitives[..]) {
            if primitive.mode != Checked::Valid(Mode::Triangles) {
                continue;
            }
            let attribute = |s: Semantic| primitive.attributes.get(&Checked::Valid(s)).copied();
            let positions = attribute(Semantic::Positions).map_or(0, count);
            // Without normals every corner also becomes its own vertex.
            let corners = match (attribute(Semantic::Normals), primitive.indices) {
                (None, Some(indices)) => count(indices),
                (None, None) => positions,
                (Some(_), _) => 0,
            };
            let built = positions + corners;
            let copies = 1 + primitive.targets.as_ref().map_or(0, Vec::len) as u128;
            vertices += u128::from(built) * copies;
        }
        if vertices > u128::from(MAX_MODEL_VERTICES) {
            return Err(format!(
                "the meshes would build {vertices} vertices (morph targets counted), more than the {MAX_MODEL_VERTICES} limit"
            ));
        }
    }
    let mut keys: u128 = 0;
    for animation in &root.animations {
        for channel in &animation.channels {
            if let Some(sampler) = animation.samplers.get(channel.sampler.value()) {
                keys += u128::from(count(sampler.input)) + u128::from(count(sampler.output));
            }
        }
    }
    if keys > u128::from(MAX_ANIMATION_KEYS) {
        return Err(format!("the animations would read {keys} keys, more than the {MAX_ANIMATION_KEYS} limit"));
    }
    Ok(())
}

/// `Err` unless `index` is one of the `len` elements called `kind`.
fn exists<T>(index: Index<T>, len: usize, kind: &str) -> Result<(), String> {
    if index.value() < len {
        Ok(())
    } else {
        Err(format!("{kind} {} does not exist", index.value()))
    }
}

/// Every index in the document names an element that exists, so nothing later
/// (the crate's validation and readers included) indexes past an array.
fn check_indices(root: &json::Root) -> Result<(), String> {
    let accessors = root.accessors.len();
    let nodes = root.nodes.len();
    let views = root.buffer_views.len();
    let textures = root.textures.len();
    if let Some(scene) = root.scene {
        exists(scene, root.scenes.len(), "scene").map_err(|e| format!("the default scene: {e}"))?;
    }
    for (i, scene) in root.scenes.iter().enumerate() {
        for &node in &scene.nodes {
            exists(node, nodes, "node").map_err(|e| format!("scene {i}: {e}"))?;
        }
    }
    let lights = root.extensions.as_ref().and_then(|e| e.khr_lights_punctual.as_ref()).map_or(0, |l| l.lights.len());
    for (i, node) in root.nodes.iter().enumerate() {
        let at = |e: String| format!("node {i}: {e}");
        if let Some(camera) = node.camera {
            exists(camera, root.cameras.len(), "camera").map_err(at)?;
        }
        for &child in node.children.iter().flatten() {
            exists(child, nodes, "child node").map_err(at)?;
        }
        if let Some(mesh) = node.mesh {
            exists(mesh, root.meshes.len(), "mesh").map_err(at)?;
        }
        if let Some(skin) = node.skin {
            exists(skin, root.skins.len(), "skin").map_err(at)?;
        }
        if let Some(light) = node.extensions.as_ref().and_then(|e| e.khr_lights_punctual.as_ref()) {
            exists(light.light, lights, "light").map_err(at)?;
        }
    }
    for (m, mesh) in root.meshes.iter().enumerate() {
        for (p, primitive) in mesh.primitives.iter().enumerate() {
            let at = |e: String| format!("mesh {m} primitive {p}: {e}");
            for &accessor in primitive.attributes.values() {
                exists(accessor, accessors, "accessor").map_err(at)?;
            }
            if let Some(indices) = primitive.indices {
                exists(indices, accessors, "accessor").map_err(at)?;
            }
            if let Some(material) = primitive.material {
                exists(material, root.materials.len(), "material").map_err(at)?;
            }
            for target in primitive.targets.iter().flatten() {
                for accessor in [target.positions, target.normals, target.tangents].into_iter().flatten() {
                    exists(accessor, accessors, "accessor").map_err(at)?;
                }
            }
        }
    }
    for (i, accessor) in root.accessors.iter().enumerate() {
        let at = |e: String| format!("accessor {i}: {e}");
        if let Some(view) = accessor.buffer_view {
            exists(view, views, "bufferView").map_err(at)?;
        }
        if let Some(sparse) = &accessor.sparse {
            exists(sparse.indices.buffer_view, views, "bufferView").map_err(at)?;
            exists(sparse.values.buffer_view, views, "bufferView").map_err(at)?;
        }
    }
    for (i, view) in root.buffer_views.iter().enumerate() {
        exists(view.buffer, root.buffers.len(), "buffer").map_err(|e| format!("bufferView {i}: {e}"))?;
    }
    for (a, animation) in root.animations.iter().enumerate() {
        for (s, sampler) in animation.samplers.iter().enumerate() {
            let at = |e: String| format!("animation {a} sampler {s}: {e}");
            exists(sampler.input, accessors, "accessor").map_err(at)?;
            exists(sampler.output, accessors, "accessor").map_err(at)?;
        }
        for (c, channel) in animation.channels.iter().enumerate() {
            let at = |e: String| format!("animation {a} channel {c}: {e}");
            exists(channel.sampler, animation.samplers.len(), "sampler").map_err(at)?;
            exists(channel.target.node, nodes, "target node").map_err(at)?;
        }
    }
    for (i, skin) in root.skins.iter().enumerate() {
        let at = |e: String| format!("skin {i}: {e}");
        if let Some(matrices) = skin.inverse_bind_matrices {
            exists(matrices, accessors, "accessor").map_err(at)?;
        }
        for &joint in &skin.joints {
            exists(joint, nodes, "joint node").map_err(at)?;
        }
        if let Some(skeleton) = skin.skeleton {
            exists(skeleton, nodes, "skeleton node").map_err(at)?;
        }
    }
    for (i, texture) in root.textures.iter().enumerate() {
        let at = |e: String| format!("texture {i}: {e}");
        exists(texture.source, root.images.len(), "image").map_err(at)?;
        if let Some(sampler) = texture.sampler {
            exists(sampler, root.samplers.len(), "sampler").map_err(at)?;
        }
    }
    for (i, image) in root.images.iter().enumerate() {
        if let Some(view) = image.buffer_view {
            exists(view, views, "bufferView").map_err(|e| format!("image {i}: {e}"))?;
        }
    }
    for (i, material) in root.materials.iter().enumerate() {
        for (slot, texture) in material_textures(material) {
            exists(texture, textures, "texture").map_err(|e| format!("material {i} {slot}: {e}"))?;
        }
    }
    Ok(())
}

/// The textures a material names, with the name of the slot.
fn material_textures(material: &json::Material) -> Vec<(&'static str, Index<json::Texture>)> {
    let pbr = &material.pbr_metallic_roughness;
    let mut out = Vec::new();
    if let Some(t) = &pbr.base_color_texture {
        out.push(("baseColorTexture", t.index));
    }
    if let Some(t) = &pbr.metallic_roughness_texture {
        out.push(("metallicRoughnessTexture", t.index));
    }
    if let Some(t) = &material.normal_texture {
        out.push(("normalTexture", t.index));
    }
    if let Some(t) = &material.occlusion_texture {
        out.push(("occlusionTexture", t.index));
    }
    if let Some(t) = &material.emissive_texture {
        out.push(("emissiveTexture", t.index));
    }
    out
}

/// Buffer views lie inside their buffers, with a stride the specification allows.
fn check_views(root: &json::Root) -> Result<(), String> {
    for (i, view) in root.buffer_views.iter().enumerate() {
        let fail = |m: String| Err(format!("bufferView {i}: {m}"));
        let Some(buffer) = root.buffers.get(view.buffer.value()) else {
            return fail(format!("buffer {} does not exist", view.buffer.value()));
        };
        let (offset, length) = (view.byte_offset.map_or(0, |o| o.0), view.byte_length.0);
        if length == 0 {
            return fail("byteLength must be at least 1".into());
        }
        let end = u128::from(offset) + u128::from(length);
        if end > u128::from(buffer.byte_length.0) {
            return fail(format!(
                "bytes {offset}..{end} are past the end of buffer {} (byteLength {})",
                view.buffer.value(),
                buffer.byte_length.0
            ));
        }
        if let Some(stride) = view.byte_stride {
            if !(4..=252).contains(&stride.0) || stride.0 % 4 != 0 {
                return fail(format!("byteStride {} must be a multiple of 4 from 4 to 252", stride.0));
            }
        }
    }
    Ok(())
}

/// Bytes of one element: components × component size, with matrix columns
/// starting on 4-byte boundaries as the specification lays them out.
fn element_size(component: ComponentType, kind: Type) -> u64 {
    let size = component.size() as u64;
    let (columns, rows) = match kind {
        Type::Scalar => (1, 1),
        Type::Vec2 => (1, 2),
        Type::Vec3 => (1, 3),
        Type::Vec4 => (1, 4),
        Type::Mat2 => (2, 2),
        Type::Mat3 => (3, 3),
        Type::Mat4 => (4, 4),
    };
    if columns == 1 {
        rows * size
    } else {
        columns * (rows * size).next_multiple_of(4)
    }
}

/// The component type and type of an accessor, when both are valid.
fn accessor_kind(accessor: &json::Accessor) -> Result<(ComponentType, Type), String> {
    let Checked::Valid(component) = accessor.component_type else {
        return Err("componentType is not one of 5120, 5121, 5122, 5123, 5125, 5126".into());
    };
    let Checked::Valid(kind) = accessor.type_ else {
        return Err("type is not one of SCALAR, VEC2, VEC3, VEC4, MAT2, MAT3, MAT4".into());
    };
    Ok((component.0, kind))
}

/// `Err` with the bytes needed unless `count` elements of `element` bytes,
/// `stride` apart from byte `offset`, fit in `length` bytes.
fn fits(offset: u64, stride: u64, count: u64, element: u64, length: u64) -> Result<(), u128> {
    let need = u128::from(offset) + u128::from(stride) * u128::from(count.saturating_sub(1)) + u128::from(element);
    if need <= u128::from(length) {
        Ok(())
    } else {
        Err(need)
    }
}

/// One accessor: a valid kind, a count of at least one, and its elements (and
/// its sparse indices and values) inside their buffer views.
fn check_accessor(root: &json::Root, accessor: &json::Accessor) -> Result<(), String> {
    let (component, kind) = accessor_kind(accessor)?;
    let count = accessor.count.0;
    if count == 0 {
        return Err("count must be at least 1".into());
    }
    if accessor.normalized && matches!(component, ComponentType::F32 | ComponentType::U32) {
        return Err("normalized is not allowed with FLOAT or UNSIGNED_INT components".into());
    }
    let element = element_size(component, kind);
    // An accessor without a view (zeros under sparse values) is built in memory:
    // it may not hold more than a buffer could.
    if u128::from(count) * u128::from(element) > u128::from(MAX_BUFFER_BYTES) {
        return Err(format!("{count} elements of {element} bytes are more than the {MAX_BUFFER_BYTES}-byte limit"));
    }
    if let Some(v) = accessor.buffer_view {
        let view =
            root.buffer_views.get(v.value()).ok_or_else(|| format!("bufferView {} does not exist", v.value()))?;
        let offset = accessor.byte_offset.map_or(0, |o| o.0);
        let size = component.size() as u64;
        let start = view.byte_offset.map_or(0, |o| o.0).saturating_add(offset);
        if offset % size != 0 || start % size != 0 {
            return Err(format!(
                "byteOffset {offset} in bufferView {} (byte {start} of its buffer) is not a multiple of the {size}-byte component",
                v.value()
            ));
        }
        let stride = match view.byte_stride {
            Some(s) if (s.0 as u64) < element => {
                return Err(format!(
                    "bufferView {} has byteStride {}, smaller than the accessor's {element}-byte elements",
                    v.value(),
                    s.0
                ))
            }
            Some(s) => s.0 as u64,
            None => element,
        };
        fits(offset, stride, count, element, view.byte_length.0).map_err(|need| {
            format!(
                "{count} elements of {element} bytes, {stride} apart from byte {offset}, need {need} bytes but bufferView {} has {}",
                v.value(),
                view.byte_length.0
            )
        })?;
    }
    if let Some(sparse) = &accessor.sparse {
        let n = sparse.count.0;
        if n == 0 || n > count {
            return Err(format!("sparse count {n} must be from 1 to the accessor's count {count}"));
        }
        let Checked::Valid(index_type) = sparse.indices.component_type else {
            return Err("sparse indices: componentType must be 5121, 5123 or 5125".into());
        };
        let index_size = index_type.0.size() as u64;
        let parts = [
            ("sparse indices", sparse.indices.buffer_view, sparse.indices.byte_offset.0, index_size),
            ("sparse values", sparse.values.buffer_view, sparse.values.byte_offset.0, element),
        ];
        for (what, v, offset, size) in parts {
            let view =
                root.buffer_views.get(v.value()).ok_or_else(|| format!("bufferView {} does not exist", v.value()))?;
            if view.byte_stride.is_some() {
                return Err(format!("{what}: bufferView {} may not have a byteStride", v.value()));
            }
            fits(offset, size, n, size, view.byte_length.0).map_err(|need| {
                format!(
                    "{what}: {n} of {size} bytes from byte {offset} need {need} bytes but bufferView {} has {}",
                    v.value(),
                    view.byte_length.0
                )
            })?;
        }
    }
    Ok(())
}

/// The sparse indices of an accessor with `count` elements, read from the
/// buffers: each below `count`, each above the one before.
fn check_sparse_indices(
    root: &json::Root,
    buffers: &[Vec<u8>],
    count: u64,
    sparse: &json::accessor::sparse::Sparse,
) -> Result<(), String> {
    let Checked::Valid(index_type) = sparse.indices.component_type else {
        return Err("sparse indices: componentType must be 5121, 5123 or 5125".into());
    };
    let size = index_type.0.size();
    let short = || "sparse indices lie outside their buffer".to_string();
    let view = root.buffer_views.get(sparse.indices.buffer_view.value()).ok_or_else(short)?;
    let start = view.byte_offset.map_or(0, |o| o.0).saturating_add(sparse.indices.byte_offset.0);
    let start = usize::try_from(start).map_err(|_| short())?;
    let n = usize::try_from(sparse.count.0).map_err(|_| short())?;
    let end = n.checked_mul(size).and_then(|b| b.checked_add(start)).ok_or_else(short)?;
    let bytes = buffers.get(view.buffer.value()).and_then(|b| b.get(start..end)).ok_or_else(short)?;
    let mut previous: Option<u64> = None;
    for (k, b) in bytes.chunks_exact(size).enumerate() {
        let index = match *b {
            [a] => u64::from(a),
            [a, b] => u64::from(u16::from_le_bytes([a, b])),
            [a, b, c, d] => u64::from(u32::from_le_bytes([a, b, c, d])),
            _ => return Err(short()),
        };
        if index >= count {
            return Err(format!("sparse index {k} is {index}, past the accessor's {count} elements"));
        }
        if let Some(p) = previous.filter(|&p| index <= p) {
            return Err(format!("sparse index {k} is {index}, not above the one before ({p}): indices must increase"));
        }
        previous = Some(index);
    }
    Ok(())
}

/// Human names of component types, for messages.
fn component_name(component: ComponentType) -> &'static str {
    match component {
        ComponentType::I8 => "BYTE",
        ComponentType::U8 => "UNSIGNED_BYTE",
        ComponentType::I16 => "SHORT",
        ComponentType::U16 => "UNSIGNED_SHORT",
        ComponentType::U32 => "UNSIGNED_INT",
        ComponentType::F32 => "FLOAT",
    }
}

/// Names of accessor types, for messages.
fn type_name(kind: Type) -> &'static str {
    match kind {
        Type::Scalar => "SCALAR",
        Type::Vec2 => "VEC2",
        Type::Vec3 => "VEC3",
        Type::Vec4 => "VEC4",
        Type::Mat2 => "MAT2",
        Type::Mat3 => "MAT3",
        Type::Mat4 => "MAT4",
    }
}

/// `Err` unless accessor `index` has one of `kinds` and one of `components`.
fn expect_kind(
    root: &json::Root,
    index: Index<json::Accessor>,
    kinds: &[Type],
    components: &[ComponentType],
) -> Result<(), String> {
    let i = index.value();
    let accessor = root.accessors.get(i).ok_or_else(|| format!("accessor {i} does not exist"))?;
    let (component, kind) = accessor_kind(accessor).map_err(|e| format!("accessor {i}: {e}"))?;
    if kinds.contains(&kind) && components.contains(&component) {
        return Ok(());
    }
    let list = |names: Vec<&str>| names.join(" or ");
    let lead =
        if kinds.contains(&kind) { format!("component type {component:?} is not allowed: ") } else { String::new() };
    Err(format!(
        "{lead}accessor {i} is {} {}; expected {} of {}",
        type_name(kind),
        component_name(component),
        list(kinds.iter().map(|&k| type_name(k)).collect()),
        list(components.iter().map(|&c| component_name(c)).collect())
    ))
}

/// Primitive attributes, indices and morph targets have the types the
/// specification (and so the crate's readers) allow.
fn check_meshes(root: &json::Root) -> Result<(), String> {
    use json::mesh::Semantic;
    for (m, mesh) in root.meshes.iter().enumerate() {
        if mesh.weights.iter().flatten().any(|w| !w.is_finite()) {
            return Err(format!("mesh {m}: weights has a non-finite value"));
        }
        for (p, primitive) in mesh.primitives.iter().enumerate() {
            for (semantic, &accessor) in &primitive.attributes {
                let (kinds, components): (&[Type], &[ComponentType]) = match semantic {
                    Checked::Valid(Semantic::Positions | Semantic::Normals) => (&[Type::Vec3], &[F32]),
                    Checked::Valid(Semantic::Tangents) => (&[Type::Vec4], &[F32]),
                    Checked::Valid(Semantic::TexCoords(_)) => (&[Type::Vec2], &[F32, U8, U16]),
                    Checked::Valid(Semantic::Colors(_)) => (&[Type::Vec3, Type::Vec4], &[F32, U8, U16]),
                    Checked::Valid(Semantic::Joints(_)) => (&[Type::Vec4], &[U8, U16]),
                    Checked::Valid(Semantic::Weights(_)) => (&[Type::Vec4], &[F32, U8, U16]),
                    _ => continue,
                };
                expect_kind(root, accessor, kinds, components)
                    .map_err(|e| format!("mesh {m} primitive {p} {}: {e}", semantic.to_string()))?;
            }
            if let Some(indices) = primitive.indices {
                expect_kind(root, indices, &[Type::Scalar], &[U8, U16, U32])
                    .map_err(|e| format!("mesh {m} primitive {p} indices: {e}"))?;
            }
            for (t, target) in primitive.targets.iter().flatten().enumerate() {
                let streams =
                    [("POSITION", target.positions), ("NORMAL", target.normals), ("TANGENT", target.tangents)];
                for (what, accessor) in streams {
                    if let Some(accessor) = accessor {
                        expect_kind(root, accessor, &[Type::Vec3], &[F32])
                            .map_err(|e| format!("mesh {m} primitive {p} morph target {t} {what}: {e}"))?;
                    }
                }
            }
        }
    }
    Ok(())
}

/// Animation samplers read float key times and values of the type their
/// channel's property needs.
fn check_animations(root: &json::Root) -> Result<(), String> {
    use json::animation::Property;
    for (a, animation) in root.animations.iter().enumerate() {
        for (s, sampler) in animation.samplers.iter().enumerate() {
            expect_kind(root, sampler.input, &[Type::Scalar], &[F32])
                .map_err(|e| format!("animation {a} sampler {s} input: {e}"))?;
        }
        for (c, channel) in animation.channels.iter().enumerate() {
            let Some(sampler) = animation.samplers.get(channel.sampler.value()) else {
                return Err(format!("animation {a} channel {c}: sampler {} does not exist", channel.sampler.value()));
            };
            let (kinds, components): (&[Type], &[ComponentType]) = match channel.target.path {
                Checked::Valid(Property::Translation | Property::Scale) => (&[Type::Vec3], &[F32]),
                Checked::Valid(Property::Rotation) => (&[Type::Vec4], &[F32, I8, U8, I16, U16]),
                Checked::Valid(Property::MorphTargetWeights) => (&[Type::Scalar], &[F32, I8, U8, I16, U16]),
                Checked::Invalid => return Err(format!("animation {a} channel {c}: target path is not valid")),
            };
            expect_kind(root, sampler.output, kinds, components)
                .map_err(|e| format!("animation {a} channel {c} output: {e}"))?;
        }
    }
    Ok(())
}

/// Inverse bind matrices are float 4×4 matrices.
fn check_skins(root: &json::Root) -> Result<(), String> {
    for (i, skin) in root.skins.iter().enumerate() {
        if let Some(matrices) = skin.inverse_bind_matrices {
            expect_kind(root, matrices, &[Type::Mat4], &[F32])
                .map_err(|e| format!("skin {i} inverseBindMatrices: {e}"))?;
        }
    }
    Ok(())
}

fn finite(values: &[f32]) -> bool {
    values.iter().all(|v| v.is_finite())
}

/// Node transforms and weights are finite, rotations are quaternions that can
/// be normalised.
fn check_nodes(root: &json::Root, warnings: &mut Vec<String>) -> Result<(), String> {
    for (i, node) in root.nodes.iter().enumerate() {
        let parts: [(&str, Option<&[f32]>); 5] = [
            ("matrix", node.matrix.as_ref().map(|m| &m[..])),
            ("translation", node.translation.as_ref().map(|t| &t[..])),
            ("rotation", node.rotation.as_ref().map(|r| &r.0[..])),
            ("scale", node.scale.as_ref().map(|s| &s[..])),
            ("weights", node.weights.as_deref()),
        ];
        for (what, values) in parts {
            if values.is_some_and(|v| !finite(v)) {
                return Err(format!("node {i}: {what} has a non-finite value"));
            }
        }
        if let Some(r) = &node.rotation {
            let length = r.0.iter().map(|v| v * v).sum::<f32>().sqrt();
            if length < 1e-6 {
                return Err(format!("node {i}: rotation {:?} is not a unit quaternion", r.0));
            }
            if (length - 1.0).abs() > 1e-3 {
                warnings.push(format!("node {i}: rotation has length {length}, not 1; it is normalised"));
            }
        }
        if node.matrix.is_some() && (node.translation.is_some() || node.rotation.is_some() || node.scale.is_some()) {
            warnings.push(format!("node {i}: has a matrix and translation, rotation or scale; the matrix is used"));
        }
    }
    Ok(())
}

/// Cameras have the projection their type names, with positive field of view,
/// aspect, magnifications and a depth range with zfar beyond znear.
fn check_cameras(root: &json::Root, warnings: &mut Vec<String>) -> Result<(), String> {
    use json::camera::Type as Kind;
    for (i, camera) in root.cameras.iter().enumerate() {
        let fail = |m: String| Err(format!("camera {i}: {m}"));
        match (camera.type_, &camera.perspective, &camera.orthographic) {
            (Checked::Valid(Kind::Perspective), Some(p), _) => {
                if !(p.yfov.is_finite() && p.yfov > 0.0) {
                    return fail(format!("yfov {} must be above 0", p.yfov));
                }
                if p.yfov >= PI {
                    warnings.push(format!("camera {i}: yfov {} is not below pi", p.yfov));
                }
                if let Some(aspect) = p.aspect_ratio.filter(|a| !(a.is_finite() && *a > 0.0)) {
                    return fail(format!("aspectRatio {aspect} must be above 0"));
                }
                if !(p.znear.is_finite() && p.znear > 0.0) {
                    return fail(format!("znear {} must be above 0", p.znear));
                }
                if let Some(far) = p.zfar.filter(|f| !(f.is_finite() && *f > p.znear)) {
                    return fail(format!("zfar {far} must be beyond znear {}", p.znear));
                }
            }
            (Checked::Valid(Kind::Orthographic), _, Some(o)) => {
                for (what, v) in [("xmag", o.xmag), ("ymag", o.ymag)] {
                    if !v.is_finite() || v == 0.0 {
                        return fail(format!("{what} {v} must be finite and not 0"));
                    }
                }
                if !(o.znear.is_finite() && o.znear >= 0.0) {
                    return fail(format!("znear {} must be 0 or above", o.znear));
                }
                if !(o.zfar.is_finite() && o.zfar > o.znear) {
                    return fail(format!("zfar {} must be beyond znear {}", o.zfar, o.znear));
                }
            }
            (Checked::Valid(Kind::Perspective), None, _) => return fail("type perspective without perspective".into()),
            (Checked::Valid(Kind::Orthographic), _, None) => {
                return fail("type orthographic without orthographic".into())
            }
            (Checked::Invalid, _, _) => return fail("type is not perspective or orthographic".into()),
        }
    }
    Ok(())
}

/// `KHR_lights_punctual` lights: non-negative finite colour and intensity, a
/// positive range, spot cones with 0 <= inner < outer <= pi/2.
fn check_lights(root: &json::Root, warnings: &mut Vec<String>) -> Result<(), String> {
    use json::extensions::scene::khr_lights_punctual::Type as Kind;
    let Some(lights) = root.extensions.as_ref().and_then(|e| e.khr_lights_punctual.as_ref()) else {
        return Ok(());
    };
    for (i, light) in lights.lights.iter().enumerate() {
        let fail = |m: String| Err(format!("light {i}: {m}"));
        if !light.color.iter().all(|c| c.is_finite() && *c >= 0.0) {
            return fail(format!("color {:?} must be finite and not negative", light.color));
        }
        if light.color.iter().any(|&c| c > 1.0) {
            warnings
                .push(format!("light {i}: color {:?} is above 1 (intensity is the place for brightness)", light.color));
        }
        if !(light.intensity.is_finite() && light.intensity >= 0.0) {
            return fail(format!("intensity {} must be finite and not negative", light.intensity));
        }
        if let Some(range) = light.range.filter(|r| !(r.is_finite() && *r > 0.0)) {
            return fail(format!("range {range} must be above 0"));
        }
        if let (Checked::Valid(Kind::Spot), Some(spot)) = (light.type_, &light.spot) {
            let (inner, outer) = (spot.inner_cone_angle, spot.outer_cone_angle);
            if !(inner.is_finite() && outer.is_finite() && 0.0 <= inner && inner < outer && outer <= FRAC_PI_2) {
                return fail(format!(
                    "spot cone angles {inner}, {outer} must satisfy 0 <= innerConeAngle < outerConeAngle <= pi/2"
                ));
            }
        }
    }
    Ok(())
}

/// Material factors inside the ranges the specification gives, finite texture
/// transforms.
fn check_materials(root: &json::Root, warnings: &mut Vec<String>) -> Result<(), String> {
    for (i, material) in root.materials.iter().enumerate() {
        let fail = |m: String| Err(format!("material {i}: {m}"));
        let pbr = &material.pbr_metallic_roughness;
        let unit: [(&str, &[f32]); 4] = [
            ("baseColorFactor", &pbr.base_color_factor.0),
            ("metallicFactor", std::slice::from_ref(&pbr.metallic_factor.0)),
            ("roughnessFactor", std::slice::from_ref(&pbr.roughness_factor.0)),
            ("emissiveFactor", &material.emissive_factor.0),
        ];
        for (what, values) in unit {
            if !values.iter().all(|v| (0.0..=1.0).contains(v)) {
                return fail(format!("{what} {values:?} must lie in [0, 1]"));
            }
        }
        if let Some(occlusion) = &material.occlusion_texture {
            if !(0.0..=1.0).contains(&occlusion.strength.0) {
                return fail(format!("occlusionTexture strength {} must lie in [0, 1]", occlusion.strength.0));
            }
        }
        if let Some(normal) = &material.normal_texture {
            if !normal.scale.is_finite() {
                return fail(format!("normalTexture scale {} must be finite", normal.scale));
            }
        }
        if let Some(cutoff) = material.alpha_cutoff.as_ref().map(|c| c.0) {
            if !(cutoff.is_finite() && cutoff >= 0.0) {
                return fail(format!("alphaCutoff {cutoff} must be finite and not negative"));
            }
            if cutoff > 1.0 {
                warnings.push(format!("material {i}: alphaCutoff {cutoff} is above 1, so every texel is cut out"));
            }
        }
        if let Some(strength) = material.extensions.as_ref().and_then(|e| e.emissive_strength.as_ref()) {
            let s = strength.emissive_strength.0;
            if !(s.is_finite() && s >= 0.0) {
                return fail(format!("KHR_materials_emissive_strength {s} must be finite and not negative"));
            }
        }
        let infos = [
            ("baseColorTexture", &pbr.base_color_texture),
            ("metallicRoughnessTexture", &pbr.metallic_roughness_texture),
            ("emissiveTexture", &material.emissive_texture),
        ];
        for (what, info) in infos {
            let transform =
                info.as_ref().and_then(|t| t.extensions.as_ref()).and_then(|e| e.texture_transform.as_ref());
            if let Some(t) = transform {
                let values = [t.offset.0[0], t.offset.0[1], t.rotation.0, t.scale.0[0], t.scale.0[1]];
                if !finite(&values) {
                    return fail(format!("{what} KHR_texture_transform has a non-finite value"));
                }
            }
        }
    }
    Ok(())
}
