//! Files as a hostile user would hand them over: FIFOs and devices where a file
//! is expected, paths and symlinks that leave the asset roots, textures past the
//! memory limit; environments whose headers lie, and what emitters and compact
//! instances ask of the frame. Each is a clear error (or, for a material
//! library, a warning), never a hang, a read of all memory, or a silent read outside.
#![cfg(unix)]

mod common;

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

/// A scene whose world's environment is `file`.
fn environment(file: &str) -> String {
    format!("{{\n\"classname\" \"world\"\n\"environment\" \"{file}\"\n}}\n")
}

/// `bytes` with the four little-endian i32s after `attribute`'s header (its
/// name, type and size) replaced by `bounds` (an OpenEXR box2i: min x, min y,
/// max x, max y).
fn patch_box(bytes: &mut [u8], attribute: &str, bounds: [i32; 4]) {
    let name = format!("{attribute}\0box2i\0");
    let at = bytes.windows(name.len()).position(|w| w == name.as_bytes()).expect("attribute") + name.len() + 4;
    for (k, v) in bounds.iter().enumerate() {
        bytes[at + 4 * k..at + 4 * k + 4].copy_from_slice(&v.to_le_bytes());
    }
}

#[test]
fn an_openexr_whose_windows_lie_is_refused_from_its_header() {
    let dir = temp_dir("exr");
    let exr = dir.join("sky.exr");
    image::Rgb32FImage::from_pixel(2, 1, image::Rgb([0.5, 0.6, 0.7])).save(&exr).expect("exr");
    let good = std::fs::read(&exr).expect("read");
    std::fs::write(dir.join("s.scn"), environment("sky.exr")).expect("write");
    load_scene(&dir.join("s.scn")).expect("the honest file loads");
    // A data window 10⁹ wide over one 32-byte chunk aborted with a 192 GB allocation.
    let mut wide = good.clone();
    patch_box(&mut wide, "dataWindow", [0, 0, 999_999_999, 0]);
    std::fs::write(&exr, &wide).expect("write");
    let error = load_scene(&dir.join("s.scn")).expect_err("data window");
    assert_eq!(error.line, Some(3), "{error}");
    assert!(error.message.contains("its data window is 1000000000 x 1 pixels"), "{error}");
    // An 8192² display window over a 2 × 1 data window took over 30 s.
    let mut display = good;
    patch_box(&mut display, "displayWindow", [0, 0, 8191, 8191]);
    std::fs::write(&exr, &display).expect("write");
    let error = load_scene(&dir.join("s.scn")).expect_err("display window");
    assert!(error.message.contains("8192 x 8192 pixels: environments may have at most 33554432 pixels"), "{error}");
}

#[test]
fn a_radiance_header_is_capped_and_never_quoted() {
    let dir = temp_dir("hdr");
    std::fs::write(dir.join("s.scn"), environment("sky.hdr")).expect("write");
    let pixels = [128u8, 128, 128, 128, 128, 128, 128, 128];
    let file = |header: &str| [header.as_bytes(), b"\n-Y 1 +X 2\n", &pixels].concat();
    std::fs::write(dir.join("sky.hdr"), file("#?RADIANCE\nFORMAT=32-bit_rle_rgbe\n")).expect("write");
    load_scene(&dir.join("s.scn")).expect("the honest file loads");
    // Millions of header lines cost ~40 bytes of memory a byte (255 MB aborted).
    let long = format!("#?RADIANCE\n{}FORMAT=32-bit_rle_rgbe\n", "# comment\n".repeat(10_000));
    std::fs::write(dir.join("sky.hdr"), file(&long)).expect("write");
    let error = load_scene(&dir.join("s.scn")).expect_err("long header");
    assert!(error.message.contains("does not end (an empty line) within its first 65536 bytes"), "{error}");
    // The decoder quoted the FORMAT value: glint says what it expected.
    let hostile = format!("#?RADIANCE\nFORMAT={}\n", "\u{1b}[31mEVIL".repeat(100));
    std::fs::write(dir.join("sky.hdr"), file(&hostile)).expect("write");
    let error = load_scene(&dir.join("s.scn")).expect_err("format").to_string();
    assert!(error.contains("FORMAT is not 32-bit_rle_rgbe") && !error.contains("EVIL"), "{error}");
    // Pixels the decoder refuses are described by kind, not by its message.
    let whole = file("#?RADIANCE\nFORMAT=32-bit_rle_rgbe\n");
    std::fs::write(dir.join("sky.hdr"), &whole[..whole.len() - 3]).expect("write");
    let error = load_scene(&dir.join("s.scn")).expect_err("cut").to_string();
    assert!(error.ends_with("cannot decode environment: it ends early (cut short)"), "{error}");
}

#[test]
fn emitters_sharing_a_sprite_upload_it_once() {
    let Some(gpu) = common::gpu() else { return };
    // Ten emitters sharing one 8192² PNG used 6.8 GB: each uploaded its own copy.
    let dir = temp_dir("sprites");
    png(&dir.join("spark.png"), 64);
    let emitter = "{\n\"classname\" \"emitter\"\n\"rate\" \"50\"\n\"texture\" \"spark.png\"\n}\n";
    let camera = "{\n\"classname\" \"camera\"\n\"origin\" \"0 1 6\"\n}\n";
    std::fs::write(dir.join("s.scn"), format!("{camera}{}", emitter.repeat(10))).expect("write");
    let desc = load_scene(&dir.join("s.scn")).expect("loads");
    assert_eq!(desc.textures.len(), 1, "one texture for the file");
    let mut renderer = glint::Renderer::new(gpu);
    let mut world = glint::World::place(desc, &mut renderer).expect("placed");
    let mut target = glint::OffscreenTarget::new(gpu, 32, 32, 1).expect("target");
    let views = world.views(None);
    world.pose(1.0, &mut renderer).expect("posed");
    let first = world.draw(&mut renderer, &views, &mut target).expect("frame");
    assert_eq!(first[0].bytes_uploaded.textures, 64 * 64 * 4, "one copy of the sprite, on the first frame");
    assert!(first[0].particles_drawn > 0, "the emitters drew");
    world.pose(1.1, &mut renderer).expect("posed");
    let second = world.draw(&mut renderer, &views, &mut target).expect("frame");
    assert_eq!(second[0].bytes_uploaded.textures, 0);
}

#[test]
fn the_naive_frame_draws_compact_tiles_as_the_optimized_frame_does() {
    let Some(gpu) = common::gpu() else { return };
    // 400 cones in 4 tiles, compact: the naive frame indexed past the boxes
    // (a compact instance has none of its own) and panicked.
    let text = "{\n\"classname\" \"camera\"\n\"origin\" \"0 12 14\"\n\"target\" \"0 0 0\"\n}\n\
                {\n\"classname\" \"light_directional\"\n\"direction\" \"-0.3 -1 -0.4\"\n}\n\
                {\n\"classname\" \"instances\"\n\"mesh\" \"cone\"\n\"count\" \"400\"\n\"tiles\" \"2\"\n\
                \"compact\" \"1\"\n\"density\" \"0.5\"\n}\n";
    let desc = glint::asset::parse_scene(Path::new("compact.scn"), text).expect("parses");
    let frame = |mode: glint::FrameMode| {
        let mut renderer = glint::Renderer::new(gpu);
        renderer.set_mode(mode);
        let entities = renderer.place_scene(&desc).entities;
        let mut target = glint::OffscreenTarget::new(gpu, 96, 96, 1).expect("target");
        let view = glint::View::new(desc.cameras[0]).with_culling(glint::Culling::Off);
        let stats = renderer.render(&entities, view, desc.lighting(), &mut target).expect("frame");
        (target.read_rgba8(gpu).expect("readback"), stats)
    };
    let (naive, naive_stats) = frame(glint::FrameMode::Naive);
    let (optimized, stats) = frame(glint::FrameMode::Optimized);
    assert_eq!(stats.instances_drawn, 200, "half of each tile, at density 0.5");
    assert_eq!(naive_stats.instances_drawn, stats.instances_drawn);
    assert!(naive_stats.draw_calls >= 200, "one call an instance: {}", naive_stats.draw_calls);
    assert!(common::max_difference(&naive, &optimized) <= 2, "the same picture");
}
