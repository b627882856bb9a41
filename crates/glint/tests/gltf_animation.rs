//! glTF skinning, morph targets, the second uv set with `KHR_texture_transform`,
//! spot lights and `.glb`, on the models `tests/models/make_models.py` writes.

mod common;

use glam::{Mat4, Vec2, Vec3};
use glint::asset::{LoadOptions, Model, SceneDesc};
use glint::scene::{LightKind, MapSlots};
use glint::{Camera, OffscreenTarget, Renderer};
use std::path::PathBuf;

fn model_path(name: &str) -> PathBuf {
    common::repo_root().join("tests/models").join(name)
}

/// Where joint matrices `joints` put `p`, skinned by `joint`s and `weights`.
fn skin_point(joints: &[Mat4], p: Vec3, joint: [u16; 4], weights: [f32; 4]) -> Vec3 {
    joint.iter().zip(weights).map(|(&j, w)| joints[j as usize].transform_point3(p) * w).sum()
}

#[test]
fn the_skinned_tube_bends_at_its_elbow() {
    let mut model = Model::load(&model_path("skinned.gltf")).expect("loads");
    assert_eq!(model.skins.len(), 1);
    assert_eq!(model.skins[0].joints.len(), 2);
    let part = &model.parts[0];
    assert_eq!(part.skin, Some(0));
    assert_eq!(part.transforms, vec![Mat4::IDENTITY], "joints place a skinned part, not its node");
    let skin = part.mesh.skin().expect("JOINTS_0 and WEIGHTS_0 read").to_vec();
    assert!(skin.iter().all(|s| (s.weights.iter().sum::<f32>() - 1.0).abs() < 1e-5));
    // The top ring follows the elbow alone; the bottom ring the root alone.
    let top = part.mesh.vertices().iter().position(|v| v.position[1] == 2.0).expect("a top vertex");
    assert_eq!(skin[top].weights, [0.0, 1.0, 0.0, 0.0]);

    let p = Vec3::from(model.parts[0].mesh.vertices()[top].position);
    // At rest nothing moves; at t = 1 the elbow (0, 1, 0) has turned a quarter
    // about +z, so (x, y, z) goes to (1 − y, 1 + x, z).
    for (time, expected) in [(0.0, p), (1.0, Vec3::new(1.0 - p.y, 1.0 + p.x, p.z))] {
        model.pose(time);
        let moved = skin_point(&model.parts[0].joints, p, skin[top].joints, skin[top].weights);
        assert!((moved - expected).length() < 1e-5, "t = {time}: top vertex at {moved}, expected {expected}");
    }
}

#[test]
fn glb_and_gltf_files_of_one_model_load_alike() {
    let mut gltf = Model::load(&model_path("skinned.gltf")).expect("loads");
    let mut glb = Model::load(&model_path("skinned.glb")).expect("loads");
    gltf.pose(0.5);
    glb.pose(0.5);
    assert_eq!(gltf.parts[0].mesh.vertices(), glb.parts[0].mesh.vertices());
    assert_eq!(gltf.parts[0].mesh.skin(), glb.parts[0].mesh.skin());
    assert_eq!(gltf.parts[0].joints, glb.parts[0].joints);
    assert_eq!(gltf.skins, glb.skins);
}

#[test]
fn a_vertex_naming_a_joint_its_skin_lacks_is_an_error() {
    let path = model_path("skinned.gltf");
    let text = std::fs::read_to_string(&path).expect("readable");
    let one_joint = text.replace(r#""joints":[1,2]"#, r#""joints":[1]"#);
    assert_ne!(one_joint, text, "the edit applies");
    let error = Model::parse(&path, one_joint.as_bytes(), LoadOptions::default()).expect_err("joint 1 is missing");
    let message = error.to_string();
    assert!(message.contains("skinned.gltf") && message.contains("joint 1"), "{message}");
    // The fuzz find: component types the spec forbids made the gltf crate panic.
    let float_indices = text.replace(r#""componentType":5123,"count":576"#, r#""componentType":5126,"count":576"#);
    assert_ne!(float_indices, text, "the edit applies");
    let error = Model::parse(&path, float_indices.as_bytes(), LoadOptions::default()).expect_err("float indices");
    assert!(error.to_string().contains("indices: component type F32 is not allowed"), "{error}");
    let u32_joints = text.replace(r#""componentType":5121"#, r#""componentType":5125"#);
    assert_ne!(u32_joints, text, "the edit applies");
    assert!(Model::parse(&path, u32_joints.as_bytes(), LoadOptions::default()).is_err(), "u32 JOINTS_0");
    let no_bind = text.replace(r#","inverseBindMatrices":5"#, "");
    assert_ne!(no_bind, text, "the edit applies");
    let model = Model::parse(&path, no_bind.as_bytes(), LoadOptions::default()).expect("bind matrices are optional");
    assert_eq!(model.skins[0].inverse_bind, vec![Mat4::IDENTITY; 2]);
}

#[test]
fn morph_targets_blend_by_animated_weights() {
    let mut model = Model::load(&model_path("morph.gltf")).expect("loads");
    let centre = |m: &Model| {
        let v = m.parts[0].mesh.vertices().iter().find(|v| v.position[0] == 0.0 && v.position[2] == 0.0).copied();
        v.expect("the centre vertex")
    };
    assert_eq!(centre(&model).position[1], 0.0, "rest weight 0: flat");
    assert_eq!(model.pose(1.0), vec![0], "part 0's mesh changed");
    assert!((centre(&model).position[1] - 0.8).abs() < 1e-6, "full bump at t = 1");
    let corner = model.parts[0].mesh.vertices().iter().find(|v| v.position[0] == -1.0 && v.position[2] == -1.0);
    assert_eq!(corner.expect("a corner").position[1], 0.0, "absent from the sparse target: no offset");
    assert!(model.pose(1.0).is_empty(), "same weights: nothing to upload");
    model.pose(0.5);
    assert!((centre(&model).position[1] - 0.4).abs() < 1e-6, "half way");
    assert!(model.parts[0].mesh.aabb().max.y > 0.39, "bounds follow the morph");
}

#[test]
fn the_second_uv_set_texture_transform_and_spot_light_are_imported() {
    let model = Model::load(&model_path("uv1.gltf")).expect("loads");
    assert!(model.warnings.is_empty(), "{:?}", model.warnings);
    let material = &model.materials[0].material;
    assert_eq!(material.uv1_maps, MapSlots::DIFFUSE);
    assert!((material.uv_rotation - std::f32::consts::FRAC_PI_2).abs() < 1e-6);
    assert_eq!(material.uv_offset, Vec2::new(1.0, 0.0));
    assert!(model.parts[0].mesh.uv1().is_some());
    match model.lights[0].kind {
        LightKind::Spot { position, direction, inner_angle, outer_angle, .. } => {
            assert_eq!(position, Vec3::new(0.0, 0.0, 2.5));
            assert!((direction - Vec3::NEG_Z).length() < 1e-6);
            assert_eq!((inner_angle, outer_angle), (0.35, 0.5));
        }
        other => panic!("expected a spot light, got {other:?}"),
    }
}

/// The model's scene with a black background and a fixed camera.
fn scene(name: &str, eye: Vec3, target: Vec3) -> SceneDesc {
    let mut desc = Model::load(&model_path(name)).expect("loads").into_scene();
    desc.environment.background = glint::Background::Color(Vec3::ZERO);
    desc.cameras[0] = Camera::perspective(45.0, 0.1, 50.0).looking_at(eye, target);
    desc
}

#[test]
fn skinned_and_morphed_models_render_at_two_times() {
    let Some(gpu) = common::gpu() else { return };
    let cases = [
        ("skinned.gltf", "gltf_skinned", Vec3::new(0.0, 1.2, 5.0), Vec3::new(-0.3, 1.0, 0.0)),
        ("morph.gltf", "gltf_morph", Vec3::new(0.0, 2.0, 3.0), Vec3::ZERO),
    ];
    for (file, name, eye, target) in cases {
        // One renderer across both times: the second frame re-uploads only what moved.
        let mut renderer = Renderer::new(gpu);
        let mut world = glint::World::place(scene(file, eye, target), &mut renderer).expect("placed");
        let mut target_image = OffscreenTarget::new(gpu, 96, 96, 4).expect("target");
        for (time, suffix) in [(0.0, "t0"), (1.0, "t1")] {
            world.pose(time, &mut renderer).expect("no cloth to fail");
            // Culled on the CPU, so that this frame's counts are known now.
            let view = glint::View::new(world.desc().cameras[0]).with_culling(glint::Culling::Cpu);
            let stats = renderer.render(world.entities(), view, world.lighting(), &mut target_image).expect("frame");
            assert_eq!(stats.instances_drawn, 1, "{name} {suffix}: in view");
            if time > 0.0 && file == "morph.gltf" {
                assert_eq!(stats.bytes_uploaded.meshes, 81 * 48, "only the 81 morphed vertices, written in place");
            }
            if file == "skinned.gltf" {
                // The instance and its two joint matrices, 64 bytes each, on both frames (the pose changed).
                assert_eq!(stats.bytes_uploaded.instances, 3 * 64, "{suffix}");
            }
            let image = target_image.read_rgba8(gpu).expect("readback");
            common::assert_matches_reference(&format!("{name}_{suffix}"), &image);
        }
    }
}

#[test]
fn the_second_uv_set_renders_through_its_transform() {
    let Some(gpu) = common::gpu() else { return };
    let desc = scene("uv1.gltf", Vec3::new(0.0, 0.0, 3.0), Vec3::ZERO);
    let (image, stats) = common::render_desc(gpu, &desc, 64, glint::Culling::Cpu);
    assert_eq!(stats.instances_drawn, 1);
    // Quadrants after the 90° turn: green top-left, red bottom-left (the spot lights the middle).
    let (tl, bl) = (image.get_pixel(20, 20), image.get_pixel(20, 44));
    assert!(tl[1] > 2 * tl[0].max(tl[2]), "top-left is green: {tl:?}");
    assert!(bl[0] > 2 * bl[1].max(bl[2]), "bottom-left is red: {bl:?}");
    common::assert_matches_reference("gltf_uv1_transform", &image);
}
