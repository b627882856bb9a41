//! Loading from files held in memory ([`Files::Memory`]), as the web viewer
//! does: load, fetch what the load found missing, load again. The scene comes
//! out as from disk, and paths are held to the set's root just as strictly. A
//! set may leave PNG and JPEG decoding to its host (the page's browser; here
//! the `image` crate stands in for it).

mod common;

use glint::asset::{load_scene_with, FileSet, Files, LoadOptions, SceneDesc};
use std::path::{Path, PathBuf};
use std::sync::Arc;

/// What a host makes of an encoded image: width, height and RGBA8 pixels.
type Decoded = Result<(u32, u32, Vec<u8>), String>;

/// A host decoding as a browser does: PNG and JPEG to straight RGBA8, turned
/// as the image's EXIF orientation says.
fn decode(encoded: &[u8]) -> Decoded {
    use image::ImageDecoder;
    let reader =
        image::ImageReader::new(std::io::Cursor::new(encoded)).with_guessed_format().map_err(|e| e.to_string())?;
    let mut decoder = reader.into_decoder().map_err(|e| e.to_string())?;
    let orientation = decoder.orientation().map_err(|e| e.to_string())?;
    let mut image = image::DynamicImage::from_decoder(decoder).map_err(|e| e.to_string())?;
    image.apply_orientation(orientation);
    let image = image.into_rgba8();
    Ok((image.width(), image.height(), image.into_raw()))
}

/// Load `scene` (a path under the repository root) from a set filled from
/// disk round by round, as a page fetching over HTTP would; returns the scene,
/// the files each round fetched and the images it had `host` decode.
fn load_from_memory(set: &Arc<FileSet>, scene: &str) -> (Result<SceneDesc, glint::Diagnostic>, Vec<Vec<PathBuf>>) {
    let (result, rounds, _) = load_with_host(set, scene, decode);
    (result, rounds)
}

/// [`load_from_memory`], with `host` decoding the images the set leaves to it
/// (after each round's files are in, as the page does); also returns how many
/// images it decoded. A round that only decodes (images inside a glTF) fetches
/// no files.
fn load_with_host(
    set: &Arc<FileSet>,
    scene: &str,
    host: impl Fn(&[u8]) -> Decoded,
) -> (Result<SceneDesc, glint::Diagnostic>, Vec<Vec<PathBuf>>, usize) {
    let options = LoadOptions { files: Files::Memory(set.clone()), ..Default::default() };
    let root = common::repo_root();
    let (mut rounds, mut decoded) = (Vec::new(), 0);
    for _ in 1..=8 {
        let result = load_scene_with(Path::new(scene), options.clone());
        let missing = set.take_missing();
        let fetched: Vec<_> = missing.iter().filter_map(|p| Some((p, std::fs::read(root.join(p)).ok()?))).collect();
        let undecoded = set.take_undecoded();
        // A missing file may be only a warning (an MTL, a texture): go on while any was found.
        if fetched.is_empty() && undecoded.is_empty() {
            return (result, rounds, decoded);
        }
        rounds.push(fetched.iter().map(|(p, _)| p.to_path_buf()).collect());
        for (path, bytes) in fetched {
            set.insert(path, bytes);
        }
        let undecoded: Vec<_> = undecoded.into_iter().chain(set.take_undecoded()).collect();
        decoded += undecoded.len();
        for encoded in undecoded {
            let pixels = host(&encoded);
            set.insert_decoded(encoded, pixels);
        }
    }
    panic!("{scene}: still missing files after 8 rounds");
}

/// A `.scn` block: one `"key" "value"` pair a line.
fn block(pairs: &[(&str, &str)]) -> String {
    let lines: String = pairs.iter().map(|(k, v)| format!("\"{k}\" \"{v}\"\n")).collect();
    format!("{{\n{lines}}}\n")
}

/// A scene using textures beside the scene's folder, a glTF with an external
/// buffer, an OBJ with its MTL and mask, under `demo/mixed.scn`.
fn mixed_scene() -> String {
    [
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
    .concat()
}

#[test]
fn a_scene_with_textures_and_models_loads_from_memory_as_from_disk() {
    // Decoded by glint, then by the host: every image (two for the material,
    // the OBJ's mask) goes to it, in the rounds that fetch them, so the load
    // takes no more passes.
    for (set, images) in [(FileSet::default(), 0), (FileSet::host_decoding(), 3)] {
        let set = Arc::new(set);
        set.insert(Path::new("demo/mixed.scn"), mixed_scene().into_bytes());
        let (scene, rounds, decoded) = load_with_host(&set, "demo/mixed.scn", decode);
        let scene = scene.unwrap_or_else(|e| panic!("{e}"));
        assert_eq!(decoded, images);
        assert_same_as_disk(&scene, &rounds);
    }
}

/// `scene`, loaded from memory in `rounds`, is the mixed scene as loaded from disk.
fn assert_same_as_disk(scene: &SceneDesc, rounds: &[Vec<PathBuf>]) {
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
fn a_jpeg_turned_by_its_exif_orientation_looks_the_same_decoded_by_glint_or_by_the_host() {
    // Stored 32 x 64 with orientation 6 (turn a quarter clockwise): a 64 x 32
    // sign, yellow along its top, red on its left, blue on its right.
    let path = common::repo_root().join("assets/textures/turned.jpg");
    let disk = glint::asset::load_texture(&path, true).expect("turned.jpg").image;
    assert_eq!(disk.dimensions(), (64, 32));
    let near = |(x, y): (u32, u32), rgb: [u8; 3]| {
        let p = disk.get_pixel(x, y).0;
        assert!((0..3).all(|i| p[i].abs_diff(rgb[i]) < 24), "({x}, {y}): {p:?}, expected about {rgb:?}");
    };
    near((32, 2), [240, 200, 40]);
    near((8, 24), [200, 40, 40]);
    near((56, 24), [40, 60, 200]);
    // The same pixels as the stored ones turned, and as a host's (a browser's) turned ones.
    let stored = image::load_from_memory(&std::fs::read(&path).unwrap()).unwrap().into_rgba8();
    assert_eq!(stored.dimensions(), (32, 64));
    assert!(image::imageops::rotate90(&stored) == disk);
    let set = Arc::new(FileSet::host_decoding());
    let scene = block(&[("classname", "material"), ("name", "sign"), ("diffuse_map", "assets/textures/turned.jpg")]);
    set.insert(Path::new("sign.scn"), scene.into_bytes());
    let (loaded, _, decoded) = load_with_host(&set, "sign.scn", decode);
    assert_eq!(decoded, 1);
    assert!(loaded.unwrap_or_else(|e| panic!("{e}")).textures[0].image == disk);
}

#[test]
fn the_showcase_asks_for_its_four_files_in_one_pass_and_loads_as_from_disk() {
    let set = Arc::new(FileSet::host_decoding());
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

#[test]
fn a_gltf_models_images_go_to_the_host_too() {
    let set = Arc::new(FileSet::host_decoding());
    let text = block(&[("classname", "entity"), ("mesh", "../tests/models/uv1.gltf")]);
    set.insert(Path::new("demo/uv1.scn"), text.into_bytes());
    // Its image is a data: URI, named when the glTF is read: the scene and the glTF, then the decoding.
    let (scene, rounds, decoded) = load_with_host(&set, "demo/uv1.scn", decode);
    assert_eq!(rounds, [vec![PathBuf::from("tests/models/uv1.gltf")], vec![]]);
    let scene = scene.unwrap_or_else(|e| panic!("{e}"));
    assert!(scene.warnings.is_empty(), "{:?}", scene.warnings);
    let disk = glint::asset::Model::load(&common::repo_root().join("tests/models/uv1.gltf")).expect("uv1.gltf");
    let textures = &scene.models[0].textures;
    assert!(!textures.is_empty() && decoded == textures.len(), "{decoded} decoded for {} textures", textures.len());
    assert!(textures.iter().zip(&disk.textures).all(|(a, b)| a.image == b.image && a.srgb == b.srgb));
}

#[test]
fn a_host_decodes_only_images_that_pass_the_header_checks_and_its_failures_are_reported() {
    let set = Arc::new(FileSet::host_decoding());
    let options = LoadOptions { files: Files::Memory(set.clone()), ..Default::default() };
    let material = |map: &str| block(&[("classname", "material"), ("name", "m"), ("diffuse_map", map)]);
    let load = |map: &str| {
        set.insert(Path::new("scenes/a.scn"), material(map).into_bytes());
        load_scene_with(Path::new("scenes/a.scn"), options.clone())
    };
    // Too wide, from its header: refused before the host sees it.
    let mut wide = std::io::Cursor::new(Vec::new());
    image::RgbaImage::new(glint::asset::MAX_TEXTURE_SIDE + 1, 1).write_to(&mut wide, image::ImageFormat::Png).unwrap();
    set.insert(Path::new("textures/wide.png"), wide.into_inner());
    let error = load("../textures/wide.png").expect_err("too wide");
    assert!(error.message.contains("at most 8192 pixels a side"), "{error}");
    assert!(set.take_undecoded().is_empty());
    // Named for decoding as it comes in; until decoded, the load fails for now and asks again.
    let tiles = std::fs::read(common::repo_root().join("assets/textures/tiles.png")).expect("tiles.png");
    set.insert(Path::new("textures/tiles.png"), tiles.clone());
    assert_eq!(set.take_undecoded(), [Arc::from(&tiles[..])]);
    assert!(load("../textures/tiles.png").is_err());
    assert_eq!(set.take_undecoded(), [Arc::from(&tiles[..])]);
    // What the host could not decode is reported, with the file's line, and never asked for again.
    set.insert_decoded(tiles.as_slice().into(), Err("the browser says no".into()));
    let error = load("../textures/tiles.png").expect_err("host failed");
    assert_eq!(error.line, Some(4), "{error}");
    assert!(error.message.contains("cannot decode texture: the browser says no"), "{error}");
    assert!(set.take_undecoded().is_empty());
    // Pixels that do not match the header's size are refused, as are too few bytes for the size given.
    set.insert_decoded(tiles.as_slice().into(), Ok((2, 2, vec![0; 16])));
    let error = load("../textures/tiles.png").expect_err("wrong size");
    assert!(error.message.contains("its header says 256 x 256 pixels, its data 2 x 2"), "{error}");
    set.insert_decoded(tiles.as_slice().into(), Ok((256, 256, vec![0; 16])));
    let error = load("../textures/tiles.png").expect_err("short");
    assert!(error.message.contains("256 x 256 pixels in 16 bytes"), "{error}");
    // The host's pixels are the texture's.
    let pixels: Vec<u8> = (0..256 * 256 * 4).map(|i| (i % 251) as u8).collect();
    set.insert_decoded(tiles.as_slice().into(), Ok((256, 256, pixels.clone())));
    let scene = load("../textures/tiles.png").unwrap_or_else(|e| panic!("{e}"));
    assert_eq!(scene.textures[0].image.as_raw(), &pixels);
}

/// The first bytes of a PNG of `w` x `h` RGBA pixels: its signature and header,
/// all that is read before decoding.
fn png_header(w: u32, h: u32) -> Vec<u8> {
    let mut png = b"\x89PNG\r\n\x1a\n\0\0\0\x0dIHDR".to_vec();
    png.extend(w.to_be_bytes());
    png.extend(h.to_be_bytes());
    png.extend([8, 6, 0, 0, 0, 0, 0, 0, 0]); // 8-bit RGBA, then a CRC nobody checks here
    png
}

#[test]
fn inserted_images_are_named_for_decoding_up_to_one_scenes_texture_memory() {
    let set = FileSet::host_decoding();
    // Four 8192-wide images fit in the 1 GiB of one scene's textures; a fifth
    // would not, and nor would one over 8192 a side or a file that is no image.
    let side = glint::asset::MAX_TEXTURE_SIDE;
    for h in 0..5 {
        set.insert(Path::new(&format!("big{h}.png")), png_header(side, side - h));
    }
    set.insert(Path::new("wide.png"), png_header(side + 1, 1));
    set.insert(Path::new("scene.scn"), b"{\n}\n".to_vec());
    let mut named: Vec<_> =
        set.take_undecoded().iter().map(|b| u32::from_be_bytes(b[20..24].try_into().unwrap())).collect();
    named.sort_unstable();
    assert_eq!(named, [side - 3, side - 2, side - 1, side]);
    // Without host decoding nothing is named.
    let plain = FileSet::default();
    plain.insert(Path::new("a.png"), png_header(4, 4));
    assert!(plain.take_undecoded().is_empty());
}
