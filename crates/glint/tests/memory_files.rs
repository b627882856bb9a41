//! Loading from files held in memory ([`Files::Memory`]), as the web viewer
//! does: load, fetch what the load found missing, load again. The scene comes
//! out as from disk, and paths are held to the set's root just as strictly.

mod common;

use glint::asset::{load_scene_with, FileSet, Files, LoadOptions, SceneDesc};
use std::path::{Path, PathBuf};
use std::sync::Arc;

/// Load `scene` (a path under the repository root) from a set filled from
/// disk round by round, as a page fetching over HTTP would; returns the scene
/// and the files each round fetched.
fn load_from_memory(set: &Arc<FileSet>, scene: &str) -> (Result<SceneDesc, glint::Diagnostic>, Vec<Vec<PathBuf>>) {
    let options = LoadOptions { files: Files::Memory(set.clone()), ..Default::default() };
    let root = common::repo_root();
    let mut rounds = Vec::new();
    for _ in 1..=8 {
        let result = load_scene_with(Path::new(scene), options.clone());
        let missing = set.take_missing();
        let fetched: Vec<_> = missing.iter().filter_map(|p| Some((p, std::fs::read(root.join(p)).ok()?))).collect();
        // A missing file may be only a warning (an MTL, a texture): go on while any was found.
        if fetched.is_empty() {
            return (result, rounds);
        }
        rounds.push(fetched.iter().map(|(p, _)| p.to_path_buf()).collect());
        for (path, bytes) in fetched {
            set.insert(path, bytes);
        }
    }
    panic!("{scene}: still missing files after 8 rounds");
}

/// A `.scn` block: one `"key" "value"` pair a line.
fn block(pairs: &[(&str, &str)]) -> String {
    let lines: String = pairs.iter().map(|(k, v)| format!("\"{k}\" \"{v}\"\n")).collect();
    format!("{{\n{lines}}}\n")
}

#[test]
fn a_scene_with_textures_and_models_loads_from_memory_as_from_disk() {
    let set = Arc::new(FileSet::default());
    // Textures beside the scene's folder, a glTF with an external buffer, an OBJ with its MTL and mask.
    let text = [
        block(&[
            ("classname", "material"),
            ("name", "tiles"),
            ("diffuse_map", "../assets/textures/tiles.png"),
            ("normal_map", "../assets/textures/tiles_normal.png"),
        ]),
        block(&[("classname", "entity"), ("mesh", "plane"), ("material", "tiles")]),
        block(&[("classname", "entity"), ("mesh", "../tests/models/animated.gltf"), ("origin", "0 1 0")]),
        block(&[("classname", "entity"), ("mesh", "../tests/models/cutout.obj"), ("origin", "2 0 0")]),
        block(&[("classname", "camera"), ("origin", "0 2 5")]),
    ]
    .concat();
    set.insert(Path::new("demo/mixed.scn"), text.into_bytes());
    let (scene, rounds) = load_from_memory(&set, "demo/mixed.scn");
    let scene = scene.unwrap_or_else(|e| panic!("{e}"));
    // A load goes past a file the set lacks: the first pass asks for both of
    // the material's textures and both models at once, the next for the
    // models' own files (the glTF's buffer, the OBJ's MTL), the last for the MTL's mask.
    let first = ["assets/textures/tiles.png", "assets/textures/tiles_normal.png", "tests/models/animated.gltf"];
    let first: Vec<PathBuf> = first.iter().chain(&["tests/models/cutout.obj"]).map(PathBuf::from).collect();
    assert_eq!(rounds.first(), Some(&first), "{rounds:?}");
    assert_eq!(rounds.len(), 3, "{rounds:?}");
    assert!(scene.warnings.is_empty(), "{:?}", scene.warnings);
    // What came from memory is what the same files give from disk.
    let root = common::repo_root();
    for (texture, file) in scene.textures.iter().zip(["tiles.png", "tiles_normal.png"]) {
        let srgb = file == "tiles.png";
        let disk = glint::asset::load_texture(&root.join("assets/textures").join(file), srgb).expect("texture");
        assert!(texture.image == disk.image && texture.srgb == srgb, "{file}");
    }
    assert_eq!(scene.models.len(), 2);
    for (model, file) in scene.models.iter().zip(["animated.gltf", "cutout.obj"]) {
        let disk = glint::asset::Model::load(&root.join("tests/models").join(file)).expect("model");
        assert_eq!(model.parts.len(), disk.parts.len(), "{file}");
        assert!(model.parts.iter().zip(&disk.parts).all(|(p, q)| p.mesh.vertices() == q.mesh.vertices()), "{file}");
        assert_eq!(model.textures.len(), disk.textures.len(), "{file}");
        assert!(model.textures.iter().zip(&disk.textures).all(|(s, t)| s.image == t.image), "{file}");
        assert_eq!(model.animations.len(), disk.animations.len(), "{file}");
    }
    assert!(!scene.models[1].textures.is_empty(), "the textures its MTL names");
}

#[test]
fn the_showcase_asks_for_its_four_files_in_one_pass_and_loads_as_from_disk() {
    let set = Arc::new(FileSet::default());
    let scene = "scenes/showcase.scn";
    set.insert(Path::new(scene), std::fs::read(common::repo_root().join(scene)).expect("the showcase"));
    let (loaded, rounds) = load_from_memory(&set, scene);
    let loaded = loaded.unwrap_or_else(|e| panic!("{e}"));
    // Its environment and its three textures, in two blocks, asked for in one pass.
    assert_eq!(rounds.len(), 1, "{rounds:?}");
    assert_eq!(rounds[0].len(), 4, "{rounds:?}");
    let disk = common::load_scene(&common::repo_root().join(scene));
    assert_eq!(loaded.textures.len(), disk.textures.len());
    assert!(loaded.textures.iter().zip(&disk.textures).all(|(a, b)| a.image == b.image && a.srgb == b.srgb));
    let (a, b) = (loaded.environment_image.expect("environment"), disk.environment_image.expect("environment"));
    assert!(a.pixels() == b.pixels());
    assert_eq!(loaded.entities.len(), disk.entities.len());
    assert_eq!(loaded.materials.len(), disk.materials.len());
}

#[test]
fn in_memory_paths_stay_under_the_root_and_missing_files_are_named() {
    let set = Arc::new(FileSet::default());
    let options = LoadOptions { files: Files::Memory(set.clone()), ..Default::default() };
    let material = |map: &str| block(&[("classname", "material"), ("name", "m"), ("diffuse_map", map)]);
    for escape in ["../../etc/passwd.png", "/etc/passwd.png", "http://elsewhere/x.png"] {
        set.insert(Path::new("scenes/escape.scn"), material(escape).into_bytes());
        let error = load_scene_with(Path::new("scenes/escape.scn"), options.clone()).expect_err(escape);
        assert_eq!(error.line, Some(4), "{error}");
        assert!(error.message.contains("points outside"), "{escape}: {error}");
        assert!(set.take_missing().is_empty(), "{escape}: never asked for");
    }
    // Inside the root but absent: an error naming the file, and the path to fetch.
    set.insert(Path::new("scenes/gone.scn"), material("../textures/gone.png").into_bytes());
    let error = load_scene_with(Path::new("scenes/gone.scn"), options.clone()).expect_err("missing");
    assert!(error.to_string().starts_with("scenes/gone.scn:4: "), "{error}");
    assert!(error.message.contains("gone.png"), "{error}");
    assert_eq!(set.take_missing(), [Path::new("textures/gone.png")]);
    // A file over its kind's limit is refused from memory too.
    set.insert(Path::new("scenes/huge.scn"), vec![b' '; (glint::asset::MAX_SCENE_BYTES + 1) as usize]);
    let error = load_scene_with(Path::new("scenes/huge.scn"), options).expect_err("too big");
    assert!(error.message.contains("larger than the"), "{error}");
}
