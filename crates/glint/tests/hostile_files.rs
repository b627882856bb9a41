//! Files as a hostile user would hand them over: FIFOs and devices where a file
//! is expected, paths and symlinks that leave the asset roots, textures past the
//! memory limit. Each is a clear error (or, for a material library, a warning),
//! never a hang, a read of all memory, or a silent read outside.
#![cfg(unix)]

use glint::asset::{load_scene, load_scene_with, LoadOptions};
use std::os::unix::fs::symlink;
use std::path::{Path, PathBuf};

/// A fresh folder under the system's temporary directory.
fn temp_dir(name: &str) -> PathBuf {
    let dir = std::env::temp_dir().join(format!("glint-hostile-{name}-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).expect("temp dir");
    dir
}

fn mkfifo(path: &Path) {
    let made = std::process::Command::new("mkfifo").arg(path).status().expect("mkfifo runs");
    assert!(made.success(), "mkfifo {}", path.display());
}

fn png(path: &Path, side: u32) {
    image::RgbaImage::from_pixel(side, side, image::Rgba([200, 100, 50, 255])).save(path).expect("png");
}

const CUBE_OBJ: &str = "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n";

fn material(name: &str, map: &str) -> String {
    format!("{{\n\"classname\" \"material\"\n\"name\" \"{name}\"\n\"diffuse_map\" \"{map}\"\n}}\n")
}

fn entity(mesh: &str) -> String {
    format!("{{\n\"classname\" \"entity\"\n\"mesh\" \"{mesh}\"\n}}\n")
}

#[test]
fn fifos_and_devices_are_refused_wherever_a_file_is_named() {
    let dir = temp_dir("fifo");
    mkfifo(&dir.join("pipe.scn"));
    mkfifo(&dir.join("pipe.obj"));
    mkfifo(&dir.join("pipe.png"));
    mkfifo(&dir.join("pipe.mtl"));
    symlink("/dev/zero", dir.join("zero.scn")).expect("symlink");
    symlink("/dev/urandom", dir.join("random.obj")).expect("symlink");
    for scene in ["pipe.scn", "zero.scn"] {
        let error = load_scene(&dir.join(scene)).expect_err(scene);
        assert!(error.to_string().ends_with(&format!("{scene}: not a regular file")), "{error}");
    }
    let cases = [
        (entity("pipe.obj"), "pipe.obj: not a regular file"),
        (entity("random.obj"), "random.obj: not a regular file"),
        (material("m", "pipe.png"), "pipe.png: not a regular file"),
        ("{\n\"classname\" \"cloth\"\n\"mesh\" \"pipe.obj\"\n}\n".to_string(), "pipe.obj: not a regular file"),
    ];
    // Outside assets allowed, so that the link to a device is refused as a device
    // (the asset roots refuse it too: /dev is outside them).
    let anywhere = LoadOptions { allow_outside_assets: true, ..LoadOptions::default() };
    for (text, expected) in cases {
        std::fs::write(dir.join("s.scn"), &text).expect("write");
        let error = load_scene_with(&dir.join("s.scn"), anywhere.clone()).expect_err(expected);
        let message = error.to_string();
        let line = if text.contains("material") { 4 } else { 3 }; // the key's line
        assert!(message.starts_with(&format!("{}:{line}:", dir.join("s.scn").display())), "{message}");
        assert!(message.ends_with(expected), "{message}");
    }
    // A material library that is a FIFO is a missing library: a warning, and the
    // model draws with the default material.
    std::fs::write(dir.join("m.obj"), format!("mtllib pipe.mtl\n{CUBE_OBJ}")).expect("write");
    std::fs::write(dir.join("s.scn"), entity("m.obj")).expect("write");
    let scene = load_scene(&dir.join("s.scn")).expect("loads with a warning");
    assert!(scene.warnings.iter().any(|w| w.to_string().contains("not a regular file")), "{:?}", scene.warnings);
}

#[test]
fn scene_paths_stay_inside_the_asset_roots_after_symlinks() {
    let dir = temp_dir("roots");
    let scenes = dir.join("scenes");
    let outside = dir.join("outside");
    std::fs::create_dir_all(&scenes).expect("dir");
    std::fs::create_dir_all(&outside).expect("dir");
    png(&outside.join("x.png"), 4);
    png(&scenes.join("own.png"), 4);
    std::fs::write(outside.join("m.obj"), CUBE_OBJ).expect("write");
    symlink(outside.join("x.png"), scenes.join("link.png")).expect("symlink");
    symlink(&outside, scenes.join("linkdir")).expect("symlink");
    let absolute = outside.join("x.png").display().to_string();
    let scene = scenes.join("s.scn");
    let escapes = [
        material("a", "../outside/x.png"),
        material("b", &absolute),
        material("c", "link.png"),
        material("d", "linkdir/x.png"),
        entity("../outside/m.obj"),
        entity("linkdir/m.obj"),
    ];
    for text in &escapes {
        std::fs::write(&scene, text).expect("write");
        let error = load_scene(&scene).expect_err(text);
        assert!(error.message.contains("points outside the scene's asset roots"), "{text}: {error}");
        assert_eq!(error.line, Some(if text.contains("entity") { 3 } else { 4 }), "{error}");
        // An asset root widens the scene's folder; allowing outside assets lifts it.
        let widened = LoadOptions { asset_roots: vec![outside.clone()], ..LoadOptions::default() };
        load_scene_with(&scene, widened).unwrap_or_else(|e| panic!("{text}: {e}"));
        let anywhere = LoadOptions { allow_outside_assets: true, ..LoadOptions::default() };
        load_scene_with(&scene, anywhere).unwrap_or_else(|e| panic!("{text}: {e}"));
    }
    std::fs::write(&scene, material("own", "own.png")).expect("write");
    load_scene(&scene).expect("a texture beside the scene is read");
}

#[test]
fn decoded_textures_stay_within_the_texture_memory_limit() {
    let dir = temp_dir("memory");
    for name in ["a.png", "b.png", "c.png"] {
        png(&dir.join(name), 256); // 256 KiB decoded each
    }
    let text = [material("a", "a.png"), material("b", "b.png"), material("c", "c.png")].concat();
    std::fs::write(dir.join("s.scn"), text).expect("write");
    let options = |bytes: u64| LoadOptions { texture_memory: bytes, ..LoadOptions::default() };
    let scene = load_scene_with(&dir.join("s.scn"), options(3 << 18)).expect("three fit exactly");
    assert_eq!(scene.textures.len(), 3);
    let error = load_scene_with(&dir.join("s.scn"), options((3 << 18) - 1)).expect_err("the third does not fit");
    assert_eq!(error.line, Some(14), "the third material's map");
    assert!(error.message.contains("256 x 256 pixels need 0.2 MiB decoded, but only 0.2 MiB"), "{error}");
    // The limit is checked from the header, before the pixels are decoded.
    png(&dir.join("big.png"), 4096);
    std::fs::write(dir.join("big.scn"), material("big", "big.png")).expect("write");
    let error = load_scene_with(&dir.join("big.scn"), options(1 << 20)).expect_err("64 MiB > 1 MiB");
    assert!(error.message.contains("4096 x 4096 pixels need 64.0 MiB decoded, but only 1.0 MiB"), "{error}");
    // Models placed by the scene draw on what the scene has left.
    std::fs::write(dir.join("m.mtl"), "newmtl m\nmap_Kd a.png\n").expect("write");
    std::fs::write(dir.join("m.obj"), format!("mtllib m.mtl\nusemtl m\n{CUBE_OBJ}")).expect("write");
    let text = [material("b", "b.png"), material("c", "c.png"), entity("m.obj")].concat();
    std::fs::write(dir.join("s.scn"), text).expect("write");
    let scene = load_scene_with(&dir.join("s.scn"), options(3 << 18)).expect("fits");
    assert!(scene.warnings.is_empty(), "{:?}", scene.warnings);
    let scene = load_scene_with(&dir.join("s.scn"), options((3 << 18) - 1)).expect("the model's map is a warning");
    assert!(scene.warnings.iter().any(|w| w.message.contains("MiB texture memory limit")), "{:?}", scene.warnings);
}
