//! Tests of glTF validation and reading, on small documents built here: one
//! triangle whose buffer is an embedded `data:` URI, changed in one place per
//! case. Each hostile shape must be an error naming the element (or a warning),
//! never a panic, a hang or a silent load.

use super::{LoadOptions, Model, MAX_BUFFER_BYTES};
use serde_json::{json, Value};
use std::path::Path;

/// Layout of the test buffer (byte offsets): three VEC3 positions at 0, three
/// u16 indices at 36 (then two bytes of padding), two key times at 44, two VEC3
/// translations at 52, four u8 (sparse indices or triangle indices) at 76, two
/// VEC3 values at 80; 104 bytes in all.
const SPARSE_BYTES: [u8; 4] = [1, 1, 0, 5];

fn buffer_bytes() -> Vec<u8> {
    let floats = |v: &[f32]| v.iter().flat_map(|f| f.to_le_bytes()).collect::<Vec<u8>>();
    let mut bytes = floats(&[0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 1.0, 0.0]);
    bytes.extend([0u16, 1, 2].iter().flat_map(|i| i.to_le_bytes()));
    bytes.extend([0, 0]);
    bytes.extend(floats(&[0.0, 1.0]));
    bytes.extend(floats(&[0.0, 0.0, 0.0, 2.0, 0.0, 0.0]));
    bytes.extend(SPARSE_BYTES);
    bytes.extend(floats(&[0.0, 0.0, 5.0, 0.0, 0.0, 7.0]));
    bytes
}

fn data_uri(bytes: &[u8]) -> String {
    format!("data:application/octet-stream;base64,{}", base64::encode(bytes))
}

/// A valid one-triangle document with spare views and accessors the cases use:
/// accessors 0 POSITION, 1 indices, 2 key times, 3 translations; views 4 (u8
/// bytes) and 5 (two VEC3) for sparse data.
fn triangle() -> Value {
    let bytes = buffer_bytes();
    let view = |offset: usize, length: usize| json!({"buffer": 0, "byteOffset": offset, "byteLength": length});
    json!({
        "asset": {"version": "2.0"},
        "scene": 0,
        "scenes": [{"nodes": [0]}],
        "nodes": [{"mesh": 0}],
        "meshes": [{"primitives": [{"attributes": {"POSITION": 0}, "indices": 1}]}],
        "buffers": [{"uri": data_uri(&bytes), "byteLength": bytes.len()}],
        "bufferViews": [view(0, 36), view(36, 6), view(44, 8), view(52, 24), view(76, 4), view(80, 24)],
        "accessors": [
            {"bufferView": 0, "componentType": 5126, "count": 3, "type": "VEC3", "min": [0, 0, 0], "max": [1, 1, 0]},
            {"bufferView": 1, "componentType": 5123, "count": 3, "type": "SCALAR"},
            {"bufferView": 2, "componentType": 5126, "count": 2, "type": "SCALAR", "min": [0], "max": [1]},
            {"bufferView": 3, "componentType": 5126, "count": 2, "type": "VEC3"}
        ]
    })
}

/// `doc` with the value at JSON pointer `at` set to `value` (objects on the way
/// are made; the last step may be a new key, an array index or one past the end).
fn with(mut doc: Value, at: &str, value: Value) -> Value {
    let mut here = &mut doc;
    let steps: Vec<&str> = at.trim_start_matches('/').split('/').collect();
    for (k, step) in steps.iter().enumerate() {
        let last = k + 1 == steps.len();
        here = match here {
            Value::Array(items) => {
                let i: usize = step.parse().expect("an array index");
                if i == items.len() {
                    items.push(Value::Null);
                }
                &mut items[i]
            }
            other => {
                if !other.is_object() {
                    *other = json!({});
                }
                let map = other.as_object_mut().expect("an object");
                map.entry(step.to_string()).or_insert(Value::Null)
            }
        };
        if last {
            *here = value.clone();
        }
    }
    doc
}

fn parse(doc: &Value) -> Result<Model, super::Diagnostic> {
    Model::parse(Path::new("m/test.gltf"), doc.to_string().as_bytes(), LoadOptions::default())
}

/// The error message `doc` gives; fails the test when it loads.
fn error(doc: &Value) -> String {
    match parse(doc) {
        Ok(_) => panic!("expected an error, the document loaded"),
        Err(e) => e.message,
    }
}

/// The warnings of a document that must load.
fn warnings(doc: &Value) -> Vec<String> {
    let model = parse(doc).unwrap_or_else(|e| panic!("expected a model: {e}"));
    model.warnings.into_iter().map(|w| w.message).collect()
}

#[track_caller]
fn assert_error(doc: &Value, expected: &str) {
    let message = error(doc);
    assert!(message.contains(expected), "expected '{expected}' in: {message}");
}

#[track_caller]
fn assert_warning(doc: &Value, expected: &str) {
    let all = warnings(doc);
    assert!(all.iter().any(|w| w.contains(expected)), "expected a warning '{expected}' in {all:?}");
}

#[test]
fn the_base_document_loads_without_warnings() {
    let model = parse(&triangle()).expect("a valid triangle");
    assert_eq!(model.parts[0].mesh.indices().len(), 3);
    assert!(model.warnings.is_empty(), "{:?}", model.warnings);
}

#[test]
fn strides_the_spec_forbids_are_errors() {
    // This panicked inside the gltf crate's reader (an assert on the element size).
    assert_error(
        &with(triangle(), "/bufferViews/0/byteStride", json!(4)),
        "accessor 0: bufferView 0 has byteStride 4, smaller than the accessor's 12-byte elements",
    );
    for stride in [0, 2, 14, 256] {
        let doc = with(triangle(), "/bufferViews/0/byteStride", json!(stride));
        assert_error(&doc, &format!("bufferView 0: byteStride {stride} must be a multiple of 4 from 4 to 252"));
    }
    // A legal stride that leaves too few bytes for the count.
    assert_error(&with(triangle(), "/bufferViews/0/byteStride", json!(16)), "accessor 0: 3 elements of 12 bytes");
}

/// The triangle with one animation over node `node` (its translation keys).
fn animated(node: usize) -> Value {
    let animation = json!([{
        "samplers": [{"input": 2, "output": 3}],
        "channels": [{"sampler": 0, "target": {"node": node, "path": "translation"}}]
    }]);
    with(triangle(), "/animations", animation)
}

#[test]
fn a_channel_targeting_a_missing_node_is_an_error() {
    assert!(parse(&animated(0)).is_ok(), "the same channel on node 0 loads");
    // This panicked inside the gltf crate (an unwrap on the node).
    assert_error(&animated(5), "animation 0 channel 0: target node 5 does not exist");
    assert_error(
        &with(animated(0), "/animations/0/channels/0/sampler", json!(3)),
        "animation 0 channel 0: sampler 3 does not exist",
    );
    assert_error(
        &with(animated(0), "/animations/0/samplers/0/output", json!(9)),
        "animation 0 sampler 0: accessor 9 does not exist",
    );
    // Key times must be float scalars, translations float VEC3s.
    assert_error(
        &with(animated(0), "/animations/0/samplers/0/input", json!(1)),
        "animation 0 sampler 0 input: component type U16 is not allowed: accessor 1 is SCALAR UNSIGNED_SHORT",
    );
    assert_error(
        &with(animated(0), "/animations/0/samplers/0/output", json!(2)),
        "animation 0 channel 0 output: accessor 2 is SCALAR FLOAT; expected VEC3",
    );
}

#[test]
fn every_index_is_checked() {
    let textured = with(
        with(triangle(), "/materials", json!([{"pbrMetallicRoughness": {"baseColorTexture": {"index": 0}}}])),
        "/textures",
        json!([{"source": 0}]),
    );
    let textured =
        with(with(textured, "/images", json!([{"uri": "missing.png"}])), "/meshes/0/primitives/0/material", json!(0));
    let cases = [
        (with(triangle(), "/scene", json!(2)), "the default scene: scene 2 does not exist"),
        (with(triangle(), "/scenes/0/nodes/0", json!(3)), "scene 0: node 3 does not exist"),
        (with(triangle(), "/nodes/0/mesh", json!(4)), "node 0: mesh 4 does not exist"),
        (with(triangle(), "/nodes/0/children", json!([7])), "node 0: child node 7 does not exist"),
        (with(triangle(), "/nodes/0/camera", json!(0)), "node 0: camera 0 does not exist"),
        (with(triangle(), "/nodes/0/skin", json!(1)), "node 0: skin 1 does not exist"),
        (
            with(triangle(), "/nodes/0/extensions", json!({"KHR_lights_punctual": {"light": 0}})),
            "node 0: light 0 does not exist",
        ),
        (with(triangle(), "/meshes/0/primitives/0/attributes/NORMAL", json!(8)), "accessor 8 does not exist"),
        (with(triangle(), "/meshes/0/primitives/0/indices", json!(8)), "mesh 0 primitive 0: accessor 8 does not exist"),
        (
            with(triangle(), "/meshes/0/primitives/0/material", json!(1)),
            "mesh 0 primitive 0: material 1 does not exist",
        ),
        (
            with(triangle(), "/meshes/0/primitives/0/targets", json!([{"POSITION": 9}])),
            "mesh 0 primitive 0: accessor 9 does not exist",
        ),
        (with(triangle(), "/accessors/0/bufferView", json!(6)), "accessor 0: bufferView 6 does not exist"),
        (with(triangle(), "/bufferViews/0/buffer", json!(1)), "bufferView 0: buffer 1 does not exist"),
        (with(triangle(), "/skins", json!([{"joints": [4]}])), "skin 0: joint node 4 does not exist"),
        (with(triangle(), "/skins", json!([{"joints": [0], "skeleton": 2}])), "skin 0: skeleton node 2 does not exist"),
        (
            with(triangle(), "/skins", json!([{"joints": [0], "inverseBindMatrices": 6}])),
            "skin 0: accessor 6 does not exist",
        ),
        (with(textured.clone(), "/textures/0/source", json!(1)), "texture 0: image 1 does not exist"),
        (with(textured.clone(), "/textures/0/sampler", json!(0)), "texture 0: sampler 0 does not exist"),
        (
            with(textured.clone(), "/materials/0/pbrMetallicRoughness/baseColorTexture/index", json!(2)),
            "material 0 baseColorTexture: texture 2 does not exist",
        ),
        (
            with(textured.clone(), "/materials/0/normalTexture", json!({"index": 3})),
            "material 0 normalTexture: texture 3",
        ),
        (
            with(textured, "/images/0", json!({"bufferView": 9, "mimeType": "image/png"})),
            "image 0: bufferView 9 does not exist",
        ),
    ];
    for (doc, expected) in cases {
        assert_error(&doc, expected);
    }
}

#[test]
fn accessors_and_views_must_fit() {
    // An accessor longer than its view; the index accessor case was drawn as one triangle.
    assert_error(&with(triangle(), "/accessors/0/count", json!(4)), "accessor 0: 4 elements of 12 bytes");
    assert_error(&with(triangle(), "/accessors/1/count", json!(6)), "accessor 1: 6 elements of 2 bytes");
    assert_error(&with(triangle(), "/accessors/0/byteOffset", json!(4)), "need 40 bytes but bufferView 0 has 36");
    assert_error(&with(triangle(), "/accessors/0/byteOffset", json!(2)), "accessor 0: byteOffset 2");
    // count 0 made the crate's reader compute count - 1.
    assert_error(&with(triangle(), "/accessors/0/count", json!(0)), "accessor 0: count must be at least 1");
    assert_error(
        &with(triangle(), "/bufferViews/3/byteLength", json!(60)),
        "bufferView 3: bytes 52..112 are past the end of buffer 0",
    );
    assert_error(&with(triangle(), "/bufferViews/3/byteOffset", json!(1u64 << 60)), "bufferView 3: bytes");
    // A buffer whose data is shorter than the byteLength it declares.
    assert_error(
        &with(triangle(), "/buffers/0/byteLength", json!(120)),
        "buffer 0: 104 bytes, fewer than its byteLength 120",
    );
    // A byteLength over the limit is refused before anything is read or decoded.
    let huge = with(triangle(), "/buffers/0/byteLength", json!(MAX_BUFFER_BYTES + 1));
    assert_error(&huge, "more than the");
    // An accessor without a view is made in memory: its size is bounded too.
    let zeros = json!({"componentType": 5126, "count": 1u64 << 40, "type": "VEC3",
        "sparse": {"count": 1, "indices": {"bufferView": 4, "componentType": 5121}, "values": {"bufferView": 5}}});
    assert_error(&with(triangle(), "/accessors/3", zeros), "accessor 3: 1099511627776 elements of 12 bytes are more");
    assert_error(&with(triangle(), "/buffers/0/uri", Value::Null), "buffer 0: no uri and no GLB binary chunk");
}

/// The triangle's POSITION with sparse substitutions: `count` u8 indices from
/// `offset` in SPARSE_BYTES, values from view 5.
fn sparse(count: usize, offset: usize) -> Value {
    let sparse = json!({"count": count, "indices": {"bufferView": 4, "byteOffset": offset, "componentType": 5121},
        "values": {"bufferView": 5}});
    with(triangle(), "/accessors/0/sparse", sparse)
}

#[test]
fn sparse_indices_must_lie_inside_and_increase() {
    // [0] at offset 2 is valid: vertex 0 moves to (0, 0, 5).
    let model = parse(&sparse(1, 2)).expect("a valid sparse accessor");
    let moved = model.parts[0].mesh.vertices().iter().any(|v| v.position == [0.0, 0.0, 5.0]);
    assert!(moved, "the sparse value replaces vertex 0");
    assert_error(&sparse(2, 0), "accessor 0: sparse index 1 is 1, not above the one before (1)");
    assert_error(&sparse(2, 1), "accessor 0: sparse index 1 is 0, not above the one before (1)");
    assert_error(&sparse(1, 3), "accessor 0: sparse index 0 is 5, past the accessor's 3 elements");
    assert_error(&sparse(4, 0), "accessor 0: sparse count 4 must be from 1 to the accessor's count 3");
    assert_error(
        &sparse(2, 3),
        "accessor 0: sparse indices: 2 of 1 bytes from byte 3 need 5 bytes but bufferView 4 has 4",
    );
}

#[test]
fn attribute_and_index_types_must_match_the_spec() {
    let attribute = |name: &str, accessor: usize| {
        with(triangle(), &format!("/meshes/0/primitives/0/attributes/{name}"), json!(accessor))
    };
    let as_vec2 = with(triangle(), "/accessors/0/type", json!("VEC2"));
    assert_error(&as_vec2, "mesh 0 primitive 0 POSITION: accessor 0 is VEC2 FLOAT; expected VEC3 of FLOAT");
    assert_error(
        &attribute("NORMAL", 1),
        "mesh 0 primitive 0 NORMAL: accessor 1 is SCALAR UNSIGNED_SHORT; expected VEC3",
    );
    assert_error(&attribute("TANGENT", 0), "mesh 0 primitive 0 TANGENT: accessor 0 is VEC3 FLOAT; expected VEC4");
    assert_error(&attribute("TEXCOORD_0", 0), "mesh 0 primitive 0 TEXCOORD_0: accessor 0 is VEC3 FLOAT; expected VEC2");
    assert_error(&attribute("JOINTS_0", 0), "mesh 0 primitive 0 JOINTS_0: accessor 0 is VEC3 FLOAT; expected VEC4");
    let indices = |accessor: usize| with(triangle(), "/meshes/0/primitives/0/indices", json!(accessor));
    assert_error(&indices(0), "mesh 0 primitive 0 indices: accessor 0 is VEC3 FLOAT; expected SCALAR");
    assert_error(
        &indices(2),
        "mesh 0 primitive 0 indices: component type F32 is not allowed: accessor 2 is SCALAR FLOAT; expected SCALAR",
    );
    assert_error(&with(triangle(), "/accessors/1/componentType", json!(5122)), "accessor 1 is SCALAR SHORT");
    // u8 indices [1, 0, 5] over three vertices.
    let past = json!({"bufferView": 4, "byteOffset": 1, "componentType": 5121, "count": 3, "type": "SCALAR"});
    assert_error(&with(triangle(), "/accessors/1", past), "mesh 0 primitive 0: index 5 is past the 3 vertices");
}

#[test]
fn node_transforms_must_be_finite() {
    // 1e39 does not fit in an f32: it reads as infinity.
    for (what, value) in [
        ("translation", json!([1e39, 0, 0])),
        ("rotation", json!([0, 0, 1e39, 1])),
        ("scale", json!([1, -1e39, 1])),
        ("matrix", json!([1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1, 0, 1e39, 0, 0, 1])),
        ("weights", json!([1e39])),
    ] {
        assert_error(
            &with(triangle(), &format!("/nodes/0/{what}"), value),
            &format!("node 0: {what} has a non-finite value"),
        );
    }
    assert_error(
        &with(triangle(), "/nodes/0/rotation", json!([0, 0, 0, 0])),
        "node 0: rotation [0.0, 0.0, 0.0, 0.0] is not a unit quaternion",
    );
    assert_warning(&with(triangle(), "/nodes/0/rotation", json!([0, 0, 0, 2])), "node 0: rotation has length 2, not 1");
    let both = with(
        with(triangle(), "/nodes/0/translation", json!([1, 0, 0])),
        "/nodes/0/matrix",
        json!([1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1]),
    );
    assert_warning(&both, "node 0: has a matrix and translation, rotation or scale; the matrix is used");
    // A matrix of scale zero decomposes to no rotation: the node keeps a finite one.
    let flat = with(triangle(), "/nodes/0/matrix", json!([0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 1]));
    let model = parse(&flat).expect("a zero-scale node loads");
    assert!(model.nodes.iter().all(|n| n.rotation.is_finite()), "{:?}", model.nodes[0].rotation);
}

#[test]
fn cameras_must_have_a_usable_projection() {
    let camera = |c: Value| with(with(triangle(), "/cameras", json!([c])), "/nodes/0/camera", json!(0));
    let perspective = |p: Value| camera(json!({"type": "perspective", "perspective": p}));
    assert!(parse(&perspective(json!({"yfov": 0.8, "znear": 0.1, "zfar": 100}))).is_ok());
    assert_error(&perspective(json!({"yfov": 0, "znear": 0.1})), "camera 0: yfov 0 must be above 0");
    assert_error(&perspective(json!({"yfov": 0.8, "znear": 0})), "camera 0: znear 0 must be above 0");
    assert_error(
        &perspective(json!({"yfov": 0.8, "znear": 1, "zfar": 0.5})),
        "camera 0: zfar 0.5 must be beyond znear 1",
    );
    assert_error(
        &perspective(json!({"yfov": 0.8, "znear": 1, "aspectRatio": 0})),
        "camera 0: aspectRatio 0 must be above 0",
    );
    assert_warning(&perspective(json!({"yfov": 3.5, "znear": 0.1})), "camera 0: yfov 3.5 is not below pi");
    let ortho = |o: Value| camera(json!({"type": "orthographic", "orthographic": o}));
    assert!(parse(&ortho(json!({"xmag": 1, "ymag": 1, "znear": 0, "zfar": 10}))).is_ok());
    assert_error(
        &ortho(json!({"xmag": 0, "ymag": 1, "znear": 0, "zfar": 10})),
        "camera 0: xmag 0 must be finite and not 0",
    );
    assert_error(&ortho(json!({"xmag": 1, "ymag": 0, "znear": 0, "zfar": 10})), "camera 0: ymag 0");
    assert_error(
        &ortho(json!({"xmag": 1, "ymag": 1, "znear": 5, "zfar": 5})),
        "camera 0: zfar 5 must be beyond znear 5",
    );
    // The gltf crate unwraps the projection its type names.
    let mismatch =
        camera(json!({"type": "perspective", "orthographic": {"xmag": 1, "ymag": 1, "znear": 0, "zfar": 10}}));
    assert_error(&mismatch, "camera 0: type perspective without perspective");
}

#[test]
fn lights_must_be_non_negative() {
    let light = |l: Value| {
        let doc = with(triangle(), "/extensions", json!({"KHR_lights_punctual": {"lights": [l]}}));
        with(doc, "/nodes/0/extensions", json!({"KHR_lights_punctual": {"light": 0}}))
    };
    let model = parse(&light(json!({"type": "point", "color": [1, 0.5, 0], "intensity": 3, "range": 10})))
        .expect("a point light");
    assert_eq!(model.lights.len(), 1);
    assert_error(
        &light(json!({"type": "point", "color": [-1, 0, 0]})),
        "light 0: color [-1.0, 0.0, 0.0] must be finite and not negative",
    );
    assert_error(
        &light(json!({"type": "point", "intensity": -2})),
        "light 0: intensity -2 must be finite and not negative",
    );
    assert_error(&light(json!({"type": "point", "intensity": 1e39})), "light 0: intensity inf");
    assert_error(&light(json!({"type": "point", "range": -1})), "light 0: range -1 must be above 0");
    assert_error(&light(json!({"type": "point", "range": 0})), "light 0: range 0 must be above 0");
    let spot = |inner: f64, outer: f64| {
        light(json!({"type": "spot", "spot": {"innerConeAngle": inner, "outerConeAngle": outer}}))
    };
    assert!(parse(&spot(0.2, 0.6)).is_ok());
    for (inner, outer) in [(0.6, 0.2), (0.5, 0.5), (-0.1, 0.5), (0.2, 2.0)] {
        assert_error(&spot(inner, outer), "light 0: spot cone angles");
    }
    assert_warning(
        &light(json!({"type": "directional", "color": [2, 1, 1]})),
        "light 0: color [2.0, 1.0, 1.0] is above 1",
    );
}

#[test]
fn material_factors_must_lie_in_their_ranges() {
    let material =
        |m: Value| with(with(triangle(), "/materials", json!([m])), "/meshes/0/primitives/0/material", json!(0));
    assert!(parse(&material(json!({"pbrMetallicRoughness": {"metallicFactor": 0.5}}))).is_ok());
    let cases = [
        (json!({"pbrMetallicRoughness": {"metallicFactor": 2}}), "material 0: metallicFactor [2.0] must lie in [0, 1]"),
        (json!({"pbrMetallicRoughness": {"roughnessFactor": -0.5}}), "material 0: roughnessFactor [-0.5]"),
        (
            json!({"pbrMetallicRoughness": {"baseColorFactor": [1, 1, 1e39, 1]}}),
            "material 0: baseColorFactor [1.0, 1.0, inf, 1.0]",
        ),
        (json!({"emissiveFactor": [0, -1, 0]}), "material 0: emissiveFactor [0.0, -1.0, 0.0]"),
        (
            json!({"alphaMode": "MASK", "alphaCutoff": -0.5}),
            "material 0: alphaCutoff -0.5 must be finite and not negative",
        ),
        (
            json!({"extensions": {"KHR_materials_emissive_strength": {"emissiveStrength": -3}}}),
            "KHR_materials_emissive_strength -3",
        ),
    ];
    for (m, expected) in cases {
        assert_error(&material(m), expected);
    }
    assert_warning(
        &material(json!({"alphaMode": "MASK", "alphaCutoff": 1.5})),
        "material 0: alphaCutoff 1.5 is above 1",
    );
}

/// A 2 × 2 PNG, encoded here.
fn png() -> Vec<u8> {
    let image = image::RgbaImage::from_pixel(2, 2, image::Rgba([200, 100, 50, 255]));
    let mut bytes = std::io::Cursor::new(Vec::new());
    image.write_to(&mut bytes, image::ImageFormat::Png).expect("encode a PNG");
    bytes.into_inner()
}

#[test]
fn texture_transforms_must_be_finite() {
    let transform = |t: Value| {
        let info = json!({"index": 0, "extensions": {"KHR_texture_transform": t}});
        let doc = with(triangle(), "/materials", json!([{"pbrMetallicRoughness": {"baseColorTexture": info}}]));
        let doc = with(doc, "/textures", json!([{"source": 0}]));
        let doc = with(doc, "/images", json!([{"uri": format!("data:image/png;base64,{}", base64::encode(png()))}]));
        with(doc, "/meshes/0/primitives/0/material", json!(0))
    };
    let model = parse(&transform(json!({"scale": [2, 2]}))).expect("a finite transform");
    assert_eq!(model.textures.len(), 1, "the used image is decoded");
    for t in [json!({"scale": [1e39, 1]}), json!({"offset": [0, -1e39]}), json!({"rotation": 1e39})] {
        assert_error(&transform(t), "material 0: baseColorTexture KHR_texture_transform has a non-finite value");
    }
}

#[test]
fn only_images_a_material_uses_are_read() {
    // Sixteen unused images took gigabytes when every image was decoded; an
    // unused image whose file is absent is not even opened.
    let unused = with(with(triangle(), "/images", json!([{"uri": "absent.png"}])), "/textures", json!([{"source": 0}]));
    let model = parse(&unused).expect("unused images are not read");
    assert!(model.textures.is_empty() && model.warnings.is_empty(), "{:?}", model.warnings);
    // A used one that cannot be read is a warning, and the model draws without it.
    let used = with(
        with(unused, "/materials", json!([{"pbrMetallicRoughness": {"baseColorTexture": {"index": 0}}}])),
        "/meshes/0/primitives/0/material",
        json!(0),
    );
    assert_warning(&used, "image 0: ");
    assert!(parse(&used).expect("loads").textures.is_empty());
    // An image in a buffer view of a GLB-style buffer: the PNG appended to the buffer.
    let mut bytes = buffer_bytes();
    let start = bytes.len();
    bytes.extend(png());
    let length = bytes.len() - start;
    let doc = with(used, "/buffers/0", json!({"uri": data_uri(&bytes), "byteLength": bytes.len()}));
    let doc = with(doc, "/bufferViews/6", json!({"buffer": 0, "byteOffset": start, "byteLength": length}));
    let doc = with(doc, "/images/0", json!({"bufferView": 6, "mimeType": "image/png"}));
    assert_eq!(parse(&doc).expect("an image in a buffer view").textures.len(), 1);
}

#[test]
fn data_uris_must_be_base64() {
    assert_error(
        &with(triangle(), "/buffers/0/uri", json!("data:application/octet-stream,abc")),
        "buffer 0: only base64 data: URIs are read",
    );
    assert_error(
        &with(triangle(), "/buffers/0/uri", json!("data:application/octet-stream;base64,@@@@")),
        "buffer 0: data: URI is not valid base64",
    );
}

#[cfg(unix)]
#[test]
fn a_fifo_named_as_a_buffer_is_refused_at_once() {
    let dir = std::env::temp_dir().join(format!("glint-gltf-fifo-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).expect("temp dir");
    let made = std::process::Command::new("mkfifo").arg(dir.join("buf.bin")).status().expect("mkfifo runs");
    assert!(made.success());
    let doc = with(triangle(), "/buffers/0/uri", json!("buf.bin"));
    let path = dir.join("fifo.gltf");
    std::fs::write(&path, doc.to_string()).expect("write");
    // Opening a FIFO blocks until a writer comes: run the load where a hang shows.
    let (send, receive) = std::sync::mpsc::channel();
    std::thread::spawn(move || {
        let _ = send.send(Model::load(&path).map(|_| ()).map_err(|e| e.message));
    });
    let result =
        receive.recv_timeout(std::time::Duration::from_secs(20)).expect("the load returns instead of blocking");
    let message = result.expect_err("a FIFO is not a buffer");
    assert!(message.contains("not a regular file"), "{message}");
    let _ = std::fs::remove_dir_all(&dir);
}

#[test]
fn the_hostile_fuzz_seeds_are_errors() {
    // fuzz/seeds/model: the first byte picks the format (as the fuzz target reads it).
    let dir = Path::new(env!("CARGO_MANIFEST_DIR")).join("../../fuzz/seeds/model");
    let hostile = [
        "gltf_stride_4",
        "gltf_channel_missing_node",
        "gltf_sparse_unsorted",
        "gltf_index_overrun",
        "gltf_zero_count",
        "gltf_camera_type_mismatch",
        "gltf_negative_light",
    ];
    for name in hostile {
        let bytes = std::fs::read(dir.join(name)).unwrap_or_else(|e| panic!("{name}: {e}"));
        let Some((&1, file)) = bytes.split_first() else { panic!("{name}: expected the glTF kind byte 1") };
        let result = Model::parse(Path::new("/nonexistent/fuzz.gltf"), file, LoadOptions::default());
        assert!(result.is_err(), "{name} is hostile and must be an error");
    }
}

#[test]
fn what_a_model_builds_is_bounded() {
    use super::gltf_check::{MAX_ANIMATION_KEYS, MAX_MODEL_VERTICES};
    // Sparse accessors over zeros: large counts in a few bytes of JSON.
    let zeros = |count: u64, kind: &str| {
        json!({"componentType": 5126, "count": count, "type": kind, "min": [0, 0, 0], "max": [1, 1, 1],
            "sparse": {"count": 1, "indices": {"bufferView": 4, "byteOffset": 2, "componentType": 5121},
                "values": {"bufferView": 5}}})
    };
    let half = MAX_MODEL_VERTICES / 2 + 1;
    let big = with(triangle(), "/accessors/0", zeros(half, "VEC3"));
    assert!(parse(&big).is_ok(), "half the limit is fine");
    // A morph target is one more copy of every vertex: over the limit before anything is read.
    let doc = with(big, "/meshes/0/primitives/0/targets", json!([{"POSITION": 0}]));
    assert_error(&doc, &format!("{} vertices (morph targets counted), more than the 16777216 limit", 2 * (half + 3)));
    let doc = with(animated(0), "/accessors/2", zeros(MAX_ANIMATION_KEYS, "SCALAR"));
    assert_error(
        &doc,
        &format!("the animations would read {} keys, more than the 16777216 limit", MAX_ANIMATION_KEYS + 2),
    );
}

/// A skinned triangle whose first vertex has the weights `first` (the others
/// weigh 1 on joint 0).
fn skinned(first: [f32; 4]) -> Value {
    let floats = |v: &[f32]| v.iter().flat_map(|f| f.to_le_bytes()).collect::<Vec<u8>>();
    let mut bytes = floats(&[0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 1.0, 0.0]);
    bytes.extend([0u16, 1, 2].iter().flat_map(|i| i.to_le_bytes()));
    bytes.extend([0, 0]);
    bytes.extend([0u8; 12]);
    bytes.extend(floats(&first));
    bytes.extend(floats(&[1.0, 0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0]));
    let view = |offset: usize, length: usize| json!({"buffer": 0, "byteOffset": offset, "byteLength": length});
    json!({
        "asset": {"version": "2.0"},
        "scene": 0,
        "scenes": [{"nodes": [0, 1]}],
        "nodes": [{"mesh": 0, "skin": 0}, {}],
        "skins": [{"joints": [1]}],
        "meshes": [{"primitives": [{"attributes": {"POSITION": 0, "JOINTS_0": 2, "WEIGHTS_0": 3}, "indices": 1}]}],
        "buffers": [{"uri": data_uri(&bytes), "byteLength": bytes.len()}],
        "bufferViews": [view(0, 36), view(36, 6), view(44, 12), view(56, 48)],
        "accessors": [
            {"bufferView": 0, "componentType": 5126, "count": 3, "type": "VEC3", "min": [0, 0, 0], "max": [1, 1, 0]},
            {"bufferView": 1, "componentType": 5123, "count": 3, "type": "SCALAR"},
            {"bufferView": 2, "componentType": 5121, "count": 3, "type": "VEC4"},
            {"bufferView": 3, "componentType": 5126, "count": 3, "type": "VEC4"}
        ]
    })
}

#[test]
fn skin_weights_must_be_finite_and_not_negative() {
    assert!(parse(&skinned([1.0, 0.0, 0.0, 0.0])).is_ok());
    for bad in [f32::NAN, f32::INFINITY, -1e30] {
        assert_error(
            &skinned([bad, 0.0, 0.0, 0.0]),
            "WEIGHTS_0: vertex 0 has a weight that is negative, NaN or infinite",
        );
    }
}

#[test]
fn only_gltf_2_is_read() {
    assert_error(&with(triangle(), "/asset/version", json!("3.0")), "asset: version must be 2.x");
    assert_error(&with(triangle(), "/asset/minVersion", json!("2.1")), "asset: minVersion must be 2.0");
    assert!(parse(&with(triangle(), "/asset/version", json!("2.1"))).is_ok(), "minor versions stay readable");
}

#[test]
fn a_glb_header_must_give_the_files_length() {
    let json = triangle().to_string();
    let padded = json.len().div_ceil(4) * 4;
    let total = 12 + 8 + padded;
    let glb = |length: u32| {
        let mut glb = b"glTF".to_vec();
        glb.extend(2u32.to_le_bytes());
        glb.extend(length.to_le_bytes());
        glb.extend((padded as u32).to_le_bytes());
        glb.extend(b"JSON");
        glb.extend(format!("{json:<padded$}").bytes());
        glb
    };
    let load = |bytes: &[u8]| Model::parse(Path::new("m/test.glb"), bytes, LoadOptions::default());
    assert!(load(&glb(total as u32)).is_ok());
    let err = load(&glb(20)).map(|_| ()).expect_err("a header length of 20 is an error").message;
    assert!(err.contains(&format!("GLB header says the file is 20 bytes, but it is {total}")), "{err}");
    assert!(load(b"glTF\x02\x00").is_err(), "a header cut short");
}
