//! glTF `MSFT_lod` (`asset/gltf_lod.rs`): the levels an author made become the
//! mesh's levels of detail, each with its error measured against full detail;
//! the level nodes are not drawn on their own; a far instance is drawn with
//! the author's coarse level; documents that name missing nodes are errors,
//! levels that do not match full detail are warnings.

mod common;

use glam::{Mat4, Vec3};
use glint::asset::{LoadOptions, Model};
use glint::scene::procedural;
use glint::{Camera, Culling, OffscreenTarget, Renderer, View};
use serde_json::{json, Value};
use std::path::Path;

/// Sphere tessellations: full detail, then the author's three coarser levels.
const SPHERES: [(u32, u32); 4] = [(48, 32), (24, 16), (12, 8), (6, 4)];

/// A document of spheres: node 0 (the scene's one node) draws the first with
/// material 0 and names nodes 1.. as its `MSFT_lod` levels, each drawing the
/// next sphere with material 0 (all in one base64 buffer).
fn lod_spheres(spheres: &[(u32, u32)]) -> Value {
    let mut bytes: Vec<u8> = Vec::new();
    let (mut views, mut accessors, mut meshes, mut nodes) = (Vec::new(), Vec::new(), Vec::new(), Vec::new());
    for (k, &(segments, rings)) in spheres.iter().enumerate() {
        let mesh = procedural::sphere(segments, rings);
        let start = bytes.len();
        bytes.extend(mesh.vertices().iter().flat_map(|v| v.position).flat_map(f32::to_le_bytes));
        let normals = bytes.len();
        bytes.extend(mesh.vertices().iter().flat_map(|v| v.normal).flat_map(f32::to_le_bytes));
        let indices = bytes.len();
        bytes.extend(mesh.indices().iter().flat_map(|i| i.to_le_bytes()));
        let n = mesh.vertices().len();
        let (lo, hi) = (mesh.aabb().min, mesh.aabb().max);
        for (offset, length) in
            [(start, normals - start), (normals, indices - normals), (indices, bytes.len() - indices)]
        {
            views.push(json!({"buffer": 0, "byteOffset": offset, "byteLength": length}));
        }
        let view = 3 * k;
        accessors.push(json!({"bufferView": view, "componentType": 5126, "count": n, "type": "VEC3",
            "min": lo.to_array(), "max": hi.to_array()}));
        accessors.push(json!({"bufferView": view + 1, "componentType": 5126, "count": n, "type": "VEC3"}));
        accessors.push(
            json!({"bufferView": view + 2, "componentType": 5125, "count": mesh.indices().len(), "type": "SCALAR"}),
        );
        meshes.push(json!({"primitives": [{"attributes": {"POSITION": view, "NORMAL": view + 1},
            "indices": view + 2, "material": 0}]}));
        nodes.push(json!({"mesh": k}));
    }
    nodes[0]["extensions"] = json!({"MSFT_lod": {"ids": (1..spheres.len()).collect::<Vec<_>>()}});
    let uri = format!("data:application/octet-stream;base64,{}", base64::encode(&bytes));
    json!({
        "asset": {"version": "2.0"},
        "extensionsUsed": ["MSFT_lod"],
        "scene": 0,
        "scenes": [{"nodes": [0]}],
        "nodes": nodes,
        "meshes": meshes,
        "materials": [{"pbrMetallicRoughness": {"baseColorFactor": [0.9, 0.5, 0.2, 1.0]}}, {}],
        "buffers": [{"uri": uri, "byteLength": bytes.len()}],
        "bufferViews": views,
        "accessors": accessors
    })
}

fn parse(doc: &Value) -> Result<Model, String> {
    let bytes = serde_json::to_vec(doc).expect("json");
    Model::parse(Path::new("lod.gltf"), &bytes, LoadOptions::default()).map_err(|e| e.to_string())
}

fn error_of(doc: &Value) -> String {
    match parse(doc) {
        Err(e) => e,
        Ok(_) => panic!("the document loads, where an error was expected"),
    }
}

fn triangles(spheres: (u32, u32)) -> usize {
    procedural::sphere(spheres.0, spheres.1).indices().len() / 3
}

#[test]
fn the_authors_levels_are_the_meshs_levels_with_measured_growing_error() {
    let model = parse(&lod_spheres(&SPHERES)).expect("loads");
    assert!(model.warnings.is_empty(), "{:?}", model.warnings);
    assert_eq!(model.parts.len(), 1, "the level nodes are not drawn on their own");
    assert_eq!(model.parts[0].transforms.len(), 1);
    let mesh = &model.parts[0].mesh;
    let given = mesh.given_levels();
    let counts: Vec<usize> = given.iter().map(|l| l.triangles()).collect();
    assert_eq!(counts, SPHERES[1..].iter().map(|&s| triangles(s)).collect::<Vec<_>>());
    assert_eq!(glint::scene::levels::detail_levels(mesh), given, "the simplifier is not asked");
    let vertices: usize = SPHERES.iter().map(|&(s, r)| procedural::sphere(s, r).vertices().len()).sum();
    assert_eq!(mesh.vertices().len(), vertices, "each level's vertices appended once");
    // A sphere of s segments strays from the round one by about 1 - cos(pi / s)
    // of its radius; full detail's own stray is in the measurement too.
    let mut before = 0.0;
    for (level, &(segments, _)) in given.iter().zip(&SPHERES[1..]) {
        let sag = 1.0 - (std::f32::consts::PI / segments as f32).cos();
        assert!(level.error > before && level.error > 0.5 * sag && level.error < 2.0 * sag, "{} vs {sag}", level.error);
        before = level.error;
    }
}

#[test]
fn levels_that_do_not_match_full_detail_are_warnings_and_missing_nodes_errors() {
    let mut other_material = lod_spheres(&SPHERES);
    other_material["meshes"][2]["primitives"][0]["material"] = json!(1);
    let model = parse(&other_material).expect("loads");
    assert_eq!(model.parts[0].mesh.given_levels().len(), 1, "levels stop at the first that does not match");
    assert!(
        model.warnings.iter().any(|w| w.to_string().contains("level node 2 has another material")),
        "{:?}",
        model.warnings
    );

    let mut moved = lod_spheres(&SPHERES);
    moved["nodes"][3]["translation"] = json!([1.0, 0.0, 0.0]);
    let model = parse(&moved).expect("loads");
    assert_eq!(model.parts[0].mesh.given_levels().len(), 2);
    assert!(
        model.warnings.iter().any(|w| w.to_string().contains("level node 3 has another transform")),
        "{:?}",
        model.warnings
    );
    let full_and_two: usize = SPHERES[..3].iter().map(|&(s, r)| procedural::sphere(s, r).vertices().len()).sum();
    assert_eq!(model.parts[0].mesh.vertices().len(), full_and_two, "a dropped level's vertices are not kept");

    let finer_later = lod_spheres(&[(24, 16), (12, 8), (48, 32)]);
    let model = parse(&finer_later).expect("loads");
    assert_eq!(model.parts[0].mesh.given_levels().len(), 1);
    assert!(
        model.warnings.iter().any(|w| w.to_string().contains("1 of its 2 MSFT_lod levels")),
        "{:?}",
        model.warnings
    );

    let mut missing = lod_spheres(&SPHERES);
    missing["nodes"][0]["extensions"]["MSFT_lod"]["ids"] = json!([1, 9]);
    let error = error_of(&missing);
    assert!(error.contains("node 0: MSFT_lod names node 9, which is not another node"), "{error}");
    missing["nodes"][0]["extensions"]["MSFT_lod"]["ids"] = json!([0]);
    assert!(error_of(&missing).contains("names node 0, which is not another node"));
    missing["nodes"][0]["extensions"]["MSFT_lod"] = json!({"ids": "1"});
    let error = error_of(&missing);
    assert!(error.contains("MSFT_lod: invalid type: string \"1\", expected a sequence at line 1 column"), "{error}");
    missing["nodes"][0]["extensions"]["MSFT_lod"] = json!({"ids": [-1]});
    let error = error_of(&missing);
    assert!(error.contains("MSFT_lod: invalid value: integer `-1`, expected usize at line 1 column"), "{error}");
}

#[test]
fn a_far_instance_draws_the_authors_coarsest_level_and_a_near_one_full_detail() {
    let Some(gpu) = common::gpu() else { return };
    let model = parse(&lod_spheres(&SPHERES)).expect("loads");
    let mut desc = model.into_scene();
    desc.cameras[0] = Camera::perspective(40.0, 0.1, 500.0).looking_at(Vec3::new(0.0, 0.0, 3.0), Vec3::ZERO);
    let mut renderer = Renderer::new(gpu);
    let world = glint::World::place(desc, &mut renderer).expect("placed");
    let mut target = OffscreenTarget::new(gpu, 256, 256, 1).expect("target");
    let mut draw = |distance: f32| {
        let mut entities = world.entities().to_vec();
        entities[0].set_transform(0, Mat4::from_translation(Vec3::new(0.0, 0.0, 3.0 - distance)));
        let view = View::new(world.desc().cameras[0]).with_culling(Culling::Cpu);
        renderer.render(&entities, view, world.lighting(), &mut target).expect("frame")
    };
    let mut seen = Vec::new();
    for distance in [1.0, 3.0, 10.0, 30.0, 400.0] {
        let stats = draw(distance);
        let level = stats.instances_per_level.iter().position(|&n| n == 1).expect("one instance drawn");
        // Inside the cross-fade band the next level is drawn too.
        let (alone, fading) = (triangles(SPHERES[level]), triangles(SPHERES[(level + 1).min(3)]));
        let drawn = stats.triangles_drawn as usize;
        assert!(
            drawn == alone || drawn == alone + fading,
            "at {distance}: {drawn} triangles for the author's level {level}"
        );
        seen.push(level);
    }
    assert!(seen.windows(2).all(|w| w[0] <= w[1]), "coarser as it goes away: {seen:?}");
    assert_eq!((seen[0], seen[seen.len() - 1]), (0, 3), "{seen:?}");
}
