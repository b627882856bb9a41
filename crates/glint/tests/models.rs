//! Model files: OBJ + MTL loading (parts, materials, options, warnings, safe
//! paths, errors with lines), models placed from `.scn` with material overrides,
//! and rendered models.

mod common;

use glam::{Vec2, Vec3, Vec4};
use glint::asset::{parse_scene, MeshRef, Model};
use glint::scene::ShadingModel;
use glint::{AlphaMode, Camera};
use std::path::{Path, PathBuf};

fn models_dir() -> PathBuf {
    common::repo_root().join("tests/models")
}

/// `../shared/assets/obj/NAME` beside the project, or `None` (with a message).
fn shared_obj(name: &str) -> Option<PathBuf> {
    let path = common::repo_root().join("../shared/assets/obj").join(name);
    if path.exists() {
        Some(path)
    } else {
        eprintln!("skipping: {} is absent", path.display());
        None
    }
}

#[test]
fn obj_parts_get_their_own_mtl_materials_textures_and_warnings() {
    let model = Model::load(&models_dir().join("two_materials.obj")).expect("loads");
    let names: Vec<(&str, Option<usize>)> = model.parts.iter().map(|p| (p.name.as_str(), p.material)).collect();
    assert_eq!(names, vec![("slab", Some(0)), ("roof", Some(1)), ("roof", Some(2))]);
    let triangles: Vec<usize> = model.parts.iter().map(|p| p.mesh.indices().len() / 3).collect();
    assert_eq!(triangles, vec![2, 3, 1], "quad and pentagon triangulated");
    // The roof had no normals: computed, unit length, facing ±Z (it lies in z = 0).
    for v in model.parts[1].mesh.vertices() {
        let n = Vec3::from(v.normal);
        assert!((n.length() - 1.0).abs() < 1e-4 && n.z.abs() > 0.99, "{n}");
    }
    let [tiled, red, painted] = &model.materials[..] else { panic!("three materials") };
    assert_eq!(tiled.material.name, "tiled");
    assert_eq!(tiled.material.uv_scale, Vec2::splat(4.0), "-s 4 4 1 is an option, not a file name");
    assert_eq!(tiled.diffuse_map, Some(0));
    assert_eq!(model.textures[0].image.dimensions(), (4, 4), "'checker tile.png', space and all");
    assert_eq!(red.material.base_color, Vec4::new(0.9, 0.1, 0.1, 0.5));
    assert_eq!(red.material.alpha_mode, AlphaMode::Blend, "d 0.5");
    assert_eq!(painted.diffuse_map, None, "missing texture: drawn without it");
    let warnings: Vec<String> = model.warnings.iter().map(|w| w.to_string()).collect();
    assert_eq!(warnings.len(), 2, "{warnings:?}");
    assert!(warnings[0].contains("missing library.mtl"), "{warnings:?}");
    assert!(warnings[1].contains("not here.png") && warnings[1].contains("painted"), "{warnings:?}");
}

#[test]
fn materials_are_overridden_by_name() {
    let mut model = Model::load(&models_dir().join("two_materials.obj")).expect("loads");
    assert!(model.override_material("red", |m| m.base_color = Vec4::new(0.0, 0.0, 1.0, 1.0)));
    assert_eq!(model.materials[1].material.base_color, Vec4::new(0.0, 0.0, 1.0, 1.0));
    assert!(!model.override_material("Wood", |_| {}), "no such material");
}

#[test]
fn scenes_place_models_and_override_their_materials_per_entity() {
    // tests/scenes/../models is outside the scene's folder: the repository is an asset root.
    let scn = common::repo_root().join("tests/scenes/inline.scn");
    let options = glint::asset::LoadOptions { asset_roots: vec![common::repo_root()], ..Default::default() };
    let text = r#"
{
"classname" "entity"
"mesh" "../models/two_materials.obj"
}
{
"classname" "entity"
"mesh" "../models/two_materials.obj"
"origin" "3 0 0"
"mtl.red.base_color" "0 0 1"
"mtl.red.alpha_mode" "opaque"
"mtl.tiled.smoothness" "0.9"
"mtl.painted.shading" "metallic_roughness"
"mtl.painted.metallic" "1"
"mtl.painted.roughness" "0.2"
"mtl.painted.emissive" "0.5 0 0"
}
{
"classname" "instances"
"mesh" "../models/two_materials.obj"
"count" "4"
}
"#;
    let desc = glint::asset::parse_scene_with(&scn, text, options.clone()).expect("valid");
    assert_eq!(desc.models.len(), 2, "the file once, plus one overridden copy");
    let red = |m: &Model| m.materials[1].material.clone();
    assert_eq!(red(&desc.models[0]).base_color, Vec4::new(0.9, 0.1, 0.1, 0.5), "the original is untouched");
    assert_eq!(red(&desc.models[1]).base_color, Vec4::new(0.0, 0.0, 1.0, 1.0));
    assert_eq!(red(&desc.models[1]).alpha_mode, AlphaMode::Opaque);
    assert_eq!(desc.models[1].materials[0].material.smoothness, 0.9);
    let painted = &desc.models[1].materials[2].material;
    assert_eq!(painted.shading, ShadingModel::MetallicRoughness);
    assert_eq!((painted.metallic, painted.roughness, painted.emissive), (1.0, 0.2, Vec3::new(0.5, 0.0, 0.0)));
    let meshes: Vec<(MeshRef, usize)> = desc.entities.iter().map(|e| (e.mesh, e.transforms.len())).collect();
    assert_eq!(meshes, vec![(MeshRef::Model(0), 1 + 4), (MeshRef::Model(1), 1)]);
    // 2 warnings from the model file itself, none from the scene.
    assert_eq!(desc.warnings.len(), 2, "{:?}", desc.warnings);

    let bad = |extra: &str| {
        let text = format!("{{\n\"classname\" \"entity\"\n\"mesh\" \"../models/two_materials.obj\"\n{extra}\n}}");
        glint::asset::parse_scene_with(&scn, &text, options.clone()).expect_err("invalid").to_string()
    };
    let e = bad("\"mtl.Wood.base_color\" \"1 0 0\"");
    assert!(
        e.contains("inline.scn:4:") && e.contains("no material 'Wood'") && e.contains("'tiled', 'red', 'painted'"),
        "{e}"
    );
    assert!(bad("\"mtl.red.smoothness\" \"2\"").contains("smoothness"));
    assert!(bad("\"mtl.red\" \"1\"").contains("expected mtl.MATERIAL.key"));
    let missing = parse_scene(&scn, "{\n\"classname\" \"entity\"\n\"mesh\" \"nowhere.obj\"\n}").expect_err("missing");
    assert!(missing.to_string().contains("inline.scn:3:") && missing.to_string().contains("nowhere.obj"), "{missing}");
}

/// Write `text` as an OBJ in a fresh folder and load it.
fn load_text(name: &str, text: &str) -> Result<Model, glint::Diagnostic> {
    let dir = std::env::temp_dir().join(format!("glint-obj-{}-{name}", std::process::id()));
    std::fs::create_dir_all(&dir).expect("temp dir");
    let path = dir.join(format!("{name}.obj"));
    std::fs::write(&path, text).expect("write");
    Model::load(&path)
}

#[test]
fn bad_obj_files_are_errors_with_file_and_line() {
    let cases = [
        ("short_vertex", "v 0 0 0\nv 1 0\nf 1 2 3\n", 2),
        ("index_out_of_range", "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 9\n", 4),
        ("bad_number", "v 0 0 0\nv 1 zero 0\n", 2),
        ("nan_position", "v 0 0 0\nv nan 0 0\nv 0 1 0\nf 1 2 3\n", 2),
        ("nan_normal", "v 0 0 0\nv 1 0 0\nv 0 1 0\nvn nan nan nan\nf 1//1 2//1 3//1\n", 4),
        ("inf_uv", "v 0 0 0\nv 1 0 0\nv 0 1 0\nvt 0 inf\nf 1/1 2/1 3/1\n", 4),
        ("only_lines", "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\ng wire\nl 1 2\nl 2 3\n", 6),
    ];
    for (name, text, line) in cases {
        let e = load_text(name, text).expect_err(name);
        assert!(e.path.ends_with(format!("{name}.obj")), "{e}");
        assert_eq!(e.line, Some(line), "{name}: {e}");
    }
    let e = load_text("no_faces", "v 0 0 0\n# nothing else\n").expect_err("no faces");
    assert!(e.to_string().contains("no faces"), "{e}");
    let e = Model::load(Path::new("model.fbx")).expect_err("not a model");
    assert!(e.to_string().contains("expected the extension .obj, .gltf or .glb"), "{e}");
    let e = Model::load(&models_dir().join("absent.obj")).expect_err("absent");
    assert!(e.to_string().contains("cannot read"), "{e}");
}

#[test]
fn hostile_paths_are_refused_and_truncation_never_panics() {
    let text = "mtllib ../../../../etc/passwd\nmtllib /etc/hostname\nv 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n";
    let model = load_text("hostile", text).expect("the geometry still loads");
    assert_eq!(model.warnings.len(), 2, "{:?}", model.warnings);
    assert!(model.warnings.iter().all(|w| w.message.contains("outside the model's folder")), "{:?}", model.warnings);
    // Every prefix of a real file: a model or an error, never a panic.
    let full = std::fs::read_to_string(models_dir().join("two_materials.obj")).expect("read");
    for cut in (0..full.len()).filter(|&i| full.is_char_boundary(i)) {
        let _ = load_text("cut", &full[..cut]);
    }
}

#[test]
fn models_render_from_their_own_framing_camera() {
    let Some(gpu) = common::gpu() else { return };
    let model = Model::load(&models_dir().join("two_materials.obj")).expect("loads");
    let desc = model.into_scene();
    let (image, stats) = common::render_desc(gpu, &desc, 128, glint::Culling::Cpu);
    assert_eq!(stats.draws, 4, "three parts and the sky");
    common::assert_matches_reference("obj_two_materials", &image);
}

#[test]
fn the_cornell_box_shows_its_red_and_green_walls() {
    let (Some(gpu), Some(path)) = (common::gpu(), shared_obj("cornell_box.obj")) else { return };
    let mut desc = Model::load(&path).expect("loads").into_scene();
    // The classic view: from the open side, looking in.
    desc.cameras[0] = Camera::perspective(40.0, 1.0, 3000.0)
        .looking_at(Vec3::new(278.0, 273.0, -800.0), Vec3::new(278.0, 273.0, 0.0));
    let (image, _) = common::render_desc(gpu, &desc, 128, glint::Culling::Cpu);
    let count = |f: &dyn Fn([u8; 4]) -> bool| image.pixels().filter(|p| f(p.0)).count();
    let red = count(&|[r, g, b, _]| r > 120 && g < 60 && b < 60);
    let green = count(&|[r, g, b, _]| g > 120 && r < 60 && b < 60);
    assert!(red > 500 && green > 500, "red {red} and green {green} pixels");
    common::assert_matches_reference("obj_cornell_box", &image);
}

/// Every corner of every triangle of `model` has about its face's normal (within
/// 3°: a slightly bent quad's two triangles share the quad's normal).
fn all_flat(model: &Model) -> bool {
    model.parts.iter().all(|part| {
        let vertex = |i: u32| part.mesh.vertices()[i as usize];
        part.mesh.indices().chunks_exact(3).all(|t| {
            let [a, b, c] = [t[0], t[1], t[2]].map(|i| Vec3::from(vertex(i).position));
            let face = (b - a).cross(c - a).normalize_or_zero();
            face == Vec3::ZERO || t.iter().all(|&i| (Vec3::from(vertex(i).normal) - face).length() < 0.05)
        })
    })
}

#[test]
fn the_cornell_box_has_flat_walls_and_boxes() {
    // No `s` statements and no normals: every face flat, as in Blender.
    let Some(path) = shared_obj("cornell_box.obj") else { return };
    assert!(all_flat(&Model::load(&path).expect("loads")));
}

#[test]
fn the_teapot_is_faceted_without_smoothing_groups_and_smooth_in_one() {
    let Some(path) = shared_obj("teapot.obj") else { return };
    let text = std::fs::read_to_string(&path).expect("read");
    assert!(!text.lines().any(|l| l.starts_with("s ") || l.starts_with("vn ")), "the file gives no smoothing");
    let faceted = Model::load(&path).expect("loads");
    assert!(all_flat(&faceted), "no s statements: flat faces");
    // The same file in one smoothing group.
    let smooth = load_text("teapot_s1", &format!("s 1\n{text}")).expect("loads");
    assert!(!all_flat(&smooth));
    for model in [&faceted, &smooth] {
        let normals = model.parts.iter().flat_map(|p| p.mesh.vertices());
        assert!(normals.into_iter().all(|v| (Vec3::from(v.normal).length() - 1.0).abs() < 1e-3));
    }
    let Some(gpu) = common::gpu() else { return };
    let (image, _) = common::render_desc(gpu, &faceted.into_scene(), 128, glint::Culling::Cpu);
    common::assert_matches_reference("obj_teapot_faceted", &image);
    let (image, _) = common::render_desc(gpu, &smooth.into_scene(), 128, glint::Culling::Cpu);
    common::assert_matches_reference("obj_teapot", &image);
}

/// `../shared/assets/gltf/NAME` beside the project, or `None` (with a message).
fn shared_gltf(name: &str) -> Option<PathBuf> {
    let path = common::repo_root().join("../shared/assets/gltf").join(name);
    path.exists().then_some(path).or_else(|| {
        eprintln!("skipping: ../shared/assets/gltf/{name} is absent");
        None
    })
}

#[test]
fn gltf_samples_load_with_hierarchy_instancing_cameras_and_flat_normals() {
    let Some(dir) = shared_gltf("Box.gltf").and_then(|p| p.parent().map(Path::to_path_buf)) else { return };
    let load = |name: &str| Model::load(&dir.join(name)).unwrap_or_else(|e| panic!("{e}"));
    let boxed = load("Box.gltf");
    assert_eq!((boxed.parts.len(), boxed.materials.len(), boxed.textures.len()), (1, 1, 0));
    // Box.gltf's node rotates the mesh a quarter turn about X: the part carries it.
    let t = boxed.parts[0].transforms[0];
    assert!(
        (t.transform_vector3(Vec3::Y) - Vec3::Z).length() < 1e-5
            || (t.transform_vector3(Vec3::Y) + Vec3::Z).length() < 1e-5
    );
    let textured = load("BoxTextured.gltf");
    assert_eq!(textured.textures.len(), 1);
    assert_eq!(textured.materials[0].diffuse_map, Some(0));
    assert_eq!(textured.materials[0].material.shading, ShadingModel::MetallicRoughness, "glTF's own BRDF");
    assert!(textured.textures[0].srgb, "base colour maps are sRGB");
    let simple = load("SimpleMeshes.gltf");
    assert_eq!(simple.parts.len(), 1, "one mesh used by two nodes is one part");
    assert_eq!(simple.parts[0].transforms.len(), 2, "... drawn at both nodes");
    let cameras = load("Cameras.gltf");
    assert_eq!(cameras.cameras.len(), 2);
    let triangle = load("Triangle.gltf");
    let normals: Vec<Vec3> = triangle.parts[0].mesh.vertices().iter().map(|v| Vec3::from(v.normal)).collect();
    assert!(normals.iter().all(|n| (*n - Vec3::Z).length() < 1e-5), "flat normals, facing +Z: {normals:?}");
    assert!(triangle.warnings.is_empty() && boxed.warnings.is_empty());
}

#[test]
fn gltf_samples_render() {
    let Some(gpu) = common::gpu() else { return };
    for (name, reference, draws) in
        [("BoxTextured.gltf", "gltf_box_textured", 2), ("SimpleMeshes.gltf", "gltf_simple_meshes", 2)]
    {
        let Some(path) = shared_gltf(name) else { return };
        let desc = Model::load(&path).expect("loads").into_scene();
        let (image, stats) = common::render_desc(gpu, &desc, 128, glint::Culling::Cpu);
        assert_eq!(stats.draws, draws, "{name}: the model (instanced) and the sky");
        common::assert_matches_reference(reference, &image);
    }
}

/// A one-triangle glTF with its buffer in a separate file, in a fresh folder.
fn write_gltf(name: &str, indices: [u16; 3], uri: &str) -> PathBuf {
    let dir = std::env::temp_dir().join(format!("glint-gltf-{}-{name}", std::process::id()));
    std::fs::create_dir_all(&dir).expect("temp dir");
    let mut bin: Vec<u8> =
        [[0.0f32, 0.0, 0.0], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0]].iter().flatten().flat_map(|v| v.to_le_bytes()).collect();
    bin.extend(indices.iter().flat_map(|i| i.to_le_bytes()));
    bin.extend([0, 0]);
    std::fs::write(dir.join("tri.bin"), &bin).expect("write bin");
    let json = format!(
        r#"{{"asset":{{"version":"2.0"}},"scene":0,"scenes":[{{"nodes":[0]}}],"nodes":[{{"mesh":0}}],
"meshes":[{{"primitives":[{{"attributes":{{"POSITION":0}},"indices":1}}]}}],
"buffers":[{{"uri":"{uri}","byteLength":44}}],
"bufferViews":[{{"buffer":0,"byteOffset":0,"byteLength":36}},{{"buffer":0,"byteOffset":36,"byteLength":6}}],
"accessors":[{{"bufferView":0,"componentType":5126,"count":3,"type":"VEC3","min":[0,0,0],"max":[1,1,0]}},
{{"bufferView":1,"componentType":5123,"count":3,"type":"SCALAR"}}]}}"#
    );
    let path = dir.join(format!("{name}.gltf"));
    std::fs::write(&path, json).expect("write gltf");
    path
}

#[test]
fn bad_and_hostile_gltf_files_are_errors() {
    let good = write_gltf("good", [0, 1, 2], "tri.bin");
    let model = Model::load(&good).expect("a valid triangle");
    assert_eq!(model.parts[0].mesh.indices().len(), 3);
    let e = Model::load(&write_gltf("bad_index", [0, 1, 5], "tri.bin")).expect_err("index past the vertices");
    assert!(e.to_string().contains("index 5 is past the 3 vertices"), "{e}");
    let e = Model::load(&write_gltf("escape", [0, 1, 2], "../../etc/passwd")).expect_err("escaping URI");
    assert!(e.to_string().contains("outside the model's folder"), "{e}");
    let e = Model::load(&write_gltf("absolute", [0, 1, 2], "/etc/passwd")).expect_err("absolute URI");
    assert!(e.to_string().contains("outside the model's folder"), "{e}");
    // The gltf crate percent-decodes relative URIs before opening them.
    let e = Model::load(&write_gltf("encoded", [0, 1, 2], "%2e%2e/%2e%2e/etc/passwd")).expect_err("encoded escape");
    assert!(e.to_string().contains("outside the model's folder"), "{e}");
    assert!(Model::load(&write_gltf("spaced", [0, 1, 2], "tr%69.bin")).is_ok(), "an encoded name that stays inside");
    // A fuzz find: a relative URI decoding to bytes that are not UTF-8 panicked in the gltf crate.
    let e = Model::load(&write_gltf("not_utf8", [0, 1, 2], "tri%ff.bin")).expect_err("not UTF-8");
    assert!(e.to_string().contains("does not decode to UTF-8"), "{e}");
    // A fuzz find: gltf-json's own validation panicked on a missing POSITION accessor.
    let missing = r#"{"asset":{"version":"2.0"},"meshes":[{"primitives":[{"attributes":{"POSITION":7}}]}]}"#;
    let e =
        Model::parse(Path::new("m/missing.gltf"), missing.as_bytes(), Default::default()).expect_err("no accessor 7");
    assert!(e.to_string().contains("accessor 7 does not exist"), "{e}");
    let sourceless = r#"{"asset":{"version":"2.0"},"images":[{"name":"nothing"}]}"#;
    let e = Model::parse(Path::new("m/image.gltf"), sourceless.as_bytes(), Default::default()).expect_err("no source");
    assert!(e.to_string().contains("image 0: expected a uri"), "{e}");
    // Every prefix of a valid file: an error or a model, never a panic.
    let text = std::fs::read_to_string(&good).expect("read");
    for cut in 0..text.len() {
        let path = good.with_file_name("cut.gltf");
        std::fs::write(&path, &text[..cut]).expect("write");
        assert!(Model::load(&path).is_err(), "a cut file is not a whole model ({cut} bytes)");
    }
}

#[test]
fn node_animations_pose_the_hierarchy_at_a_time() {
    // tests/models/animated.gltf: a quad on a child node 0.5 up; the root slides +2
    // in x over one second (linear) and the child turns a quarter about z at
    // t = 0.5 (step). Buffers in anim.bin.
    let path = models_dir().join("animated.gltf");
    let mut model = Model::load(&path).expect("loads");
    assert_eq!((model.nodes.len(), model.animations.len()), (2, 1));
    assert_eq!(model.animations[0].duration(), 1.0);
    let at = |model: &mut Model, t: f32| {
        model.pose(t);
        model.parts[0].transforms[0]
    };
    let start = at(&mut model, 0.0);
    assert!((start.w_axis.truncate() - Vec3::new(0.0, 0.5, 0.0)).length() < 1e-6, "child offset, parent at rest");
    let mid = at(&mut model, 0.75);
    assert!((mid.w_axis.truncate() - Vec3::new(1.5, 0.5, 0.0)).length() < 1e-5, "{:?}", mid.w_axis);
    assert!((mid.transform_vector3(Vec3::X) - Vec3::Y).length() < 1e-5, "turned a quarter after t = 0.5");
    let early = at(&mut model, 0.25);
    assert!((early.transform_vector3(Vec3::X) - Vec3::X).length() < 1e-6, "step: not turned yet");

    let Some(gpu) = common::gpu() else { return };
    for (time, name) in [(0.0, "gltf_animated_t0"), (0.75, "gltf_animated_t075")] {
        let mut model = Model::load(&path).expect("loads");
        let mut desc = model.clone().into_scene();
        model.pose(time);
        desc.models[0] = model;
        // Black behind the grey quad: a quad in the wrong place fails the comparison.
        desc.environment.background = glint::Background::Color(Vec3::ZERO);
        desc.cameras[0] =
            Camera::perspective(50.0, 0.1, 50.0).looking_at(Vec3::new(0.8, 0.5, 3.0), Vec3::new(0.8, 0.5, 0.0));
        let (image, _) = common::render_desc(gpu, &desc, 64, glint::Culling::Cpu);
        common::assert_matches_reference(name, &image);
    }
}

#[test]
fn obj_map_d_cuts_the_surface_away() {
    // tests/models/cutout.obj: a quad whose material has only a map_d (left half
    // white, right half black), written by make_models.py.
    let model = Model::load(&models_dir().join("cutout.obj")).expect("loads");
    assert!(model.warnings.is_empty(), "{:?}", model.warnings);
    let leaf = &model.materials[0];
    assert_eq!(leaf.material.alpha_mode, AlphaMode::Mask { cutoff: 0.5 });
    let texture = &model.textures[leaf.diffuse_map.expect("map_d becomes the colour map's alpha")];
    let (w, h) = texture.image.dimensions();
    assert_eq!(texture.image.get_pixel(0, h / 2).0, [255, 255, 255, 255], "white, opaque on the left");
    assert_eq!(texture.image.get_pixel(w - 1, h / 2)[3], 0, "cut away on the right");

    let Some(gpu) = common::gpu() else { return };
    let mut desc = model.into_scene();
    desc.environment.background = glint::Background::Color(Vec3::ZERO);
    desc.cameras[0] = Camera::perspective(60.0, 0.1, 10.0).looking_at(Vec3::new(0.0, 0.0, 2.0), Vec3::ZERO);
    let (image, _) = common::render_desc(gpu, &desc, 48, glint::Culling::Cpu);
    let (left, right) = (image.get_pixel(12, 24), image.get_pixel(36, 24));
    assert!(left[1] > 60, "the green left half is drawn: {left:?}");
    assert_eq!(&right.0[..3], &[0, 0, 0], "the right half shows the background");
    common::assert_matches_reference("obj_map_d_cutout", &image);
}

#[test]
fn obj_smoothing_groups_decide_which_edges_are_sharp() {
    // tests/models/smoothing.obj (make_models.py): two octagonal prisms without
    // normals; the left one's sides are smoothing group 1 with flat caps (`s off`),
    // the right one is flat all over.
    let model = Model::load(&models_dir().join("smoothing.obj")).expect("loads");
    assert!(model.warnings.is_empty(), "{:?}", model.warnings);
    let normals = |part: usize| -> Vec<Vec3> {
        model.parts[part].mesh.vertices().iter().map(|v| Vec3::from(v.normal)).collect::<Vec<_>>()
    };
    let (rounded, faceted) = (normals(0), normals(1));
    let horizontal = |n: &&Vec3| n.y.abs() < 1e-5;
    let vertical = |n: &&Vec3| (n.y.abs() - 1.0).abs() < 1e-5;
    assert_eq!(rounded.iter().filter(horizontal).count(), 16, "smooth sides share one normal per corner");
    assert_eq!(faceted.iter().filter(horizontal).count(), 32, "flat sides: four corners each");
    for n in [&rounded, &faceted] {
        assert_eq!(n.iter().filter(vertical).count(), 16, "flat caps");
        assert_eq!(n.len(), n.iter().filter(horizontal).count() + 16, "nothing smooths across the rim");
    }

    // Without its `s` statements the file is flat all over: the rounded prism's
    // sides get four corners each too.
    let text = std::fs::read_to_string(models_dir().join("smoothing.obj")).expect("read");
    let without_s: String = text.lines().filter(|l| !l.starts_with("s ")).map(|l| format!("{l}\n")).collect();
    let flat = load_text("smoothing_without_s", &without_s).expect("loads");
    for part in &flat.parts {
        let horizontal = part.mesh.vertices().iter().filter(|v| v.normal[1].abs() < 1e-5).count();
        assert_eq!(horizontal, 32, "{}: flat sides", part.name);
    }

    let Some(gpu) = common::gpu() else { return };
    let mut desc = model.into_scene();
    desc.environment.background = glint::Background::Color(Vec3::ZERO);
    desc.cameras[0] = Camera::perspective(50.0, 0.1, 20.0).looking_at(Vec3::new(0.0, 2.5, 4.5), Vec3::ZERO);
    // A low sun from the left, so the sides' shading runs across them.
    desc.lights = vec![glint::Light::directional(Vec3::new(1.0, -0.3, -0.4), Vec3::ONE, 0.8)];
    let (image, _) = common::render_desc(gpu, &desc, 96, glint::Culling::Cpu);
    common::assert_matches_reference("obj_smoothing_groups", &image);
}
