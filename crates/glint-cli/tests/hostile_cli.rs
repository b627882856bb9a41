//! Hostile input, rounds two and three, as a user meets it on the command
//! line: every case is one error line and its exit code, never a panic, a
//! hang or an allocation past the limits of `docs/limits.md`.

mod common;

use common::*;
use std::path::{Path, PathBuf};
use std::process::Command;

/// A fresh folder for one test's files.
fn scratch(name: &str) -> PathBuf {
    let dir = std::env::temp_dir().join(format!("glint-hostile-{name}-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).unwrap();
    dir
}

fn path(p: &Path) -> &str {
    p.to_str().expect("a UTF-8 path")
}

/// Exit 1 and one error line containing `expected`, no panic.
#[track_caller]
fn assert_bad_input(out: &std::process::Output, expected: &str) {
    let text = stderr(out);
    assert_eq!(out.status.code(), Some(1), "{text}");
    assert!(!text.contains("panicked"), "{text}");
    let errors = error_lines(out);
    assert_eq!(errors.len(), 1, "{text}");
    assert!(errors[0].contains(expected), "expected {expected:?} in {errors:?}");
}

#[test]
fn check_refuses_render_targets_render_could_not_hold() {
    let dir = scratch("targets");
    let block = |k: usize| {
        format!(
            "{{\n\"classname\" \"render_target\"\n\"name\" \"t{k}\"\n\"size\" \"2048 2048\"\n\"format\" \"hdr\"\n}}\n"
        )
    };
    let scene = dir.join("targets.scn");
    std::fs::write(&scene, (0..120).map(block).collect::<String>()).unwrap();
    for command in ["check", "render"] {
        let out =
            glint(&[command, path(&scene), "-o", path(&dir.join("out.png"))][..if command == "check" { 2 } else { 4 }]);
        assert_bad_input(&out, "targets.scn:127: with this render target the scene's targets need 1056 MiB");
    }
    std::fs::remove_dir_all(&dir).unwrap();
}

#[test]
fn frame_number_formats_are_bounded_and_checked_before_drawing() {
    let out = glint(&["render", "tests/scenes/shapes.scn", "--size", "8x8", "-o", "x%065536d.png"]);
    assert_bad_input(&out, "x%065536d.png: bad frame-number format: expected %d or %0Nd with N at most 32");
    let out = glint(&["render", "tests/scenes/shapes.scn", "--size", "8x8", "-o", "x%-5d.png"]);
    assert_bad_input(&out, "bad frame-number format");
}

#[test]
fn compare_reads_through_the_common_reader_and_limits() {
    let dir = scratch("compare");
    let reference = "tests/reference/split.png";
    // A FIFO would block image::open for ever; a device named like an image
    // would be read without end.
    let fifo = dir.join("pipe.png");
    assert!(Command::new("mkfifo").arg(&fifo).status().unwrap().success());
    let zero = dir.join("zero.jpg");
    std::os::unix::fs::symlink("/dev/zero", &zero).unwrap();
    for special in [&fifo, &zero] {
        let out = glint(&["compare", reference, path(special)]);
        assert_bad_input(&out, "not a regular file");
    }
    // Images past the side limit, or two that together need more than the
    // comparison's memory, are refused from their headers.
    let wide = dir.join("wide.png");
    image::GrayImage::new(8193, 1).save(&wide).unwrap();
    assert_bad_input(&glint(&["compare", path(&wide), reference]), "at most 8192 pixels a side");
    let big = dir.join("big.png");
    image::GrayImage::new(8192, 8192).save(&big).unwrap();
    assert_bad_input(&glint(&["compare", path(&big), reference]), "MiB decoded, but only 0.0 MiB");
    std::fs::remove_dir_all(&dir).unwrap();
}

#[test]
fn compare_writes_and_prints_through_the_checked_output() {
    let reference = "tests/reference/split.png";
    if let Some(out) = glint_to_full_stdout(&["compare", path(&repo(reference)), path(&repo(reference))]) {
        assert_write_failed(&out, "standard output");
    }
    if Path::new("/dev/full").exists() {
        let dir = scratch("compare-diff");
        let full = dir.join("full.png");
        std::os::unix::fs::symlink("/dev/full", &full).unwrap();
        let out = glint(&["compare", reference, "tests/reference/monitor.png", "--diff", path(&full)]);
        assert_eq!(out.status.code(), Some(1), "the sizes differ first: {}", stderr(&out));
        let out =
            glint(&["compare", "tests/reference/lights.png", "tests/reference/shapes.png", "--diff", path(&full)]);
        assert_write_failed(&out, path(&full));
        std::fs::remove_dir_all(&dir).unwrap();
    }
}

#[test]
fn bench_post_follows_the_scene_files_rules_at_parse() {
    for (post, expected) in [
        ("bloom bloom", "'bloom' is named twice"),
        ("bloom tonemap fxaa edges vignette glow", "'glow' is not a post effect"),
    ] {
        let out = glint(&["bench", "tests/scenes/shapes.scn", "--frames", "1", "--post", post]);
        let text = stderr(&out);
        assert_eq!(out.status.code(), Some(1), "{text}");
        assert!(text.contains(expected) && !text.contains("adapter"), "{text}");
    }
}

#[test]
fn a_model_with_more_lights_than_a_frame_holds_is_bad_input_for_render_too() {
    let dir = scratch("lights");
    // A glTF of `n` point lights and one triangle.
    let model = |n: usize| {
        let lights: Vec<serde_json::Value> =
            (0..n).map(|_| serde_json::json!({"type": "point", "intensity": 1.0})).collect();
        let mut nodes: Vec<serde_json::Value> =
            (0..n).map(|k| serde_json::json!({"extensions": {"KHR_lights_punctual": {"light": k}}})).collect();
        nodes.push(serde_json::json!({"mesh": 0}));
        // One triangle: three VEC3 positions, 36 bytes.
        let positions: Vec<u8> = [0f32, 0., 0., 1., 0., 0., 0., 1., 0.].iter().flat_map(|f| f.to_le_bytes()).collect();
        std::fs::write(dir.join("tri.bin"), &positions).unwrap();
        let doc = serde_json::json!({
            "asset": {"version": "2.0"},
            "extensionsUsed": ["KHR_lights_punctual"],
            "extensions": {"KHR_lights_punctual": {"lights": lights}},
            "scene": 0,
            "scenes": [{"nodes": (0..=n).collect::<Vec<_>>()}],
            "nodes": nodes,
            "meshes": [{"primitives": [{"attributes": {"POSITION": 0}}]}],
            "buffers": [{"uri": "tri.bin", "byteLength": 36}],
            "bufferViews": [{"buffer": 0, "byteLength": 36}],
            "accessors": [{"bufferView": 0, "componentType": 5126, "count": 3, "type": "VEC3", "min": [0, 0, 0], "max": [1, 1, 0]}]
        });
        let path = dir.join(format!("lamps_{n}.gltf"));
        std::fs::write(&path, doc.to_string()).unwrap();
        path
    };
    let too_many = model(4097);
    for args in [&["check", path(&too_many)][..], &["render", path(&too_many), "-o", path(&dir.join("o.png"))]] {
        assert_bad_input(&glint(args), "lamps_4097.gltf: 4097 lights, but a frame can use at most 4096");
    }
    // 100 are drawn with light clusters, and refused without them.
    let hundred = model(100);
    let out = glint(&["render", path(&hundred), "-o", path(&dir.join("o.png")), "--size", "32x32"]);
    if !no_adapter(&out) {
        assert_eq!(out.status.code(), Some(0), "{}", stderr(&out));
        let off = glint(&["render", path(&hundred), "-o", path(&dir.join("o.png")), "--clusters", "off"]);
        assert_ne!(off.status.code(), Some(0));
        assert!(
            stderr(&off).contains("lights with light clusters off given, but a frame can use at most 64"),
            "{}",
            stderr(&off)
        );
    }
    std::fs::remove_dir_all(&dir).unwrap();
}

#[test]
fn sim_cloth_mesh_errors_name_their_line() {
    let dir = scratch("cloth-obj");
    let mesh = dir.join("sheet.obj");
    std::fs::write(&mesh, "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\nf 1 2 7\n").unwrap();
    let out = glint(&["sim", "cloth", "--mesh", path(&mesh), "--steps", "1"]);
    assert_bad_input(&out, "sheet.obj:5: expected a face of three or more vertex numbers");
    std::fs::remove_dir_all(&dir).unwrap();
}

#[test]
fn a_cloth_no_step_can_resolve_is_refused_by_check() {
    let dir = scratch("cloth-gravity");
    let scene = dir.join("fall.scn");
    std::fs::write(&scene, "{\n\"classname\" \"cloth\"\n\"gravity\" \"3e38 0 0\"\n}\n").unwrap();
    assert_bad_input(&glint(&["check", path(&scene)]), "fall.scn:3: \"gravity\" is");
    std::fs::remove_dir_all(&dir).unwrap();
}

#[test]
fn frames_larger_than_one_buffer_are_read_back_in_bands() {
    // 8193 × 8192 RGBA is 268 MB, past the 256 MiB max_buffer_size: it used to
    // panic when saving. Drawn without MSAA, it is a few seconds on lavapipe.
    let dir = scratch("big-frame");
    let png = dir.join("big.png");
    let out = glint(&["render", "tests/scenes/shapes.scn", "--size", "8193x8192", "--msaa", "1", "-o", path(&png)]);
    if no_adapter(&out) {
        return;
    }
    assert_eq!(out.status.code(), Some(0), "{}", stderr(&out));
    let image = image::open(&png).unwrap().into_rgba8();
    assert_eq!(image.dimensions(), (8193, 8192));
    // The bands meet: the rows either side of the first band's end are not blank.
    let band = (256u64 << 20) / u64::from((8193 * 4u32).div_ceil(256) * 256);
    let row_sum = |y: u32| (0..8193).map(|x| u64::from(image.get_pixel(x, y)[1])).sum::<u64>();
    assert!(row_sum(band as u32 - 1) > 0 && row_sum(band as u32) > 0);
    std::fs::remove_dir_all(&dir).unwrap();
}

#[test]
fn a_target_the_device_cannot_hold_is_exit_3_never_a_panic() {
    // 16384² with 4× MSAA is 9 GiB of textures: lavapipe runs out of memory,
    // which wgpu's default handler turned into a panic.
    let dir = scratch("oom");
    let out = glint(&["render", "tests/scenes/shapes.scn", "--size", "16384x16384", "-o", path(&dir.join("o.png"))]);
    if no_adapter(&out) {
        return;
    }
    let text = stderr(&out);
    assert!(!text.contains("panicked"), "{text}");
    match out.status.code() {
        // A device that holds it draws it.
        Some(0) => assert_eq!(image::image_dimensions(dir.join("o.png")).unwrap(), (16384, 16384)),
        Some(3) => assert_eq!(
            error_lines(&out),
            ["error: cannot make a 16384x16384 target with 4 samples: the GPU is out of memory"]
        ),
        other => panic!("exit {other:?}: {text}"),
    }
    std::fs::remove_dir_all(&dir).unwrap();
}

#[test]
fn sim_reports_are_checked_writes() {
    // `glint sim school` and `sim particles` panicked on a full stdout.
    let cases: [&[&str]; 4] = [
        &["sim", "school", "--fish", "20", "--steps", "1"],
        &["sim", "school", "--fish", "20", "--steps", "1", "--bench", "--json"],
        &["sim", "particles", "--alive", "1000", "--steps", "1"],
        &["sim", "particles", "--alive", "1000", "--steps", "1", "--json"],
    ];
    for args in cases {
        if let Some(out) = glint_to_full_stdout(args) {
            assert_write_failed(&out, "standard output");
        }
    }
}

#[test]
fn a_time_step_must_stay_a_32_bit_number() {
    // 1e300 is finite as f64 and infinite as f32 (NaN statistics, exit 0); 1e-300 is 0.
    for dt in ["1e300", "1e-300"] {
        let out = glint(&["sim", "school", "--fish", "20", "--steps", "1", "--dt", dt]);
        assert_bad_input(&out, "(a 32-bit float)");
    }
}

#[test]
fn long_command_line_values_are_quoted_to_the_policy() {
    let long = "9".repeat(100_000);
    let cases: [&[&str]; 8] = [
        &["render", "tests/scenes/shapes.scn", "--fps", &long],
        &["render", "tests/scenes/shapes.scn", "--size", &long],
        &["render", "tests/scenes/shapes.scn", "--time", &long],
        &["render", "tests/scenes/shapes.scn", "--frame-range", &long],
        &["render", "tests/scenes/shapes.scn", "--time-of-day", &long],
        &["bench", "tests/scenes/shapes.scn", "--density", &long],
        &["view", "tests/scenes/shapes.scn", "--at", &long],
        &["render", "tests/scenes/shapes.scn", &format!("--{long}")],
    ];
    for args in cases {
        let out = glint(args);
        let text = stderr(&out);
        assert_eq!(out.status.code(), Some(1), "{}", glint::text::shorten(&text, 400));
        assert!(text.len() < 1000 && text.contains(" characters)"), "{}", glint::text::shorten(&text, 400));
    }
}

#[test]
fn the_naive_frame_refuses_scenes_past_its_limit_before_the_gpu() {
    let dir = scratch("naive");
    let scene = dir.join("many.scn");
    let count = glint::render::MAX_NAIVE_DRAWS + 1;
    std::fs::write(&scene, format!("{{\n\"classname\" \"instances\"\n\"mesh\" \"cube\"\n\"count\" \"{count}\"\n}}\n"))
        .unwrap();
    let expected = "this scene has 150001, more than the 150000 it draws";
    assert_bad_input(&glint(&["bench", path(&scene), "--mode", "naive", "--frames", "1"]), expected);
    assert_bad_input(&glint(&["bench", path(&scene), "--mode", "both", "--frames", "1"]), expected);
    assert_bad_input(&glint(&["explain", path(&scene), "--naive"]), expected);
    std::fs::remove_dir_all(&dir).unwrap();
}

#[test]
fn the_instance_limit_counts_each_part_of_a_placed_model() {
    // An OBJ of two objects placed 2,000,000 times passed check and failed in render.
    let dir = scratch("parts");
    std::fs::write(
        dir.join("two.obj"),
        "o a\nv 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\no b\nv 0 0 1\nv 1 0 1\nv 0 1 1\nf 4 5 6\n",
    )
    .unwrap();
    let scene = dir.join("parts.scn");
    let block =
        |count: u64| format!("{{\n\"classname\" \"instances\"\n\"mesh\" \"two.obj\"\n\"count\" \"{count}\"\n}}\n");
    std::fs::write(&scene, block(1_000_001)).unwrap();
    assert_bad_input(
        &glint(&["check", path(&scene)]),
        "parts.scn:4: the scene places 2000002 instances (1000001 placements of a model that makes 2 instances each)",
    );
    std::fs::write(&scene, block(1_000_000)).unwrap();
    let out = glint(&["check", path(&scene)]);
    assert_eq!(out.status.code(), Some(0), "{}", stderr(&out));
    assert!(String::from_utf8_lossy(&out.stdout).contains("instances:  2000000"));
    std::fs::remove_dir_all(&dir).unwrap();
}

#[test]
fn a_swaying_sun_far_in_the_future_still_draws() {
    // At --time 6e37 the sway's phase overflowed to NaN: exit 3 with an internal message.
    let dir = scratch("sway");
    let scene = dir.join("sway.scn");
    std::fs::write(
        &scene,
        "{\n\"classname\" \"light_directional\"\n\"direction\" \"0.3 -1 0.2\"\n\"sway\" \"10 4\"\n\"shadows\" \"1\"\n}\n\
         {\n\"classname\" \"entity\"\n\"mesh\" \"cube\"\n}\n{\n\"classname\" \"camera\"\n\"origin\" \"2 2 4\"\n}\n",
    )
    .unwrap();
    let out = glint(&["render", path(&scene), "--time", "6e37", "--size", "16x16", "-o", path(&dir.join("o.png"))]);
    if no_adapter(&out) {
        return;
    }
    assert_eq!(out.status.code(), Some(0), "{}", stderr(&out));
    std::fs::remove_dir_all(&dir).unwrap();
}
